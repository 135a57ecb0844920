"""Cut, subset and tile bead models (coupons from relaxed fabrics).

All three rebuild the fibres from the bonds that survive, so the bead-model
invariants hold afterwards: whole bonds only, beads of a fibre contiguous and
ordered along it, fibre ids increasing with bead index, no fibre shorter than
``min_beads`` (no dangling single beads).
"""

from __future__ import annotations

import math

import numpy as np

from .. import inputs
from ..errors import InputError
from .bead_model import BeadModel, Yarn


# -- chains --------------------------------------------------------------------------------
def _chains(n: int, bonds: np.ndarray) -> list[tuple[np.ndarray, bool]]:
    """Order beads into chains along ``bonds`` (each bead has at most two).

    Returns (bead indices in chain order, closed) for every chain, chains in the
    order of their smallest bead index.
    """
    bonds = np.asarray(bonds, np.int64).reshape(-1, 2)
    ends = np.concatenate([bonds[:, 0], bonds[:, 1]])
    other = np.concatenate([bonds[:, 1], bonds[:, 0]])
    deg = np.bincount(ends, minlength=n)
    if deg.size and deg.max() > 2:
        raise InputError(f"bead {int(deg.argmax())} has more than two bonds: not a fibre chain")
    order = np.argsort(ends, kind="stable")
    start = np.concatenate([[0], np.cumsum(deg)[:-1]])
    nb = np.full((n, 2), -1, dtype=np.int64)
    has = deg >= 1
    nb[has, 0] = other[order[start[has]]]
    two = deg == 2
    nb[two, 1] = other[order[start[two] + 1]]
    seen = np.zeros(n, dtype=bool)
    chains: list[tuple[np.ndarray, bool]] = []

    def walk(start: int) -> list[int]:
        order = [start]
        seen[start] = True
        prev, cur = -1, start
        while True:
            nxt = nb[cur, 0] if nb[cur, 0] != prev else nb[cur, 1]
            if nxt < 0 or seen[nxt]:
                return order
            order.append(int(nxt))
            seen[nxt] = True
            prev, cur = cur, nxt

    # open chains start at an end (degree <= 1); walk from the end with the lower index
    for start in np.flatnonzero(deg <= 1):
        if not seen[start]:
            chains.append((np.asarray(walk(int(start))), False))
    for start in range(n):  # what is left are closed loops
        if not seen[start]:
            chains.append((np.asarray(walk(start)), True))
    chains.sort(key=lambda c: int(c[0].min()))
    return chains


def _rebuild(model: BeadModel, positions: np.ndarray, keep_src: np.ndarray,
             bonds: np.ndarray, bond_types: np.ndarray, yarn_key: list, yarns_out: list[Yarn],
             box_lo, box_hi, periodic, images: np.ndarray | None, min_beads: int,
             info: dict) -> BeadModel:
    """New model from beads (source index ``keep_src``) and bonds between new indices."""
    n = len(keep_src)
    chains = [(c, closed) for c, closed in _chains(n, bonds) if len(c) >= min_beads]
    if not chains:
        raise InputError("nothing is left: no fibre with at least "
                         f"{min_beads} beads lies inside the region")
    order = np.concatenate([c for c, _ in chains])
    new_index = np.full(n, -1, dtype=np.int64)
    new_index[order] = np.arange(len(order))
    fibre_ids = np.concatenate([np.full(len(c), k + 1) for k, (c, _) in enumerate(chains)])
    # bonds between surviving beads, renumbered
    b = new_index[bonds] if len(bonds) else np.zeros((0, 2), np.int64)
    ok = (b >= 0).all(axis=1) if len(b) else np.zeros(0, bool)
    b, bt = b[ok], bond_types[ok]
    b.sort(axis=1)
    # yarns: fibres keep their yarn identity (key per chain from its first bead)
    keys = [yarn_key[int(c[0])] for c, _ in chains]
    uniq: dict = {}
    for key in keys:
        uniq.setdefault(key, len(uniq) + 1)
    fibre_yarn = np.array([uniq[k] for k in keys], dtype=np.int64)
    yarns = [None] * len(uniq)
    for key, yid in uniq.items():
        yarns[yid - 1] = yarns_out[key]
    src = keep_src[order]
    angles = _chain_angles(chains, new_index) if len(model.angles) else np.zeros((0, 3), int)
    angle_types = np.zeros(len(angles), np.int64)
    if len(angles):
        family_type = {at.family: i + 1 for i, at in enumerate(model.angle_type_table)}
        middle_family = np.asarray(model.family_names)[model.atom_types[src[angles[:, 1]]] - 1]
        angle_types = np.array([family_type[f] for f in middle_family], np.int64)
    return BeadModel(
        positions=positions[order], diameters=model.diameters[src], masses=model.masses[src],
        atom_types=model.atom_types[src], fibre_ids=fibre_ids, bonds=b, bond_types=bt,
        family_names=model.family_names, bond_type_table=list(model.bond_type_table),
        fibre_yarn=fibre_yarn, yarns=yarns, box_lo=box_lo, box_hi=box_hi, periodic=periodic,
        images=None if images is None else images[order],
        angles=angles, angle_types=angle_types,
        angle_type_table=list(model.angle_type_table), info=info)


