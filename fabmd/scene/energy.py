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
  hold;
* contact elastic energy U_c (:class:`ContactEnergy`, sampled with the contact power at
  the output steps, in-process only): the normal springs' ½·k_n·δ² of every overlapping
  pair (Hertz: 0.4·k_n·sqrt(R_eff)·δ^2.5) plus the pair style's own energy (the
  within-family law's table part; the granular styles report none). The balance splits
  the contact work into ΔU_c and what the contacts dissipated; the quasi-static verdict
  judges KE/U with U = bonds + U_c. The tangential springs' energy is left out (the
  granular styles do not report it, and under hybrid/overlay not even their force).

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

    def __init__(self, pair_style: str = "gran/hooke/history",
                 energy: ContactEnergy | None = None):
        self.granular = pair_style == "granular"
        self.measured = not pair_style.startswith("hybrid")  # module docstring
        self.energy = energy  # also sample the contacts' elastic energy (None: not)
        self.steps: list[int] = []
        self.power_w: list[float] = []
        self.energy_j: list[float] = []

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
        if self.energy is None:
            total = mpi.allreduce_sum([local])[0]
        else:
            total, elastic = mpi.allreduce_sum([local, self.energy.local_energy_j(lmp)])
        step = int(lmp.extract_global("ntimestep"))
        if self.steps and step <= self.steps[-1]:  # the clock was reset: a new phase
            self.steps, self.power_w, self.energy_j = [], [], []
        self.steps.append(step)
        self.power_w.append(total)
        if self.energy is not None:
            self.energy_j.append(elastic)

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
        # a ghost's velocity carries the box's deformation rate (fix deform remap v)
        nlocal, (tag, x, v) = _with_ghosts(lmp, "id", "x", "v")
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
        return {"steps": list(self.steps), "power_w": list(self.power_w),
                "energy_j": list(self.energy_j)}

    def restore(self, state: dict) -> None:
        """Continue from a checkpoint's samples."""
        self.steps = [int(s) for s in state["steps"]]
        self.power_w = [float(p) for p in state["power_w"]]
        self.energy_j = [float(e) for e in state.get("energy_j", [])]

    def elastic_energy_j(self, steps: np.ndarray) -> np.ndarray | None:
        """Contact elastic energy U_c at ``steps`` [J] (:class:`ContactEnergy`; None if not
        sampled). Sampled at the output steps from the first one after step 0: step 0
        takes the first sample's value."""
        if self.energy is None or not self.energy_j or len(self.energy_j) != len(self.steps):
            return None
        return np.interp(steps, np.asarray(self.steps, float), np.asarray(self.energy_j))

    def work_j(self, steps: np.ndarray, dt: float) -> np.ndarray | None:
        """Cumulative work taken by the contacts at ``steps`` [J] (None if not sampled)."""
        if len(self.steps) < 2:
            return None
        s = np.asarray(self.steps, float)
        p = -np.asarray(self.power_w)  # power going into the contacts
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(s) * dt)])
        return np.interp(steps, s, cum, left=0.0)


