"""Crimp: turn a loose, idealised fabric into its as-woven state.

The loom's work is imitated by a thermal-expansion-like ramp of the bond rest
length per yarn family, r0 → r0·(1 + α·ΔT): binders shrink (α·ΔT < 0), put
themselves in tension and compact the fabric; warp and weft may expand
(α·ΔT > 0) to make room for their longer wavy path. In the finite-piece form
the end bead of every fibre is held in all directions; in the periodic form
(a unit cell with continuous yarns) nothing is held. After the ramp the final
rest lengths are kept and damped dynamics run until the fabric is quasi-static
(see :class:`fabmd.scene.quasi_static.QuasiStatic`), not for a fixed number of
steps.

Outputs in the run folder: ``crimped.data`` + ``crimped.json`` (the as-woven
bead model, reusable by the test protocols), ``history.dat``/``history.csv``,
``summary.json`` (loose and crimped measures, the yarn tension per family in N and
cN/tex: :mod:`fabmd.results.yarn_tension`), ``history.png``,
``sections.png`` (top view and cuts along warp and weft), ``cuts/`` (one image and CSV
per cut plane and the overview ``cuts.png``) and the
trajectory of the ramp and the relaxation (``trajectory.h5``, ParaView files; the
crimped state is its last frame).
"""

from __future__ import annotations

import dataclasses
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
from ..model.timestep import fibre_transit_s, stable_time_step_s
from ..results.cuts import cut_pngs
from ..results.folder import read_print_file, write_csv, write_json
from ..results.measure import areal_density_kg_m2, fabric_measures, passed_through
from ..results.plots import plot_curves
from ..results.preview import preview_png
from ..results.run_record import RunEnd, read_run_end
from ..results.yarn_tension import yarn_tension
from ..scene import blocks
from ..scene.outputs import TrajectoryOutput, check_trajectory
from ..scene.plan import RunPlan, cached_plan, read_plan
from ..scene.quasi_static import SETTLE_STRAIN, Damping, QuasiStatic
from ..scene.templates import render
from .common import DATA_FILE, open_run_folder, overlap_summary, run_with_trajectory, scene_dict
from .crimp_balance import crimp_interchange, warn_interchange

PROTOCOL = "crimp"
CRIMPED = "crimped"
#: what may reach a family's crimp (``Crimp.crimp_by``, ``CrimpTargets.crimp_by``)
CRIMP_BY = ("expansion", "loose_height")


