"""The search of :mod:`fabmd.protocols.calibrate`, without LAMMPS: one knob (a strain and
the quantity it sets) moved by secant steps, false position inside a bracket, golden-section
steps towards a turn, the physics' direction across a flat range (:func:`next_strain`);
several coupled knobs by finite-difference columns and Newton/Broyden steps
(:class:`CoupledSearch`). Strains are rest-length strains α·ΔT; quantities are thickness
[m], crimp [%] or yarn tension [N per yarn].
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: the largest shrink or expansion the calibration tries (where no loose crimp bounds it)
STRAIN_LIMIT = 0.4
#: strains are tried on this grid (so that the scene file gets short, exact numbers)
STRAIN_RESOLUTION = 1e-5
#: a turn narrower than this (in strain) is not refined further; a bracket narrower than
#: this is bisected (not false position: the response may be a snap inside it)
MIN_STRAIN_WIDTH = 2e-3
#: a bracket narrower than this is a jump across the target, not refined further. Not
#: 2e-3: the example's cell (drawn 0.621 mm, s/d 0.25) thins 0.774 -> 0.619 mm between
#: -4.43 and -4.59 % of shrink, steeply but continuously (0.697 mm at -4.53 %); 1e-4 of
#: strain moves that by 0.01 mm, about the 1 % tolerance
MIN_JUMP_WIDTH = 1e-4
#: the same for a yarn tension, which follows the fibres' own strain: E·A × 2e-3 is about
#: 4× a 1 cN/tex weaving tension on glass, so a bracket that narrow is no jump — it is
#: refined to a few grid steps (:data:`STRAIN_RESOLUTION`)
MIN_TENSION_STRAIN_WIDTH = 4 * STRAIN_RESOLUTION
#: the Newton step of :class:`CoupledSearch` on loose heights leaves out the directions
#: whose sensitivity is below this fraction of the largest (truncated least squares): in a
#: balanced weave the warp and weft loose heights move both crimps alike, and the small
#: difference the runs measure is mostly the crimp's scatter (±0.03 % on the example)
RCOND = 0.1


@dataclass
class Knob:
    """One scalar unknown: a strain applied to ``families`` and the quantity it sets.

    ``kind``: ``thickness`` [m], ``crimp`` [%] or ``tension`` [N per yarn]; ``sign``: +1
    when the quantity is expected to grow with the strain, −1 when it falls (the first
    step only; the search then follows what it measures). ``acts_on``: ``expansion`` (the
    strain is the families' rest-length strain α·ΔT) or ``loose_height`` (the strain is
    the relative change of the families' loose section height, h = h0·(1 + strain)).
    """

    name: str
    kind: str
    families: tuple[str, ...]
    target: float
    tolerance: float
    sign: int
    bounds: tuple[float, float]
    value: float
    first_step: float = 0.03
    samples: list = field(default_factory=list)  # (strain, quantity, other knobs' strains)
    verdict: str = ""  # "" searching, "reached", or why it stopped
    acts_on: str = "expansion"

    @property
    def min_jump_width(self) -> float:
        """Narrowest bracket refined further [strain]: :data:`MIN_JUMP_WIDTH`,
        :data:`MIN_TENSION_STRAIN_WIDTH` for a tension."""
        return MIN_TENSION_STRAIN_WIDTH if self.kind == "tension" else MIN_JUMP_WIDTH

    @property
    def min_width(self) -> float:
        """Narrowest bracket or turn refined further [strain] (:data:`MIN_STRAIN_WIDTH`,
        :data:`MIN_TENSION_STRAIN_WIDTH` for a tension)."""
        return MIN_TENSION_STRAIN_WIDTH if self.kind == "tension" else MIN_STRAIN_WIDTH

    @property
    def max_step(self) -> float:
        """Largest move of one Newton step (:class:`CoupledSearch`): 0.05 of strain; 0.15
        of a loose height (the crimp moves about a tenth as much per unit of it)."""
        return 0.15 if self.acts_on == "loose_height" else 0.05

    def error(self, q: float) -> float:
        return q - self.target

    def converged(self, q: float) -> bool:
        return abs(self.error(q)) <= self.tolerance

    def text(self, q: float | None) -> str:
        """A quantity in the knob's display unit."""
        if q is None:
            return "–"
        if self.kind == "thickness":
            return f"{1e3 * q:.4g} mm"
        return f"{q:.4g} %" if self.kind == "crimp" else f"{q:.4g} N"

    def describe(self) -> dict:
        return {"name": self.name, "kind": self.kind, "families": list(self.families),
                "acts_on": self.acts_on,
                "target": self.target, "tolerance": self.tolerance,
                "strain_range": list(self.bounds), "verdict": self.verdict,
                "samples": [{"strain": s, "value": q} for s, q, _ in self.samples]}


def next_strain(knob: Knob) -> tuple[float | None, str]:
    """The next strain to try for ``knob`` from its samples, or (None, why) when no strain
    in its range can reach the target (module docstring: bracket, secant, turn).

    The steps, tried in order, each answering where it applies: inside a bracket
    (:func:`_in_bracket`), a first step (:func:`_first_step`), across a flat range
    (:func:`_across_flat`), outwards from an end of the range tried (:func:`_outwards`),
    towards a turn (:func:`_towards_turn`)."""
    seen = Seen.of(knob)
    for step in (_in_bracket, _first_step, _across_flat, _outwards):
        answer = step(seen)
        if answer is not None:
            return answer
    return _towards_turn(seen)


@dataclass
class Seen:
    """What a knob has seen where the other knobs are now: (strain, quantity) sorted by
    strain (a strain tried twice: its latest value), their errors and the best one."""

    knob: Knob
    pts: list[tuple[float, float]]
    err: list[float]
    best: int

    @classmethod
    def of(cls, knob: Knob) -> Seen:
        by_strain: dict[float, float] = {}
        context = knob.samples[-1][2]
        for s, q, c in knob.samples:
            if c == context:  # taken with the other knobs where they are now
                by_strain[s] = q  # a strain tried twice: its latest value
        pts = sorted(by_strain.items())
        err = [knob.error(q) for _, q in pts]
        return cls(knob, pts, err, min(range(len(pts)), key=lambda i: abs(err[i])))

    @property
    def tried(self) -> str:
        what = ("loose-height changes" if self.knob.acts_on == "loose_height"
                else "strains")
        return (f"{what} {self.pts[0][0]:+.4f} to {self.pts[-1][0]:+.4f} tried on "
                f"{'+'.join(self.knob.families)}")

    @property
    def best_text(self) -> str:
        knob, (s, q) = self.knob, self.pts[self.best]
        return (f"closest {knob.text(q)} at {s:+.4f} "
                f"(target {knob.text(knob.target)} ± {knob.text(knob.tolerance)})")

    @property
    def sigma(self) -> int:
        """+1 where the best sample is above the target, −1 where below."""
        return 1 if self.err[self.best] > 0 else -1


def _in_bracket(seen: Seen) -> tuple[float | None, str] | None:
    """Two neighbouring samples on both sides of the target (the pair nearest the best
    that is still wide enough to refine): false position kept inside the bracket, or
    (None, why) where every bracket is narrower than the knob's
    :attr:`Knob.min_jump_width` (the response jumps across the target); a bracket narrower
    than :attr:`Knob.min_width` is bisected. A bracket across which the quantity moves the
    way the knob's ``sign`` says comes first. A jump beside another bracket is passed over:
    the example's cell drawn 0.621 mm at s/d 0.5 thins to 0.628 / 0.640 mm at −5.08 /
    −5.40 % and jumps back to 0.863 mm at −5.59 %; 0.70 mm lies in the jump and between
    −4.43 % (0.810 mm) and −5.08 % (benchmarks/RESULTS.md "The tension search takes the
    root past the snap")."""
    knob, pts, err, best = seen.knob, seen.pts, seen.err, seen.best
    brackets = [i for i in range(len(pts) - 1) if err[i] * err[i + 1] < 0]
    if not brackets:
        return None
    wide = [j for j in brackets if pts[j + 1][0] - pts[j][0] >= knob.min_jump_width]
    # of those, one where the quantity moves the way the physics says (thickness falls
    # with the shrink): the other side of a jump back is not where the target is sought
    usual = [j for j in wide if (pts[j + 1][1] - pts[j][1]) * knob.sign > 0]
    i = min(usual or wide or brackets,
            key=lambda j: min(abs(j - best), abs(j + 1 - best)))
    (s0, q0), (s1, q1) = pts[i], pts[i + 1]
    e0, e1 = err[i], err[i + 1]
    width = s1 - s0
    if width < knob.min_jump_width:
        return None, (f"{knob.name}: the response jumps from {knob.text(q0)} at "
                      f"{s0:+.4f} to {knob.text(q1)} at {s1:+.4f}, across the target "
                      f"{knob.text(knob.target)}: no strain in between reaches it within "
                      f"± {knob.text(knob.tolerance)} ({seen.tried})")
    if width < knob.min_width:  # steep or a snap inside: halve it
        return on_grid(0.5 * (s0 + s1)), ""
    return on_grid(inside_bracket(s0, e0, s1, e1)), ""


def inside_bracket(s0: float, e0: float, s1: float, e1: float) -> float:
    """False position between strain ``s0`` (error ``e0``) and ``s1`` (error ``e1``, of
    the other sign), kept inside the bracket's middle three fifths, so that the bracket
    shrinks by a fifth at least with every run (also where the response is not linear
    inside it: a snap, a slack range)."""
    width = s1 - s0
    new = s0 - e0 * width / (e1 - e0)
    return min(max(new, s0 + 0.2 * width), s1 - 0.2 * width)


def _first_step(seen: Seen) -> tuple[float | None, str] | None:
    """One sample: a first step the way the quantity should move (with the slope from
    before the other knobs moved, where there is one)."""
    if len(seen.pts) != 1:
        return None
    knob, (s_best, q_best), e_best = seen.knob, seen.pts[0], seen.err[0]
    lo, hi = knob.bounds
    step = knob.first_step
    slope = _old_slope(knob)  # from before the other knobs moved, where there is one
    if slope:
        step = min(max(abs(e_best / slope), 10 * STRAIN_RESOLUTION), 0.1)
        direction = -1 if e_best * slope > 0 else 1
    else:
        direction = -seen.sigma * knob.sign
    new = on_grid(min(max(s_best + direction * step, lo), hi))
    if new == s_best:
        return None, (f"{knob.name}: {knob.text(q_best)} at the strain limit "
                      f"{s_best:+.4f} on {'+'.join(knob.families)}, target "
                      f"{knob.text(knob.target)}; widen calibrate.strain_range")
    return new, ""


def _across_flat(seen: Seen) -> tuple[float | None, str] | None:
    """Every sample within the tolerance of the others (slack yarns carry no tension
    whatever their expansion): go the way the physics says, beyond the samples, with a
    step as wide as the range tried."""
    knob, pts = seen.knob, seen.pts
    values = [q for _, q in pts]
    if not max(values) - min(values) < knob.tolerance:
        return None
    prior = -seen.sigma * knob.sign
    edge = pts[0][0] if prior < 0 else pts[-1][0]
    step = min(max(knob.first_step, pts[-1][0] - pts[0][0]), 0.1)
    new = on_grid(min(max(edge + prior * step, knob.bounds[0]), knob.bounds[1]))
    if new == edge:
        return None, (f"{knob.name}: the quantity hardly moves ({knob.text(pts[0][1])} "
                      f"at {pts[0][0]:+.4f}, {knob.text(pts[-1][1])} at "
                      f"{pts[-1][0]:+.4f}) up to the strain limit {edge:+.4f}; "
                      f"{seen.best_text}; widen calibrate.strain_range or change the target")
    return new, ""


def _outwards(seen: Seen) -> tuple[float | None, str] | None:
    """The best sample at an end of the range tried: go on outwards (secant from its
    neighbour, the step limited)."""
    knob, pts, best = seen.knob, seen.pts, seen.best
    if best not in (0, len(pts) - 1):
        return None
    j = 1 if best == 0 else len(pts) - 2
    outward = -1 if best == 0 else 1
    (s_best, q_best), (s_j, q_j) = pts[best], pts[j]
    gap = abs(s_best - s_j)
    slope = (q_best - q_j) / (s_best - s_j)
    step = abs(seen.err[best] / slope) if slope else knob.first_step
    step = min(max(step, 0.25 * gap, STRAIN_RESOLUTION * 10), max(2 * gap, knob.first_step),
               0.1)
    new = on_grid(min(max(s_best + outward * step, knob.bounds[0]), knob.bounds[1]))
    if new == s_best:
        if knob.acts_on == "loose_height":
            limit, why = "lowest" if outward < 0 else "highest", ""
            limit += " loose-height"
            advice = ("change the target (the loose height moves within "
                      f"{knob.bounds[0]:+.2f} … {knob.bounds[1]:+.2f} of the scene's)")
        else:
            limit = "shrink" if outward < 0 else "expansion"
            why = (" (a shrink beyond the loose crimp pulls the yarns straight: not a "
                   "woven state)" if outward < 0 and knob.kind != "tension" else "")
            advice = "widen calibrate.strain_range or change the target"
        return None, (f"{knob.name}: not reached at the {limit} limit {s_best:+.4f}{why}; "
                      f"{seen.best_text}; {seen.tried}, the quantity still moving towards "
                      f"the target ({knob.text(q_j)} at {s_j:+.4f}): {advice}")
    return new, ""


def _towards_turn(seen: Seen) -> tuple[float | None, str]:
    """The best sample inside the range tried: the response turns between its
    neighbours; a golden-section step towards the turning point, or (None, why) once the
    turn is known to the tolerance and misses the target."""
    knob, pts, best = seen.knob, seen.pts, seen.best
    (s_l, q_l), (s_best, q_best), (s_r, q_r) = pts[best - 1], pts[best], pts[best + 1]
    resolved = max(abs(q_l - q_best), abs(q_r - q_best)) < knob.tolerance
    if s_r - s_l < 2 * knob.min_width or resolved:  # the turn known to the tolerance
        way = "lowest" if seen.err[best] > 0 else "highest"  # the turn short of the target
        why = {("thickness", "lowest"): "more shrink makes the fabric thicker again",
               ("thickness", "highest"): "less shrink makes the fabric thinner again"}.get(
            (knob.kind, way), "the response turns there")
        return None, (f"{knob.name}: cannot reach {knob.text(knob.target)}: the {way} value "
                      f"the strain gives is {knob.text(q_best)} at {s_best:+.4f} "
                      f"({knob.text(q_l)} at {s_l:+.4f}, {knob.text(q_r)} at {s_r:+.4f}): "
                      f"{why}; {seen.tried}")
    left, right = s_best - s_l, s_r - s_best
    golden = 0.381966
    new = s_best + golden * right if right >= left else s_best - golden * left
    return on_grid(new), ""


def _old_slope(knob: Knob) -> float | None:
    """d quantity / d strain from the latest two samples of one context (None: none)."""
    for i in range(len(knob.samples) - 1, 0, -1):
        for j in range(i - 1, -1, -1):
            (s1, q1, c1), (s0, q0, c0) = knob.samples[i], knob.samples[j]
            if c1 == c0 and s1 != s0:
                return (q1 - q0) / (s1 - s0) or None
    return None


class CoupledSearch:
    """Several knobs whose quantities all move with every strain (the warp shrink sets the
    thickness, the weft's moves it too): each knob is first moved alone (its first step),
    which measures one column of the sensitivity J = d quantity / d strain (in tolerances
    per unit strain); then Newton steps from the best run, J Δs = −e, at most
    :attr:`Knob.max_step` per knob (0.05 of strain, 0.15 of a loose height),
    halved after a step that made things worse; J is corrected after each step (Broyden).
    Brackets, turns and flat ranges are the one-knob search's (:func:`next_strain`)."""

    def __init__(self, n: int):
        import numpy as np

        self.jac = np.full((n, n), np.nan)
        self.pending: tuple | None = None  # (knob moved alone, strains, errors before)
        self.newton: tuple | None = None   # (strains, errors) the last Newton step left
        self.damping = 1.0
        self.history: list = []  # (strains, errors in tolerances) of every run

    def describe(self, knobs: list[Knob]) -> dict | None:
        if len(knobs) < 2:
            return None
        return {"note": "d quantity / d strain, in tolerances per unit strain (rows: "
                        "quantities, columns: knobs)",
                "knobs": [kn.name for kn in knobs],
                "matrix": [[None if v != v else float(v) for v in row] for row in self.jac]}

    def step(self, knobs: list[Knob]) -> tuple[list[float] | None, str]:
        import numpy as np

        s = np.array([kn.value for kn in knobs])
        e = np.array([kn.error(kn.samples[-1][1]) / kn.tolerance for kn in knobs])
        self.history.append((s, e))
        if self.pending is not None:  # the last run moved knob i alone: column i
            i, s0, e0 = self.pending
            self.jac[:, i] = (e - e0) / (s[i] - s0[i])
            self.pending = None
        if self.newton is not None:  # Broyden: J Δs must give the Δe measured
            s0, e0 = self.newton
            ds, de = s - s0, e - e0
            if ds @ ds > 0:
                self.jac += np.outer(de - self.jac @ ds, ds) / (ds @ ds)
            self.newton = None
        missing = [i for i in range(len(knobs)) if np.isnan(self.jac[0, i])]
        if missing:
            i = missing[0]
            knob = knobs[i]
            direction = -1 if e[i] * knob.sign > 0 else 1
            lo, hi = knob.bounds
            new = s.copy()
            new[i] = on_grid(min(max(s[i] + direction * knob.first_step, lo), hi))
            if new[i] == s[i]:
                new[i] = on_grid(min(max(s[i] - direction * knob.first_step, lo), hi))
            self.pending = (i, s, e)
            return [float(v) for v in new], ""
        best = min(range(len(self.history)), key=lambda k: np.abs(self.history[k][1]).max())
        s_best, e_best = self.history[best]
        self.damping = 1.0 if best == len(self.history) - 1 else 0.5 * self.damping
        # loose heights only: directions the runs hardly resolve (two heights that move
        # both crimps alike) are not stepped along (strains with quantities in other units
        # keep every direction: a stiff tension beside a thickness is no scatter)
        rcond = RCOND if all(kn.acts_on == "loose_height" for kn in knobs) else None
        ds, *_ = np.linalg.lstsq(self.jac, -e_best, rcond=rcond)
        caps = np.array([kn.max_step for kn in knobs])
        ds *= self.damping * min(1.0, float((caps / np.maximum(np.abs(ds), 1e-12)).min()))
        new = np.array([on_grid(min(max(s_best[k] + ds[k], kn.bounds[0]), kn.bounds[1]))
                        for k, kn in enumerate(knobs)])
        if np.abs(new - s_best).max() < 10 * STRAIN_RESOLUTION or self.damping < 1 / 16:
            names = ", ".join(f"{kn.name} {kn.text(kn.target + e_best[k] * kn.tolerance)}"
                              for k, kn in enumerate(knobs))
            stuck = ("no longer improves" if self.damping < 1 / 16
                     else "leaves the strain range")
            return None, (f"the coupled targets ({', '.join(kn.name for kn in knobs)}) "
                          f"cannot be met together from strains "
                          f"{', '.join(f'{v:+.4f}' for v in s_best)}: closest {names}; the "
                          f"Newton step {stuck} (sensitivities in calibration.json)")
        self.newton = (s_best, e_best)
        return [float(v) for v in new], ""


def on_grid(strain: float) -> float:
    """``strain`` rounded to :data:`STRAIN_RESOLUTION`."""
    return round(round(strain / STRAIN_RESOLUTION) * STRAIN_RESOLUTION, 10)
