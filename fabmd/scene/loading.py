"""Loads and schedules as small objects rendered to LAMMPS formulas.

Each schedule knows its value as a function of time in Python (for checks and
post-processing) and as a LAMMPS equal-style formula of a time variable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from .templates import fmt


@dataclass(frozen=True)
class SmoothStartSpeed:
    """Constant speed reached smoothly: v(t) = v0·(1 − cos(π t/t_r))/2 for t < t_r.

    A sudden start sends a stress wave of amplitude E·A·v/c through a fibre;
    the smooth start over several wave-transit times keeps it small.

    Args:
        speed_m_s: final speed v0 [m/s] (> 0).
        ramp_time_s: time to reach it, t_r [s] (>= 0; 0 is a sudden start).
    """

    speed_m_s: float
    ramp_time_s: float

    def __post_init__(self):
        inputs.positive("loading.speed_m_s", self.speed_m_s)
        inputs.non_negative("loading.ramp_time_s", self.ramp_time_s)

    def displacement(self, t):
        """Displacement [m] at time(s) t [s]."""
        t = np.asarray(t, float)
        v0, tr = self.speed_m_s, self.ramp_time_s
        if tr == 0:
            return v0 * t
        early = v0 * (t / 2 - tr / (2 * math.pi) * np.sin(math.pi * t / tr))
        return np.where(t < tr, early, v0 * (t - tr / 2))

    def time_for(self, displacement_m: float) -> float:
        """Time [s] at which the displacement reaches ``displacement_m`` (past the ramp)."""
        v0, tr = self.speed_m_s, self.ramp_time_s
        t = displacement_m / v0 + tr / 2
        if t < tr:  # inside the ramp: solve numerically
            ts = np.linspace(0, tr, 20001)
            return float(np.interp(displacement_m, self.displacement(ts), ts))
        return t

    def lammps_displacement(self, t: str = "t") -> str:
        v0, tr = fmt(self.speed_m_s), fmt(self.ramp_time_s)
        if self.ramp_time_s == 0:
            return f"{v0}*v_{t}"
        return (f"(v_{t}<{tr})*{v0}*(v_{t}/2-{tr}/(2*PI)*sin(PI*v_{t}/{tr}))"
                f"+(v_{t}>={tr})*{v0}*(v_{t}-{tr}/2)")

    def lammps_ramp(self, t: str = "t") -> str:
        """The smooth-start factor v(t)/v0, from 0 to 1 over the ramp: a load ramped up the
        same way is its final value times this formula."""
        if self.ramp_time_s == 0:
            return "1.0"
        tr = fmt(self.ramp_time_s)
        return f"((v_{t}<{tr})*(1-cos(PI*v_{t}/{tr}))/2+(v_{t}>={tr}))"

    def lammps_velocity(self, t: str = "t") -> str:
        v0, tr = fmt(self.speed_m_s), fmt(self.ramp_time_s)
        if self.ramp_time_s == 0:
            return v0
        return f"(v_{t}<{tr})*{v0}*(1-cos(PI*v_{t}/{tr}))/2+(v_{t}>={tr})*{v0}"