@dataclass(frozen=True)
class Crimp:
    """The crimp stage.

    Args:
        expansion: rest-length strain α·ΔT per yarn family reached at the end of
            the ramp, e.g. ``{"binder": -0.08, "warp": 0.01}``; families not named
            keep their rest length. Each value in (−0.5, 0.5).
        hold_ends: hold the end bead of every fibre (finite pieces; ignored for a
            periodic model, which has no ends).
        contact: fibre–fibre contact.
        damping: numerical damping of the relaxation.
        quasi_static: stop criterion of the relaxation.
        time_step: time-step policy.
        ramp_transits: ramp duration in axial wave-transit times of the longest fibre.
        samples: history lines written.
        target_tension: the yarn tension the crimped fabric should carry, per family
            (``{"warp": "1 cN/tex", "weft": "4 N"}``) or one for all: N per yarn or
            cN/tex; the expansion of those families is then searched for it
            (:mod:`fabmd.protocols.crimp_tension`; ``expansion`` is the start; a root
            that 0.1 % more shrink slackens is passed for the one past the snap). None:
            the expansion as given, whatever tension it leaves (reported either way).
        target_crimp_pct: the crimp [%] per family the crimped fabric should have, its
            expansion then derived from the loose geometry (1 + c)/(1 + c0) − 1
            (:mod:`fabmd.protocols.crimp_target`), e.g. ``{"warp": 1.2, "weft": 0.8}``;
            ``"auto"`` (binders): shrink by the loose crimp less ``auto_margin_pct``, so
            the yarns end under tension but still woven. A family is given either here or
            in ``expansion``; beside ``target_tension`` only ``"auto"``, which then bounds
            the tension search's shrink instead of setting it.
        auto_margin_pct: the crimp [%] an ``"auto"`` family keeps (> 0; default 3).
        crimp_by: what reaches a number in ``target_crimp_pct``: ``"expansion"``
            (default: the family's expansion is derived from it) or ``"loose_height"``
            (the height of the family's loose section is searched for it, while
            ``target_tension`` sets the expansion: crimp and weaving tension of one family
            together, as the fabric states them; the crimp a discretisation leaves at a
            tension follows the loose section it is drawn with). ``"loose_height"`` draws
            the cell again for each height, so it runs from a scene
            (:func:`fabmd.loose_height.pin_crimp`, done by ``fabmd crimp``, ``fabmd test``
            and ``fabmd demo``), not from :meth:`run` on a model.
        crimp_tolerance_pct: with ``crimp_by = "loose_height"``, how close each family's
            crimp comes to its target [percentage points] (> 0; default 0.05).
        loose_height_start_m: with ``crimp_by = "loose_height"``, the loose section
            height the search's first run draws [m], one for all searched families or
            per family (``"0.57 mm"``, ``{ warp = "0.57 mm", weft = "0.6 mm" }``);
            default the yarns' ``height_m``, and the search's range stays a half to one
            and a half times that. A start where a discretisation's search ended before
            saves its runs and makes the fabric independent of the search's path: the
            search accepts the first run within ``crimp_tolerance_pct``, and a run at the
            tolerance's edge is accepted on one rank count and not on another (round-off
            grown through a crimp moves a family's crimp by about 0.02 pp), after which
            the two crimp different fabrics (benchmarks/RESULTS.md "The demo on 2 ranks
            against one, idle", "The demo from a stated start"). Read but not used
            without ``crimp_by = "loose_height"``, as ``crimp_tolerance_pct`` (a scene
            whose search was taken out keeps its drawn sections: set ``[yarns.<family>]
            height_m`` to draw them at that height).
        settle_force_n: the force a virtual fibre is meant to carry once crimped [N]: the
            relaxation's quasi-static reference (its force residual and kinetic-energy
            floor are judged against it). Set by the tension search to its target per
            virtual fibre; None: the force at 0.1 % fibre strain, 1e-3·E·A
            (:data:`SETTLE_STRAIN`), about a weaving tension's. The shrink's own
            |expansion|·E·A, the reference until 2026-12-06, is near a hundred times a
            weaving tension: a run at 1 cN/tex stopped while its kinetic energy was still
            40 % of its bonds' energy and the tension it reported fell to a third once the
            run went on (benchmarks/RESULTS.md "The crimp stopped before the fabric was at
            rest", "A crimp with a stated shrink judged at rest").
        release_tension: after the crimp (and its searches), let the periodic cell shed
            its weaving tension down to ``handling_tension``, as cloth taken off the loom
            (:mod:`fabmd.protocols.release`, in the folder's ``release/``): the stage's
            model and its ``crimped`` measures are then the released cell's (a crimp
            target is judged on it, as ASTM D3883 measures crimp on relaxed fabric), the
            summary's ``woven`` the cell under the weaving tension, ``yarn_tension`` the
            weaving tension, ``released`` what the release did. Needs the periodic cell.
        handling_tension: the yarn tension the released cell is held at (N per yarn or
            cN/tex, one for all or per family; default 0.05 cN/tex, a twentieth of a
            weaving tension: strings held at none shorten without end).
        trajectory: trajectory frames (``trajectory.h5``, ParaView files). The run
            stops once quasi-static, so frames are spread over :meth:`expected_steps`
            (the ramp and a quarter of the relaxation budget); the crimped state is
            always the last frame. ``TrajectoryOutput(frames=0)`` writes none.
    """

    expansion: dict[str, float] = field(default_factory=dict)
    hold_ends: bool = True
    contact: ContactModel = field(default_factory=ContactModel)
    damping: Damping = field(default_factory=Damping)
    quasi_static: QuasiStatic = field(default_factory=QuasiStatic)
    time_step: TimeStep = field(default_factory=TimeStep)
    ramp_transits: float = 40.0
    samples: int = 200
    trajectory: TrajectoryOutput = field(default_factory=lambda: TrajectoryOutput(frames=20))
    target_tension: dict | str | float | None = None
    target_crimp_pct: dict[str, float | str] = field(default_factory=dict)
    auto_margin_pct: float = 3.0
    crimp_by: str = "expansion"
    crimp_tolerance_pct: float = 0.05
    loose_height_start_m: dict[str, float | str] | float | str | None = None
    settle_force_n: float | None = None
    release_tension: bool = False
    handling_tension: dict | str | float = "0.05 cN/tex"

    def __post_init__(self):
        if not isinstance(self.expansion, dict):
            raise InputError(f"crimp.expansion must be a table family -> strain, "
                             f"got {self.expansion!r}")
        for fam, value in self.expansion.items():
            inputs.in_range(f"crimp.expansion.{fam}", value, -0.5, 0.5, low_open=True,
                            high_open=True)
        inputs.positive("crimp.ramp_transits", self.ramp_transits)
        inputs.positive_int("crimp.samples", self.samples, minimum=2)
        check_trajectory("crimp.trajectory", self.trajectory)
        if self.target_tension is not None:
            from .crimp_tension import check_target_tension

            check_target_tension(self.target_tension)
        if self.crimp_by not in CRIMP_BY:
            raise InputError(f"crimp.crimp_by must be one of {', '.join(CRIMP_BY)}, got "
                             f"{self.crimp_by!r}")
        inputs.positive("crimp.crimp_tolerance_pct", self.crimp_tolerance_pct)
        if self.settle_force_n is not None:
            inputs.positive("crimp.settle_force_n", self.settle_force_n)
        inputs.boolean("crimp.release_tension", self.release_tension)
        if self.release_tension:
            from .crimp_tension import check_target_tension

            check_target_tension(self.handling_tension, "crimp.handling_tension")
        if self.loose_height_start_m is not None:
            object.__setattr__(self, "loose_height_start_m", self._start_heights())
        if self.crimp_by == "loose_height":
            self._check_loose_height()
        elif self.target_crimp_pct:
            self._check_crimp_targets()
        if self.crimp_by == "loose_height":
            self.start_heights_m()  # names only searched families

    def _start_heights(self) -> dict[str, float] | float:
        """``loose_height_start_m`` read into metres (a dict per family or one value)."""
        from ..units import quantity

        key = "crimp.loose_height_start_m"
        given = self.loose_height_start_m
        if isinstance(given, dict):
            heights = {fam: quantity(v, "length", f"{key}.{fam}") for fam, v in given.items()}
            for fam, h in heights.items():
                inputs.positive(f"{key}.{fam}", h)
            return heights
        height = quantity(given, "length", key)
        inputs.positive(key, height)
        return height

    def start_heights_m(self) -> dict[str, float]:
        """The loose height [m] the search starts from per family of
        ``target_crimp_pct`` that ``loose_height_start_m`` names ({} where it is None)."""
        given = self.loose_height_start_m
        if given is None:
            return {}
        if isinstance(given, dict):
            unknown = sorted(set(given) - set(self.target_crimp_pct))
            if unknown:
                raise InputError(f"crimp.loose_height_start_m names {unknown}, whose crimp "
                                 f"is not searched (crimp.target_crimp_pct names "
                                 f"{sorted(self.target_crimp_pct)})")
            return dict(given)
        return {fam: float(given) for fam in self.target_crimp_pct}

    @property
    def pins_crimp(self) -> bool:
        """Crimp and tension reached together through the loose section (``crimp_by =
        "loose_height"``): the scene's cell is drawn again, see :attr:`crimp_by`."""
        return self.crimp_by == "loose_height"

    def _check_loose_height(self) -> None:
        from .crimp_target import check_target_crimp
        from .crimp_tension import check_target_tension

        words = {f: v for f, v in self.target_crimp_pct.items() if isinstance(v, str)}
        if not self.target_crimp_pct or words:
            raise InputError(
                "crimp.crimp_by = \"loose_height\" searches each family's loose section "
                "height for its crimp: give crimp.target_crimp_pct as numbers per family "
                f"(e.g. {{ warp = 1.5, weft = 1.5 }}), got {self.target_crimp_pct!r}")
        check_target_crimp(self.target_crimp_pct, self.auto_margin_pct)
        if self.target_tension is None:
            raise InputError(
                "crimp.crimp_by = \"loose_height\" reaches the crimp at a weaving tension: "
                "give crimp.target_tension too (e.g. \"1 cN/tex\"); a crimp alone is "
                "reached by the expansion (crimp_by = \"expansion\", the default)")
        check_target_tension(self.target_tension)
        tension = self.target_tension
        if isinstance(tension, dict):
            missing = sorted(set(self.target_crimp_pct) - set(tension))
            if missing:
                raise InputError(f"crimp.crimp_by = \"loose_height\": crimp.target_tension "
                                 f"names no tension for {missing}, whose crimp is a target "
                                 f"(the tension sets their expansion)")

    def _check_crimp_targets(self) -> None:
        from .crimp_target import check_target_crimp

        check_target_crimp(self.target_crimp_pct, self.auto_margin_pct)
        both = sorted(set(self.target_crimp_pct) & set(self.expansion))
        if both:
            raise InputError(f"crimp.target_crimp_pct and crimp.expansion both name {both}: "
                             f"a family's expansion is given or derived from its target "
                             f"crimp, not both")
        tension = self.target_tension
        named = set(tension) if isinstance(tension, dict) else (
            set() if tension is None else set(self.target_crimp_pct))
        # "auto" beside a target tension bounds the tension search's shrink
        numbers = {f for f, v in self.target_crimp_pct.items() if not isinstance(v, str)}
        if named & numbers:
            raise InputError(f"crimp.target_crimp_pct and crimp.target_tension both name "
                             f"{sorted(named & numbers)}: a family's expansion serves one "
                             f"target (\"auto\" may stand beside a tension: it bounds the "
                             f"shrink); crimp_by = \"loose_height\" reaches both, the "
                             f"crimp by the loose section's height")

    def release_stage(self):
        """The :class:`~fabmd.protocols.release.Release` run after the crimp
        (``release_tension``), with the crimp's contact, time step and settle force."""
        from .release import Release

        return Release(contact=self.contact, time_step=self.time_step,
                       handling_tension=self.handling_tension,
                       settle_force_n=self.settle_force_n)

    # -- derived from the model --------------------------------------------------------
    def check_model(self, model: BeadModel) -> None:
        if self.release_tension:
            self.release_stage().check_model(model)
        unknown = set(self.expansion) - set(model.family_names)
        if unknown:
            raise InputError(f"crimp.expansion names families {sorted(unknown)} that the fabric "
                             f"does not have (it has {list(model.family_names)})")
        self.family_expansion(model)  # refuses unreachable crimp targets

    def crimp_targets(self, model: BeadModel) -> dict[str, dict]:
        """Per family of ``target_crimp_pct``: loose rest crimp, target and the derived
        expansion (:func:`fabmd.protocols.crimp_target.derive_expansion`); {} without, or
        where the loose height serves the crimp."""
        if not self.target_crimp_pct or self.pins_crimp:
            return {}
        from .crimp_target import derive_expansion

        return derive_expansion(model, self.target_crimp_pct, self.auto_margin_pct)

    def family_expansion(self, model: BeadModel) -> dict[str, float]:
        """The strain α·ΔT per family the ramp reaches: ``expansion`` and those derived
        from ``target_crimp_pct`` (the same dict as ``expansion`` without targets, or
        where the loose height serves the crimp)."""
        if not self.target_crimp_pct or self.pins_crimp:
            return self.expansion
        derived = {f: t["expansion"] for f, t in self.crimp_targets(model).items()}
        return {**self.expansion, **derived}

    def shrink_warnings(self, model: BeadModel) -> list[str]:
        """Families told to shrink more than their loose crimp (``model.info["crimp"]``):
        such a yarn cannot end where a woven fabric is; it is pulled into straight
        zig-zags and bends what it crosses. One line per family."""
        loose = model.info.get("crimp") or {}
        out = []
        for fam, strain in self.family_expansion(model).items():
            crimp = loose.get(fam)
            if isinstance(crimp, int | float) and strain < 0 and -strain > crimp:
                out.append(f"crimp.expansion.{fam} = {strain:g} shrinks the {fam} yarns by "
                           f"{-100 * strain:.3g} %, more than their loose crimp "
                           f"{100 * crimp:.3g} %: they end straight and taut, not woven; "
                           f"shrink them by less than {100 * crimp:.3g} %")
        return out

    def rest_length_scale(self, model: BeadModel) -> dict[int, float]:
        """Final rest-length factor of every bond type (1-based)."""
        expansion = self.family_expansion(model)
        return {i: 1.0 + expansion.get(bt.family, 0.0)
                for i, bt in enumerate(model.bond_type_table, start=1)}

    def time_step_s(self, model: BeadModel) -> float:
        return self.plan(model).time_step_s

    def ramp_steps(self, model: BeadModel) -> int:
        return self.plan(model).extra["ramp_steps"]

    def expected_steps(self, model: BeadModel) -> int:
        """Steps the run is planned for: the ramp and a quarter of the relaxation budget
        (the relaxation stops once quasi-static); spaces history lines and frames."""
        return self.plan(model).steps

    def plan(self, model: BeadModel) -> RunPlan:
        """Time step, ramp steps, expected steps and output interval: derived once per
        model, kept in ``plan.json``."""
        return cached_plan(self, model, self.derive_plan)

    def derive_plan(self, model: BeadModel) -> RunPlan:
        dt = stable_time_step_s(model, [self.contact], self.time_step)
        ramp = max(1000, int(self.ramp_transits * fibre_transit_s(model) / dt))
        steps = ramp + self.quasi_static.max_steps // 4
        return RunPlan(time_step_s=dt, steps=steps, every=max(1, steps // self.samples),
                       duration_s=steps * dt, extra={"ramp_steps": ramp})

    def reference_force_n(self, model: BeadModel) -> float:
        """The relaxation's quasi-static reference force [N] (``settle_force_n``, else the
        force at :data:`SETTLE_STRAIN` of the stiffest fibre bond)."""
        if self.settle_force_n is not None:
            return float(self.settle_force_n)
        # no force stated: the force at 0.1 % fibre strain. The shrink's |expansion|·E·A
        # is tens of times the tension a woven fabric keeps: judged against it, the 3D
        # example's crimp stopped with its kinetic energy 5 % of its bonds' energy and
        # reported 3.0 N per binder, 0.12 N at rest (benchmarks/RESULTS.md "A crimp with
        # a stated shrink judged at rest")
        return SETTLE_STRAIN * max(bt.bond_axial_stiffness_n for bt in model.bond_type_table)

    def reference_energy_j(self, model: BeadModel) -> float:
        """Strain energy of every bond at the reference force, F²/(2k) each [J]."""
        f = self.reference_force_n(model)
        k = max(bt.spring_n_per_m for bt in model.bond_type_table)
        return model.n_bonds * f * f / (2 * k)

    def held_beads(self, model: BeadModel) -> np.ndarray:
        if not self.hold_ends or any(model.periodic[:2]):
            return np.zeros(0, np.int64)
        return np.unique(model.fibre_ends().ravel())

    def input_text(self, model: BeadModel) -> str:
        self.check_model(model)
        dt = self.time_step_s(model)
        beads = model_bead_parameters(model)
        ramp = self.ramp_steps(model)
        every = self.plan(model).every
        held = self.held_beads(model)
        if len(held):
            hold_fix = "# held beads are not integrated: they keep their position"
        else:
            hold_fix = "# periodic cell: nothing is held"
        scale = self.rest_length_scale(model)
        strains = {i: scale[i] - 1.0 for i in scale}
        mass = float(np.median(model.masses))
        text = render(
            "crimp", held_group=blocks.group_ids("held", held + 1),
            ramp=blocks.bond_ramp(model, "crimp", strains), hold_fix=hold_fix,
            damping=self.damping.commands("free", mass, default_time_s=ramp * dt / 10),
            monitors=self.quasi_static.monitors("free", self.reference_force_n(model),
                                                self.reference_energy_j(model)),
            every=every, ramp_steps=ramp,
            ramp_end=blocks.bond_ramp_end(model, "crimp", scale),
            stop_fix=self.quasi_static.stop_when_reached(),
            relax_steps=self.quasi_static.max_steps)
        max_scale = max(1.0, *scale.values())
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            blocks.overlap_monitor(model, self.contact, beads, every=every),
            blocks.guards(model, dt, max_rest_length_scale=max_scale, check_lost=False),
            self.trajectory.commands(self.expected_steps(model)),
            text,
            self.trajectory.final_commands(),
            blocks.lost_check(),
            render("finish", final_data=f"{CRIMPED}.data"),
        ])

    # -- run ------------------------------------------------------------------------
    def run(self, model: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False, resume: bool = False, figures: bool = True,
            quiet: bool = False) -> CrimpResult:
        """Crimp ``model`` (the loose fabric); returns the as-woven state and its measures.

        ``figures=False`` draws no ``sections.png``, ``cuts/`` and ``history.png`` (the
        calibration's trial runs: the figures take longer than a small cell's crimp).

        ``resume``: continue the interrupted crimp in ``out`` from its checkpoint. A shrink
        beyond a family's loose crimp is warned about (``UserWarning``) and listed in the
        summary's ``shrink_warnings``. With ``target_tension``, several crimp runs search
        the expansion for it (not resumable: a resume starts the search again). A crimp
        interchange (warp and weft drawn alike, crimped apart: :func:`crimp_interchange`)
        is warned about and kept in the summary's ``crimp_interchange``; ``quiet``: not
        warned (the runs of a search, which judges the outcome itself).
        """
        if self.pins_crimp:
            raise InputError("crimp.crimp_by = \"loose_height\" draws the scene's cell again "
                             "for each loose height: crimp from the scene (fabmd crimp / "
                             "fabmd test, fabmd.pipeline.run_crimp, or "
                             "fabmd.loose_height.pin_crimp, which returns the scene to crimp)")
        engine = engine or Engine()
        if self.release_tension:  # the crimp (and its searches) first, then the release
            self.check_model(model)
            woven = dataclasses.replace(self, release_tension=False).run(
                model, out, engine=engine, overwrite=overwrite, resume=resume,
                figures=figures, quiet=quiet)
            return release_crimped(self, woven, engine, figures=figures)
        if self.target_tension is not None:
            from .crimp_tension import crimp_to_tension

            self.check_model(model)
            return crimp_to_tension(self, model, out, engine=engine, overwrite=overwrite,
                                    quiet=quiet)
        shrink = self.shrink_warnings(model)
        if mpi.is_root() and not quiet:  # a search's runs: judged on what they crimp
            for message in shrink:
                warnings.warn(message, UserWarning, stacklevel=2)
        model = with_room_in_z(model)
        text = self.input_text(model)  # validates before anything is written
        run_dir = open_run_folder(out, PROTOCOL, model, text,
                                  {"crimp": scene_dict(self), "model": model.metadata()},
                                  overwrite, resume, plan=self.plan(model),
                                  files=blocks.contact_files(self.contact,
                                                             model_bead_parameters(model)))
        run, trajectory = run_with_trajectory(engine, run_dir, PROTOCOL, self.trajectory, model,
                                              resume)
        summary = None
        crimped = None
        if mpi.is_root():
            crimped, summary = reduce(run_dir, model, self, figures=figures)
            summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend,
                           shrink_warnings=shrink,
                           trajectory=trajectory.name if trajectory else None)
            write_json(run_dir / "summary.json", summary)
            if not quiet:
                warn_interchange(run_dir, summary, stacklevel=3)
        summary = mpi.bcast_json(summary)
        if crimped is None:
            crimped = load_crimped(run_dir, released=False)
        return CrimpResult(Path(run_dir), crimped, summary)


