"""Analysis of fabric states (pure numpy, SI): yarn centrelines and curvature, crimp,
yarn cross-sections, in-plane yarn angles and the shear-angle field (also on a draped,
curved fabric: :func:`surface_shear_angle_field`).

Every function works on a :class:`FabricFrame` — the unwrapped bead positions of
one frame with their fibre/yarn identity — made from a bead model, a trajectory
frame or an MDAnalysis universe::

    import fabmd
    from fabmd import analysis

    u = fabmd.load("runs/crimp")
    frame = analysis.FabricFrame.from_universe(u)          # the current frame
    analysis.crimp_by_family(frame)                        # {"warp": 0.012, ...}
    field = analysis.shear_angle_field(frame, cells=(8, 8))
    centre = analysis.zone_mask(frame.positions, (0.01, 0.01), (0.002, 0.002))
    analysis.zone_shear_angle_deg(frame, centre)          # one zone, signed by the test
"""

from .angles import (
    Field,
    axial_mean_deg,
    family_axes_deg,
    fibre_segments,
    in_plane_angle_field,
    segment_directions,
    shear_angle_field,
    shear_between_axes_deg,
    zone_mask,
    zone_shear_angle_deg,
)
from .frame import FabricFrame
from .sections import CrossSection, FabricCut, convex_hull, cross_section, fabric_cut
from .surface import fibre_tangents, grid_edges, surface_shear_angle_field
from .yarns import (
    centreline,
    crimp,
    crimp_by_family,
    crimp_by_yarn,
    curvature,
    path_length,
    resample,
    yarn_centreline,
    yarn_centrelines,
)

__all__ = [
    "CrossSection",
    "FabricCut",
    "FabricFrame",
    "Field",
    "axial_mean_deg",
    "centreline",
    "convex_hull",
    "crimp",
    "crimp_by_family",
    "crimp_by_yarn",
    "cross_section",
    "fabric_cut",
    "curvature",
    "family_axes_deg",
    "fibre_segments",
    "fibre_tangents",
    "grid_edges",
    "in_plane_angle_field",
    "path_length",
    "resample",
    "segment_directions",
    "shear_angle_field",
    "shear_between_axes_deg",
    "surface_shear_angle_field",
    "yarn_centreline",
    "yarn_centrelines",
    "zone_mask",
    "zone_shear_angle_deg",
]
