"""Export a fabric state for composite analysis: reconstruct its yarns, voxelise them,
write the voxel mesh (VTU, Abaqus ``.inp``), the yarn surfaces (STL, VTU), and check the
result against the bead model (``export.json``)."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError
from .checks import bead_fibre_volume_fraction, direction_errors, domain
from .surfaces import interpenetration_report, write_surfaces
from .voxel import VoxelGrid, voxelise
from .writers import write_abaqus, write_vtu
from .yarns import reconstruct_yarns

#: default voxel edge: the smallest fibre (bead) diameter over this
VOXELS_PER_FIBRE_DIAMETER = 4

#: state files of a run folder, most advanced first (as ``fabmd measure``)
STATES = (("final.data", "model.json"), ("crimped.data", "crimped.json"),
          ("coupon.data", "coupon.json"), ("model.data", "model.json"))


def load_state(folder: Path):
    """The most advanced fabric state a run folder holds: (model, data file name)."""
    from ..model.bead_model import BeadModel

    folder = Path(folder)
    for data, meta in STATES:
        if (folder / data).exists() and (folder / meta).exists():
            return BeadModel.load(folder / data, folder / meta), data
    raise InputError(f"{folder} holds no fabric state (looked for "
                     f"{', '.join(d for d, _ in STATES)} with their .json)")


#: voxel against bead fibre volume fraction beyond which an export warns
VOLUME_FRACTION_TOLERANCE = 0.02


def default_voxel_size_m(model) -> float:
    """Smallest bead diameter / :data:`VOXELS_PER_FIBRE_DIAMETER` [m]."""
    return float(model.diameters.min()) / VOXELS_PER_FIBRE_DIAMETER


def voxel_grid(model, voxels: int | None = None, voxel_size_m: float | None = None
               ) -> VoxelGrid:
    """The voxel grid of a state: ``voxels`` along its longest edge, or a voxel size [m]
    (default :func:`default_voxel_size_m`)."""
    lo, hi = domain(model)
    if voxels is None and voxel_size_m is None:
        voxel_size_m = default_voxel_size_m(model)
    return VoxelGrid.covering(lo, hi, model.periodic, voxels, voxel_size_m)


def export_state(model, out: Path, voxels: int | None = None,
                 voxel_size_m: float | None = None, stations: int | None = None,
                 angles: int = 24, smoothing: int = 2, samples: int | None = None,
                 stem: str = "voxels", keep_mesh: bool = False) -> dict:
    """Write the exports of one state into ``out`` and return the summary.

    Files: ``<stem>.vtu``, ``<stem>.inp`` + ``<stem>_elements.csv``,
    ``surfaces/<yarn>.stl`` + ``surfaces/yarn_surfaces.vtu``, ``export.json`` (the
    summary: grid, cell fibre volume fraction voxel vs beads, direction errors,
    interpenetration, surfaces, timings). ``samples`` None: the voxel centres, and where
    their fibre volume fraction misses the beads' by more than
    :data:`VOLUME_FRACTION_TOLERANCE`, 2³ points per voxel (9× the voxelising; the
    summary's ``centre_sampling_error`` keeps the first miss: the example's crimped cell
    at rest, flat yarns, is +3.3 % at the centres, +0.005 % with 2³); ``keep_mesh`` adds the
    :class:`~fabmd.export.voxel.VoxelMesh` under ``"mesh"`` (not written).
    """
    from ..results.folder import write_json

    out = Path(out)
    grid = voxel_grid(model, voxels, voxel_size_m)  # bad sizes fail before any file
    t0 = time.perf_counter()
    yarns = reconstruct_yarns(model, stations=stations, angles=angles, smoothing=smoothing)
    t1 = time.perf_counter()
    mesh = voxelise(yarns, grid, samples=samples or 1)
    vf_beads = bead_fibre_volume_fraction(model, grid)
    centre_error = None  # the centres' miss, where it made the grid be sampled again
    if samples is None:
        samples = 1
        miss = mesh.cell_fibre_volume_fraction() / vf_beads - 1.0
        if abs(miss) > VOLUME_FRACTION_TOLERANCE:  # thin yarns: sample inside the voxels
            samples, centre_error = 2, miss
            mesh = voxelise(yarns, grid, samples=samples)
    out.mkdir(parents=True, exist_ok=True)
    t2 = time.perf_counter()
    write_vtu(mesh, out / f"{stem}.vtu")
    write_abaqus(mesh, out / f"{stem}.inp")
    surfaces = write_surfaces(yarns, out / "surfaces")
    t3 = time.perf_counter()
    vf_voxel = mesh.cell_fibre_volume_fraction()
    summary = {
        "voxels": list(grid.counts), "samples_per_axis": samples,
        "voxel_size_m": grid.size_m.tolist(),
        "domain_lo_m": grid.lo_m.tolist(), "domain_hi_m": grid.hi_m.tolist(),
        "periodic": list(grid.periodic),
        "fibre_volume_fraction": {"voxels": vf_voxel, "beads": vf_beads,
                                  "relative_error": vf_voxel / vf_beads - 1.0,
                                  "centre_sampling_error": centre_error},
        "yarn_volume_share": mesh.yarn_volume_fraction(),
        "direction_error": direction_errors(model, mesh),
        "interpenetration": interpenetration_report(mesh, yarns),
        "yarns": {y.name: {"family": y.family, "closed": y.closed, "stations": y.n_stations,
                           "volume_m3": y.volume_m3(),
                           "mean_fibre_volume_fraction":
                               float(np.mean(y.fibre_volume_fraction))} for y in yarns},
        "surfaces": surfaces,
        "all_surfaces_watertight": all(s["watertight"] for s in surfaces.values()),
        "timing_s": {"reconstruct": t1 - t0, "voxelise": t2 - t1, "write": t3 - t2},
        "files": [f"{stem}.vtu", f"{stem}.inp", f"{stem}_elements.csv", "surfaces/"],
    }
    error = summary["fibre_volume_fraction"]["relative_error"]
    if abs(error) > VOLUME_FRACTION_TOLERANCE:
        # thin yarns a few voxels across are sampled coarsely (one-fibre yarns at d/4)
        summary["warnings"] = [
            f"the voxel fibre volume fraction is {100 * error:+.1f} % off the bead model's "
            f"(more than {100 * VOLUME_FRACTION_TOLERANCE:g} %"
            f"{', with 2^3 samples per voxel' if samples == 2 else ''}): use "
            f"--samples {samples + 1} (sub-voxel sampling) or a smaller --voxel-size"]
        warnings.warn(summary["warnings"][0], UserWarning, stacklevel=2)
    write_json(out / "export.json", summary)
    if keep_mesh:
        summary["mesh"] = mesh
    return summary
