"""Render a :class:`~fabmd.geometry.fabric.Fabric` into a :class:`BeadModel`.

Per yarn family: the section packing gives the fibre offsets and the contact
(bead) diameter d (:mod:`fabmd.geometry.section`); the filament area of a fibre
is A = tex·1e-6/ρ/N (:meth:`VirtualFibre.from_yarn`); bead spacing, mass and
bond coefficient come from :func:`fabmd.model.beads.bead_parameters`.

* Non-periodic fabric: beads exactly l0 = (s/d)·d apart (chord) from the start
  of each fibre; one bond type per family.
* Periodic fabric (x and y periodic, z not): each fibre closes on itself across
  the box with a whole number of bonds, so its rest length is its own length
  divided by its bond count (within ½ bond of l0). Fibres with equal rest
  lengths share a bond type; bond types are numbered family by family, so
  those of one family form a contiguous range.

Identity: atom type = family (order ``warp, weft, binder``, only families
present), molecule id = fibre id, fibres numbered yarn by yarn and beads
contiguous along each fibre. :func:`render_fabric` also checks that no two
beads of different yarns overlap (:mod:`fabmd.model.overlap`) and that no yarn
bends so tightly that its inner fibres fold, and records facts later stages
need in ``BeadModel.info`` (see :func:`render_fabric`).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..geometry.fabric import Fabric
from ..geometry.material import VirtualFibre
from ..geometry.paths import YarnPath, fibre_beads
from .bead_model import AngleType, BeadModel, BondType, Yarn
from .beads import BeadParameters, Discretisation, bead_parameters
from .fabric_info import INFO_FORMAT, fabric_info  # noqa: F401 - also by this name
from .overlap import ClosestApproach, closest_approach

#: rest lengths closer than this relative difference share a bond type
REST_LENGTH_TOLERANCE = 1e-9
#: a yarn folds when curvature × largest fibre offset reaches this
FOLD_LIMIT = 0.95
#: the words of every fold refusal (the loose-state search recognises them)
FOLD_WORDS = "would fold"


@dataclass(frozen=True)
class FamilyBeads:
    """What one yarn family becomes: fibre, section packing and bead parameters."""

    family: str
    fibre: VirtualFibre
    offsets_m: np.ndarray
    beads: BeadParameters

    def at_spacing(self, bond_length_m: float, discretisation: Discretisation) -> BeadParameters:
        return bead_parameters(self.fibre, discretisation, bond_length_m=bond_length_m)


def family_beads(fabric: Fabric, discretisation: Discretisation | None = None
                 ) -> dict[str, FamilyBeads]:
    """Virtual fibre, fibre offsets and bead parameters of every family present."""
    disc = discretisation or Discretisation()
    out = {}
    for fam, spec in fabric.specs().items():
        out[fam] = _spec_beads(fam, spec, disc)
    return out


def yarn_spec_beads(fabric: Fabric, discretisation: Discretisation | None = None
                    ) -> dict[str, FamilyBeads]:
    """Like :func:`family_beads`, for every yarn spec of the fabric by its key (the
    families, and ``"<family>:<k>"`` for override k; see ``Fabric.yarn_spec_table``)."""
    disc = discretisation or Discretisation()
    out = {}
    for key, spec in fabric.yarn_spec_table().items():
        out[key] = _spec_beads(key.split(":")[0], spec, disc)
    return out


def _spec_beads(family: str, spec, disc: Discretisation) -> FamilyBeads:
    """One yarn spec's virtual fibre (its share of tex and E·I), packing and beads."""
    offsets, d = spec.packing()
    fibre = VirtualFibre.from_yarn(spec.material, spec.linear_density_tex, spec.n_fibres, d,
                                   spec.yarn_bending_stiffness_nm2)
    return FamilyBeads(family, fibre, offsets, bead_parameters(fibre, disc))


def bead_parameter_list(model: BeadModel, fabric: Fabric,
                        discretisation: Discretisation | None = None) -> list[BeadParameters]:
    """One :class:`BeadParameters` per bond type of ``model`` (for contact and time step)."""
    disc = discretisation or Discretisation()
    fams = yarn_spec_beads(fabric, disc)
    return [fams[bt.spec or bt.family].at_spacing(bt.rest_length_m, disc)
            for bt in model.bond_type_table]


