"""Single virtual-fibre tension: the first closed-form check, F = E·A·ε.

A straight bead chain along x; the first bead is held, the last is moved along
x (smooth start, then constant speed in the quasi-static range). The reaction
force on the held bead against strain ε = u/L0 (L0: distance between the two
clamp beads) must follow E·A·ε.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import inputs
from ..engine import mpi
from ..model.bead_model import BeadModel, BondType, Yarn
from ..model.beads import Discretisation, TimeStep, bead_parameters
from ..model.material import VirtualFibre
from ..results.folder import read_print_file
from ..results.plots import plot_curves
from ..scene import blocks
from ..scene.loading import SmoothStartSpeed
from ..scene.outputs import TrajectoryOutput
from ..scene.templates import render
from .common import DATA_FILE, RunResult
from .single_fibre import SingleFibreCheck, default_fibre

PROTOCOL = "fibre_tension"


@dataclass(frozen=True)
class FibreTension(SingleFibreCheck):
    """A single virtual fibre pulled at constant speed.

    Args:
        fibre: the virtual fibre (default: 0.1 mm E-glass).
        length_m: clamp-to-clamp length L0 [m].
        discretisation: bead spacing, mass scaling, bending.
        time_step: time-step policy.
        max_strain: strain at the end of the run (> 0, <= 0.2).
        speed_fraction: pull speed as a fraction of the fibre's axial wave speed;
            quasi-static when small (default 1e-4).
        ramp_transits: smooth-start time in axial wave-transit times L0/c.
        samples: number of curve points written.
        trajectory: trajectory frames written (``trajectory.h5``, ParaView files;
            ``TrajectoryOutput(frames=0)`` writes none).
    """

    fibre: VirtualFibre = field(default_factory=default_fibre)
    length_m: float = 0.01
    discretisation: Discretisation = field(default_factory=Discretisation)
    time_step: TimeStep = field(default_factory=TimeStep)
    max_strain: float = 0.015
    speed_fraction: float = 1e-4
    ramp_transits: float = 10.0
    samples: int = 300
    trajectory: TrajectoryOutput = field(default_factory=lambda: TrajectoryOutput(frames=20))

    protocol: ClassVar[str] = PROTOCOL

    def __post_init__(self):
        inputs.positive("fibre_tension.length_m", self.length_m)
        inputs.in_range("fibre_tension.max_strain", self.max_strain, 0.0, 0.2, low_open=True)
        inputs.in_range("fibre_tension.speed_fraction", self.speed_fraction, 0.0, 0.1,
                        low_open=True)
        inputs.non_negative("fibre_tension.ramp_transits", self.ramp_transits)
        inputs.positive_int("fibre_tension.samples", self.samples, minimum=10)
        n = self.n_bonds
        if n < 2:
            raise inputs.InputError(
                f"fibre_tension.length_m = {self.length_m:g} m gives {n} bond(s); "
                f"need at least 2 (longer fibre or smaller spacing_ratio)")
        _ = self.time_step_s  # validates an explicit time step against the stable one

    # -- derived ----------------------------------------------------------------------
    @property
    def n_bonds(self) -> int:
        l0 = self.discretisation.spacing_ratio * self.fibre.diameter_m
        return max(1, round(self.length_m / l0))

    @property
    def beads(self):
        return bead_parameters(self.fibre, self.discretisation,
                               bond_length_m=self.length_m / self.n_bonds)

    @property
    def loading(self) -> SmoothStartSpeed:
        c = self.fibre.material.wave_speed_m_s / np.sqrt(self.discretisation.mass_scaling)
        transit = self.length_m / c
        return SmoothStartSpeed(self.speed_fraction * c, self.ramp_transits * transit)

    @property
    def duration_s(self) -> float:
        return self.loading.time_for(self.max_strain * self.length_m)

    def model(self) -> BeadModel:
        """The straight chain along x."""
        b = self.beads
        n = self.n_bonds + 1
        x = np.arange(n) * b.bond_length_m
        pos = np.column_stack([x, np.zeros(n), np.zeros(n)])
        pad = 5 * b.diameter_m
        hi = np.array([x[-1] * (1 + 2 * self.max_strain) + pad, pad, pad])
        return BeadModel(
            positions=pos, diameters=b.diameter_m, masses=b.mass_kg, atom_types=1,
            fibre_ids=np.ones(n, np.int64),
            bonds=np.column_stack([np.arange(n - 1), np.arange(1, n)]), bond_types=1,
            family_names=("fibre",),
            bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "fibre",
                                      b.axial_stiffness_n)],
            fibre_yarn=[1], yarns=[Yarn("fibre-1", "fibre")],
            box_lo=[-pad, -pad, -pad], box_hi=hi)

    def input_text(self, model: BeadModel) -> str:
        dt = self.time_step_s
        every = max(1, self.steps // self.samples)
        load = self.loading
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            render("contact_none"),
            render("fibre_tension", held_id=1, moving_id=model.n_beads,
                   displacement=load.lammps_displacement(), velocity=load.lammps_velocity(),
                   every=every, thermo_every=max(every, self.steps // 20)),
            blocks.guards(model, dt),
            self.trajectory.commands(self.steps),
            render("run", steps=self.steps),
            self.trajectory.final_commands(),
            render("finish", final_data="final.data"),
        ])

    def reduce(self, run_dir: Path, model: BeadModel) -> FibreTensionResult:
        return reduce(run_dir, self)


class FibreTensionResult(RunResult):
    """Curve and summary of a fibre-tension run."""

    def plot(self) -> None:
        c = self.curve
        s = self.summary
        plot_curves(self.run_dir / "curve.png", [
            {"x": c["strain_pct"], "y": c["force_n"], "label": "tension at held end"},
            {"x": c["strain_pct"], "y": c["force_moving_n"], "label": "force on moving clamp",
             "style": "--"},
            {"x": c["strain_pct"], "y": c["expected_force_n"], "label": "E·A·ε", "style": ":"},
        ], "strain [%]", "force [N]", title="Single virtual fibre in tension",
            notes=f"E·A = {s['axial_stiffness_n']:.4g} N\nrel. error at "
                  f"{s['check_strain_pct']:g} %: {s['rel_error']:.2e}")


def reduce(run_dir: Path, test: FibreTension, check_strain: float = 0.01) -> FibreTensionResult:
    """Read ``curve.dat`` of a finished run and compare with E·A·ε."""
    raw = read_print_file(Path(run_dir) / "curve.dat") if mpi.is_root() else None
    ea = test.fibre.axial_stiffness_n
    if raw is None:
        return FibreTensionResult(Path(run_dir), {}, {})
    strain = raw["displacement_m"] / test.length_m
    # the stretched fibre pulls the held bead towards +x: that force is the fibre tension
    reaction = raw["force_held_n"]
    curve = {
        "time_s": raw["time_s"],
        "displacement_m": raw["displacement_m"],
        "strain_pct": 100 * strain,
        "force_n": reaction,
        "force_moving_n": raw["force_moving_n"],
        "expected_force_n": ea * strain,
        "kinetic_energy_j": raw["kinetic_j"],
        "strain_energy_j": raw["strain_energy_j"],
    }
    measured = float(np.interp(check_strain, strain, reaction))
    expected = ea * check_strain
    loaded = strain > 0.2 * test.max_strain
    ke_ratio = raw["kinetic_j"][loaded] / np.maximum(raw["strain_energy_j"][loaded], 1e-300)
    summary = {
        "protocol": PROTOCOL,
        "axial_stiffness_n": ea,
        "length_m": test.length_m,
        "n_beads": test.n_bonds + 1,
        "time_step_s": test.time_step_s,
        "steps": test.steps,
        "speed_m_s": float(test.loading.speed_m_s),
        "check_strain_pct": 100 * check_strain,
        "expected_force_n": expected,
        "measured_force_n": measured,
        "rel_error": abs(measured - expected) / expected,
        "max_kinetic_to_strain_energy": float(ke_ratio.max()) if ke_ratio.size else None,
    }
    return FibreTensionResult(Path(run_dir), curve, summary)
