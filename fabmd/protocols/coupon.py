"""Coupons: cut (or tile) a test piece from a relaxed fabric and let it relax free.

A crimped fabric holds its yarn tensions through its held ends or its periodic
box; a coupon cut out of it springs back where fibres were cut. The coupon is
therefore relaxed free (nothing held, damped until quasi-static) and saved as a
reusable state — ``coupon.data`` + ``coupon.json`` — that the test protocols
start from (and, with ``trajectory`` frames, the relaxation as ``trajectory.h5``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import inputs
from ..engine import Engine, mpi
from ..errors import InputError, QuasiStaticWarning
from ..model.bead_model import BeadModel
from ..model.beads import TimeStep, model_bead_parameters
from ..model.bending import add_bending
from ..model.cohesion import DEFAULT_REACH, add_cohesion
from ..model.contact import ContactModel
from ..model.rest_state import relieve_fibre_tension
from ..model.timestep import stable_time_step_s
from ..model.transform import cut, tile
from ..results.folder import write_json
from ..results.measure import fabric_measures
from ..results.run_record import read_run_end
from ..scene import blocks
from ..scene.outputs import TrajectoryOutput, check_trajectory
from ..scene.quasi_static import QuasiStatic, relaxation_settled
from ..scene.templates import render, render_inline
from .common import (
    DATA_FILE,
    StateResult,
    load_state,
    open_run_folder,
    overlap_summary,
    run_with_trajectory,
    scene_dict,
    write_run_folder,
)

PROTOCOL = "coupon"
COUPON = "coupon"


@dataclass(frozen=True)
class Coupon:
    """A rectangular coupon cut from a fabric.

    Args:
        length_m, width_m: coupon size [m] (length along x in the coupon).
        angle_deg: coupon axis against the fabric's warp (x) axis; 45 for bias extension.
        edge_zone_m: band along the fabric's edges the coupon stays out of [m].
        tile: (nx, ny) copies of a periodic cell to build before cutting (None: cut
            the fabric as it is; a periodic cell is tiled just enough automatically).
        relax: stop criterion of the free relaxation (None: no relaxation).
        contact: contact during the relaxation.
        time_step: time-step policy of the relaxation.
        trajectory: trajectory frames of the relaxation (``trajectory.h5``, ParaView
            files; spread over a quarter of ``relax.max_steps``, the relaxed state the last
            frame); default none.
        bending_factor: give the cut fibres bending stiffness with a straight rest shape,
            this fraction of the solid virtual fibre's E·I, before the relaxation (0,
            default: none; :mod:`fabmd.model.bending`): the woven crimp becomes elastic and
            presses the crossings together. Bead chains without bending are strings: cut
            free, their crossings carry no force.
        cohesion_factor: link the touching fibres of each yarn, after the free relaxation,
            with springs at rest in the relaxed coupon, this fraction of the fibre bond's
            spring (0, default: none; :mod:`fabmd.model.cohesion`): each yarn stays a
            yarn, with its cross-section, its woven shape and an in-plane bending
            stiffness, as sizing and twist keep a real one — what a bias-extension coupon
            needs to trellis instead of fraying.
        cohesion_reach: link beads of other fibres of the yarn closer than this many bead
            diameters.
        relieve_tension: set every fibre bond's rest length to its length as cut, before
            the relaxation (:func:`fabmd.model.rest_state.relieve_fibre_tension`): the
            crimp's locked-in yarn tension leaves the whole coupon evenly, as a fabric
            conditioned free of tension before cutting, instead of through the cut edges
            (which leaves a crimp that varies along the coupon and with its length).
            False (default): the fibres keep the crimp's rest lengths.
        cells: (nx, ny) whole periodic cells of the source: the coupon's length and width
            are then those of the cell it is cut from (a released cell is shorter than
            the drawn one), ``length_m``/``width_m`` only where the source is no cell.
    """

    length_m: float
    width_m: float
    angle_deg: float = 0.0
    edge_zone_m: float = 0.0
    tile: tuple[int, int] | None = None
    relax: QuasiStatic | None = field(default_factory=lambda: QuasiStatic(max_steps=100_000))
    contact: ContactModel = field(default_factory=ContactModel)
    time_step: TimeStep = field(default_factory=TimeStep)
    trajectory: TrajectoryOutput = field(default_factory=lambda: TrajectoryOutput(frames=0))
    bending_factor: float = 0.0
    cohesion_factor: float = 0.0
    cohesion_reach: float = DEFAULT_REACH
    relieve_tension: bool = False
    cells: tuple[int, int] | None = None

    def __post_init__(self):
        inputs.positive("coupon.length_m", self.length_m)
        inputs.positive("coupon.width_m", self.width_m)
        inputs.finite("coupon.angle_deg", self.angle_deg)
        inputs.non_negative("coupon.edge_zone_m", self.edge_zone_m)
        if self.tile is not None:
            inputs.positive_int("coupon.tile[0]", self.tile[0])
            inputs.positive_int("coupon.tile[1]", self.tile[1])
        if self.cells is not None:
            inputs.positive_int("coupon.cells[0]", self.cells[0])
            inputs.positive_int("coupon.cells[1]", self.cells[1])
        check_trajectory("coupon.trajectory", self.trajectory)
        inputs.in_range("coupon.bending_factor", self.bending_factor, 0.0, 1.0)
        inputs.in_range("coupon.cohesion_factor", self.cohesion_factor, 0.0, 1.0)
        inputs.in_range("coupon.cohesion_reach", self.cohesion_reach, 1.0, 3.0)
        if not isinstance(self.relieve_tension, bool):
            raise InputError(f"coupon.relieve_tension must be true or false, got "
                             f"{self.relieve_tension!r}")

    def size_m(self, fabric: BeadModel) -> tuple[float, float]:
        """(length, width) [m] of the coupon cut from ``fabric``: ``cells`` whole cells of a
        periodic source, else ``length_m`` × ``width_m``."""
        if self.cells is None or not (fabric.periodic[0] and fabric.periodic[1]):
            return self.length_m, self.width_m
        cell = fabric.box_hi - fabric.box_lo
        return self.cells[0] * float(cell[0]), self.cells[1] * float(cell[1])

    def cells_needed(self, fabric: BeadModel) -> tuple[int, int]:
        """Copies of a periodic cell that hold the coupon (any angle) plus the edge zone."""
        cell = fabric.box_hi - fabric.box_lo
        a = np.radians(self.angle_deg)
        length, width = self.size_m(fabric)
        span_x = abs(length * np.cos(a)) + abs(width * np.sin(a))
        span_y = abs(length * np.sin(a)) + abs(width * np.cos(a))
        pad = 2 * self.edge_zone_m + 2 * float(fabric.diameters.max())
        return (int(np.ceil((span_x + pad) / cell[0])) + 1,
                int(np.ceil((span_y + pad) / cell[1])) + 1)

    def geometry(self, fabric: BeadModel) -> BeadModel:
        """The coupon beads (before relaxation), length along x."""
        source = fabric
        length, width = self.size_m(fabric)
        if self.tile is not None:
            source = tile(fabric, *self.tile, periodic=False)
        elif fabric.periodic[0] and fabric.periodic[1]:
            source = tile(fabric, *self.cells_needed(fabric), periodic=False)
        elif any(fabric.periodic):
            raise InputError("a fabric periodic in one direction only cannot be cut; "
                             "use a fully periodic cell or a finite piece")
        coupon = cut(source, length, width, angle_deg=self.angle_deg,
                     edge_zone_m=self.edge_zone_m)
        if self.relieve_tension:
            coupon = relieve_fibre_tension(coupon)
        if self.bending_factor > 0:
            coupon = add_bending(coupon, self.bending_factor)
        return coupon

    def with_cohesion(self, model: BeadModel) -> BeadModel:
        """``model`` with this coupon's yarn cohesion (if any), at rest in its shape."""
        if self.cohesion_factor <= 0:
            return model
        linked = add_cohesion(model, self.cohesion_factor, self.cohesion_reach)
        if linked is model:
            warnings.warn("coupon.cohesion_factor has no effect: no two fibres of one yarn "
                          "touch (yarns of one virtual fibre, e.g. --fast, have nothing to "
                          "link)", UserWarning, stacklevel=3)
        return linked

    def input_text(self, model: BeadModel) -> str:
        beads = model_bead_parameters(model)
        dt = stable_time_step_s(beads, [self.contact], self.time_step)
        ea = max(bt.bond_axial_stiffness_n for bt in model.fibre_bond_types())
        k = max(bt.spring_n_per_m for bt in model.fibre_bond_types())
        ref = 1e-3 * ea
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            blocks.overlap_monitor(model, self.contact, beads),
            render_inline("coupon_free"),
            blocks.guards(model, dt),  # before the relaxation: it is the run to guard
            blocks.relax(model, dt, "held", "free", self.relax, ref,
                         int(model.fibre_bond_mask().sum()) * ref**2 / (2 * k),
                         trajectory=self.trajectory),
            render("finish", final_data=f"{COUPON}.data"),
        ])

    def run(self, fabric: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False, resume: bool = False) -> CouponResult:
        """Cut the coupon from ``fabric``, relax it free and save it in ``out``
        (``resume``: continue the interrupted relaxation in ``out`` from its checkpoint)."""
        geometry = self.geometry(fabric)
        if self.relax is None:
            run_dir = write_run_folder(out, PROTOCOL, geometry, "# not relaxed\n",
                                       {"coupon": scene_dict(self)}, overwrite=overwrite)
            geometry = self.with_cohesion(geometry)
            if mpi.is_root():
                geometry.save(run_dir, stem=COUPON)
                write_json(Path(run_dir) / "summary.json", {"relaxed": False})  # done mark
            return CouponResult(Path(run_dir), geometry, {"relaxed": False})
        text = self.input_text(geometry)
        run_dir = open_run_folder(out, PROTOCOL, geometry, text, {"coupon": scene_dict(self)},
                                  overwrite, resume, files=blocks.contact_files(
                                      self.contact, model_bead_parameters(geometry)))
        _, trajectory = run_with_trajectory(engine or Engine(), run_dir, PROTOCOL,
                                            self.trajectory, geometry, resume)
        summary = None
        if mpi.is_root():
            relaxed = BeadModel.load(Path(run_dir) / f"{COUPON}.data", Path(run_dir) / "model.json")
            # cohesion links go in after the relaxation: at rest with the fibres unloaded
            # (linked while the cut fibres still carry the crimp tension, they would hold it)
            relaxed = self.with_cohesion(relaxed)
            relaxed.save(run_dir, stem=COUPON)
            settled = relaxation_settled(Path(run_dir) / "log.lammps")
            if resume and not settled:  # it settled after the resume
                settled = relaxation_settled(Path(run_dir) / "log.resume.lammps")
            if settled is False:
                warnings.warn(f"coupon in {run_dir}: the free relaxation did not settle within "
                              f"{self.relax.max_steps} steps, the coupon is still moving: raise "
                              f"relax.max_steps, or check that the coupon holds together",
                              QuasiStaticWarning, stacklevel=2)
            bending = None
            if len(geometry.angles):  # a known defect: say so where it applies
                bending = (f"coupon in {run_dir}: its fibres bend; cut free, with straight "
                           f"rest shapes and its fibre tension relieved, such a coupon warps "
                           f"out of its woven shape as it relaxes and need not come to rest "
                           f"within the budget (benchmarks/RESULTS.md \"A relaxation that "
                           f"waits until nothing moves\"); the start state and the tension "
                           f"toe of its tests are provisional")
                warnings.warn(bending, QuasiStaticWarning, stacklevel=2)
            end = read_run_end(run_dir, relaxation=True)  # where LAMMPS stopped, and why
            summary = {"relaxed": True, "settled": settled,
                       "rest_note": bending,
                       "steps": end.final_step if end else None,
                       "stop": end.sentence() if end else None,
                       "cut": fabric_measures(geometry),
                       "relaxed_state": fabric_measures(relaxed),
                       "overlap": overlap_summary(run_dir, self.contact),
                       "cohesion_links": int((~relaxed.fibre_bond_mask()).sum()),
                       "trajectory": trajectory.name if trajectory else None}
            write_json(Path(run_dir) / "summary.json", summary)
        summary = mpi.bcast_json(summary)
        return CouponResult(Path(run_dir), load_coupon(run_dir), summary)


#: the coupon stage's result: run folder, coupon state, summary
CouponResult = StateResult


def load_coupon(run_dir: Path) -> BeadModel:
    """A saved coupon state (``coupon.data`` + ``coupon.json``)."""
    return load_state(run_dir, COUPON)