def _check_folding(paths: list[YarnPath], fams: dict[str, FamilyBeads],
                   keys: list[str]) -> None:
    seen = set()
    for path in paths:
        if path.straight or path.cell_index in seen:
            continue
        seen.add(path.cell_index)
        reach = float(np.abs(fams[keys[path.cell_index]].offsets_m[:, 1]).max())
        kappa = path.max_curvature()
        if kappa * reach >= FOLD_LIMIT:
            raise InputError(
                f"yarn {path.name} bends with radius {1e3 / kappa:.3g} mm, tighter than its "
                f"fibres reach from its centreline ({1e3 * reach:.3g} mm): its inner fibres "
                f"would fold; increase the weft spacing, reduce fabric.plateau or the "
                f"{path.family} height")


#: loose-state search of ``Fabric.auto_clearance``: warp and weft loose widths tried
#: (fractions of the width given; the section area is kept; 3D binders keep theirs), and
#: per width the lifts tried: 0, then a
#: quarter of the smallest yarn height growing ×1.5, then bisection of the last step
LOOSE_WIDTH_FACTORS = (1.0, 0.85, 0.7, 0.55)
LIFT_TRIES = 7
LIFT_GROWTH = 1.5
LIFT_BISECTIONS = 3
#: a loose state is accepted when the smallest gap between yarns is at least this
#: fraction of the clearance
AUTO_GAP_FRACTION = 0.5


def render_fabric(fabric: Fabric, discretisation: Discretisation | None = None, *,
                  check: bool = True, pad_fraction: float = 0.1) -> BeadModel:
    """Beads, bonds and types of ``fabric`` (see :func:`render_loose`).

    With ``fabric.auto_clearance`` the loose state of a dense fabric is searched
    for: at each loose width of :data:`LOOSE_WIDTH_FACTORS` (warp and weft; the
    narrower yarns are taller, same area, and spread again during the crimp) the crossing
    yarns are lifted apart (``lift_m``, :data:`LIFT_TRIES` growing tries, then
    :data:`LIFT_BISECTIONS` halvings) until no yarns overlap and the smallest gap
    between yarns is :data:`AUTO_GAP_FRACTION` of the clearance. A width at which a
    lift folds a yarn is left for the next (more lift bends tighter). Where no try
    reaches that gap, the try without overlap with the largest gap is taken
    (``info["auto_clearance_gap_short"]``: true). ``info`` records ``lift_m``,
    ``loose_width_factor`` and ``auto_clearance_tries``.
    """
    if not (fabric.auto_clearance and check):
        return render_loose(fabric, discretisation, check=check, pad_fraction=pad_fraction)
    search = _LooseSearch(discretisation, pad_fraction)
    factors = LOOSE_WIDTH_FACTORS
    for factor in factors:
        base = fabric.with_loose_width(factor)
        step = 0.25 * min(s.height_m for s in base.specs().values())
        lifts = [0.0] + [step * LIFT_GROWTH ** k for k in range(LIFT_TRIES - 1)]
        search.folded, search.factor = "", factor
        for k, lift in enumerate(lifts):
            model = search.attempt(dataclasses.replace(base, lift_m=fabric.lift_m + lift))
            if search.folded:
                break
            if model is None:
                continue
            low, high = (lifts[k - 1], lift) if k else (0.0, 0.0)
            for _ in range(LIFT_BISECTIONS if k else 0):
                mid = 0.5 * (low + high)
                found = search.attempt(dataclasses.replace(base, lift_m=fabric.lift_m + mid))
                if found is None:
                    low = mid
                else:
                    high, model = mid, found
            model.info.update(auto_clearance_tries=search.tries, loose_width_factor=factor)
            return model
    if search.near is not None:
        _, factor, model = search.near
        model.info.update(auto_clearance_tries=search.tries, loose_width_factor=factor,
                          auto_clearance_gap_short=True)
        return model
    folded = f"; at loose width {factors[-1]:g}: {search.folded}" if search.folded else ""
    raise InputError(f"{search.last or 'no loose state'}{folded} (clearance \"auto\": no loose "
                     f"state found with loose widths down to {factors[-1]:g} of the given ones "
                     f"and lifts up to {1e3 * lifts[-1]:.3g} mm: a yarn overlaps its crossing "
                     f"yarns until lifting or narrowing bends some yarn tighter than its fibres "
                     f"reach)")


