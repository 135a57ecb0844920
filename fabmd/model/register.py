"""Where the beads of crossing fibres sit: the registers of a 2D weave's fibre crossings.

A crossing of two bead chains is a point contact: its force depends on where the two
chains' beads sit relative to the crossing point (the *register*, a fraction of the bead
spacing along each chain). The per-crossing contact (README "Crossing per crossing") and
the within-family law are exact for the *average* over registers. A fabric whose fibres
all start their beads at the yarn's start (``bead_register = "aligned"``) can put every
crossing in nearly the same register; then the whole fabric carries that register's
force, not the average (on the Twintex cell at s/d 0.5: about 4× the average at an
overlap of 2 % of d). ``bead_register = "staggered"`` spreads them
(:meth:`fabmd.model.beads.Discretisation.bead_phases`).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .bead_model import BeadModel
from .contact import crossing_force_n, crossing_law_force_n


def _fibres_along(model: BeadModel, family: str, axis: int) -> list[np.ndarray]:
    """Bead positions of every fibre of ``family`` (each sorted along ``axis``)."""
    kinds = np.asarray(model.family_names)[model.atom_types - 1]
    out = []
    for fibre in np.unique(model.fibre_ids[kinds == family]):
        pos = model.positions[model.fibre_ids == fibre]
        out.append(pos[np.argsort(pos[:, axis])])
    return out


def crossing_registers(model: BeadModel, families: tuple[str, str] = ("warp", "weft")
                       ) -> np.ndarray:
    """(n, 2) registers in [0, 1) of every fibre crossing of a 2D weave.

    Fibres of ``families[0]`` run along x, those of ``families[1]`` along y (fabmd's 2D
    weaves). For each pair, the first register is where the x-fibre's crossing point
    falls between its two nearest beads (0: on a bead), the second the same along the
    y-fibre. Pairs that do not cross inside both fibres' spans are left out.
    """
    if not all(f in model.family_names for f in families):
        raise InputError(f"crossing registers need the families {families}; the model has "
                         f"{model.family_names}")
    xs, ys = _fibres_along(model, families[0], 0), _fibres_along(model, families[1], 1)
    out = []
    for a in xs:
        y_a = float(np.mean(a[:, 1]))
        x_b = np.array([float(np.mean(b[:, 0])) for b in ys])
        i = np.searchsorted(a[:, 0], x_b)
        inside_a = (i > 0) & (i < len(a))
        for b, xb, k, ok in zip(ys, x_b, i, inside_a, strict=True):
            j = np.searchsorted(b[:, 1], y_a)
            if not ok or j == 0 or j == len(b):
                continue
            ra = (xb - a[k - 1, 0]) / (a[k, 0] - a[k - 1, 0])
            rb = (y_a - b[j - 1, 1]) / (b[j, 1] - b[j - 1, 1])
            out.append((ra % 1.0, rb % 1.0))
    return np.asarray(out, float).reshape(-1, 2)


def crossing_register_bias(registers: np.ndarray, spacing_ratio: float,
                           overlap_ratio: float, angle_deg: float = 90.0) -> dict:
    """Mean / min / max force of crossings at these registers over the register average.

    Straight chains of diameter d crossing at ``angle_deg``, pressed to an overlap of
    ``overlap_ratio``·d, per-crossing pair stiffness (the ratio does not depend on it);
    1.0 means the fabric's crossings carry the force the contact law states.
    """
    d, l0 = 1.0, spacing_ratio
    forces = np.array([crossing_force_n(1.0, l0, d, overlap_ratio * d, angle_deg, ra * l0,
                                        rb * l0, "per_crossing") for ra, rb in registers])
    mean = crossing_law_force_n(1.0, d, overlap_ratio * d, angle_deg)
    return {"mean": float(forces.mean() / mean), "min": float(forces.min() / mean),
            "max": float(forces.max() / mean), "crossings": len(forces)}
