"""Numerical drag of a driven test: on the velocity relative to the tools' affine field.

A driven test's clamps or frame carry the fabric at up to the loading speed. A drag on
the beads' absolute velocity (``fix viscous``) then pulls against that motion and the
power balance counts it as fabric force (issue 16: 88 % of a picture frame's force at
10° was drag, and it changed with the damping time).

``"affine"`` (the default) damps only the motion relative to the affine velocity field
the tools impose on the fabric between them, f = −γ·(v − v_affine) (``fix addforce``
with atom-style variables, ``lammps_templates/affine_drag.lmp``): a fabric that follows
the tools feels no drag, its own vibrations and non-affine slips are damped.
``"absolute"`` keeps the old ``fix viscous`` (f = −γ·v), for comparison.

Either way the drag's power on the free beads, −f·v [W], is what the energy balance
counts as damping dissipation: γ·(v − v_affine)·v summed over the free beads.
"""

from __future__ import annotations

from dataclasses import dataclass

from .templates import fmt, render

DRAG_KINDS = ("affine", "absolute")


@dataclass(frozen=True)
class AffineField:
    """The tools' in-plane velocity field, as LAMMPS atom-style expressions of x, y [m/s].

    Args:
        vx, vy: expressions (may use LAMMPS variables the test defines).
        tools: what imposes it, for the comment in the input ("frame", "clamps").
    """

    vx: str
    vy: str
    tools: str


def drag_commands(kind: str, group: str, gamma_kg_s: float,
                  field: AffineField) -> tuple[str, str]:
    """(LAMMPS text, per-atom power expression) of the drag on ``group``.

    The power expression is the drag's dissipation per bead, −f·v [W], for
    ``driven_outputs.lmp``; γ [kg/s].
    """
    g = fmt(float(gamma_kg_s))
    if kind == "absolute":
        return (f"# drag on the absolute velocity (biases the force when the tools carry the "
                f"fabric)\nfix             damping {group} viscous {g}",
                f"{g}*(vx*vx+vy*vy+vz*vz)")
    if kind != "affine":
        raise ValueError(f"drag kind must be one of {DRAG_KINDS}, got {kind!r}")
    text = render("affine_drag", tools=field.tools, affine_vx=field.vx, affine_vy=field.vy,
                  gamma=float(gamma_kg_s), group=group)
    return text, f"{g}*((vx-({field.vx}))*vx+(vy-({field.vy}))*vy+vz*vz)"