class ContactEnergy:
    """Elastic energy held by the fibre–fibre contacts [J], sampled between chunks.

    Per overlapping pair (``compute pair/local dist eng`` and ``property/local patom1
    patom2``, ``lammps_templates/contact_energy.lmp``), with δ = r_i + r_j − r:
    ½·k_n·δ² of the Hooke normal spring (Hertz: 0.4·k_n·sqrt(R_eff)·δ^2.5,
    R_eff = r_i·r_j/(r_i + r_j), as LAMMPS's hertz force k_n·δ·sqrt(δ·R_eff)), k_n of the
    pair's two atom types, plus the pair style's own energy (``eng``: the table's part of
    the within-family law, the integral of its excess force from the cutoff; 0 for the
    granular styles). The tangential springs are left out (module docstring). A sample whose
    rows do not line up (a distance no image of the pair's atoms has) is NaN.

    Args:
        stiffness_n_per_m: k_n [N/m] by atom type pair, a symmetric (types + 1)² array
            (row and column 0 unused).
        hertz: the normal force is Hertz (else Hooke).
    """

    pairs_id = "fabmd_contact_gaps"
    atoms_id = "fabmd_contact_gap_atoms"

    def __init__(self, stiffness_n_per_m, hertz: bool = False):
        self.stiffness = np.asarray(stiffness_n_per_m, float)
        self.hertz = hertz

    @classmethod
    def for_contact(cls, contact, beads, families: tuple[str, ...]) -> ContactEnergy:
        """The energy of ``contact`` (a :class:`~fabmd.model.contact.ContactModel`) on a
        model with ``beads`` and one atom type per family in ``families``."""
        n = len(families)
        k = np.zeros((n + 1, n + 1))
        if contact.split:
            for i, j, c in contact.type_pair_coefficients(beads, n, families):
                k[i, j] = k[j, i] = c["kn"]
        else:
            k[1:, 1:] = contact.pair_coefficients(beads)["kn"]
        return cls(k, hertz=contact.normal == "hertz")

    @classmethod
    def commands(cls) -> str:
        """LAMMPS text of the sampling computes (evaluated only when sampled)."""
        return render("contact_energy", pairs_id=cls.pairs_id,
                      atoms_id=cls.atoms_id).removesuffix("\n")

    def pair_energy_j(self, overlap_m, radius_i_m, radius_j_m, type_i, type_j) -> np.ndarray:
        """The normal springs' energy of pairs with overlaps δ [m] (arrays) [J]."""
        k = self.stiffness[np.asarray(type_i), np.asarray(type_j)]
        d = np.maximum(np.asarray(overlap_m, float), 0.0)
        if self.hertz:
            r_eff = radius_i_m * radius_j_m / (radius_i_m + radius_j_m)
            return 0.4 * k * np.sqrt(r_eff) * d**2.5
        return 0.5 * k * d * d

    def local_energy_j(self, lmp) -> float:
        """U_c of the pairs this rank holds [J] (NaN when the rows do not line up)."""
        pairs = ContactPower._local(lmp, self.pairs_id, 2)
        tags = ContactPower._local(lmp, self.atoms_id, 2).astype(np.int64)
        if len(pairs) != len(tags):
            return float("nan")
        if not len(pairs):
            return 0.0
        nlocal, (tag, x, radius, kind) = _with_ghosts(lmp, "id", "x", "radius", "type")
        owned, found = _candidates(tag[:nlocal], tags[:, 0])
        i = owned[:, 0]
        cand, valid = _candidates(tag, tags[:, 1])
        dist = pairs[:, 0]
        # the image of j at the reported distance: the rows describe these pairs
        miss = np.abs(np.linalg.norm(x[i][:, None, :] - x[cand], axis=2) - dist[:, None])
        miss[~(valid & found[:, :1])] = np.inf
        best = np.argmin(miss, axis=1)
        rows = np.arange(len(pairs))
        if np.any(miss[rows, best] > 1e-6 * (radius[i] + radius[cand[rows, best]])):
            return float("nan")
        j = cand[rows, best]
        spring = self.pair_energy_j(radius[i] + radius[j] - dist, radius[i], radius[j],
                                    kind[i], kind[j])
        return float(np.sum(spring) + np.sum(pairs[:, 1]))


def _with_ghosts(lmp, *names: str) -> tuple[int, list[np.ndarray]]:
    """This rank's atoms and their ghost images, as the pair style saw them: the number
    owned and, per per-atom property in ``names`` ("id", "type", "x", "v", "radius"), its
    array over all of them (ids and types as int64, vectors as (n, 3))."""
    nlocal = int(lmp.extract_global("nlocal"))
    nall = nlocal + int(lmp.extract_global("nghost"))
    arrays = []
    for name in names:
        dtype = np.int64 if name in ("id", "type") else float
        a = np.asarray(lmp.numpy.extract_atom(name, nelem=nall), dtype)
        arrays.append(a.reshape(-1, 3) if name in ("x", "v") else a.reshape(-1))
    return nlocal, arrays


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


def balance(external_j, strain_j, kinetic_j, damping_j, contact_j,
            contact_energy_j=None) -> dict:
    """Energy balance at the end of a run: the terms and the relative closing error.

    ``contact_energy_j``: the contacts' elastic energy U_c at the samples (None: not
    sampled); the contact work is then split into ``contact_energy_change_j`` (ΔU_c) and
    ``contact_dissipation_j`` (friction and contact damping: the rest), which does not
    change the closing error."""
    terms = {"external_work_j": float(external_j[-1]),
             "strain_energy_change_j": float(strain_j[-1] - strain_j[0]),
             "kinetic_energy_change_j": float(kinetic_j[-1] - kinetic_j[0]),
             "damping_dissipation_j": float(damping_j[-1]),
             "contact_work_j": None if contact_j is None else float(contact_j[-1])}
    if contact_energy_j is not None and np.all(np.isfinite(contact_energy_j)):
        terms["contact_energy_change_j"] = float(contact_energy_j[-1] - contact_energy_j[0])
        if contact_j is not None and np.all(np.isfinite(contact_j)):
            terms["contact_dissipation_j"] = (terms["contact_work_j"]
                                              - terms["contact_energy_change_j"])
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
