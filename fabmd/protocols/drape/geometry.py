"""Where the blank and the tools of a drape lie: the blank centred between yarns and cut to the
modelled part, the tools' heights and the bead zones that can reach each tool (lengths in m).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...errors import InputError
from ...model.bead_model import BeadModel
from ...model.transform import subset

if TYPE_CHECKING:
    from .protocol import Drape


@dataclass(frozen=True)
class DrapeGeometry:
    """Tools and zones of a drape on a prepared (centred) blank; lengths in m."""

    quarter: bool
    radius_m: float
    die_radius_m: float
    holder_radius_m: float
    z_die_m: float
    z_holder_m: float
    punch_z_m: float
    gap_m: float
    thickness_m: float
    spacing_m: float
    half_size_m: tuple[float, float]
    punch_reach_m: float
    die_reach_m: float
    contact_angle_rad: float
    flange_reach_m: float
    face_radius_m: float
    diameter_m: float
    sym_x: tuple[int, ...]
    sym_y: tuple[int, ...]

    @property
    def share(self) -> float:
        """Part of the whole blank the model holds (1/4 for the quarter)."""
        return 0.25 if self.quarter else 1.0


def yarn_centres(model: BeadModel, family: str, axis: int) -> np.ndarray:
    """Sorted mean ``axis`` coordinate of every yarn of ``family`` [m]."""
    yid = model.yarn_ids
    pos = model.positions[:, axis]
    out = [float(pos[yid == k + 1].mean()) for k, y in enumerate(model.yarns)
           if y.family == family and np.any(yid == k + 1)]
    return np.sort(np.asarray(out))


def gap_line(centres: np.ndarray, near: float) -> float:
    """The mid-line between two neighbouring yarns closest to ``near``."""
    if len(centres) < 2:
        raise InputError("the blank needs at least two yarns of each family")
    mids = 0.5 * (centres[1:] + centres[:-1])
    return float(mids[np.argmin(np.abs(mids - near))])


def contact_angle_rad(radius: float, die_radius: float, centre_above_die: float,
                      thickness: float) -> float:
    """Polar angle (from the punch's lowest point) up to which a taut fabric wraps the punch:
    the tangent from the die edge (offset by half the fabric thickness) to the punch."""
    r = radius + 0.5 * thickness
    ex, ez = die_radius, 0.5 * thickness - centre_above_die  # die edge relative to the centre
    dist = math.hypot(ex, ez)
    if dist <= r:
        return math.pi / 2
    towards_edge = math.atan2(ex, -ez)  # angle of the edge from the downward axis
    return max(0.0, towards_edge - math.acos(r / dist))



def check_orientation(model: BeadModel) -> None:
    """Warp along x and weft along y (within 15°), both present."""
    from ...analysis import FabricFrame, family_axes_deg

    axes = family_axes_deg(FabricFrame.from_model(model))
    for fam, want in (("warp", 0.0), ("weft", 90.0)):
        got = axes.get(fam)
        if got is None:
            raise InputError(f"drape needs warp and weft yarns; the blank has "
                             f"{list(model.family_names)}")
        if abs(((got - want) + 90) % 180 - 90) > 15:
            raise InputError(f"drape needs {fam} along {'x' if want == 0 else 'y'}, but "
                             f"its fibres run at {got:.0f} deg; cut the blank at "
                             f"angle_deg = 0")


def centre_blank(model: BeadModel) -> tuple[BeadModel, float]:
    """The blank with its centre lines (between yarns) on x = 0, y = 0 and its mid-plane
    on z = 0; and the yarn spacing [m]."""
    if any(model.periodic):
        raise InputError("drape needs a finite blank, not a periodic cell; cut one with "
                         "Coupon(length_m=L, width_m=L) (fabmd test drape does)")
    check_orientation(model)
    p = model.unwrapped_positions
    lo, hi = p.min(axis=0), p.max(axis=0)
    centre = 0.5 * (lo + hi)
    weft_x = yarn_centres(model, "weft", 0)
    warp_y = yarn_centres(model, "warp", 1)
    x0 = gap_line(weft_x, centre[0])
    y0 = gap_line(warp_y, centre[1])
    spacing = float(max(np.median(np.diff(weft_x)), np.median(np.diff(warp_y))))
    shift = np.array([x0, y0, centre[2]])
    moved = dataclasses.replace(model, positions=p - shift, images=None,
                                box_lo=model.box_lo - shift, box_hi=model.box_hi - shift,
                                info=dict(model.info))
    d = float(model.diameters.max())
    for axis, fam in ((0, "weft"), (1, "warp")):
        on_plane = np.abs(moved.positions[:, axis]) < 0.5 * d
        if np.any(on_plane & (moved.families == fam)):
            raise InputError(f"a {fam} yarn lies on the symmetry plane "
                             f"{'xy'[axis]} = 0 of the blank; the yarns are too wide "
                             f"for their spacing")
    return moved, spacing


def cut_blank(test: Drape, model: BeadModel) -> BeadModel:
    """The model to run: the blank centred (:func:`centre_blank`), its x > 0, y > 0 quarter for
    ``symmetry="quarter"``; checked against the tools."""
    full, spacing = centre_blank(model)
    p = full.positions
    half = (float(min(p[:, 0].max(), -p[:, 0].min())),
            float(min(p[:, 1].max(), -p[:, 1].min())))
    holder_radius = test.holder_radius_m
    need = holder_radius + spacing
    if min(half) < need:
        raise InputError(f"the blank ({2e3 * half[0]:.1f} x {2e3 * half[1]:.1f} mm) must "
                         f"reach past the holder's opening (radius "
                         f"{1e3 * holder_radius:.1f} mm) by a yarn spacing: use a "
                         f"blank at least {2e3 * need:.1f} mm wide")
    keep = (p[:, 0] > 0) & (p[:, 1] > 0) if test.symmetry == "quarter" else \
        np.ones(full.n_beads, bool)
    run = subset(full, keep)
    if test.modulus_scale != 1.0:
        k = test.modulus_scale
        run.bond_type_table = [dataclasses.replace(bt, coefficient=bt.coefficient * k,
                                                   axial_stiffness_n=bt.axial_stiffness_n * k)
                               for bt in run.bond_type_table]
        run.angle_type_table = [dataclasses.replace(at, coefficient=at.coefficient * k)
                                for at in run.angle_type_table]
    run.info = dict(run.info, drape={"modulus_scale": test.modulus_scale,
        "symmetry": test.symmetry, "spacing_m": spacing, "blank_half_size_m": list(half),
        "thickness_m": float(np.ptp(p[:, 2]) + full.diameters.max())})
    g = tool_geometry(test, run)
    # the fabric must pass between the punch and the die edge at full depth
    edge_gap = math.hypot(g.die_radius_m, g.punch_z_m - test.travel_m(run) - g.z_die_m) \
        - g.radius_m
    if edge_gap < g.thickness_m:
        raise InputError(f"at depth {1e3 * test.depth_m:g} mm the punch passes "
                         f"{1e3 * edge_gap:.2f} mm from the die edge, less than the fabric "
                         f"thickness {1e3 * g.thickness_m:.2f} mm: raise "
                         f"drape.die_clearance_m (now {1e3 * test.die_clearance_m:g} mm) "
                         f"or lower drape.depth_m")
    return run


def tool_geometry(test: Drape, model: BeadModel) -> DrapeGeometry:
    """Tools and zones of ``test`` on a model from :func:`cut_blank` (its ``info``
    carries the blank's spacing, half size, symmetry and thickness)."""
    q = model.positions
    d = float(model.diameters.max())
    info = model.info["drape"]
    spacing = float(info["spacing_m"])
    half = tuple(float(h) for h in info["blank_half_size_m"])
    quarter = info["symmetry"] == "quarter"
    thickness = float(info["thickness_m"])
    r_xy = np.hypot(q[:, 0], q[:, 1])
    z_die = float(q[:, 2].min() - 0.5 * d)
    holder_radius = test.holder_radius_m
    z_holder = float(q[r_xy > holder_radius, 2].max() + 0.5 * d)
    cap = r_xy < test.die_radius_m + d
    gap = 0.1 * d
    punch_z = float((q[cap, 2].max() if cap.any() else q[:, 2].max()) + 0.5 * d + gap
                    + test.punch_radius_m)
    r = test.punch_radius_m
    # arc of the punch below the die face at full depth, plus a margin: fibres do not
    # stretch, so beads that start further out cannot wrap it
    wrap = r * math.acos(max(-1.0, 1.0 - test.depth_m / r))
    sym_x: tuple[int, ...] = ()
    sym_y: tuple[int, ...] = ()
    if quarter:  # fibre ends cut by the symmetry planes
        longest = max(bt.rest_length_m for bt in model.fibre_bond_types())
        ends = np.unique(model.fibre_ends().ravel())
        sym_x = tuple(int(i) for i in ends[q[ends, 0] < 1.01 * longest])
        sym_y = tuple(int(i) for i in ends[q[ends, 1] < 1.01 * longest])
    centre_above_die = punch_z - test.travel_from(gap) - z_die
    # fabric that ends up inside the opening: at most the punch arc below the die face
    # plus the way out to the die edge (fibres do not stretch), plus margins
    theta = math.acos(max(-1.0, 1.0 - test.depth_m / r))
    path = r * theta + max(0.0, test.die_radius_m - r * math.sin(theta))
    flange = max(1.1 * path + 2 * spacing + d, test.die_radius_m + 2 * spacing + d)
    return DrapeGeometry(
        quarter=quarter, radius_m=r, die_radius_m=test.die_radius_m,
        holder_radius_m=holder_radius, z_die_m=z_die, z_holder_m=z_holder,
        punch_z_m=punch_z, gap_m=gap, thickness_m=thickness, spacing_m=spacing,
        half_size_m=half, punch_reach_m=1.25 * wrap + 2 * spacing + d,
        die_reach_m=max(0.0, test.die_radius_m - 2 * spacing - d),
        contact_angle_rad=contact_angle_rad(r, test.die_radius_m, centre_above_die,
                                            thickness),
        flange_reach_m=flange, face_radius_m=2.0 * math.hypot(*half) + 10 * d,
        diameter_m=d, sym_x=sym_x, sym_y=sym_y)


def tool_reach(g: DrapeGeometry, tool_zones: bool = True) -> dict[str, float]:
    """Radii of the punch, die and die-wall contact zones [m]; without ``tool_zones``
    every bead gets punch, die and die-wall contact (the holder's zone stays: it also
    defines the beads whose force is the holder force)."""
    if tool_zones:
        return {"punch_reach": g.punch_reach_m, "die_reach": g.die_reach_m,
                "flange_reach": g.flange_reach_m}
    return {"punch_reach": g.face_radius_m, "die_reach": 1e-3 * g.diameter_m,
            "flange_reach": g.face_radius_m}