class _LooseSearch:
    """One try of the loose-state search and what the tries so far found."""

    def __init__(self, discretisation: Discretisation | None, pad_fraction: float):
        self.discretisation, self.pad_fraction = discretisation, pad_fraction
        self.tries, self.factor = 0, 1.0
        self.last, self.folded = "", ""
        #: (gap [m], loose width factor, model): the widest-gap try without overlap
        self.near: tuple | None = None

    def attempt(self, trial: Fabric) -> BeadModel | None:
        """The model of ``trial`` if its yarns keep the gap, else None (and why)."""
        self.tries += 1
        try:
            model = render_loose(trial, self.discretisation, check=True,
                                 pad_fraction=self.pad_fraction)
        except InputError as exc:
            text = str(exc)
            if FOLD_WORDS in text:
                self.folded = f"{text.split(':')[0]} at a lift of {1e3 * trial.lift_m:.3g} mm"
                return None
            if "overlap" not in text:
                raise
            self.last = text
            return None
        gap = model.info["clearance_m"]
        if gap is not None and gap < AUTO_GAP_FRACTION * trial.clearance_m:
            pair = " and ".join(model.info["clearance_pair"] or ())
            self.last = (f"yarns {pair} come within {1e3 * gap:.3g} mm, less than "
                         f"{AUTO_GAP_FRACTION:g} x the clearance "
                         f"{1e3 * trial.clearance_m:.3g} mm")
            if gap > 0 and (self.near is None or gap > self.near[0]):
                self.near = (gap, self.factor, model)
            return None
        return model


def render_loose(fabric: Fabric, discretisation: Discretisation | None = None, *,
                 check: bool = True, pad_fraction: float = 0.1) -> BeadModel:
    """Beads, bonds and types of ``fabric``.

    Args:
        fabric: the fabric description.
        discretisation: bead spacing ratio, mass scaling, bending (defaults if None).
        check: run the overlap check (raises :class:`InputError` on overlap).
        pad_fraction: non-periodic box margin around the beads, as a fraction of
            the fabric size in x and y (z: one fabric thickness on each side).

    ``BeadModel.info`` holds (JSON): ``format``, ``architecture`` (name, kind,
    matrix or layers/binder paths), ``unit_cell_m`` [x, y], ``tiling``,
    ``fabric_size_m`` [x, y], ``periodic``, ``yarns_per_unit_cell``,
    ``yarn_axis`` (family → 0 for x, 1 for y), ``spacing_m`` and
    ``count_per_m`` per family, ``families`` (per family: tex, n_fibres,
    width/height, fibre contact diameter, filament area, bond length, E·A,
    modulus, density), ``yarn_offset_m`` / ``yarn_level`` (per yarn, in yarn
    order), ``z_levels_m``, ``loose_thickness_m`` and ``z_extent_m`` (bead
    extent incl. radius), ``crimp`` per family (loose centreline crimp),
    ``areal_density_kg_m2``, ``clearance_m`` (smallest gap between beads of
    different yarns; ``None`` if above the search cutoff), ``clearance_pair``
    (the two yarns), ``requested_clearance_m``, ``lift_m`` (loose-state lift),
    ``datasheet`` (areal density given, built/given − 1, straight-yarn areal density
    per family, thickness and its pressure), ``yarn_packing`` (per family: yarn fibre
    volume fraction, filament and section area, shape, width, height, woven width;
    also per override key ``"<family>:<k>"``), ``yarn_specs`` (per override key: as
    ``families``, plus the names of its yarns), ``yarn_spec`` (per yarn, its spec key),
    ``bond_types_per_family``,
    ``build_s`` and ``fabric`` (the description as plain data).
    """
    t0 = time.perf_counter()
    disc = discretisation or Discretisation()
    fams = yarn_spec_beads(fabric, disc)
    families = fabric.families
    paths = fabric.yarn_paths()
    cell_keys = fabric.cell_spec_keys()
    _check_folding(paths, fams, cell_keys)
    periodic = fabric.periodic
    per_yarn = _fibre_shapes(paths, fams, cell_keys, periodic, disc)
    type_table, type_params = _bond_types(fams, families, paths, per_yarn, cell_keys, disc)
    beads = _place_beads(paths, per_yarn, families, cell_keys, type_table, type_params)
    pos, diam, fibre_ids, fibre_type = beads["positions"], beads["diameters"], \
        beads["fibre_ids"], beads.pop("fibre_type")
    links = _links(fibre_ids, fibre_type, beads.pop("counts"), periodic, disc, type_params,
                   type_table)
    # box, wrapping and image flags
    r = 0.5 * diam
    z_lo, z_hi = float((pos[:, 2] - r).min()), float((pos[:, 2] + r).max())
    thickness = z_hi - z_lo
    box = _box(np.array(fabric.size_m), pos, r, (z_lo, z_hi), periodic, pad_fraction)
    model = BeadModel(**beads, **links, **box, family_names=families,
                      bond_type_table=type_table, periodic=(periodic, periodic, False))

    approach = None
    if check:
        approach = check_overlaps(model, fabric)
    model.info = fabric_info(fabric, disc, fams, paths, model, approach, thickness,
                             (z_lo, z_hi), cell_keys)
    model.info["build_s"] = time.perf_counter() - t0
    return model


