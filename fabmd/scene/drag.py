"""Numerical drag of a driven test: on the velocity relative to the tools' affine field.

A driven test's clamps or frame carry the fabric at up to the loading speed. A drag on
the beads' absolute velocity (``fix viscous``) then pulls against that motion and the
power balance counts it as fabric force (issue 16: 88 % of a picture frame's force at
10° was drag, and it changed with the damping time).

``"affine"`` (the default) damps only the motion relative to the affine velocity field
the tools impose on the fabric between them, f = −γ·(v − v_affine)
(``lammps_templates/affine_drag.lmp``): a fabric that follows the tools feels no drag,
its own vibrations and non-affine slips are damped. ``"absolute"`` keeps the old
``fix viscous`` (f = −γ·v), for comparison.

Either way the drag's power on the free beads, −f·v [W], is what the energy balance
counts as damping dissipation: γ·(v − v_affine)·v summed over the free beads
(:func:`damping_power`).

Per-step cost (issue 20): LAMMPS evaluates an atom-style variable's formula node by node
for every bead on every step, which made these per-bead formulas most of a tension run's
time. The field is therefore kept as an origin and a velocity gradient whose entries are
equal-style expressions (evaluated once a step): −γ·v is ``fix viscous``, +γ·v_affine an
``addforce`` of a few multiply-adds per bead, and the damping power
γ·(Σ|v|² − Σ v_affine·v) is built from sums LAMMPS forms itself (``reduce sumsq``, ``sum``)
plus one product per non-zero gradient entry.
"""

from __future__ import annotations

from dataclasses import dataclass

from .templates import fmt, render, render_inline

DRAG_KINDS = ("affine", "absolute")
_AXES = ("x", "y")


@dataclass(frozen=True)
class AffineField:
    """The tools' in-plane velocity field, affine in the position [m/s]:

        v_affine = L · (r − r0),  r = (x, y),  L = [[xx, xy], [yx, yy]],

    Args:
        origin_m: r0 = (x0, y0), a point the field leaves at rest [m].
        xx, xy, yx, yy: the entries of the velocity gradient L [1/s], as LAMMPS
            equal-style expressions (may use variables the test defines; ``"0"``: none).
        tools: what imposes it, for the comment in the input ("frame", "clamps").
    """

    origin_m: tuple[float, float]
    tools: str
    xx: str = "0"
    xy: str = "0"
    yx: str = "0"
    yy: str = "0"

    def gradient(self) -> dict[str, str]:
        """The non-zero entries of L by name (``"xx"``: ∂v_x/∂x, ``"xy"``: ∂v_x/∂y, …)."""
        return {k: e for k in ("xx", "xy", "yx", "yy") if (e := getattr(self, k)) != "0"}

    def component(self, axis: str) -> str:
        """v_affine along ``axis`` ("x" or "y") written out as one LAMMPS expression."""
        terms = [f"({e})*{self.offset(k[1])}" for k, e in self.gradient().items()
                 if k[0] == axis]
        return "+".join(terms) or "0"

    def origin(self, axis: str) -> str:
        """r0 along ``axis`` as LAMMPS text [m]."""
        return fmt(float(self.origin_m[_AXES.index(axis)]))

    def offset(self, axis: str) -> str:
        """(r − r0) along ``axis`` as a LAMMPS per-atom expression [m]."""
        return f"({axis}-({self.origin(axis)}))"

    @property
    def vx(self) -> str:
        return self.component("x")

    @property
    def vy(self) -> str:
        return self.component("y")


def drag_commands(kind: str, group: str, gamma_kg_s: float,
                  field: AffineField) -> tuple[str, str]:
    """(LAMMPS text, LAMMPS text of the drag's power ``v_p_damp``) on ``group``; γ [kg/s].

    The power block defines the equal-style ``v_p_damp``, the drag's dissipation
    −f·v summed over ``group`` [W] (:func:`damping_power`), for ``driven_outputs.lmp``.
    """
    if kind == "absolute":
        return (render("absolute_drag", group=group, gamma=float(gamma_kg_s)),
                damping_power(group, gamma_kg_s))
    if kind != "affine":
        raise ValueError(f"drag kind must be one of {DRAG_KINDS}, got {kind!r}")
    g = float(gamma_kg_s)
    grad = field.gradient()
    coefficients = "\n".join(render_inline("affine_drag_coefficient", component=k, gamma=g,
                                           gradient=e) for k, e in grad.items())
    forces = []
    for axis in _AXES:
        terms = [f"v_drag_k{k}*{field.offset(k[1])}" for k in grad if k[0] == axis]
        if terms:
            forces.append(render_inline("affine_drag_force", axis=axis,
                                        expression="+".join(terms)))
    refs = {axis: name or "0.0" for axis, name in affine_force_names(field).items()}
    text = render("affine_drag", tools=field.tools, affine_vx=field.vx, affine_vy=field.vy,
                  gamma=g, group=group, coefficients=coefficients or "# (no gradient)",
                  forces="\n".join(forces) or "# (no affine force)", fx=refs["x"],
                  fy=refs["y"])
    return text, damping_power(group, gamma_kg_s, field)


def affine_force_names(field: AffineField) -> dict[str, str]:
    """Per axis ("x", "y"): the atom variable holding the affine drag's +γ·v_affine
    (``affine_drag_force.lmp``), or "" where the field has no gradient along it."""
    rows = {k[0] for k in field.gradient()}
    return {axis: f"v_drag_f{axis}" if axis in rows else "" for axis in _AXES}


def damping_power(group: str, gamma_kg_s: float, field: AffineField | None = None) -> str:
    """LAMMPS text defining ``v_p_damp``: the power a drag −γ·(v − v_affine) takes from
    ``group`` [W], γ·(Σ|v|² − Σ v_affine·v) (``field`` None: the absolute drag −γ·v).

    Σ v_affine·v = Σ_ij L_ij (Σ r_j v_i − r0_j Σ v_i): one per-bead product r_j·v_i per
    non-zero entry of L, the rest from LAMMPS's own sums.
    """
    grad = field.gradient() if field is not None else {}
    if not grad:
        return render("damping_power", group=group, gamma=float(gamma_kg_s),
                      moments="# (no affine field)", affine="")
    products, affine = [], []
    sums = {"x": "c_damp_moments[1]", "y": "c_damp_moments[2]"}
    for n, (k, e) in enumerate(grad.items()):
        products.append(render_inline("damping_product", name=k, expression=f"{k[1]}*v{k[0]}"))
        affine.append(f"-({e})*(c_damp_moments[{n + 3}]-({field.origin(k[1])})*{sums[k[0]]})")
    moments = render_inline("damping_moments", group=group, products="\n".join(products),
                            product_refs=" ".join(f"v_damp_{k}" for k in grad))
    return render("damping_power", group=group, gamma=float(gamma_kg_s), moments=moments,
                  affine="".join(affine))
