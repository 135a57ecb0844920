"""Adaptive quasi-static loading: the boundary speed follows the quasi-static measures.

A driven test at a fixed speed spends most of its steps where the fabric is quiet. With
``AdaptiveLoading(adaptive=True)`` the speed of the driven boundary becomes
``v = v0 · ramp(t) · f``: ``v0`` the plan's (base) speed and smooth start, ``f`` a factor
in [``min_speed_factor``, ``max_speed_factor``] that LAMMPS itself adjusts, so the run
folder stays runnable with plain ``mpirun -np N lmp -in`` (no Python between chunks, no
``jump`` loop). Take as the base the fixed speed at which the curve is converged in speed
(the test at it and at half of it agree): where the curve is rate-sensitive the run stays
near it, where it is not the run goes faster.

* every control interval (``control_interval`` output intervals, at least
  ``control_transits`` wave transits of the specimen) ``fix ave/time`` averages the power
  the boundary puts in and the drag's power;
* the event signal is the **drag's share of the work** in the interval: at a given drag it
  is linear in the speed (the drag force of the non-affine motion grows with the speed, its
  power with its square, the boundary's power with the speed) and about the share of the
  boundary force the speed adds, so holding it at ``target`` holds that error. The work
  is taken at least as a floor force times the current speed (a slack fabric takes almost
  no work; its drag is weighed against the floor force). The share is the larger of the
  last interval's and its mean over the drag time τ (``damping_time_s``): a fabric the
  drag held back (the slack toe of a tension test) lags its quasi-static curve until
  about τ has passed (measured: without this memory the 7-fibre tension sped up at the
  end of its toe and its force at 4 % came out 10 % high). KE/U (of the per-interval
  verdict, :data:`fabmd.scene.quasi_static.INTERVAL_LIMITS`) is kept under
  ``max_kinetic_ratio``; the kinetic energy's share of the work is not used (in an
  adaptive run it is mostly the controller's own speed changes: the fabric moving with the
  boundary);
* ``busy`` is the largest of them over what it may be; an integral controller (``fix
  controller``) moves ln f by ``-gain·ln(busy)`` each interval, at most by
  ln ``max_speed_step`` up and twice that down (a ramp limit: a short control interval and
  free steps made the speed oscillate); held during the smooth start, and the part of
  ln f outside its bounds is taken back at once (no wind-up);
* the factor applied follows the controller's with a first-order lag of one control
  interval (a second ``fix controller`` every step), so the speed never jumps: a speed
  jump sends a stress wave through the coupon;
* the boundary moves by integrating the speed (``fix move variable NULL ... v_v``); its
  displacement is read back from the clamps' centres of mass, and a ``fix halt`` ends the
  run on the first output step at or past the travel.

The plan (:func:`adaptive_plan`) keeps the fixed-speed plan's time step, drag and base
speed and shortens its smooth start to ``start_fraction`` of it (the start moves the
slack toe, not the report points past it: benchmarks/RESULTS.md "Adaptive loading"),
takes an output interval ``max_speed_factor`` times shorter, at most
:data:`OUTPUT_SPEEDUP` times (about ``samples`` curve points up to that speed; the curve's
forces are averaged over the fixed run's interval travel, :func:`window_mean`, so that it
is as smooth) and runs at most the fixed run's steps over ``min_speed_factor``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError
from .energy import mean_sample_every
from .plan import RunPlan
from .quasi_static import INTERVAL_LIMITS
from .templates import fmt, render

#: largest boundary speed over the fibres' wave speed any driven test may reach (the limit
#: of ``speed_fraction``)
MAX_SPEED_FRACTION = 0.05
#: the output interval is at most this many times shorter than the fixed run's (above
#: it the faster parts get fewer curve points: each output costs a print and an energy sum)
OUTPUT_SPEEDUP = 8


@dataclass(frozen=True)
class AdaptiveLoading:
    """Opt-in adaptive loading speed (see the module docstring).

    Args:
        adaptive: adapt the speed (default False: the fixed speed of ``speed_fraction``).
        max_speed_factor: the fastest speed over the base speed (``speed_fraction``), in
            [1, 100]; ``speed_fraction`` × it may not exceed 0.05 of the wave speed.
        min_speed_factor: the slowest speed over the base speed, in [0.1, 1] (below 1:
            the run may go slower than the base at events).
        target: the drag's share of the work held per control interval, in (0, 0.1]
            (about the share of the boundary force the speed may add).
        gain: change of ln(speed factor) per control interval per unit of
            ln(measure / what it may be), in (0, 1].
        max_speed_step: largest rise of the speed factor over one control interval (a
            ratio, in (1, 4]; a fall may be twice as steep in ln).
        max_kinetic_ratio: kinetic over strain energy (with a floor) held under this, in
            (0, 0.1] (the per-interval verdict's limit is 0.1).
        start_fraction: the smooth start's length over the fixed-speed run's, in (0, 1]
            (its travel is spent at or below the base speed).
        floor_force_n: the boundary force [N] below which the drag is weighed against this
            force instead (> 0; default None: the protocol's, one fibre at a tenth of the
            test's strain): about the smallest force whose error matters.
        control_interval: fewest output intervals per control interval (>= 1).
        control_transits: fewest axial wave transits of the specimen per control interval
            (>= 1): the measures of a shorter one answer the controller's own last
            speed change (a control interval under one transit made the picture-frame
            speed oscillate between 1x and 2x and moved its forces by 10-60 %).
    """

    adaptive: bool = False
    max_speed_factor: float = 8.0
    min_speed_factor: float = 1.0
    target: float = 0.05
    gain: float = 0.5
    max_speed_step: float = 2.0
    max_kinetic_ratio: float = 0.02
    start_fraction: float = 0.25
    floor_force_n: float | None = None
    control_interval: int = 4
    control_transits: float = 2.0

    def __post_init__(self):
        if not isinstance(self.adaptive, bool):
            raise InputError(f"loading_speed.adaptive must be true or false, got "
                             f"{self.adaptive!r}")
        inputs.in_range("loading_speed.max_speed_factor", self.max_speed_factor, 1.0, 100.0)
        inputs.in_range("loading_speed.min_speed_factor", self.min_speed_factor, 0.1, 1.0)
        inputs.in_range("loading_speed.target", self.target, 0.0, 0.1, low_open=True)
        inputs.in_range("loading_speed.gain", self.gain, 0.0, 1.0, low_open=True)
        inputs.in_range("loading_speed.max_speed_step", self.max_speed_step, 1.0, 4.0,
                        low_open=True)
        inputs.in_range("loading_speed.max_kinetic_ratio", self.max_kinetic_ratio, 0.0,
                        INTERVAL_LIMITS["kinetic_to_strain_energy"], low_open=True)
        inputs.in_range("loading_speed.start_fraction", self.start_fraction, 0.0, 1.0,
                        low_open=True)
        if self.floor_force_n is not None:
            inputs.positive("loading_speed.floor_force_n", self.floor_force_n)
        inputs.positive_int("loading_speed.control_interval", self.control_interval)
        inputs.in_range("loading_speed.control_transits", self.control_transits, 1.0, 1000.0)

    def check_speed(self, section: str, speed_fraction: float) -> None:
        """The fastest speed stays within :data:`MAX_SPEED_FRACTION` of the wave speed."""
        if self.adaptive and speed_fraction * self.max_speed_factor > MAX_SPEED_FRACTION \
                * (1 + 1e-12):
            raise InputError(
                f"{section}.loading_speed.max_speed_factor = {self.max_speed_factor:g} with "
                f"speed_fraction = {speed_fraction:g} would load at "
                f"{speed_fraction * self.max_speed_factor:g} of the wave speed; at most "
                f"{MAX_SPEED_FRACTION:g} (max_speed_factor <= "
                f"{MAX_SPEED_FRACTION / speed_fraction:g})")


def adaptive_plan(plan: RunPlan, loading: AdaptiveLoading, travel_m: float,
                  transit_s: float = 0.0, every_multiple: int = 1) -> RunPlan:
    """The fixed-speed ``plan`` made adaptive (see the module docstring); unchanged when
    ``loading`` is not adaptive. ``transit_s``: the axial wave transit time of the
    specimen [s] (its length over the fibres' wave speed); ``every_multiple``: the output
    interval is a multiple of it (a protocol that samples its means every n steps).
    ``extra`` keeps the fixed run's steps and output interval, the travel and the control
    settings."""
    if not loading.adaptive:
        return plan
    k = loading.max_speed_factor
    n = every_multiple
    every = n * max(1, int(plan.every // min(k, OUTPUT_SPEEDUP)) // n)
    steps = every * math.ceil(plan.steps / loading.min_speed_factor / every)
    transits = math.ceil(loading.control_transits * transit_s / (every * plan.time_step_s)
                         - 1e-9)  # not one more for a rounding error
    extra = {**plan.extra, "adaptive": True, "max_speed_factor": k,
             "min_speed_factor": loading.min_speed_factor,
             "target": loading.target, "gain": loading.gain,
             "max_speed_step": loading.max_speed_step,
             "max_kinetic_ratio": loading.max_kinetic_ratio,
             "floor_force_n": loading.floor_force_n,
             "control_interval_steps": every * max(loading.control_interval, transits),
             "transit_s": transit_s,
             "travel_m": travel_m, "fixed_speed_steps": plan.steps,
             "fixed_speed_every": plan.every}
    return dataclasses.replace(plan, every=every, steps=steps, extra=extra,
                               ramp_time_s=plan.ramp_time_s * loading.start_fraction)


def speed_commands(plan: RunPlan, external_ref: str, energy_floor_j: float,
                   power_floor_w: float, displacement: str = "u",
                   kinetic: tuple[str, str] | None = None,
                   memory_s: float | None = None,
                   gate: tuple[str, str] | None = None) -> str:
    """The LAMMPS text of the adaptive speed (``lammps_templates/adaptive_speed.lmp``):
    it defines ``v_adapt_factor`` (the speed factor) and the halt at the travel; put it
    after the driven outputs (it reads ``external_ref``, ``v_p_damp``, ``c_ke_free``,
    ``v_ebond``) and make the protocol's speed ``base formula * v_adapt_factor``, its
    displacement ``v_u`` (read back from the boundary) and its time ``v_t``.

    Args:
        energy_floor_j: strain energy below which KE/U is taken against this floor (a
            slack fabric has almost none).
        power_floor_w: boundary power at the base speed below which the work shares are
            taken against it (times the speed factor); ``floor_force_n`` × the base speed
            where the loading sets it.
        displacement: the variable (without ``v_``) of the boundary's travel [m].
        kinetic: (LAMMPS formula, what it is) of the kinetic measure held under
            ``max_kinetic_ratio``; default KE/U with the energy floor (a drape, whose
            fabric rides on the punch with a kinetic energy far above its strain energy,
            gives its inertial force over the punch force instead).
        memory_s: the time over which the drag's share is also averaged [s]; default the
            drag time τ (a fabric the drag held back lags for about τ).
        gate: (LAMMPS variable, what it is) that is 1 where the speed may rise above its
            base and 0 where it may not (the upper bound of ln(factor) is ln
            ``max_speed_factor`` times it; a drape's punch keeps its base speed until it
            carries force: faster in its free travel, it would reach the blank moving).
    """
    x = plan.extra
    interval = x["control_interval_steps"]
    gain = x["gain"]
    sample = mean_sample_every(interval)  # as the outputs' interval means
    ln_up = math.log(x["max_speed_step"])
    if x.get("floor_force_n"):
        power_floor_w = x["floor_force_n"] * plan.speed_m_s
    memory = max(1, math.ceil((memory_s or plan.damping_time_s) / (interval * plan.time_step_s)
                              - 1e-9))
    ln_max = fmt(math.log(x["max_speed_factor"]))
    return render("adaptive_speed", interval=interval, every=plan.every, memory=memory,
                  ln_cap=f"{ln_max}*{gate[0]}" if gate else ln_max,
                  ln_cap_why=f"ln {x['max_speed_factor']:g}" + (f", times {gate[1]}" if gate
                                                               else ""),
                  max_factor=x["max_speed_factor"],
                  ln_min=math.log(x["min_speed_factor"]), min_factor=x["min_speed_factor"],
                  sample_every=sample, samples=interval // sample,
                  external_ref=external_ref, power_floor=power_floor_w,
                  kinetic=kinetic[0] if kinetic else f"c_ke_free/(v_ebond+{fmt(energy_floor_j)})",
                  kinetic_name=kinetic[1] if kinetic else "KE/U",
                  kinetic_limit=x["max_kinetic_ratio"],
                  target=x["target"], ramp_time=plan.ramp_time_s, gain=gain,
                  ln_up=f"{ln_up:.4g}", ln_down=f"{2 * ln_up:.4g}",
                  step_up=-ln_up / gain, step_down=2 * ln_up / gain,
                  alpha=gain / (interval * plan.time_step_s),
                  lag_alpha=1.0 / (interval * plan.time_step_s), travel=x["travel_m"],
                  displacement=displacement)


def adaptive_summary(plan: RunPlan, steps, time_s, speed_m_s) -> dict:
    """What an adaptive run did (``{}`` for a fixed-speed one): the loading steps it took
    against the fixed-speed run's and its speed over the base speed (``steps``,
    ``time_s``, ``speed_m_s``: the curve's samples)."""
    if not plan.extra.get("adaptive"):
        return {}
    taken = int(steps[-1] - steps[0])
    factor = np.asarray(speed_m_s, float) / plan.speed_m_s
    after = np.asarray(time_s, float) > plan.ramp_time_s
    return {"adaptive_loading": {
        "steps": taken, "fixed_speed_steps": plan.extra["fixed_speed_steps"],
        "step_ratio": plan.extra["fixed_speed_steps"] / max(taken, 1),
        "max_speed_factor": float(factor.max()),
        "min_speed_factor_after_start": float(factor[after].min()) if after.any() else None,
        "mean_speed_factor_after_start": float(factor[after].mean()) if after.any() else None,
        "allowed_speed_factor": plan.extra["max_speed_factor"],
        "note": "speed factor: boundary speed over the base speed (speed_fraction x wave "
                "speed); steps: of the loading, the fixed-speed run's from its plan"}}


def window_width_m(plan: RunPlan) -> float | None:
    """Travel of the driven boundary over one output interval of the fixed-speed run [m]
    (None for a fixed-speed plan): an adaptive run's interval means are averaged over it
    (:func:`window_mean`), so that its curve is as smooth as the fixed run's."""
    x = plan.extra
    if not x.get("adaptive"):
        return None
    return x["travel_m"] * x["fixed_speed_every"] / x["fixed_speed_steps"]


def window_mean(displacement, values, width: float) -> np.ndarray:
    """Each sample's mean of ``values`` over the travel ``width`` before it.

    ``values[i]`` is the mean over the interval that ends at sample ``i`` (from sample
    ``i-1``: the interval means of ``means.dat``), so the integral of the values over the
    travel is piecewise linear in it; each sample gets that integral over
    [d_i - width, d_i] divided by the travel it spans (less at the start).
    """
    d = np.asarray(displacement, float)
    y = np.asarray(values, float)
    step = np.diff(d, prepend=d[0])
    integral = np.cumsum(y * step)
    start = np.maximum(d - width, d[0])
    span = d - start
    inside = np.interp(start, d, integral)
    out = y.copy()
    moving = span > 0
    out[moving] = (integral[moving] - inside[moving]) / span[moving]
    return out
