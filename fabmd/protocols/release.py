"""Release: the crimped periodic cell loses its weaving tension, as cloth off the loom.

The crimp reaches the as-woven geometry under a weaving tension (about 1 cN/tex): the
periodic box holds the yarns at the loom's length. A fabric taken off the loom, conditioned
and cut (ISO 139; ASTM D3883 measures crimp on it) carries none: it shortens until its
yarns are slack and its crossings unloaded. Kept, that tension is what the tests measure:
in the plain-weave example's cell the yarns stay one row of fibres pressed into the
crossings, the crossing yarns must stretch to shear and the cell locks at 17° instead of
37° (benchmarks/RESULTS.md "Yarns that keep their width").

Here the box's in-plane sizes follow the membrane forces of a light handling tension
(``handling_tension``, default 0.05 cN/tex, a twentieth of a weaving tension: Berendsen on x
and y, each on its own; the box drags the beads through the fibres that cross its faces),
damped, until the cell is at rest with its membrane forces within ``tolerance`` of those.
A handling tension and not none: the virtual fibres are strings, and a cell of strings
held at no tension has nothing that stops it shortening, as a real yarn's bending
stiffness does (the example's cell released towards zero went on shrinking, −0.9 … −1.3 %
and still moving after 400,000 steps). The run folder holds ``released.data`` (the model at
rest; its fibres keep their rest lengths), ``history.dat`` (box and membrane forces) and
``summary.json`` (cell before and after, strain, membrane forces before, aimed at and
left, fabric measures, yarn tension before and after).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import inputs
from ..engine import Engine, mpi
from ..errors import InputError, QuasiStaticWarning
from ..model.bead_model import BeadModel
from ..model.beads import TimeStep, model_bead_parameters
from ..model.contact import ContactModel
from ..model.timestep import berendsen_modulus_pa, fibre_transit_s, stable_time_step_s
from ..results.folder import read_print_file, write_json
from ..results.measure import areal_density_kg_m2, fabric_measures
from ..results.run_record import read_run_end
from ..results.yarn_tension import yarn_tension
from ..scene import blocks
from ..scene.quasi_static import SETTLE_STRAIN, QuasiStatic
from ..scene.templates import render
from .common import (
    DATA_FILE,
    StateResult,
    load_state,
    open_run_folder,
    overlap_summary,
    run_folder,
    scene_dict,
)

PROTOCOL = "release"
RELEASED = "released"


@dataclass(frozen=True)
class Release:
    """Let a crimped periodic cell shed its in-plane membrane forces.

    Args:
        time_constant_transits: the Berendsen time constant in axial wave transits of the
            cell's longest fibre (> 0; default 50: 50 and 150 leave the example's cell at
            the same state, strain −0.660 / −0.656 %, crimp 2.114 / 2.111 %; it is
            numerical, the released state is set by the handling tension).
        handling_tension: the yarn tension the released cell is held at, per family
            (``{"warp": "0.05 cN/tex"}``) or one for all, in N per yarn or cN/tex (> 0).
        tolerance: how close the membrane forces come to the handling tension's,
            relative, in (0, 1); default 0.05 (0.2 left the example's cell 0.02 % less
            shrunk and its crimp 0.02 pp lower, at two thirds of the steps).
        min_time_constants: the release runs at least this many time constants (>= 1).
        contact: fibre–fibre contact (the crimp's).
        quasi_static: when the cell is at rest (its ``max_steps`` bounds the run).
        time_step: time-step policy.
        damping_ratio: local (Cundall) damping of the beads, in (0, 1).
        settle_force_n: the quasi-static reference force [N] (None: 1e-3·E·A, a weaving
            tension's order, as the crimp).
    """

    time_constant_transits: float = 50.0
    handling_tension: dict | str | float = "0.05 cN/tex"
    tolerance: float = 0.05
    min_time_constants: float = 3.0
    contact: ContactModel = field(default_factory=ContactModel)
    quasi_static: QuasiStatic = field(default_factory=lambda: QuasiStatic(max_steps=400_000))
    time_step: TimeStep = field(default_factory=TimeStep)
    damping_ratio: float = 0.7
    settle_force_n: float | None = None

    def __post_init__(self):
        inputs.positive("release.time_constant_transits", self.time_constant_transits)
        from .crimp_tension import check_target_tension

        check_target_tension(self.handling_tension, "release.handling_tension")
        inputs.in_range("release.tolerance", self.tolerance, 0.0, 1.0, low_open=True,
                        high_open=True)
        inputs.in_range("release.min_time_constants", self.min_time_constants, 1.0, 100.0)
        inputs.in_range("release.damping_ratio", self.damping_ratio, 0.0, 1.0, low_open=True,
                        high_open=True)
        if self.settle_force_n is not None:
            inputs.positive("release.settle_force_n", self.settle_force_n)

    # -- derived from the model --------------------------------------------------------
    @staticmethod
    def check_model(model: BeadModel) -> None:
        if not (model.periodic[0] and model.periodic[1]):
            raise InputError("the release of the weaving tension needs the periodic cell "
                             "(fabmd crimp --form cell; the tests crimp it by default): a "
                             "finite piece keeps its held ends, and its coupons are relieved "
                             "when cut ([tension.coupon] relieve_tension)")

    def time_step_s(self, model: BeadModel) -> float:
        return stable_time_step_s(model, [self.contact], self.time_step)

    def time_constant_s(self, model: BeadModel) -> float:
        """Berendsen's time constant [s]: ``time_constant_transits`` axial wave transits
        of the longest fibre (bead count × √(m/k), as the crimp's ramp)."""
        return self.time_constant_transits * fibre_transit_s(model)

    def reference_force_n(self, model: BeadModel) -> float:
        if self.settle_force_n is not None:
            return float(self.settle_force_n)
        return SETTLE_STRAIN * max(bt.bond_axial_stiffness_n for bt in model.bond_type_table)

    def membrane_target_n_m(self, model: BeadModel) -> tuple[float, float]:
        """(N_xx, N_yy) [N/m] of the handling tension: each yarn's tension over the cell's
        side across it (a yarn runs along x or y: its longer extent in the cell)."""
        from .crimp_tension import target_tensions_n

        tension = target_tensions_n(self.handling_tension, model, "release.handling_tension")
        size = model.box_hi - model.box_lo
        p = model.unwrapped_positions
        n = [0.0, 0.0]
        yarn_ids = model.yarn_ids
        for y in np.unique(yarn_ids):
            sel = yarn_ids == y
            fam = model.yarns[int(y) - 1].family
            along = int(np.ptp(p[sel, 1]) > np.ptp(p[sel, 0]))
            n[along] += tension.get(fam, 0.0) / float(size[1 - along])
        return n[0], n[1]

    def input_text(self, model: BeadModel) -> str:
        self.check_model(model)
        dt = self.time_step_s(model)
        beads = model_bead_parameters(model)
        lz = float(model.box_hi[2] - model.box_lo[2])
        k = max(bt.spring_n_per_m for bt in model.bond_type_table)
        f_ref = self.reference_force_n(model)
        pdamp = self.time_constant_s(model)
        modulus = berendsen_modulus_pa(model)
        check = self.quasi_static.check_every
        every = max(1, check // 50)
        qs = self.quasi_static
        nxx, nyy = self.membrane_target_n_m(model)
        text = render(
            "release", pdamp=pdamp, modulus=modulus, damping_ratio=self.damping_ratio,
            nxx_target=nxx, nyy_target=nyy, pxx=-nxx / lz, pyy=-nyy / lz,
            nxx_tolerance=self.tolerance * nxx, nyy_tolerance=self.tolerance * nyy,
            tolerance_pct=100 * self.tolerance, check_every=check, mean_every=every,
            mean_repeat=check // every, min_steps=math.ceil(self.min_time_constants * pdamp / dt),
            max_steps=qs.max_steps,
            monitors=qs.monitors("all", f_ref, model.n_bonds * f_ref**2 / (2 * k)))
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            blocks.overlap_monitor(model, self.contact, beads),
            blocks.guards(model, dt),
            text,
            render("finish", final_data=f"{RELEASED}.data"),
        ])

    # -- run ------------------------------------------------------------------------
    def run(self, model: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False) -> ReleaseResult:
        """Release the crimped cell ``model``; returns the released state and its measures."""
        text = self.input_text(model)  # validates before anything is written
        run_dir = open_run_folder(out, PROTOCOL, model, text, {"release": scene_dict(self)},
                                  overwrite, files=blocks.contact_files(
                                      self.contact, model_bead_parameters(model)))
        run = run_folder(engine or Engine(), run_dir, PROTOCOL)
        summary = None
        if mpi.is_root():
            summary = self.reduce(run_dir, model)
            summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend)
            write_json(Path(run_dir) / "summary.json", summary)
        summary = mpi.bcast_json(summary)
        return ReleaseResult(Path(run_dir), load_released(run_dir), summary)

    def reduce(self, run_dir: Path, woven: BeadModel) -> dict:
        run_dir = Path(run_dir)
        released = BeadModel.load(run_dir / f"{RELEASED}.data", run_dir / "model.json")
        released.save(run_dir, stem=RELEASED)
        history = read_print_file(run_dir / "history.dat")
        before = (woven.box_hi - woven.box_lo)[:2]
        after = (released.box_hi - released.box_lo)[:2]
        start = (run_dir / "woven.dat").read_text().split()
        end = read_run_end(run_dir, relaxation=True)
        settled = bool(end is not None and end.quasi_static)
        left = [float(history["n_xx_n_m"][-1]), float(history["n_yy_n_m"][-1])]
        if not settled:
            warnings.warn(f"release in {run_dir}: {end.sentence() if end else 'no log'}; the "
                          f"membrane forces left are {left[0]:.4g} / {left[1]:.4g} N/m (woven "
                          f"{float(start[1]):.4g} / {float(start[2]):.4g}): raise "
                          f"release's quasi_static.max_steps or time_constant_transits",
                          QuasiStaticWarning, stacklevel=3)
        return {
            "protocol": PROTOCOL,
            "settled": settled,
            "steps": end.final_step if end else None,
            "stop": end.sentence() if end else None,
            "time_constant_s": self.time_constant_s(woven),
            "cell_before_m": before.tolist(), "cell_after_m": after.tolist(),
            "strain_pct": (100 * (after / before - 1)).tolist(),
            "membrane_force_woven_n_m": [float(start[1]), float(start[2])],
            "membrane_force_target_n_m": list(self.membrane_target_n_m(woven)),
            "membrane_force_left_n_m": left,
            "woven": fabric_measures(woven),
            "released": fabric_measures(released),
            "areal_density_kg_m2": areal_density_kg_m2(released),
            "yarn_tension_woven": yarn_tension(woven),
            "yarn_tension_released": yarn_tension(released),
            "overlap": overlap_summary(run_dir, self.contact),
        }


#: what the crimp's summary keeps of a release's (``released``)
RELEASE_KEYS = ("settled", "steps", "stop", "time_constant_s", "cell_before_m", "cell_after_m",
                "strain_pct", "membrane_force_woven_n_m", "membrane_force_target_n_m",
                "membrane_force_left_n_m", "yarn_tension_released", "wall_s")


#: the release's result: run folder, released cell, summary
ReleaseResult = StateResult


def load_released(run_dir: Path) -> BeadModel:
    """A released cell (``released.data`` + ``released.json``)."""
    return load_state(run_dir, RELEASED)
