"""Sliding: a fibre pulled across another under a normal load, F_t/F_n = μ.

Two virtual fibres cross at right angles: the *track* lies along x and is held
still; the *slider* lies along y on top of it, is pressed down by a normal load
F_n (spread by ``fix aveforce`` so that it moves up and down as one piece) and
is moved along x at a slow constant speed, so that the crossing slides along
the track over its beads. The forces on the held track are the contact forces:
F_t = Σ f_x, F_n = −Σ f_z.

Coulomb friction gives F_t/F_n = μ on a smooth fibre. Bead chains are bumpy:
the contact normal tilts as the slider rides over each bead, so F_t/F_n ripples
with the bead period and its mean over whole periods exceeds μ slightly; both
grow with the spacing ratio s/d (``benchmarks/ripple.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import inputs
from ..engine import mpi
from ..model.bead_model import BeadModel, BondType, Yarn
from ..model.beads import Discretisation, TimeStep
from ..model.contact import ContactModel
from ..model.material import VirtualFibre
from ..results.folder import read_print_file
from ..results.plots import plot_curves
from ..scene import blocks
from ..scene.loading import SmoothStartSpeed
from ..scene.templates import render
from .common import DATA_FILE, RunResult, overlap_summary
from .single_fibre import SingleFibreCheck, default_fibre, load_ramp

PROTOCOL = "sliding"
#: beads of the slider (odd: one bead sits on the crossing)
SLIDER_BEADS = 7
#: output samples per bead period (the ripple must be resolved)
SAMPLES_PER_PERIOD = 40


@dataclass(frozen=True)
class Sliding(SingleFibreCheck):
    """A fibre pulled across another under a normal load.

    Args:
        fibre: both virtual fibres (default 0.1 mm E-glass).
        contact: fibre–fibre contact (its μ is the expected F_t/F_n).
        load_strain: normal load F_n as a fraction of the fibre's E·A, in (0, 0.01].
        periods: bead periods l0 slid at constant speed and averaged over (>= 1).
        speed_fraction: slide speed in bead periods per period of the slider's
            vertical vibration on the contact spring, in (0, 0.5]; quasi-static when small.
        ramp_periods: load ramp and speed ramp, each in vertical vibration periods (>= 0).
        discretisation: bead spacing (the ripple grows with it), mass scaling, bending.
        time_step: time-step policy.
    """

    fibre: VirtualFibre = field(default_factory=default_fibre)
    contact: ContactModel = field(default_factory=ContactModel)
    load_strain: float = 1e-3
    periods: int = 4
    speed_fraction: float = 0.02
    ramp_periods: float = 5.0
    discretisation: Discretisation = field(default_factory=Discretisation)
    time_step: TimeStep = field(default_factory=TimeStep)

    protocol: ClassVar[str] = PROTOCOL

    def __post_init__(self):
        inputs.in_range("sliding.load_strain", self.load_strain, 0.0, 0.01, low_open=True)
        object.__setattr__(self, "periods", inputs.positive_int("sliding.periods",
                                                                self.periods))
        inputs.in_range("sliding.speed_fraction", self.speed_fraction, 0.0, 0.5,
                        low_open=True)
        inputs.non_negative("sliding.ramp_periods", self.ramp_periods)
        _ = self.time_step_s  # validates an explicit time step against the stable one

    # -- derived ----------------------------------------------------------------------
    def plan_contacts(self) -> tuple:
        return (self.contact,)

    @property
    def normal_load_n(self) -> float:
        return self.load_strain * self.fibre.axial_stiffness_n

    @property
    def vibration_period_s(self) -> float:
        """Period of the slider bouncing on one contact spring, 2π·sqrt(M/k_n)."""
        b = self.beads
        kn = self.contact.normal_stiffness_n_per_m([b])
        return 2 * math.pi * math.sqrt(SLIDER_BEADS * b.mass_kg / kn)

    @property
    def ramp_time_s(self) -> float:
        return self.ramp_periods * self.vibration_period_s

    @property
    def loading(self) -> SmoothStartSpeed:
        l0 = self.beads.bond_length_m
        return SmoothStartSpeed(self.speed_fraction * l0 / self.vibration_period_s,
                                self.ramp_time_s)

    @property
    def window_m(self) -> tuple[float, float]:
        """Slide distance range averaged over: whole bead periods at constant speed."""
        l0 = self.beads.bond_length_m
        start = float(self.loading.displacement(self.ramp_time_s)) + l0  # one period to settle
        return start, start + self.periods * l0

    @property
    def duration_s(self) -> float:
        return self.ramp_time_s + self.loading.time_for(self.window_m[1])

    @property
    def output_every(self) -> int:
        period_steps = self.beads.bond_length_m / self.loading.speed_m_s / self.time_step_s
        return max(1, int(period_steps / SAMPLES_PER_PERIOD))

    def model(self) -> BeadModel:
        """Track along x (fibre 1, beads on both sides of the slide), slider along y on top."""
        b = self.beads
        l0, d = b.bond_length_m, b.diameter_m
        reach = self.window_m[1] + 3 * d
        n_track = int(math.ceil((reach + 3 * d) / l0)) + 1
        track_x = -3 * d + l0 * np.arange(n_track)
        track_x -= track_x[np.argmin(np.abs(track_x))]  # a track bead under the slider
        track = np.column_stack([track_x, np.zeros(n_track), np.zeros(n_track)])
        half = SLIDER_BEADS // 2
        slider = np.column_stack([np.zeros(SLIDER_BEADS), l0 * np.arange(-half, half + 1),
                                  np.full(SLIDER_BEADS, d)])
        pos = np.vstack([track, slider])
        fibre_ids = np.r_[np.ones(n_track, np.int64), np.full(SLIDER_BEADS, 2)]
        bonds = np.vstack([np.column_stack([np.arange(n_track - 1), np.arange(1, n_track)]),
                           n_track + np.column_stack([np.arange(SLIDER_BEADS - 1),
                                                      np.arange(1, SLIDER_BEADS)])])
        pad = 4 * d
        lo = pos.min(axis=0) - pad
        hi = pos.max(axis=0) + pad
        return BeadModel(
            positions=pos, diameters=d, masses=b.mass_kg, atom_types=1, fibre_ids=fibre_ids,
            bonds=bonds, bond_types=1, family_names=("fibre",),
            bond_type_table=[BondType(b.bond_coefficient, l0, "fibre", b.axial_stiffness_n)],
            fibre_yarn=[1, 2], yarns=[Yarn("track", "fibre"), Yarn("slider", "fibre")],
            box_lo=lo, box_hi=hi, info={"protocol": PROTOCOL})

    def input_text(self, model: BeadModel) -> str:
        dt = self.time_step_s
        every = self.output_every
        load = self.loading
        tr = self.ramp_time_s
        beads = [self.beads]
        ramp = load_ramp(tr)
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            render("sliding", load_ramp=ramp, load_each=self.normal_load_n / SLIDER_BEADS,
                   ramp_time=tr, displacement=load.lammps_displacement("tp"),
                   velocity=load.lammps_velocity("tp"), every=every,
                   thermo_every=max(every, self.steps // 20)),
            blocks.guards(model, dt),
            blocks.overlap_monitor(model, self.contact, beads, every=max(every, 100)),
            render("run", steps=self.steps),
            render("finish", final_data="final.data"),
        ])

    def reduce(self, run_dir: Path, model: BeadModel) -> SlidingResult:
        return reduce(run_dir, self)


class SlidingResult(RunResult):
    """Curve and summary of a sliding run."""

    def plot(self) -> None:
        c, s = self.curve, self.summary
        x = c["displacement_m"] / s["bond_length_m"]
        plot_curves(self.run_dir / "curve.png", [
            {"x": x, "y": c["friction_ratio"], "label": "F_t / F_n"},
            {"x": x, "y": np.full_like(x, s["mu"]), "label": "μ", "style": ":"},
        ], "slide distance [bead spacings]", "F_t / F_n [–]",
            title=f"Fibre sliding across a fibre, s/d = {s['spacing_ratio']:g}",
            notes=f"mean {s['measured_ratio']:.4f} (μ = {s['mu']:g})\n"
                  f"ripple {s['ratio_min']:.3f} .. {s['ratio_max']:.3f}")


def reduce(run_dir: Path, test: Sliding) -> SlidingResult:
    """Read ``curve.dat``; mean and ripple of F_t/F_n over whole bead periods."""
    if not mpi.is_root():
        return SlidingResult(Path(run_dir), {}, {})
    raw = read_print_file(Path(run_dir) / "curve.dat")
    u, ft, fn = raw["displacement_m"], raw["ft_n"], raw["fn_n"]
    ratio = np.divide(ft, fn, out=np.zeros_like(ft), where=fn > 0)
    lo, hi = test.window_m
    # ave/time values at step k average the interval before it: centre them
    centre = u - 0.5 * test.loading.speed_m_s * test.output_every * test.time_step_s
    steady = (centre >= lo) & (centre <= hi)
    mean_ratio = float(np.mean(ft[steady]) / np.mean(fn[steady]))
    mu = test.contact.friction
    r = ratio[steady]
    summary = {
        "protocol": PROTOCOL,
        "mu": mu,
        "spacing_ratio": test.discretisation.spacing_ratio,
        "normal": test.contact.normal,
        "pair_style": test.contact.pair_style(),
        "bond_length_m": test.beads.bond_length_m,
        "normal_load_n": test.normal_load_n,
        "mean_normal_force_n": float(np.mean(fn[steady])),
        "measured_ratio": mean_ratio,
        "rel_error": abs(mean_ratio - mu) / mu if mu > 0 else abs(mean_ratio),
        "ratio_min": float(r.min()),
        "ratio_max": float(r.max()),
        "ratio_std": float(r.std()),
        "ripple": float(r.max() - r.min()),
        "periods": test.periods,
        "steps": test.steps,
        "time_step_s": test.time_step_s,
        "speed_m_s": test.loading.speed_m_s,
        "steady_samples": int(steady.sum()),
    }
    summary.update(overlap_summary(run_dir, test.contact))
    curve = {"time_s": raw["time_s"], "displacement_m": u, "tangential_force_n": ft,
             "normal_force_n": fn, "friction_ratio": ratio, "slider_z_m": raw["slider_z_m"],
             "kinetic_j": raw["kinetic_j"]}
    return SlidingResult(Path(run_dir), curve, summary)