def _chain_angles(chains, new_index) -> np.ndarray:
    triples = []
    for c, closed in chains:
        idx = new_index[c]
        if len(idx) >= 3:
            triples.append(np.column_stack([idx[:-2], idx[1:-1], idx[2:]]))
            if closed:
                triples.append(np.array([[idx[-2], idx[-1], idx[0]], [idx[-1], idx[0], idx[1]]]))
    return np.vstack(triples) if triples else np.zeros((0, 3), np.int64)


# -- public --------------------------------------------------------------------------------
def subset(model: BeadModel, keep: np.ndarray, min_beads: int = 2,
           box_padding_m: float | None = None) -> BeadModel:
    """The beads where ``keep`` is true, as an open (non-periodic) model.

    Whole bonds only; a fibre cut into pieces becomes several fibres; pieces with
    fewer than ``min_beads`` beads are dropped. Positions are unwrapped.
    """
    keep = np.asarray(keep, bool)
    if keep.shape != (model.n_beads,):
        raise InputError(f"keep must have one entry per bead ({model.n_beads})")
    min_beads = inputs.positive_int("min_beads", min_beads, minimum=2)
    src = np.flatnonzero(keep)
    local = np.full(model.n_beads, -1, np.int64)
    local[src] = np.arange(len(src))
    lb = local[model.bonds]
    ok = (lb >= 0).all(axis=1)
    # a bond that crosses a periodic face is torn when the model is opened up
    unwrapped = model.unwrapped_positions
    if any(model.periodic) and len(model.bonds):
        span = np.linalg.norm(unwrapped[model.bonds[:, 1]] - unwrapped[model.bonds[:, 0]], axis=1)
        rest = np.array([bt.rest_length_m for bt in model.bond_type_table])[model.bond_types - 1]
        ok &= span < 2.0 * rest
    pos = unwrapped[src]
    pad = box_padding_m if box_padding_m is not None else 2.0 * float(model.diameters.max())
    lo = pos.min(axis=0) - pad
    hi = pos.max(axis=0) + pad
    yarn_of_bead = model.yarn_ids[src] - 1
    return _rebuild(model, pos, src, lb[ok], model.bond_types[ok], list(yarn_of_bead),
                    list(model.yarns), lo, hi, (False, False, False), None, min_beads,
                    dict(model.info))


def cut(model: BeadModel, length_m: float, width_m: float, angle_deg: float = 0.0,
        centre_m: tuple[float, float] | None = None, edge_zone_m: float = 0.0,
        min_beads: int = 2) -> BeadModel:
    """Cut a rectangular coupon, its length along x in the result.

    Args:
        length_m, width_m: coupon size [m].
        angle_deg: angle of the coupon's length axis to the fabric x (warp) axis;
            45 gives a bias-extension coupon.
        centre_m: (x, y) centre in the fabric [m]; default the fabric's centre.
        edge_zone_m: band along the fabric edges the coupon must stay out of [m].

    Raises:
        InputError: the rectangle does not fit inside the fabric minus its edge zone.
    """
    length = inputs.positive("coupon.length_m", length_m)
    width = inputs.positive("coupon.width_m", width_m)
    inputs.finite("coupon.angle_deg", angle_deg)
    edge = inputs.non_negative("coupon.edge_zone_m", edge_zone_m)
    pos = model.unwrapped_positions
    lo, hi = pos[:, :2].min(axis=0), pos[:, :2].max(axis=0)
    centre = (lo + hi) / 2 if centre_m is None else np.asarray(centre_m, float)
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    corners = centre + np.array([[sx * length / 2 * c - sy * width / 2 * s,
                                  sx * length / 2 * s + sy * width / 2 * c]
                                 for sx in (-1, 1) for sy in (-1, 1)])
    if (corners.min(axis=0) < lo + edge - 1e-12).any() or \
            (corners.max(axis=0) > hi - edge + 1e-12).any():
        raise InputError(
            f"a {length * 1e3:g} x {width * 1e3:g} mm coupon at {angle_deg:g} deg does not fit "
            f"inside the fabric ({(hi - lo)[0] * 1e3:.1f} x {(hi - lo)[1] * 1e3:.1f} mm) minus "
            f"its {edge * 1e3:g} mm edge zone; cut a smaller coupon or build a larger fabric")
    rel = pos[:, :2] - centre
    along = rel[:, 0] * c + rel[:, 1] * s
    across = -rel[:, 0] * s + rel[:, 1] * c
    keep = (np.abs(along) <= length / 2) & (np.abs(across) <= width / 2)
    coupon = subset(model, keep, min_beads=min_beads)
    # rotate the coupon so that its length is along x, centred at the origin in-plane
    p = coupon.positions
    rel = p[:, :2] - centre
    p = np.column_stack([rel[:, 0] * c + rel[:, 1] * s, -rel[:, 0] * s + rel[:, 1] * c, p[:, 2]])
    pad = coupon.box_hi - coupon.positions.max(axis=0)
    coupon.positions = p
    coupon.box_lo = p.min(axis=0) - pad
    coupon.box_hi = p.max(axis=0) + pad
    coupon.info = dict(coupon.info, coupon={"length_m": length, "width_m": width,
                                            "angle_deg": angle_deg,
                                            "centre_m": centre.tolist(), "edge_zone_m": edge})
    return coupon