@dataclass
class CrimpResult:
    """The as-woven bead model and the measures of the crimp run."""

    run_dir: Path
    model: BeadModel
    summary: dict


#: the crimp folder's subfolder of the release (``Crimp.release_tension``)
RELEASE_DIR = "release"


def release_crimped(crimp: Crimp, woven: CrimpResult, engine: Engine,
                    figures: bool = True) -> CrimpResult:
    """Release the woven cell of ``woven`` (:meth:`Crimp.release_stage`, in its folder's
    ``release/``); the result is the released cell, its summary the crimp's with
    ``crimped`` the released cell's measures, ``woven`` the woven cell's and ``released``
    the release's (written back to the crimp's ``summary.json``)."""
    from .release import RELEASE_KEYS

    release = crimp.release_stage().run(woven.model, Path(woven.run_dir) / RELEASE_DIR,
                                        engine=engine, overwrite=True)
    rs = release.summary
    summary = dict(woven.summary)
    summary.update(woven=summary["crimped"], crimped=rs["released"],
                   areal_density_kg_m2=rs["areal_density_kg_m2"],
                   released={k: rs[k] for k in RELEASE_KEYS})
    if mpi.is_root():
        write_json(Path(woven.run_dir) / "summary.json", summary)
        if figures:
            preview_png(release.model, Path(release.run_dir) / "sections.png",
                        title="Released: the as-woven cell without its weaving tension")
    return CrimpResult(Path(woven.run_dir), release.model, summary)


