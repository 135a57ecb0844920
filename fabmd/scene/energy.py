"""Energy bookkeeping of a quasi-static test.

External work = Δ(bond strain energy) + Δ(kinetic energy) + viscous damping
dissipation + work taken by the contacts (friction, contact damping and contact
elastic energy). Every term is measured on its own:

* external work and damping dissipation: power summed over the beads every step
  and averaged over each output interval in LAMMPS (exact integration);
* strain and kinetic energy: LAMMPS energies at each output;
* contact work: the power of the contact forces on the relative motion of every
  contact pair, summed from ``compute pair/local`` between chunks of the
  in-process run (sampled; not available in the standalone back end).
"""

from __future__ import annotations

import numpy as np

from ..engine import mpi

LMP_STYLE_LOCAL = 2
LMP_TYPE_ARRAY = 2


class ContactPower:
    """Samples the power of all contact forces (callable as an engine monitor).

    Columns of ``compute pair/local`` for the gran/* styles: normal force on i
    (fx fy fz), tangential force on i (p1..p3), relative normal velocity (p5..p7)
    and relative tangential velocity (p8..p10) of i with respect to j.
    """

    compute_id = "fabmd_contacts"

    def __init__(self):
        self.steps: list[int] = []
        self.power_w: list[float] = []

    @classmethod
    def commands(cls) -> str:
        return (f"compute         {cls.compute_id} all pair/local fx fy fz p1 p2 p3 p5 p6 p7 "
                f"p8 p9 p10")

    def __call__(self, lmp) -> None:
        try:
            a = lmp.numpy.extract_compute(self.compute_id, LMP_STYLE_LOCAL, LMP_TYPE_ARRAY)
        except Exception:  # noqa: BLE001 - no pairs on this rank
            a = None
        local = 0.0
        if a is not None and len(a):
            a = np.asarray(a).reshape(-1, 12)
            local = float(np.einsum("ij,ij->", a[:, 0:3], a[:, 6:9])
                          + np.einsum("ij,ij->", a[:, 3:6], a[:, 9:12]))
        total = mpi.allreduce_sum([local])[0]
        step = int(lmp.extract_global("ntimestep"))
        if self.steps and step <= self.steps[-1]:  # the clock was reset: a new phase
            self.steps, self.power_w = [], []
        self.steps.append(step)
        self.power_w.append(total)

    def state(self) -> dict:
        """Samples so far (saved with a checkpoint)."""
        return {"steps": list(self.steps), "power_w": list(self.power_w)}

    def restore(self, state: dict) -> None:
        """Continue from a checkpoint's samples."""
        self.steps = [int(s) for s in state["steps"]]
        self.power_w = [float(p) for p in state["power_w"]]

    def work_j(self, steps: np.ndarray, dt: float) -> np.ndarray | None:
        """Cumulative work taken by the contacts at ``steps`` [J] (None if not sampled)."""
        if len(self.steps) < 2:
            return None
        s = np.asarray(self.steps, float)
        p = -np.asarray(self.power_w)  # power going into the contacts
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(s) * dt)])
        return np.interp(steps, s, cum, left=0.0)


def cumulative(interval_mean: np.ndarray, every: int, dt: float) -> np.ndarray:
    """Integral of a quantity LAMMPS averaged over each output interval."""
    return np.cumsum(np.asarray(interval_mean) * every * dt)


def balance(external_j, strain_j, kinetic_j, damping_j, contact_j) -> dict:
    """Energy balance at the end of a run: the terms and the relative closing error."""
    terms = {"external_work_j": float(external_j[-1]),
             "strain_energy_change_j": float(strain_j[-1] - strain_j[0]),
             "kinetic_energy_change_j": float(kinetic_j[-1] - kinetic_j[0]),
             "damping_dissipation_j": float(damping_j[-1]),
             "contact_work_j": None if contact_j is None else float(contact_j[-1])}
    if contact_j is None:
        terms["relative_error"] = None
        terms["note"] = ("contact work is sampled by the in-process back end only; "
                         "not measured here")
        return terms
    accounted = (terms["strain_energy_change_j"] + terms["kinetic_energy_change_j"]
                 + terms["damping_dissipation_j"] + terms["contact_work_j"])
    w = terms["external_work_j"]
    terms["relative_error"] = abs(w - accounted) / abs(w) if w else None
    return terms
