"""Energy bookkeeping of a quasi-static test.

External work = Δ(bond strain energy) + Δ(kinetic energy) + viscous damping
dissipation + work taken by the contacts (friction, contact damping and contact
elastic energy). Every term is measured on its own:

* external work and damping dissipation: power summed over the beads and averaged
  over each output interval in LAMMPS (every step, or every 10 steps of a long interval:
  a Riemann sum on that grid, :func:`mean_sample_every`);
* strain and kinetic energy: LAMMPS energies at each output;
* contact work: the power of the contact forces on the relative motion of every
  contact pair, summed from ``compute pair/local`` between chunks of the
  in-process run (sampled; not available in the standalone back end). It includes
  what friction and contact damping dissipate and the elastic energy the contacts
  hold (no pair style here reports a contact energy).

``pair_style granular`` (the split contact) reports forces but no relative velocities
in ``pair/local``: its contact power pairs the forces with the velocities of the two
atoms (``property/local patom1 patom2``; atom j is the image, owned or ghost, whose
centre vector is the one ``pair/local`` reports), as the gran/* styles see them.

``pair_style hybrid/overlay granular table`` (the within-family law) is not sampled: LAMMPS
sums the normal forces of the sub-styles in ``pair/local`` but leaves the extra columns
(tangential force, centre vector) of the overlaid same-family pairs zero (measured on
22Jul2025), so friction within a yarn would be missing. Its samples are NaN and the
balance says "not measured" (:data:`UNMEASURED_NOTE`).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..engine import mpi
from ..errors import QuasiStaticWarning
from .templates import render

#: the interval means (forces, powers) sample every this many steps once the output
#: interval is at least :data:`MEAN_SAMPLING_FROM` steps: a Riemann sum on a 10-step grid
#: instead of every step (issue 20: the per-bead sums were most of a step's cost; the
#: error is measured in benchmarks/RESULTS.md "Per-step cost of fabmd's fixes")
MEAN_SAMPLE_EVERY = 10
MEAN_SAMPLING_FROM = 20 * MEAN_SAMPLE_EVERY


def mean_sample_every(every: int) -> int:
    """Steps between the samples of the interval means for output interval ``every``:
    :data:`MEAN_SAMPLE_EVERY` where it divides a long enough interval, else every step."""
    if every >= MEAN_SAMPLING_FROM and every % MEAN_SAMPLE_EVERY == 0:
        return MEAN_SAMPLE_EVERY
    return 1


LMP_STYLE_LOCAL = 2
LMP_TYPE_ARRAY = 2


class ContactPower:
    """Samples the power of all contact forces (callable as an engine monitor).

    ``pair_style``: the fibre-fibre contact's LAMMPS pair style. Columns of ``compute
    pair/local`` for the gran/* styles: normal force on i (fx fy fz), tangential force
    on i (p1..p3), relative normal velocity (p5..p7) and relative tangential velocity
    (p8..p10) of i with respect to j. For ``granular``: fx fy fz, tangential force on i
    (p1..p3), x_i - x_j (p10..p12); the velocities come from the atoms (see module).
    A sample whose rows do not line up is NaN: the balance then says it is not measured.
    """

    compute_id = "fabmd_contacts"
    atoms_id = "fabmd_contact_atoms"

    def __init__(self, pair_style: str = "gran/hooke/history"):
        self.granular = pair_style == "granular"
        self.measured = not pair_style.startswith("hybrid")  # module docstring
        self.steps: list[int] = []
        self.power_w: list[float] = []

    @classmethod
    def commands(cls, pair_style: str = "gran/hooke/history") -> str:
        """LAMMPS text of the sampling computes for ``pair_style``."""
        if pair_style.startswith("hybrid"):
            return render("contact_power_none").removesuffix("\n")
        if pair_style == "granular":
            return render("contact_power_granular", forces_id=cls.compute_id,
                          atoms_id=cls.atoms_id).removesuffix("\n")
        return (f"compute         {cls.compute_id} all pair/local fx fy fz p1 p2 p3 p5 p6 p7 "
                f"p8 p9 p10")

    def __call__(self, lmp) -> None:
        if not self.measured:
            local = float("nan")
        else:
            local = self._granular_power(lmp) if self.granular else self._gran_power(lmp)
        total = mpi.allreduce_sum([local])[0]
        step = int(lmp.extract_global("ntimestep"))
        if self.steps and step <= self.steps[-1]:  # the clock was reset: a new phase
            self.steps, self.power_w = [], []
        self.steps.append(step)
        self.power_w.append(total)

    @classmethod
    def _local(cls, lmp, compute_id: str, columns: int) -> np.ndarray:
        try:
            a = lmp.numpy.extract_compute(compute_id, LMP_STYLE_LOCAL, LMP_TYPE_ARRAY)
        except Exception:  # noqa: BLE001 - no pairs on this rank
            a = None
        if a is None or not len(a):
            return np.zeros((0, columns))
        return np.asarray(a, float).reshape(-1, columns)

    def _gran_power(self, lmp) -> float:
        a = self._local(lmp, self.compute_id, 12)
        return float(np.einsum("ij,ij->", a[:, 0:3], a[:, 6:9])
                     + np.einsum("ij,ij->", a[:, 3:6], a[:, 9:12]))

    def _granular_power(self, lmp) -> float:
        f = self._local(lmp, self.compute_id, 9)
        tags = self._local(lmp, self.atoms_id, 2).astype(np.int64)
        if len(f) != len(tags):
            return float("nan")
        if not len(f):
            return 0.0
        # this rank's atoms and ghost images, as the pair style saw them: a ghost's
        # velocity carries the box's deformation rate (fix deform remap v)
        nlocal = int(lmp.extract_global("nlocal"))
        nall = nlocal + int(lmp.extract_global("nghost"))
        tag = np.asarray(lmp.numpy.extract_atom("id", nelem=nall), np.int64).reshape(-1)
        x = np.asarray(lmp.numpy.extract_atom("x", nelem=nall), float).reshape(-1, 3)
        v = np.asarray(lmp.numpy.extract_atom("v", nelem=nall), float).reshape(-1, 3)
        dx = f[:, 6:9]
        owned, found = _candidates(tag[:nlocal], tags[:, 0])  # atom i is owned: one local
        i = owned[:, 0]
        cand, valid = _candidates(tag, tags[:, 1])  # j: the image with x_i - x_j = dx
        miss = np.linalg.norm(x[i][:, None, :] - x[cand] - dx[:, None, :], axis=2)
        miss[~(valid & found[:, :1])] = np.inf
        best = np.argmin(miss, axis=1)
        rows = np.arange(len(f))
        # the rows describe the same pairs (else this sample is not measured)
        if np.any(~np.isfinite(miss[rows, best])) or np.any(
                miss[rows, best] > 0.01 * np.linalg.norm(dx, axis=1)):
            return float("nan")
        j = cand[rows, best]
        return float(np.einsum("ij,ij->", f[:, 0:3] + f[:, 3:6], v[i] - v[j]))

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


def _candidates(tag: np.ndarray, wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices into ``tag`` holding each ``wanted`` atom id (one row per id, padded; an id
    not there gets index 0, marked False in the second array)."""
    order = np.argsort(tag, kind="stable")
    sorted_tag = tag[order]
    lo = np.searchsorted(sorted_tag, wanted, "left")
    count = np.searchsorted(sorted_tag, wanted, "right") - lo
    width = max(1, int(count.max()))
    k = np.arange(width)
    valid = k[None, :] < count[:, None]
    index = np.where(valid, np.minimum(lo[:, None] + k[None, :], len(tag) - 1), 0)
    return order[index] if len(tag) else np.zeros_like(index), valid


def cumulative(interval_mean: np.ndarray, every: int, dt: float) -> np.ndarray:
    """Integral of a quantity LAMMPS averaged over each output interval."""
    return np.cumsum(np.asarray(interval_mean) * every * dt)


#: why a balance has no closing error although the contacts were sampled
UNMEASURED_NOTE = ("energy balance not measured: the contact work could not be sampled (the "
                   "contact forces did not line up with their atoms, or the within-family "
                   "law contact, whose pair/local rows lack the tangential force); the "
                   "quasi-static verdict does not judge the energy balance")


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
    if not np.all(np.isfinite(contact_j)):  # a sample could not be measured: say so
        terms["contact_work_j"] = terms["relative_error"] = None
        terms["note"] = UNMEASURED_NOTE
        warnings.warn(QuasiStaticWarning(UNMEASURED_NOTE), stacklevel=2)
        return terms
    accounted = (terms["strain_energy_change_j"] + terms["kinetic_energy_change_j"]
                 + terms["damping_dissipation_j"] + terms["contact_work_j"])
    w = terms["external_work_j"]
    terms["relative_error"] = abs(w - accounted) / abs(w) if w else None
    return terms