def with_room_in_z(model: BeadModel, margin_diameters: float = 6.0) -> BeadModel:
    """The model with at least ``margin_diameters`` bead diameters of box above and below."""
    z = model.positions[:, 2]
    need = margin_diameters * float(model.diameters.max())
    lo = min(model.box_lo[2], z.min() - need)
    hi = max(model.box_hi[2], z.max() + need)
    if lo == model.box_lo[2] and hi == model.box_hi[2]:
        return model
    box_lo, box_hi = model.box_lo.copy(), model.box_hi.copy()
    box_lo[2], box_hi[2] = lo, hi
    return BeadModel(**{**model.__dict__, "box_lo": box_lo, "box_hi": box_hi})


def has_release(run_dir: Path) -> bool:
    """Did the crimp in ``run_dir`` end with a finished release (``release/``)?"""
    return (Path(run_dir) / RELEASE_DIR / "summary.json").exists()


def load_crimped(run_dir: Path, released: bool = True) -> BeadModel:
    """The crimp stage's product: the released cell where the crimp released its weaving
    tension (``release/``, unless ``released`` is False), else the as-woven model LAMMPS
    wrote (``crimped.data`` + the loose model's metadata)."""
    run_dir = Path(run_dir)
    if released and has_release(run_dir):
        from .release import load_released

        return load_released(run_dir / RELEASE_DIR)
    meta = run_dir / f"{CRIMPED}.json"
    if not meta.exists():
        meta = run_dir / "model.json"
    return BeadModel.load(run_dir / f"{CRIMPED}.data", meta)


