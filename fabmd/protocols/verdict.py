"""Is a driven test's curve quasi-static? The verdict, its remedies and its marks.

After a driven run (:class:`fabmd.protocols.driven.DrivenTest`) the summary's measures
are judged against limits (:func:`quasi_static_verdict`), the curve interval by interval
(:func:`add_interval_verdict`, :func:`fabmd.scene.quasi_static.interval_verdict`); a
failure names what to change in the scene file (:data:`QUASI_STATIC_REMEDIES`), marks
the plots (:func:`mark_plots`) and warns (:func:`judge`).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import QuasiStaticWarning
from ..scene.quasi_static import interval_columns, interval_verdict

if TYPE_CHECKING:
    from .driven import DrivenResult

#: above these a driven test's curve is not quasi-static (after start-up): kinetic over
#: strain energy and over the work done (inertia; KE/U = 0.1 moved the tension force at 1 %
#: by about 1 %, benchmarks/stability.py "Loading speed"), and the share of the work the
#: viscous drag took (a force that grows with the loading speed); and the energy balance's
#: closing error (work that went somewhere no term accounts for)
QUASI_STATIC_LIMITS = {"max_kinetic_to_strain_energy": 0.1,
                       "max_kinetic_to_external_work": 0.1, "damping_share": 0.5,
                       "energy_balance_error": 0.05, "start_spike_ratio": 1.0}

GENERIC_REMEDY = "lower speed_fraction, or check the specimen holds together"
#: what to change when a quasi-static measure fails (scene-file fields of the test table)
QUASI_STATIC_REMEDIES = {
    "max_kinetic_to_strain_energy": "inertia: lower speed_fraction",
    "max_kinetic_to_external_work": "inertia: lower speed_fraction",
    "mean_inertial_to_punch_force": "inertia: lower speed_fraction",
    "damping_share": "the drag takes the work: raise damping_time_s (less drag), or "
                     "lower speed_fraction",
    "energy_balance_error": "the energy does not balance (time step or contact): lower "
                            "time_step.factor, or raise the contact stiffness_factor; a "
                            "lower speed_fraction does not cure it",
    "start_spike_ratio": "the force jumps when the loading starts, before the clamps have "
                         "moved (strain energy stored in the start state is released; a "
                         "fibre far stiffer than the rest makes this likely): relax the start "
                         "state further (lower relax.force_ratio and relax.kinetic_ratio, "
                         "raise relax.max_steps); a lower speed_fraction does not cure it",
    "start_settled": "the specimen was not at rest when the loading started: raise "
                     "relax.max_steps (or lower relax.kinetic_ratio); a lower speed_fraction "
                     "does not cure it",
    "interval": "part of the curve is not quasi-static (the flagged intervals): lower "
                "speed_fraction, or use only the trusted ranges",
}


def damping_share(summary: dict) -> float | None:
    """Share of the external work the viscous drag dissipated."""
    balance_ = summary.get("energy_balance") or {}
    work, drag = balance_.get("external_work_j"), balance_.get("damping_dissipation_j")
    return drag / work if work and drag is not None and work > 0 else None


def quasi_static_verdict(summary: dict, limits: dict[str, float] | None = None) -> dict:
    """Is the curve quasi-static, and does its energy balance close? Each measure in
    ``limits`` (default
    :data:`QUASI_STATIC_LIMITS`) is read from the summary (``damping_share`` computed from
    its energy balance); a measure the test does not report is not judged. A summary whose
    ``start_settled`` is False (the relaxation before the loading did not settle) fails.
    With a per-interval verdict (``quasi_static_intervals``, :func:`add_interval_verdict`)
    every failed interval is a problem too; ``partly`` is True when only intervals failed
    and some passed (``trusted``: their ranges), so the rest of the curve can be used."""
    limits = QUASI_STATIC_LIMITS if limits is None else limits
    derived = {"damping_share": lambda: damping_share(summary),
               "energy_balance_error": lambda: (summary.get("energy_balance") or {}).get(
                   "relative_error")}
    values = {name: derived[name]() if name in derived else summary.get(name)
              for name in limits}
    problems = [f"{name} = {v:.2g} > {limits[name]:g}" for name, v in values.items()
                if v is not None and v > limits[name]]
    failed = [name for name, v in values.items() if v is not None and v > limits[name]]
    if summary.get("start_settled") is False:
        problems.append("the specimen was still moving when the loading started (its "
                        "relaxation did not settle within relax.max_steps)")
        failed.append("start_settled")
    intervals = summary.get("quasi_static_intervals")
    whole_run_ok = not problems
    trusted = flagged = []
    if intervals:
        trusted, flagged = intervals["trusted"], intervals["flagged"]
        interval_problems = [p for i in intervals["intervals"] for p in i["problems"]]
        problems += interval_problems
        if interval_problems:
            failed.append("interval")
    remedies = list(dict.fromkeys(f"{name}: {QUASI_STATIC_REMEDIES.get(name, GENERIC_REMEDY)}"
                                  for name in failed))
    return {"ok": not problems, "values": values, "limits": dict(limits),
            "problems": problems, "remedies": remedies, "flagged": flagged,
            "trusted": trusted, "partly": bool(whole_run_ok and flagged and trusted)}


def mark_fitted_stiffness(summary: dict, low: float, high: float | None, unit: str,
                          into: dict | None = None, fitted_on: str = "") -> None:
    """Say whether ``initial_stiffness`` (fitted over ``low``-``high`` of the curve's
    interval axis, in ``unit``) comes from quasi-static intervals: where the verdict of
    ``summary`` flags part of that range, ``initial_stiffness_trusted`` is false and
    ``initial_stiffness_note`` names the part (an upper bound: its force holds drag).
    ``into``: the dict that gets the two keys (default ``summary``; the tension's
    ``optical_gauge``); ``fitted_on``: where the fit's own axis differs from the
    intervals' (the gauge strain, the bias extension's displacement), what it is, said in
    the note."""
    flagged = (summary.get("quasi_static") or {}).get("flagged") or []
    if high is None or not np.isfinite(high):
        return
    into = summary if into is None else into
    overlap = [(max(a, low), min(b, high)) for a, b in flagged if a < high and b > low]
    into["initial_stiffness_trusted"] = not overlap
    if overlap:
        where = ", ".join(f"{a:.3g}-{b:.3g} {unit}" for a, b in overlap)
        into["initial_stiffness_note"] = (
            f"not the fabric's: the range it is fitted over ({fitted_on}{low:.3g}-{high:.3g} "
            f"{unit}) is not quasi-static over {where} (drag and inertia in the force; it "
            f"falls with the speed); an upper bound: lower speed_fraction to measure it")


def start_spike_ratio(force, fraction: float = 0.05) -> float | None:
    """Largest |force| in the first ``fraction`` of the samples (the first excluded: it is
    printed before any force) over the largest after them; above 1 the force jumps when
    the loading starts, before the clamps have moved: the start state was not in
    equilibrium. None for curves too short to tell."""
    if force is None:
        return None
    f = np.abs(np.asarray(force, float))
    head = max(2, int(round(fraction * len(f))) + 1)
    if len(f) < head + 2:
        return None
    later = float(f[head:].max())
    early = float(f[1:head].max())
    return early / max(later, 1e-300) if early > 0 else 0.0


def elastic_energy_j(curve: dict) -> np.ndarray:
    """U of KE/U [J]: the bonds' strain energy plus the contacts' elastic energy
    (``contact_energy_j``, where the run sampled it: in-process; a standalone run has
    bonds only). Most of a sheared fabric's elastic energy sits in lateral compaction,
    in the contacts (benchmarks/RESULTS.md "Contact energy in the verdict")."""
    u = np.asarray(curve["strain_energy_j"], float)
    contact = curve.get("contact_energy_j")
    if contact is None or not np.all(np.isfinite(contact)):
        return u
    return u + np.asarray(contact, float)


def add_interval_verdict(result: DrivenResult, column: str, width: float) -> dict:
    """Judge ``result``'s curve per interval of ``column`` (:func:`~fabmd.scene.
    quasi_static.interval_verdict`): the verdict goes into the summary
    (``quasi_static_intervals``), its per-sample columns into the curve. KE/U takes the
    kinetic energy relative to the tools' affine field where the curve has it
    (``kinetic_relative_j``: picture frame, tension, bias extension) and U =
    :func:`elastic_energy_j`."""
    c = result.curve
    verdict = interval_verdict(c[column], c["external_work_j"], c["damping_dissipation_j"],
                               c["kinetic_energy_j"], elastic_energy_j(c), width,
                               name=column, relative_kinetic_j=c.get("kinetic_relative_j"))
    result.summary["quasi_static_intervals"] = verdict
    result.curve.update(interval_columns(c[column], verdict))
    return verdict


def mark_plots(result: DrivenResult, verdict: dict,
               interval_axis: tuple[str, float] | None) -> None:
    """Say on every plot that the curve is not (or only partly) quasi-static: a
    whole-run failure in the title, failed intervals shaded (a plot spec whose x is not
    the interval column names its own: ``x_column``, ``x_scale``)."""
    for spec in getattr(result, "plots", []):
        if verdict.get("partly") and interval_axis is not None:
            column = spec.get("x_column", interval_axis[0])
            scale = spec.get("x_scale", 1.0)
            axis = result.curve[interval_axis[0]]
            spec["spans"] = [[scale * float(np.interp(v, axis, result.curve[column]))
                              for v in ab] for ab in verdict["flagged"]]
            spec["title"] = "PARTLY NOT QUASI-STATIC (shaded): " + spec.get("title", "")
        else:  # no plot that looks valid
            spec["title"] = "NOT QUASI-STATIC, do not use: " + spec.get("title", "")
        spec["notes"] = "\n".join([spec.get("notes", ""), *verdict["problems"][:4]])


def judge(result: DrivenResult, protocol: str, run_dir: Path, limits: dict[str, float],
          interval_axis: tuple[str, float] | None, curve_column: str) -> dict:
    """The whole verdict on a driven run's result: the start spike of ``curve_column``,
    the per-interval verdict (``interval_axis``: column and width, None: none), the
    summary's ``quasi_static``; when it fails, the plots are marked and a
    :class:`~fabmd.errors.QuasiStaticWarning` names the problems and the remedies."""
    spike = start_spike_ratio(result.curve.get(curve_column))
    if spike is not None:
        result.summary["start_spike_ratio"] = spike
    if interval_axis is not None:
        add_interval_verdict(result, *interval_axis)
    verdict = quasi_static_verdict(result.summary, limits)
    result.summary["quasi_static"] = verdict
    if not verdict["ok"]:
        mark_plots(result, verdict, interval_axis)
        where = ("; trust only " + ", ".join(f"{a:g}-{b:g}" for a, b in verdict["trusted"])
                 if verdict.get("partly") else ": do not use the curve")
        # stacklevel 3: the warning points at the caller of the protocol's run()
        warnings.warn(f"{protocol} in {run_dir}: not quasi-static "
                      f"({'; '.join(verdict['problems'])}){where}; "
                      f"{'; '.join(verdict['remedies'])}", QuasiStaticWarning, stacklevel=3)
    return verdict
