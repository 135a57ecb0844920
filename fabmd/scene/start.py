"""How a driven test starts: the tools' speed ramped up from a fabric at rest, or the
fabric already moving with the tools.

A smooth start (``"smooth"``) ramps the tools' speed up over part of the test while the
fabric they carry is at rest: the tools then pay its kinetic energy, ½·Σ m·|v_affine|²,
from their force. Where the fabric is slack that is most of the force at first (the
plain-weave example's picture frame: 0.79 of the frame's work over 0–5° went into
kinetic energy, all of it the fabric riding with the frame). ``"affine"`` gives the free
beads the tools' affine velocity at full speed before the first step
(``lammps_templates/affine_start.lmp``) and starts the tools at full speed: nothing to
accelerate, no wave from the clamps, and the energy balance counts the change of kinetic
energy from that start.
"""

from __future__ import annotations

from .drag import AffineField
from .templates import render_inline

START_KINDS = ("smooth", "affine")


def affine_start(group: str, field: AffineField) -> str:
    """LAMMPS text giving ``group``'s beads the velocity of ``field`` at their place
    (in-plane; z kept). The field's gradient entries must be valid before the run
    (numbers, or equal-style variables that need no fix)."""
    return render_inline("affine_start", tools=field.tools, group=group, vx=field.vx,
                         vy=field.vy, x0=field.origin("x"), y0=field.origin("y"))
