"""Reading a driven test's run folder back: ``curve.dat`` with the interval means of
``means.dat`` on its steps, the cumulative works, the energy columns every driven curve
carries, the energy balance and the kinetic-energy ratios after start-up (SI: J, s).

Split from :mod:`fabmd.protocols.driven` (which writes and runs the inputs these read).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..results.folder import read_ave_time, read_print_file
from ..scene.energy import ContactPower, balance, cumulative
from ..scene.loading import SmoothStartSpeed


# -- reading a driven run back ----------------------------------------------------------
@dataclass
class Outputs:
    """``curve.dat`` columns, with the interval means of ``means.dat`` put on its steps
    (a mean is reported at its interval's end; 0 at step 0) and the cumulative works."""

    columns: dict[str, np.ndarray]
    means: dict[str, np.ndarray]
    external_work_j: np.ndarray
    damping_j: np.ndarray
    contact_j: np.ndarray | None
    #: the contacts' elastic energy U_c at the curve's steps (None: not sampled)
    contact_energy_j: np.ndarray | None = None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def contact_energy_measured(self) -> bool:
        """Was the contacts' elastic energy sampled at every output (in-process)?"""
        return self.contact_energy_j is not None and bool(
            np.all(np.isfinite(self.contact_energy_j)))

    @property
    def elastic_energy_j(self) -> np.ndarray:
        """U = bond strain energy + the contacts' elastic energy where sampled [J]."""
        u = self["strain_energy_j"]
        return u + self.contact_energy_j if self.contact_energy_measured else u


def read_outputs(run_dir: Path, every: int, dt: float,
                 monitor: ContactPower | None = None) -> Outputs:
    """Read ``curve.dat`` and ``means.dat`` of a driven run."""
    raw = read_print_file(Path(run_dir) / "curve.dat")
    means = read_ave_time(Path(run_dir) / "means.dat")
    for name in means:
        if name != "step":
            raw[name] = np.interp(raw["step"], means["step"], means[name], left=0.0)
    external = np.interp(raw["step"], means["step"],
                         cumulative(means["external_power_w"], every, dt), left=0.0)
    damping = np.interp(raw["step"], means["step"],
                        cumulative(means["damping_power_w"], every, dt), left=0.0)
    contact = monitor.work_j(raw["step"], dt) if monitor is not None else None
    elastic = monitor.elastic_energy_j(raw["step"]) if monitor is not None else None
    return Outputs(raw, means, external, damping, contact, elastic)


def energy_columns(out: Outputs) -> dict[str, np.ndarray]:
    """The energy columns every driven curve carries."""
    cols = {"kinetic_energy_j": out["kinetic_j"], "strain_energy_j": out["strain_energy_j"],
            "external_work_j": out.external_work_j, "damping_dissipation_j": out.damping_j}
    if out.contact_j is not None:
        cols["contact_work_j"] = out.contact_j
    if out.contact_energy_j is not None:
        cols["contact_energy_j"] = out.contact_energy_j
    if "kinetic_relative_j" in out.columns:  # relative to the tools' affine field
        cols["kinetic_relative_j"] = out["kinetic_relative_j"]
    return cols


def energy_balance(out: Outputs) -> dict:
    """External work = Δ strain + Δ kinetic + damping + contact work, closing error (the
    contact work split into ΔU_c and the rest where U_c was sampled)."""
    return balance(out.external_work_j, out["strain_energy_j"], out["kinetic_j"],
                   out.damping_j, out.contact_j, out.contact_energy_j)


def _largest_ratio(numerator: np.ndarray, denominator: np.ndarray) -> float | None:
    """Largest numerator / |denominator| over the samples where the denominator is not
    zero; None when there is none (not measured — a floor would read as 1e+288)."""
    den = np.abs(np.asarray(denominator, dtype=float))
    measured = den > 0
    if not measured.any():
        return None
    return float((np.asarray(numerator, dtype=float)[measured] / den[measured]).max())


def kinetic_ratio(out: Outputs, started: np.ndarray) -> float | None:
    """Largest kinetic / elastic energy after start-up: KE relative to the tools' affine
    field where the curve has it (``kinetic_relative_j``), U = bonds + contacts where the
    contacts' energy was sampled (None when nothing is started or no started sample has
    elastic energy)."""
    ke = out.columns.get("kinetic_relative_j", out["kinetic_j"])
    return _largest_ratio(ke[started], out.elastic_energy_j[started])


def kinetic_to_work_ratio(out: Outputs, started: np.ndarray) -> float | None:
    """Largest kinetic energy / external work done so far, after start-up, KE relative to
    the tools' affine field where the curve has it (as :func:`kinetic_ratio`: the
    carriage's force is the per-interval inertia share's business; None when no started
    sample has work done)."""
    ke = out.columns.get("kinetic_relative_j", out["kinetic_j"])
    return _largest_ratio(ke[started], out.external_work_j[started])


STARTED_NOTE = ("kinetic/strain energy after start-up: after the smooth start (if any), "
                "the first tenth of the test, and once the strain energy gained exceeds 1 % of "
                "its final gain (a slack fabric carries no load at first)")


def started_mask(out: Outputs, loading: SmoothStartSpeed, progress: np.ndarray,
                 fraction: float = 0.1) -> np.ndarray:
    """After start-up (see :data:`STARTED_NOTE`); ``progress`` of the test in [0, 1]."""
    u = out["strain_energy_j"]
    loaded = (u - u[0]) > 0.01 * (u[-1] - u[0])
    return (out["time_s"] > loading.ramp_time_s) & (np.asarray(progress) > fraction) & loaded
