"""``fabmd build SCENE.toml --out DIR``: render a fabric into beads and write it out.

Writes into DIR (never over an existing folder unless ``--overwrite``):
``model.data`` + ``model.json`` (LAMMPS data file and yarn/fibre identity),
``fibres.vtu`` and ``yarns.vtu`` (ParaView), ``preview.png`` (top view and two
sections), ``scene.json`` (the resolved scene) and ``summary.json`` (counts,
clearance, thickness, timings).
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", type=Path, help="scene file (TOML), e.g. examples/plain_weave.toml")
    p.add_argument("--out", type=Path, required=True,
                   help="results folder (must not exist unless --overwrite)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing fabmd results folder")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def build(scene, out: Path, overwrite: bool = False) -> dict:
    """Render ``scene`` (a :class:`fabmd.scenefile.Scene`) and write the build folder.

    Returns the summary (every rank gets rank 0's).
    """
    import time

    from ..engine import mpi
    from ..preflight import check_scene
    from ..results.folder import abandon_run, begin_run, finish_run

    t0 = time.perf_counter()
    check_scene(scene)  # the stage tables too: a typo in [tension] fails here, not later
    model = scene.model()  # validates and checks overlaps before any folder is made
    t_build = time.perf_counter() - t0
    run_dir = begin_run(out, overwrite=overwrite, prefix="build")
    try:
        summary = _write(scene, model, run_dir, t_build)
    except BaseException as exc:
        abandon_run(out, run_dir, exc)
        raise
    return mpi.bcast_json(finish_run(out, run_dir, summary))


def _write(scene, model, run_dir: Path, t_build: float) -> dict:
    """The build folder's files (rank 0); returns the summary."""
    import time

    from ..engine import mpi
    from ..results.folder import write_json
    from ..results.preview import preview_png
    from ..results.vtu import write_fibres_vtu, write_yarns_vtu

    summary = {}
    if mpi.is_root():
        t1 = time.perf_counter()
        model.save(run_dir, stem="model")
        write_fibres_vtu(model, run_dir / "fibres.vtu")
        write_yarns_vtu(model, run_dir / "yarns.vtu")
        preview_png(model, run_dir / "preview.png", title=scene.title or "")
        write_json(run_dir / "scene.json", scene.to_dict())
        summary = summarise(model, scene)
        summary.update(build_s=t_build, write_s=time.perf_counter() - t1,
                       run_dir=str(run_dir))
        write_json(run_dir / "summary.json", summary)
    mpi.barrier()
    return summary


def summarise(model, scene) -> dict:
    """Counts, clearance, thickness and the stable time step of a built fabric."""
    import numpy as np

    from ..model.fabric_model import bead_parameter_list
    from ..model.timestep import critical_time_step_s

    info = model.info
    fams = model.family_names
    yarn_fam = np.array([y.family for y in model.yarns])
    fibre_fam = yarn_fam[model.fibre_yarn - 1]
    beads = bead_parameter_list(model, scene.fabric, scene.discretisation)
    dt = critical_time_step_s(beads, [scene.contact])  # stability stiffness: Hertz's tangent
    return {
        "architecture": info["architecture"]["name"],
        "periodic": bool(model.periodic[0]),
        "n_beads": model.n_beads,
        "n_bonds": model.n_bonds,
        "n_angles": int(len(model.angles)),
        "n_fibres": model.n_fibres,
        "n_yarns": len(model.yarns),
        "yarns": {f: int(np.count_nonzero(yarn_fam == f)) for f in fams},
        "fibres": {f: int(np.count_nonzero(fibre_fam == f)) for f in fams},
        "beads": {f: int(np.count_nonzero(model.atom_types == k + 1))
                  for k, f in enumerate(fams)},
        "bond_types": len(model.bond_type_table),
        "fibre_diameter_m": {f: info["families"][f]["fibre_diameter_m"] for f in fams},
        "yarn_bending_stiffness_nm2": {
            f: info["families"][f].get("yarn_bending_stiffness_nm2", 0.0) for f in fams},
        "clearance_m": info["clearance_m"],
        "clearance_pair": info["clearance_pair"],
        "thickness_m": info["loose_thickness_m"],
        "fabric_size_m": info["fabric_size_m"],
        "unit_cell_m": info["unit_cell_m"],
        "tiling": info["tiling"],
        "areal_density_kg_m2": info["areal_density_kg_m2"],
        "crimp": info["crimp"],
        "datasheet": info.get("datasheet"),
        "yarn_packing": info.get("yarn_packing"),
        "within_family_law": scene.contact.law_realisation(fams),
        "critical_time_step_s": dt,
    }


def law_line(s: dict) -> str:
    """One line on how the within-family law is realised ('' without the law)."""
    laws = s.get("within_family_law")
    if not laws:
        return ""
    texts = {}  # families that read the same share one text
    for f, r in laws.items():
        text = f"touch at Vf {r['touching_vf']:.2f}"
        if r["cut_pressure_pa"] > 0:
            text += (f" (the law's Vf0 {r['law_vf0']:.2f}: its first "
                     f"{1e-3 * r['cut_pressure_pa']:.3g} kPa cut off)")
        texts.setdefault(text, []).append(f)
    return "\n  within-family law: " + "; ".join(
        f"{', '.join(fams)} fibres {text}" for text, fams in texts.items())


def datasheet_lines(s: dict) -> str:
    """Areal density, thickness and yarn packing built, against the datasheet (text)."""
    ds = s.get("datasheet") or {}
    rho = 1e3 * s["areal_density_kg_m2"]
    line = f"  areal density {rho:.4g} g/m²"
    if ds.get("areal_density_kg_m2"):
        line += (f" (datasheet {1e3 * ds['areal_density_kg_m2']:.4g} g/m², "
                 f"{100 * ds['areal_density_deviation']:+.1f} %)")
    line += f"; loose thickness {1e3 * s['thickness_m']:.3g} mm"
    if ds.get("thickness_m"):
        at = ds.get("thickness_pressure_pa")
        line += (f" (datasheet {1e3 * ds['thickness_m']:.3g} mm"
                 + (f" at {1e-3 * at:.3g} kPa" if at else "") + ")")
    pack = s.get("yarn_packing") or {}
    if pack:
        line += "\n  yarn packing: " + ", ".join(
            f"{f} Vf {p['yarn_fibre_volume_fraction']:.2f} ({p['shape']} "
            f"{1e3 * p['width_m']:.3g} x {1e3 * p['height_m']:.3g} mm"
            + (f", woven width {1e3 * p['woven_width_m']:.3g} mm"
               if abs(p["woven_width_m"] - p["width_m"]) > 1e-12 else "") + ")"
            for f, p in pack.items())
    return line + bending_line(s) + law_line(s)


def bending_line(s: dict) -> str:
    """The yarns' bending rigidity where they have one (text)."""
    texts = {}
    for f, ei in (s.get("yarn_bending_stiffness_nm2") or {}).items():
        if ei > 0:
            texts.setdefault(f"{1e6 * ei:.3g} N·mm²", []).append(f)
    if not texts:
        return ""
    return "\n  yarn bending stiffness E·I: " + "; ".join(
        f"{', '.join(fams)} {text}" for text, fams in texts.items())


def run(args) -> int:
    from ..engine import mpi
    from ..scenefile import load_scene
    from .common import emit

    scene = load_scene(args.scene)
    s = build(scene, args.out, overwrite=args.overwrite)
    if mpi.is_root():
        clear = s["clearance_m"]
        text = (f"fabmd build: {s['architecture']}{' (periodic)' if s['periodic'] else ''}\n"
                f"  {s['n_beads']:,} beads, {s['n_fibres']:,} fibres, {s['n_yarns']} yarns "
                f"({', '.join(f'{n} {f}' for f, n in s['yarns'].items())})\n"
                f"  size {s['fabric_size_m'][0] * 1e3:.4g} x {s['fabric_size_m'][1] * 1e3:.4g} mm,"
                f" thickness {s['thickness_m'] * 1e3:.3g} mm, smallest gap between yarns "
                + (f"{clear * 1e3:.3g} mm" if clear is not None else "(none near)") + "\n"
                + datasheet_lines(s) + "\n"
                f"  built in {s['build_s']:.2f} s, written in {s['write_s']:.2f} s; "
                f"results in {s['run_dir']}")
        emit(s, args.json, text)
    return 0