def tile(model: BeadModel, nx: int, ny: int, periodic: bool = True) -> BeadModel:
    """Repeat a model periodic in x and y ``nx`` × ``ny`` times.

    Fibres that cross the cell faces join their copies in the neighbouring cells
    into one longer fibre. With ``periodic=True`` the result is periodic over the
    larger box; otherwise the fibres are cut open at its faces.
    """
    nx = inputs.positive_int("tile.nx", nx)
    ny = inputs.positive_int("tile.ny", ny)
    if not (model.periodic[0] and model.periodic[1]):
        raise InputError("tile needs a model periodic in x and y (build it with periodic = true)")
    n = model.n_beads
    length = model.box_hi - model.box_lo
    cells = [(a, b) for b in range(ny) for a in range(nx)]
    shift = np.array([[a * length[0], b * length[1], 0.0] for a, b in cells])
    pos = (model.positions[None, :, :] + shift[:, None, :]).reshape(-1, 3)
    src = np.tile(np.arange(n), len(cells))
    # image of j nearest to i, as whole cells
    d = model.positions[model.bonds[:, 1]] - model.positions[model.bonds[:, 0]]
    k = -np.round(d[:, :2] / length[:2]).astype(np.int64)
    bonds, types = [], []
    for c, (a, b) in enumerate(cells):
        ta, tb = a + k[:, 0], b + k[:, 1]
        if periodic:
            ta, tb = ta % nx, tb % ny
            inside = np.ones(len(ta), bool)
        else:
            inside = (ta >= 0) & (ta < nx) & (tb >= 0) & (tb < ny)
        target = (tb * nx + ta) * n + model.bonds[:, 1]
        bonds.append(np.column_stack([c * n + model.bonds[inside, 0], target[inside]]))
        types.append(model.bond_types[inside])
    bonds = np.vstack(bonds)
    types = np.concatenate(types)
    big = model.box_lo + length * np.array([nx, ny, 1])
    # yarn identity: original yarn + the cells its fibre spans (chains merge across cells)
    cell_of = np.repeat(np.arange(len(cells)), n)
    chain_key = np.zeros(len(pos), dtype=object)
    for chain, _closed in _chains(len(pos), bonds):
        y = int(model.yarn_ids[src[chain[0]]] - 1)
        key = (y, tuple(np.unique(cell_of[chain]).tolist()))
        for i in chain:
            chain_key[i] = key
    names = {}
    for key in dict.fromkeys(chain_key.tolist()):
        y, spanned = key
        a, b = cells[spanned[0]]
        names[key] = Yarn(f"{model.yarns[y].name}@{a},{b}", model.yarns[y].family)
    info = dict(model.info, tiling={"nx": nx, "ny": ny, "cell_m": length[:2].tolist()})
    tiled = _rebuild(model, pos, src, bonds, types, list(chain_key), names, model.box_lo,
                     big, (periodic, periodic, model.periodic[2]), None, 2, info)
    if periodic:
        tiled.images = continuous_images(tiled)
    else:
        tiled = subset(tiled, np.ones(tiled.n_beads, bool))
    return tiled


def continuous_images(model: BeadModel) -> np.ndarray:
    """Image flags that make every fibre continuous in ``unwrapped_positions``.

    Walks each fibre from its first bead, adding minimum-image bond vectors.
    """
    length = model.box_hi - model.box_lo
    images = np.zeros((model.n_beads, 3), np.int64)
    ends = model.fibre_ends()
    for first, last in ends:
        idx = np.arange(first, last + 1)
        d = np.diff(model.positions[idx], axis=0)
        for k in range(3):
            if model.periodic[k]:
                d[:, k] -= length[k] * np.round(d[:, k] / length[k])
        unwrapped = model.positions[first] + np.vstack([np.zeros(3), np.cumsum(d, axis=0)])
        images[idx] = np.round((unwrapped - model.positions[idx]) / length).astype(np.int64)
    for k in range(3):
        if not model.periodic[k]:
            images[:, k] = 0
    return images