def _fibre_shapes(paths: list[YarnPath], fams: dict[str, FamilyBeads], cell_keys: list[str],
                  periodic: bool, disc: Discretisation) -> list[list]:
    """The fibres of every yarn (in ``paths`` order): those of each distinct unit-cell
    yarn are computed once (at offset 0) and shared by its copies; each fibre's first
    bead sits at its phase (``disc.bead_register``)."""
    shapes: dict[int, list] = {}
    per_yarn = []
    for path in paths:
        fam = fams[cell_keys[path.cell_index]]
        if path.cell_index not in shapes:
            phases = disc.bead_phases(len(fam.offsets_m))
            base = YarnPath(path.name, path.family, path.axis, 0.0, path.length_m,
                            path.period_m, path.node_u_m, path.node_z_m, path.plateau_m,
                            path.z_m, path.level, path.cell_index)
            shapes[path.cell_index] = fibre_beads(base, fam.offsets_m, fam.beads.bond_length_m,
                                                  periodic, phases)
        per_yarn.append(shapes[path.cell_index])
    return per_yarn


def _bond_types(fams: dict[str, FamilyBeads], families: tuple[str, ...],
                paths: list[YarnPath], per_yarn: list[list], cell_keys: list[str],
                disc: Discretisation) -> tuple[list[BondType], list[BeadParameters]]:
    """Bond types per family, per yarn spec (overrides), grouped by rest length [m],
    with the bead parameters of each; the types of one family form a contiguous range."""
    type_table: list[BondType] = []
    type_params: list[BeadParameters] = []
    for key in fams:
        fam_name = key.split(":")[0]
        if fam_name not in families:
            continue
        lengths = sorted({fb.spacing_m for path, fibres in zip(paths, per_yarn, strict=True)
                          if cell_keys[path.cell_index] == key for fb in fibres})
        groups: list[float] = []
        for length in lengths:
            if not groups or length > groups[-1] * (1 + REST_LENGTH_TOLERANCE):
                groups.append(length)
        for length in groups:
            p = fams[key].at_spacing(length, disc)
            type_table.append(BondType(p.bond_coefficient, length, fam_name, p.axial_stiffness_n,
                                       spec=key))
            type_params.append(p)
    # families first, so that the types of one family stay a contiguous range
    order = sorted(range(len(type_table)), key=lambda k: families.index(type_table[k].family))
    return [type_table[k] for k in order], [type_params[k] for k in order]


def _place_beads(paths: list[YarnPath], per_yarn: list[list], families: tuple[str, ...],
                 cell_keys: list[str], type_table: list[BondType],
                 type_params: list[BeadParameters]) -> dict:
    """Per-bead arrays (SI) of every fibre moved to its yarn's offset, as BeadModel
    keywords, plus ``fibre_type`` (bond type of each fibre) and ``counts`` (its beads)."""
    def type_of(key: str, length: float) -> int:
        best = min((abs(bt.rest_length_m - length), k) for k, bt in enumerate(type_table)
                   if bt.spec == key)
        return best[1] + 1

    counts = [len(fb.positions) for fibres in per_yarn for fb in fibres]
    n = int(sum(counts))
    pos = np.empty((n, 3))
    diam = np.empty(n)
    mass = np.empty(n)
    atype = np.empty(n, np.int64)
    fibre_ids = np.empty(n, np.int64)
    fibre_yarn = []
    fibre_type = []
    yarns = []
    cursor = 0
    fid = 0
    for yid, (path, fibres) in enumerate(zip(paths, per_yarn, strict=True), start=1):
        yarns.append(Yarn(path.name, path.family))
        t = families.index(path.family) + 1
        shift = np.zeros(3)
        shift[1 - path.axis] = path.offset_m
        for fb in fibres:
            k = len(fb.positions)
            fid += 1
            btype = type_of(cell_keys[path.cell_index], fb.spacing_m)
            fibre_type.append(btype)
            sl = slice(cursor, cursor + k)
            pos[sl] = fb.positions + shift
            diam[sl] = type_params[btype - 1].diameter_m
            mass[sl] = type_params[btype - 1].mass_kg
            atype[sl] = t
            fibre_ids[sl] = fid
            fibre_yarn.append(yid)
            cursor += k
    return {"positions": pos, "diameters": diam, "masses": mass, "atom_types": atype,
            "fibre_ids": fibre_ids, "fibre_yarn": np.asarray(fibre_yarn, np.int64),
            "yarns": yarns, "fibre_type": np.asarray(fibre_type, np.int64), "counts": counts}


