"""Capstan: a virtual fibre pulled over a fixed cylinder, T_out/T_in = exp(μθ).

One virtual fibre lies in the x–y plane over a rigid cylinder (axis z, radius R,
``fix wall/gran/region`` with the tool's friction μ): a straight part, an arc of
wrap angle θ, a straight part. A load T_in pulls one end away from the cylinder
along its straight part; the other end is held while the load ramps up, then
moved slowly along its straight part so that the whole fibre slides over the
cylinder. In steady sliding the belt-friction equation gives
T_out/T_in = exp(μθ), independent of R and of E (for small stretch).

The pulled bead is moved by ``fix move``, so the force on it is the reaction:
T_out is its component along the pull direction. The ratio is averaged over the
second half of the pull (steady sliding).
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
from ..model.contact import ToolContact
from ..model.material import VirtualFibre
from ..results.folder import read_print_file
from ..results.plots import plot_curves
from ..scene import blocks
from ..scene.loading import SmoothStartSpeed
from ..scene.templates import render
from .common import DATA_FILE, RunResult, overlap_summary
from .single_fibre import SingleFibreCheck, default_fibre, load_ramp

PROTOCOL = "capstan"
TOOL_FIX = "capstan"


@dataclass(frozen=True)
class Capstan(SingleFibreCheck):
    """A virtual fibre wrapped over a fixed cylinder and pulled against a load.

    Args:
        fibre: the virtual fibre (default 0.1 mm E-glass).
        tool: the fibre–cylinder contact; its friction is the μ of exp(μθ)
            (default μ = 0.3).
        wrap_angle_rad: wrap angle θ, in (0, 2π).
        radius_m: cylinder radius R [m] (> 0).
        load_strain: T_in as a fraction of the fibre's E·A, in (0, 0.01].
        pull_distance_m: how far the pulled end moves [m]; default 3 bead diameters.
        speed_fraction: pull speed over the transverse wave speed sqrt(T_in/λ), in
            (0, 0.2]; quasi-static when small (LAMMPS-NOTES: ≲ 0.05).
        ramp_transits: load ramp and speed ramp, each in transverse wave transits of
            the whole fibre (>= 0).
        discretisation: bead spacing, mass scaling, bending.
        time_step: time-step policy.
        samples: number of curve points written.
    """

    fibre: VirtualFibre = field(default_factory=default_fibre)
    tool: ToolContact = field(default_factory=lambda: ToolContact(friction=0.3))
    wrap_angle_rad: float = math.pi
    radius_m: float = 0.3e-3
    load_strain: float = 1e-3
    pull_distance_m: float | None = None
    speed_fraction: float = 0.03
    ramp_transits: float = 2.0
    discretisation: Discretisation = field(default_factory=Discretisation)
    time_step: TimeStep = field(default_factory=TimeStep)
    samples: int = 400

    protocol: ClassVar[str] = PROTOCOL

    def __post_init__(self):
        inputs.in_range("capstan.wrap_angle_rad", self.wrap_angle_rad, 0.0, 2 * math.pi,
                        low_open=True, high_open=True)
        inputs.positive("capstan.radius_m", self.radius_m)
        inputs.in_range("capstan.load_strain", self.load_strain, 0.0, 0.01, low_open=True)
        if self.pull_distance_m is not None:
            inputs.positive("capstan.pull_distance_m", self.pull_distance_m)
        inputs.in_range("capstan.speed_fraction", self.speed_fraction, 0.0, 0.2,
                        low_open=True)
        inputs.non_negative("capstan.ramp_transits", self.ramp_transits)
        inputs.positive_int("capstan.samples", self.samples, minimum=10)
        _ = self.time_step_s  # validates an explicit time step against the stable one

    # -- derived ----------------------------------------------------------------------
    @property
    def friction(self) -> float:
        """μ between fibre and cylinder."""
        return self.tool.friction

    def plan_contacts(self) -> tuple:
        return (self.tool,)

    @property
    def tension_in_n(self) -> float:
        """T_in [N]."""
        return self.load_strain * self.fibre.axial_stiffness_n

    @property
    def expected_ratio(self) -> float:
        return math.exp(self.friction * self.wrap_angle_rad)

    @property
    def pull_m(self) -> float:
        return self.pull_distance_m or 3.0 * self.fibre.diameter_m

    @property
    def straight_length_m(self) -> float:
        """Each straight part: the pull distance plus five bead diameters."""
        return self.pull_m + 5.0 * self.fibre.diameter_m

    @property
    def contact_radius_m(self) -> float:
        """Radius of the bead centres on the cylinder, R + d/2."""
        return self.radius_m + 0.5 * self.fibre.diameter_m

    @property
    def fibre_length_m(self) -> float:
        return 2 * self.straight_length_m + self.wrap_angle_rad * self.contact_radius_m

    @property
    def transverse_speed_m_s(self) -> float:
        """sqrt(T_in/λ), λ = mass per length of the chain (with mass scaling)."""
        lam = self.fibre.mass_per_length_kg_m * self.discretisation.mass_scaling
        return math.sqrt(self.tension_in_n / lam)

    @property
    def ramp_time_s(self) -> float:
        return self.ramp_transits * self.fibre_length_m / self.transverse_speed_m_s

    @property
    def loading(self) -> SmoothStartSpeed:
        return SmoothStartSpeed(self.speed_fraction * self.transverse_speed_m_s,
                                self.ramp_time_s)

    @property
    def duration_s(self) -> float:
        return self.ramp_time_s + self.loading.time_for(self.pull_m)

    def _directions(self):
        """Arc start/end angles and unit tangents (path direction: load end → pulled end)."""
        a0 = 0.5 * math.pi + 0.5 * self.wrap_angle_rad
        a1 = 0.5 * math.pi - 0.5 * self.wrap_angle_rad
        t0 = np.array([math.sin(a0), -math.cos(a0), 0.0])
        t1 = np.array([math.sin(a1), -math.cos(a1), 0.0])
        return a0, a1, t0, t1

    def model(self) -> BeadModel:
        """The fibre: straight part, arc of θ on radius R + d/2, straight part."""
        b = self.beads
        l0 = b.bond_length_m
        rc = self.contact_radius_m
        a0, _, t0, t1 = self._directions()
        n_straight = int(round(self.straight_length_m / l0))
        # arc from a0 clockwise to a1 exactly, in equal steps with chords <= l0
        largest_step = 2.0 * math.asin(min(1.0, l0 / (2 * rc)))
        n_arc = max(1, math.ceil(self.wrap_angle_rad / largest_step))
        angles = a0 - self.wrap_angle_rad * np.arange(n_arc + 1) / n_arc
        arc = rc * np.column_stack([np.cos(angles), np.sin(angles), np.zeros(n_arc + 1)])
        lead = arc[0] - l0 * np.arange(n_straight, 0, -1)[:, None] * t0
        tail = arc[-1] + l0 * np.arange(1, n_straight + 1)[:, None] * t1
        pos = np.vstack([lead, arc, tail])
        n = len(pos)
        pad = 4 * b.diameter_m
        lo = np.minimum(pos.min(axis=0), -rc) - pad - self.pull_m
        hi = np.maximum(pos.max(axis=0), rc) + pad + self.pull_m
        lo[2], hi[2] = -pad, pad
        return BeadModel(
            positions=pos, diameters=b.diameter_m, masses=b.mass_kg, atom_types=1,
            fibre_ids=np.ones(n, np.int64),
            bonds=np.column_stack([np.arange(n - 1), np.arange(1, n)]), bond_types=1,
            family_names=("fibre",),
            bond_type_table=[BondType(b.bond_coefficient, l0, "fibre", b.axial_stiffness_n)],
            fibre_yarn=[1], yarns=[Yarn("fibre-1", "fibre")],
            box_lo=lo, box_hi=hi,
            info={"protocol": PROTOCOL, "wrap_angle_rad": self.wrap_angle_rad,
                  "radius_m": self.radius_m})

    def pull_direction(self, model: BeadModel) -> np.ndarray:
        """Unit vector along which the last bead is pulled (its straight part)."""
        d = model.positions[-1] - model.positions[-2]
        return d / np.linalg.norm(d)

    def load_direction(self, model: BeadModel) -> np.ndarray:
        """Unit vector of the load on the first bead (away from the cylinder)."""
        d = model.positions[0] - model.positions[1]
        return d / np.linalg.norm(d)

    def input_text(self, model: BeadModel) -> str:
        dt = self.time_step_s
        every = max(1, self.steps // self.samples)
        load = self.loading
        pull = self.pull_direction(model)
        tin = self.load_direction(model) * self.tension_in_n
        tr = self.ramp_time_s
        beads = [self.beads]
        ramp = load_ramp(tr)
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            render("contact_none"),
            render("capstan", radius=self.radius_m, zlo=model.box_lo[2], zhi=model.box_hi[2],
                   tool=blocks.tool_region(self.tool, beads, "cylinder", fix_id=TOOL_FIX),
                   load_id=1, pulled_id=model.n_beads, load_ramp=ramp,
                   load_x=tin[0], load_y=tin[1], pull_x=pull[0], pull_y=pull[1],
                   ramp_time=tr, displacement=load.lammps_displacement("tp"),
                   velocity=load.lammps_velocity("tp"), every=every,
                   thermo_every=max(every, self.steps // 20)),
            blocks.guards(model, dt),
            blocks.overlap_monitor(model, None, beads, every=every, tool_fixes=(TOOL_FIX,)),
            render("run", steps=self.steps),
            render("finish", final_data="final.data"),
        ])

    def reduce(self, run_dir: Path, model: BeadModel) -> CapstanResult:
        return reduce(run_dir, self, model)


class CapstanResult(RunResult):
    """Curve and summary of a capstan run."""

    def plot(self) -> None:
        c, s = self.curve, self.summary
        pulling = c["displacement_m"] > 0  # the load has ramped up
        u = 1e3 * c["displacement_m"][pulling]
        plot_curves(self.run_dir / "curve.png", [
            {"x": u, "y": c["ratio"][pulling], "label": "T_out / T_in"},
            {"x": u, "y": np.full_like(u, s["expected_ratio"]), "label": "exp(μθ)",
             "style": ":"},
        ], "pulled-end displacement [mm]", "T_out / T_in [–]",
            title=f"Capstan, μ = {s['mu']:g}, θ = {math.degrees(s['theta_rad']):.0f}°",
            notes=f"measured {s['measured_ratio']:.4f}\nexpected {s['expected_ratio']:.4f}\n"
                  f"rel. error {s['rel_error']:.2e}")


def reduce(run_dir: Path, test: Capstan, model: BeadModel) -> CapstanResult:
    """Read ``curve.dat`` and compare the steady T_out/T_in with exp(μθ)."""
    if not mpi.is_root():
        return CapstanResult(Path(run_dir), {}, {})
    raw = read_print_file(Path(run_dir) / "curve.dat")
    pull = test.pull_direction(model)
    # the fibre pulls the moved bead back towards the cylinder: T_out = -f·pull
    t_out = -(raw["fx_pulled_n"] * pull[0] + raw["fy_pulled_n"] * pull[1])
    t_in = raw["load_n"]
    ratio = np.divide(t_out, t_in, out=np.zeros_like(t_out), where=t_in > 0)
    u = raw["displacement_m"]
    steady = u >= 0.5 * test.pull_m
    measured = float(np.mean(t_out[steady]) / np.mean(t_in[steady]))
    expected = test.expected_ratio
    curve = {"time_s": raw["time_s"], "displacement_m": u, "tension_in_n": t_in,
             "tension_out_n": t_out, "ratio": ratio, "kinetic_j": raw["kinetic_j"]}
    summary = {
        "protocol": PROTOCOL,
        "mu": test.friction,
        "theta_rad": test.wrap_angle_rad,
        "expected_ratio": expected,
        "measured_ratio": measured,
        "rel_error": abs(measured - expected) / expected,
        "ratio_std": float(np.std(ratio[steady])),
        "tension_in_n": test.tension_in_n,
        "radius_m": test.radius_m,
        "n_beads": model.n_beads,
        "time_step_s": test.time_step_s,
        "steps": test.steps,
        "pull_speed_m_s": test.loading.speed_m_s,
        "steady_samples": int(steady.sum()),
    }
    summary.update(overlap_summary(run_dir, None))
    return CapstanResult(Path(run_dir), curve, summary)
