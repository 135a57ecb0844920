"""Damping and the quasi-static stop criterion, shared by the relaxation stages.

Damping kinds:

* ``"cundall"`` — local non-viscous damping (``fix damping/cundall``): each force
  component is reduced by a fraction of its magnitude against the velocity. It
  damps every mode at the same rate per cycle and vanishes at equilibrium: the
  DEM choice for reaching a quasi-static state in few steps.
* ``"viscous"`` — ``fix viscous`` with γ = m/τ: drag proportional to velocity.
* ``"none"``.

Quasi-static criterion (checked every ``check_every`` steps): the kinetic energy
is below ``kinetic_ratio`` × (bond strain energy + a floor: the bonds' energy at
the reference force) AND the largest force on a free bead is below
``force_ratio`` × a reference force (the largest fibre tension the stage imposes).

A driven test's curve is judged interval by interval (:func:`interval_verdict`): the
drag's and the kinetic energy's share of the work done in each interval and KE/U there,
so a curve whose first part is drag is flagged there even when the run as a whole passes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import inputs
from .templates import render

DAMPING_KINDS = ("cundall", "viscous", "none")


#: a crimp (or release) that states no settle force is judged at rest against the force
#: this fibre strain gives, E·A × 1e-3 (1 cN/tex, a weaving tension, strains glass 0.035 %)
SETTLE_STRAIN = 1e-3


@dataclass(frozen=True)
class Damping:
    """Numerical damping for quasi-static relaxation.

    Args:
        kind: ``"cundall"`` (default), ``"viscous"`` or ``"none"``.
        cundall_ratio: fraction of the force removed against the motion, in [0, 1).
        viscous_time_s: τ of viscous damping (γ = m/τ) [s], > 0.
    """

    kind: str = "cundall"
    cundall_ratio: float = 0.7
    viscous_time_s: float | None = None

    def __post_init__(self):
        inputs.one_of("damping.kind", self.kind, DAMPING_KINDS)
        inputs.in_range("damping.cundall_ratio", self.cundall_ratio, 0.0, 1.0, high_open=True)
        if self.viscous_time_s is not None:
            inputs.positive("damping.viscous_time_s", self.viscous_time_s)

    def commands(self, group: str, bead_mass_kg: float, default_time_s: float) -> str:
        """LAMMPS text for this damping acting on ``group``."""
        if self.kind == "none":
            return "# no numerical damping"
        if self.kind == "cundall":
            return f"fix             damping {group} damping/cundall {self.cundall_ratio:.6g} 0.0"
        tau = self.viscous_time_s or default_time_s
        return f"fix             damping {group} viscous {bead_mass_kg / tau:.10g}"


@dataclass(frozen=True)
class QuasiStatic:
    """When a relaxation is quasi-static (see the module docstring).

    Args:
        kinetic_ratio: KE / bond strain energy below which the state is at rest.
        force_ratio: largest free-bead force / reference force below which it is.
        check_every: steps between checks.
        max_steps: give up relaxing after this many steps (the summary then says
            the criterion was not met); a relaxation's damped and undamped runs
            (:func:`fabmd.scene.blocks.relax`) have this many each.
        motion_ratio: a relaxation's undamped run is at rest only once no free bead
            moved more than this fraction of the smallest bead diameter over the last
            check interval.
    """

    kinetic_ratio: float = 1e-4
    force_ratio: float = 2e-3
    check_every: int = 500
    max_steps: int = 200_000
    motion_ratio: float = 1e-4

    def __post_init__(self):
        inputs.positive("quasi_static.kinetic_ratio", self.kinetic_ratio)
        inputs.positive("quasi_static.force_ratio", self.force_ratio)
        inputs.positive_int("quasi_static.check_every", self.check_every)
        inputs.positive_int("quasi_static.max_steps", self.max_steps)
        inputs.positive("quasi_static.motion_ratio", self.motion_ratio)

    def monitors(self, group: str, reference_force_n: float, reference_energy_j: float) -> str:
        """Computes and variables: ``v_qs_ke_ratio``, ``v_qs_force_ratio``, ``v_quasi_static``
        (and its limits ``v_qs_energy_floor``, ``v_qs_kinetic_limit``, ``v_qs_force_limit``).

        Args:
            reference_force_n: the largest force the stage imposes on a fibre.
            reference_energy_j: an energy floor for the kinetic-energy ratio (the
                strain energy of the bonds at the reference force), so that a
                state with slack yarns can still be judged at rest.
        """
        return render("quasi_static", group=group, reference_force=reference_force_n,
                      reference_energy=reference_energy_j, kinetic_ratio=self.kinetic_ratio,
                      force_ratio=self.force_ratio)

    def stop_when_reached(self) -> str:
        """A ``fix halt`` that ends the next run once the criterion holds."""
        return (f"fix             settled all halt {self.check_every} v_quasi_static > 0.5 "
                f"error continue message yes")


#: what LAMMPS writes when the ``settled`` halt of a relaxation fires
SETTLED_MESSAGE = "Fix halt condition for fix-id settled met"


def relaxation_settled(log_path) -> bool | None:
    """Did the relaxation in this LAMMPS log reach the quasi-static criterion before its
    step limit? (None: no log to tell.) A relaxation that did not leaves a state still
    moving, and a test started from it mixes that motion into its curve."""
    path = Path(log_path)
    if not path.is_file():
        return None
    with path.open(errors="replace") as f:
        return any(SETTLED_MESSAGE in line for line in f)


# -- the quasi-static verdict per interval of a driven test's curve ---------------------
#: above these an interval of a driven test's curve is not quasi-static: the share of the
#: interval's external work the drag took and the share that went into kinetic energy
#: (each is about the relative error of the force there), and the largest kinetic over
#: strain energy in it (as for the whole run). The inertia share was measured at 1.0-2.3x
#: the interval's force error against the slow limit (Twintex and plain-weave picture
#: frames at two or three speeds, benchmarks/RESULTS.md "Twintex loading speed, whole
#: yarns" and "The plain-weave example with the law ..."): 0.03 keeps that error to about
#: 5-7 % (0.1 let 10-25 % through)
INTERVAL_LIMITS = {"damping_share": 0.1, "inertia_share": 0.03,
                   "kinetic_to_strain_energy": 0.1}


def interval_verdict(x, external_work_j, damping_j, kinetic_j, strain_j, width: float,
                     limits: dict[str, float] | None = None, name: str = "x",
                     relative_kinetic_j=None) -> dict:
    """Judge a driven test's curve interval by interval.

    The range of ``x`` (the test's progress: shear angle [deg], elongation [%];
    increasing) is cut into intervals ``width`` wide from 0. For each interval:

    * ``damping_share`` = ΔW_drag / ΔW_external: the drag's share of the work done in it;
    * ``inertia_share`` = |ΔKE| / ΔW_external: the share that went into kinetic energy;
    * ``kinetic_to_strain_energy``: the largest KE / U at the samples in it, U no less
      than 1 % of the run's largest (a slack start has almost none). ``strain_j`` is the
      elastic energy U: the bonds' plus, where sampled, the contacts' (the driven tests
      pass both: :func:`fabmd.protocols.verdict.elastic_energy_j`). KE is
      ``relative_kinetic_j`` where given: the kinetic energy relative to the tools' affine
      velocity field (what the tools carry along is not a dynamic error; the inertia
      share keeps the absolute KE, whose growth the tools pay for).

    The cumulative works are read at the interval's ends by interpolation. A share
    whose interval took no external work (|ΔW| below 1e-9 of the run's) is not
    judged (None). An interval fails when a measure exceeds ``limits``
    (default :data:`INTERVAL_LIMITS`).

    Returns:
        ``axis`` (``name``), ``width``, ``limits``, ``intervals`` (a list of dicts:
        ``from``, ``to``, the measures, ``ok``, ``problems``), ``flagged`` and
        ``trusted`` (lists of [from, to] of failed and passed intervals, neighbours
        merged).
    """
    limits = INTERVAL_LIMITS if limits is None else limits
    x = np.asarray(x, float)
    w_ext, w_drag, ke, u = (np.asarray(a, float) for a in (external_work_j, damping_j,
                                                            kinetic_j, strain_j))
    ke_u = ke if relative_kinetic_j is None else np.asarray(relative_kinetic_j, float)
    if width <= 0:
        raise ValueError(f"interval width must be > 0, got {width}")
    top = float(x.max())
    if top <= 0:
        return {"axis": name, "width": float(width), "limits": dict(limits),
                "intervals": [], "flagged": [], "trusted": []}
    edges = np.arange(0.0, top, width)
    edges = np.append(edges, top) if top > edges[-1] else edges
    floor = 1e-9 * max(float(np.abs(w_ext).max()), 1e-300)
    u_floor = max(0.01 * float(u.max()), 1e-300)
    intervals = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b - a < 1e-6 * width:
            continue
        dw = float(np.diff(np.interp([a, b], x, w_ext))[0])
        ddrag = float(np.diff(np.interp([a, b], x, w_drag))[0])
        dke = float(np.diff(np.interp([a, b], x, ke))[0])
        inside = (x >= a) & (x <= b)
        at = np.interp([a, b], x, ke_u), np.interp([a, b], x, u)
        kes = np.concatenate([ke_u[inside], at[0]])
        us = np.concatenate([u[inside], at[1]])
        measures = {
            "damping_share": ddrag / dw if abs(dw) > floor else None,
            "inertia_share": abs(dke) / abs(dw) if abs(dw) > floor else None,
            "kinetic_to_strain_energy": float(np.max(kes / np.maximum(us, u_floor))),
        }
        problems = [f"{name} {a:g}-{b:g}: {k} = {v:.2g} > {limits[k]:g}"
                    for k, v in measures.items()
                    if k in limits and v is not None and v > limits[k]]
        intervals.append({"from": float(a), "to": float(b), **measures,
                          "ok": not problems, "problems": problems})
    return {"axis": name, "width": float(width), "limits": dict(limits),
            "intervals": intervals,
            "flagged": _merge([(i["from"], i["to"]) for i in intervals if not i["ok"]]),
            "trusted": _merge([(i["from"], i["to"]) for i in intervals if i["ok"]])}


def _merge(ranges: list[tuple[float, float]]) -> list[list[float]]:
    """Join touching [from, to] ranges (in order)."""
    out: list[list[float]] = []
    for a, b in ranges:
        if out and abs(out[-1][1] - a) < 1e-12 * max(1.0, abs(a)):
            out[-1][1] = b
        else:
            out.append([a, b])
    return out


def interval_columns(x, verdict: dict) -> dict[str, np.ndarray]:
    """Per-sample columns of an interval verdict for ``curve.csv``: each sample carries
    the measures of the interval it lies in (NaN where not judged) and
    ``interval_quasi_static`` (1 or 0)."""
    x = np.asarray(x, float)
    intervals = verdict["intervals"]
    keys = ("damping_share", "inertia_share", "kinetic_to_strain_energy")
    cols = {f"interval_{k}": np.full(len(x), np.nan) for k in keys}
    cols["interval_quasi_static"] = np.ones(len(x))
    if not intervals:
        return cols
    starts = np.array([i["from"] for i in intervals])
    index = np.clip(np.searchsorted(starts, x, side="right") - 1, 0, len(intervals) - 1)
    for n, i in enumerate(index):
        iv = intervals[i]
        for k in keys:
            cols[f"interval_{k}"][n] = np.nan if iv[k] is None else iv[k]
        cols["interval_quasi_static"][n] = 1.0 if iv["ok"] else 0.0
    return cols