def _links(fibre_ids: np.ndarray, fibre_type: np.ndarray, counts: list[int], periodic: bool,
           disc: Discretisation, type_params: list[BeadParameters],
           type_table: list[BondType]) -> dict:
    """Bonds along each fibre (+ closing bonds when periodic) and, with bending, the
    angles of three consecutive beads, as BeadModel keywords."""
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    ends = starts + np.asarray(counts, np.int64) - 1
    i = np.flatnonzero(fibre_ids[:-1] == fibre_ids[1:])
    bonds = np.column_stack([i, i + 1])
    btypes = fibre_type[fibre_ids[i] - 1]
    if periodic:
        bonds = np.vstack([bonds, np.column_stack([ends, starts])])
        btypes = np.concatenate([btypes, fibre_type])

    angles = np.zeros((0, 3), np.int64)
    angle_types = np.zeros(0, np.int64)
    angle_table: list[AngleType] = []
    if any(p.bending_stiffness_nm2 > 0 for p in type_params):
        angle_table = [AngleType(p.angle_coefficient, bt.family)
                       for p, bt in zip(type_params, type_table, strict=True)]
        j = np.flatnonzero((fibre_ids[:-2] == fibre_ids[1:-1]) & (fibre_ids[1:-1] == fibre_ids[2:]))
        angles = np.column_stack([j, j + 1, j + 2])
        if periodic:
            angles = np.vstack([angles, np.column_stack([ends - 1, ends, starts]),
                                np.column_stack([ends, starts, starts + 1])])
        angle_types = fibre_type[fibre_ids[angles[:, 1]] - 1]
    return {"bonds": bonds, "bond_types": btypes, "angles": angles, "angle_types": angle_types,
            "angle_type_table": angle_table}


def _box(size: np.ndarray, pos: np.ndarray, r: np.ndarray, z_extent: tuple[float, float],
         periodic: bool, pad_fraction: float) -> dict:
    """Box [m] and image flags; a periodic fabric's beads are wrapped into the box
    (``pos`` is changed in place). z: one bead-extent thickness of room on each side."""
    z_lo, z_hi = z_extent
    thickness = z_hi - z_lo
    images = np.zeros((len(pos), 3), np.int64)
    if periodic:
        box_lo = np.array([0.0, 0.0, z_lo - thickness])
        box_hi = np.array([size[0], size[1], z_hi + thickness])
        for k in range(2):
            images[:, k] = np.floor(pos[:, k] / size[k]).astype(np.int64)
            pos[:, k] -= images[:, k] * size[k]
    else:
        pad = pad_fraction * size
        box_lo = np.array([(pos[:, 0] - r).min() - pad[0], (pos[:, 1] - r).min() - pad[1],
                           z_lo - thickness])
        box_hi = np.array([(pos[:, 0] + r).max() + pad[0], (pos[:, 1] + r).max() + pad[1],
                           z_hi + thickness])
    return {"box_lo": box_lo, "box_hi": box_hi, "images": images}


def check_overlaps(model: BeadModel, fabric: Fabric | None = None) -> ClosestApproach:
    """Closest approach between beads of different yarns; raise if any overlap.

    Raises:
        InputError: naming the two yarns, where, by how much, and what to change.
    """
    tol = 1e-6 * float(model.diameters.min())
    cutoff = float(model.diameters.max()) + 2.0 * max(
        (fabric.clearance_m if fabric else 0.0), 0.25 * float(model.diameters.max()))
    for _ in range(3):  # widen the search until some pair of different yarns is seen
        res = closest_approach(model.positions, model.diameters, model.yarn_ids, model.box_lo,
                               model.box_hi, model.periodic, cutoff_m=cutoff, tolerance_m=tol)
        if res.gap_m is not None:
            break
        cutoff *= 2.0
    if res.gap_m is not None and res.gap_m < -tol:
        ya = model.yarns[model.yarn_ids[res.i] - 1].name
        yb = model.yarns[model.yarn_ids[res.j] - 1].name
        where = ", ".join(f"{1e3 * v:.3f}" for v in model.positions[res.i])
        raise InputError(
            f"beads of yarns {ya} and {yb} overlap by {1e3 * -res.gap_m:.3g} mm near "
            f"({where}) mm ({res.overlaps} overlapping bead pairs): increase "
            f"fabric.clearance_m or the yarn spacing, or reduce yarn heights/widths or "
            f"fabric.plateau")
    return res