def reduce(run_dir: Path, loose: BeadModel, crimp: Crimp,
           figures: bool = True) -> tuple[BeadModel, dict]:
    """Read the crimp run back: crimped model (with final rest lengths), measures, history
    (and its figures unless ``figures`` is False)."""
    run_dir = Path(run_dir)
    raw = read_print_file(run_dir / "history.dat")
    crimped = BeadModel.load(run_dir / f"{CRIMPED}.data", run_dir / "model.json")
    scale = crimp.rest_length_scale(loose)
    # the crimped model carries its final rest lengths, so later stages start unstressed
    # only where the fabric is; bond coefficients stay those of the original E·A/l0
    from ..model.bead_model import BondType

    crimped.bond_type_table = [
        BondType(bt.coefficient, bt.rest_length_m * scale[i], bt.family, bt.axial_stiffness_n,
                 spec=bt.spec)
        for i, bt in enumerate(crimped.bond_type_table, start=1)]
    expansion = crimp.family_expansion(loose)
    crimped.info = dict(crimped.info, crimp={"expansion": expansion})
    crimped.save(run_dir, stem=CRIMPED)
    qs = crimp.quasi_static
    # how the run ended, from LAMMPS's log: the relaxation stops at its 'settled' halt,
    # usually between two history lines
    end = read_run_end(run_dir, relaxation=True)
    if end is None:  # no log (e.g. removed): fall back on the last history line
        settled = bool(raw["ke_ratio"][-1] < qs.kinetic_ratio
                       and raw["force_ratio"][-1] < qs.force_ratio)
        end = RunEnd(int(raw["step"][-1]), "quasi-static" if settled else "budget")
    settled = end.quasi_static
    steps = end.final_step
    if not settled:
        warnings.warn(f"crimp in {run_dir}: {end.sentence()}; the crimped state may still be "
                      f"moving (raise crimp.quasi_static.max_steps)", QuasiStaticWarning,
                      stacklevel=2)
    # the last history line's KE over the bonds' energy, no floor: a state still moving
    # shows here whatever the reference
    moving = float(raw["kinetic_j"][-1] / max(raw["strain_energy_j"][-1], 1e-300))
    final_ke = end.final_thermo.get("v_qs_ke_ratio", float(raw["ke_ratio"][-1]))
    final_force = end.final_thermo.get("v_qs_force_ratio", float(raw["force_ratio"][-1]))
    history = {"step": raw["step"], "kinetic_energy_j": raw["kinetic_j"],
               "strain_energy_j": raw["strain_energy_j"],
               "ke_to_strain_energy": raw["ke_ratio"], "force_residual_ratio": raw["force_ratio"],
               "thickness_m": raw["bead_centre_span_m"] + float(loose.diameters.max())}
    write_csv(run_dir / "history.csv", history)
    plan = read_plan(run_dir) or crimp.plan(loose)  # what the run was written with
    ramp = plan.extra["ramp_steps"]
    if figures:
        _figures(run_dir, crimped, raw, history, end, final_ke, qs.kinetic_ratio, ramp)
    summary = {
        "protocol": PROTOCOL,
        "expansion": expansion,
        # where the expansion came from the crimp the fabric needs: loose, target, strain
        "crimp_targets": crimp.crimp_targets(loose) or None,
        "time_step_s": plan.time_step_s,
        "ramp_steps": ramp,
        "steps": steps,
        "stopped_by": end.stopped_by,
        "stop": end.sentence(),
        "quasi_static": settled,
        "criterion": {"kinetic_ratio": qs.kinetic_ratio, "force_ratio": qs.force_ratio,
                      "final_kinetic_ratio": float(final_ke),
                      "final_force_ratio": float(final_force),
                      "reference_force_n": crimp.reference_force_n(loose),
                      "final_kinetic_to_strain_energy": moving,
                      "max_steps": qs.max_steps},
        "loose": fabric_measures(loose),
        "crimped": fabric_measures(crimped),
        "overlap": overlap_summary(run_dir, crimp.contact),
        # where the law's fibres touch in this model: its first kPa are cut off above Vf0
        "within_family_law": crimp.contact.law_realisation(loose.family_names),
        # no yarn may pass through another on the way to the woven state
        "pass_through": passed_through(loose, crimped),
        "areal_density_kg_m2": areal_density_kg_m2(crimped),
        "datasheet": loose.info.get("datasheet"),
        # the tension the crimp leaves in the yarns (N per yarn, cN/tex), per family
        "yarn_tension": yarn_tension(crimped),
    }
    summary["crimp_interchange"] = crimp_interchange(summary["loose"], summary["crimped"])
    return crimped, summary


def _figures(run_dir: Path, crimped: BeadModel, raw, history: dict, end, final_ke: float,
             kinetic_limit: float, ramp: int) -> None:
    """The crimp's pictures: sections, cuts and the thickness history."""
    steps = end.final_step
    preview_png(crimped, run_dir / "sections.png",
                title="As-woven state after the crimp stage (cuts along warp and weft)")
    cut_pngs(crimped, run_dir / "cuts", title="As-woven state after the crimp stage")
    plot_curves(run_dir / "history.png", [
        {"x": raw["step"], "y": 1e3 * history["thickness_m"], "label": "thickness"},
    ], "time step [–]", "thickness [mm]",
        title="Crimp: thickness during ramp and relaxation",
        notes=f"{end.sentence()}\nKE/U at the end {final_ke:.3g}"
              f" (limit {kinetic_limit:.3g})",
        marks=[{"kind": "vline", "x": ramp, "label": f"ramp ends (step {ramp:,})"},
               {"kind": "vline", "x": steps, "style": "-",
                "label": f"LAMMPS stopped (step {steps:,}): {end.stopped_by}"}])
