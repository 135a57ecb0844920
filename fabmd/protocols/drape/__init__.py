"""Draping with a hemispherical punch: how a fabric follows a double-curved tool.

The blank (warp along x, weft along y) lies flat on a die, a plane with a
circular opening of radius R + c (punch radius R, clearance c). A blank holder,
a plane pressing down on the fabric outside the opening, is force-controlled: it
moves down at a speed proportional to the difference between the set force and
the contact force it takes (``fix controller``), like a plate on a viscous guide
pressed by the set force. Once the holder has clamped the fabric, a rigid sphere
of radius R on the opening's axis moves down by the set depth (smooth start, then
constant speed) and draws the fabric into the opening. Tools touch fibres through
``fix wall/gran/region`` with their own friction (:class:`ToolContact`); only
beads that can reach a tool are given its contact (groups of the initial
positions: punch within the arc it can wrap plus a margin, die and holder outside
the opening).

Symmetry: the quarter model (default) keeps the blank's x > 0, y > 0 part; the
symmetry planes x = 0 and y = 0 are the blank's centre lines, placed between
yarns, and the fibre ends cut there are held in that plane's normal direction
(``fix setforce`` on that component, zero velocity; ``fix nve`` then never moves
them across). Forces are reported for the whole blank (4 × the quarter's).

Outputs (besides the driven-test evidence, see :mod:`fabmd.protocols.driven`):
punch force against depth, the holder force and its error after start-up, the
in-plane shear-angle field over the draped fabric from the local warp and weft
tangents (:func:`fabmd.analysis.surface_shear_angle_field`, grid over the initial
positions; CSV + NPZ + PNG map) and its largest value, a wrinkling indicator
(distance of the beads over the punch cap, where the fabric should lie on it, to
the sphere minus half the fabric thickness: max and RMS), the edge draw-in along
warp, weft and the diagonal, the final shape (``final.vtu``, ``shape.png``) and
the trajectory (``trajectory.h5``, ParaView files).

Energy: the external work of punch and holder = Δ strain energy + Δ kinetic
energy + viscous damping + fibre–fibre contact work (sampled by the in-process
engine) + the work the tool contacts absorb (exact, each step: force · (tool
velocity − bead velocity)); the closing error is reported.

The package: :mod:`.protocol` (the :class:`Drape` dataclass: parameters, loading, holder
control), :mod:`.geometry` (blank and tools), :mod:`.input` (LAMMPS input from
``lammps_templates/drape*.lmp``), :mod:`.reduce` (curves and summary), :mod:`.measures`
(shape measures), :mod:`.report` (shear-angle files, final shape, plots). The run itself is
:meth:`fabmd.protocols.driven.DrivenTest.run`: one trajectory conversion per run (after a
failure, the frames written so far).
"""

from .geometry import DrapeGeometry, contact_angle_rad, gap_line, yarn_centres
from .input import CLAMP_OVERLAP_FILE, OVERLAP_EVERY, SAMPLE_EVERY, TOOLS
from .measures import blank_shear_deg, draw_in, shear_grid, wrinkling
from .protocol import PROTOCOL, SYMMETRIES, Drape
from .reduce import clamp_steps, merged_overlap

__all__ = [
    "CLAMP_OVERLAP_FILE", "OVERLAP_EVERY", "PROTOCOL", "SAMPLE_EVERY", "SYMMETRIES", "TOOLS",
    "Drape", "DrapeGeometry", "blank_shear_deg", "clamp_steps", "contact_angle_rad",
    "draw_in", "gap_line", "merged_overlap", "shear_grid", "wrinkling", "yarn_centres",
]
