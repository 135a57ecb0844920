"""What every protocol does around its own fixes: write the run folder, run, read back."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..describe import scene_dict  # noqa: F401 - protocols take it from here
from ..engine import Engine, EngineResult, mpi
from ..engine.library import REQUIRED_PACKAGES
from ..engine.run_script import run_sh_text
from ..errors import OverlapWarning, SimulationFailed
from ..model.bead_model import BeadModel
from ..model.contact import ContactModel
from ..results.folder import prepare_run_folder, read_print_file, write_csv, write_json
from ..results.trajectory import finalise, salvage
from ..scene.blocks import OVERLAP_FILE, TOOL_OVERLAP_WARNING
from ..scene.outputs import TrajectoryOutput
from ..scene.plan import RunPlan

DATA_FILE = "model.data"


@dataclass
class RunResult:
    """Curve and summary of a run; :meth:`write` saves them (rank 0) with the plot."""

    run_dir: Path
    curve: dict[str, np.ndarray]
    summary: dict

    def write(self) -> None:
        if not mpi.is_root():
            return
        write_csv(self.run_dir / "curve.csv", self.curve)
        write_json(self.run_dir / "summary.json", self.summary)
        self.plot()

    def plot(self) -> None:
        """The protocol's plot(s) into the run folder (none by default)."""


@dataclass
class StateResult:
    """A stage that leaves a fabric state for the next (a coupon, a released cell): its run
    folder, the state and the stage's summary."""

    run_dir: Path
    model: BeadModel
    summary: dict


def load_state(run_dir: Path, stem: str) -> BeadModel:
    """A saved fabric state of a run folder (``<stem>.data`` + ``<stem>.json``)."""
    run_dir = Path(run_dir)
    return BeadModel.load(run_dir / f"{stem}.data", run_dir / f"{stem}.json")


def input_name(protocol: str) -> str:
    """``in.<protocol>``: the input file name of a protocol."""
    return f"in.{protocol}"


def write_run_folder(out: Path | None, protocol: str, model: BeadModel, input_text: str,
                     scene: dict, overwrite: bool = False,
                     files: dict[str, str] | None = None) -> Path:
    """Create the run folder and write data file, metadata, input, scene and ``run.sh``
    (``files``: more files the input reads, name -> text, e.g.
    :func:`fabmd.scene.blocks.contact_files`)."""
    run_dir = prepare_run_folder(out, overwrite=overwrite, prefix=protocol)
    if mpi.is_root():
        model.save(run_dir, stem=Path(DATA_FILE).stem)
        name = input_name(protocol)
        (run_dir / name).write_text(input_text)
        for file_name, text in (files or {}).items():
            (run_dir / file_name).write_text(text)
        write_json(run_dir / "scene.json", scene)
        (run_dir / "run.sh").write_text(run_sh_text(name))
        write_slurm_script(run_dir, name, model.n_beads)
    mpi.barrier()  # every rank reads the input that rank 0 wrote
    return run_dir


#: beads per MPI rank a Slurm script asks for: the cluster projection (benchmarks/RESULTS.md,
#: "Cluster projection") keeps >= 85 % parallel efficiency there on the 3D fabric
BEADS_PER_RANK = 5000
#: most ranks a Slurm script asks for (64 left the 19-fibre 3D picture frame ~40 h)
MAX_SLURM_RANKS = 1024
#: rank counts LAMMPS splits a sheet into even patches with (a prime count makes strips)
EVEN_RANKS = tuple(sorted({m * 2**k for k in range(11) for m in (1, 3)}))
SLURM_SCRIPT = "slurm.sh"


def slurm_ranks(n_beads: int, beads_per_rank: int = BEADS_PER_RANK) -> int:
    """MPI ranks for a model of ``n_beads`` beads: one per ``beads_per_rank``, rounded
    down to 2^k or 3·2^k (:data:`EVEN_RANKS`), 1 to :data:`MAX_SLURM_RANKS`."""
    want = max(1, min(MAX_SLURM_RANKS, n_beads // beads_per_rank))
    return max(r for r in EVEN_RANKS if r <= want)


def write_slurm_script(run_dir: Path, input_name_: str, n_beads: int,
                       hours: float = 12.0) -> Path:
    """``slurm.sh`` beside ``run.sh``: the same LAMMPS command as a Slurm batch job.

    Ranks from the model's size (:func:`slurm_ranks`), a wall time of ``hours``; both
    are ``#SBATCH`` lines to edit. Submit from the run folder (``sbatch slurm.sh``);
    ``LMP`` names the cluster's LAMMPS (default ``lmp``), ``MPIRUN`` its launcher
    (default ``srun``; e.g. ``MPIRUN="mpirun -np $SLURM_NTASKS"``).
    """
    ranks = slurm_ranks(n_beads)
    minutes = int(round(hours * 60))
    lines = [
        "#!/bin/bash",
        "# Slurm batch job: this folder with plain LAMMPS (the command of run.sh).",
        "#   cd THIS_FOLDER && sbatch slurm.sh",
        f"# Ranks: one per {BEADS_PER_RANK} beads ({n_beads} here), rounded down to 2^k or"
        f" 3*2^k, at most {MAX_SLURM_RANKS}. Edit the lines below",
        "# (partition, account, time) for your cluster. It needs a LAMMPS with the packages",
        f"# {' '.join(REQUIRED_PACKAGES)} (e.g. module load lammps).",
        f"#SBATCH --job-name=fabmd-{Path(input_name_).suffix.lstrip('.') or 'run'}",
        f"#SBATCH --ntasks={ranks}",
        "#SBATCH --cpus-per-task=1",
        f"#SBATCH --time={minutes // 60:02d}:{minutes % 60:02d}:00",
        "#SBATCH --output=slurm-%j.out",
        'cd "${SLURM_SUBMIT_DIR:-$(dirname "$0")}"',
        'export OMP_NUM_THREADS="${SLURM_CPUS_PER_TASK:-1}"',
        f'exec ${{MPIRUN:-srun}} "${{LMP:-lmp}}" -in {input_name_} -log log.lammps',
    ]
    path = Path(run_dir) / SLURM_SCRIPT
    path.write_text("\n".join(lines) + "\n")
    return path


def resume_folder(out: Path | None) -> Path:
    """The run folder to resume: it must exist and hold a checkpoint."""
    from ..engine.checkpoint import has_checkpoint
    from ..errors import InputError

    if out is None or not has_checkpoint(out):
        raise InputError(f"nothing to resume in {out}: no checkpoint there (run with "
                         f"checkpoints on, e.g. --checkpoint-every STEPS)")
    return Path(out).resolve()


def run_folder(engine: Engine, run_dir: Path, protocol: str, resume: bool = False,
               **options) -> EngineResult:
    """Run the protocol's input in ``run_dir`` with ``engine`` (``resume``: from its
    checkpoint; ``options``: more keywords of :meth:`Engine.run`, e.g. ``monitor``)."""
    return engine.run(run_dir, input_name(protocol), label=protocol, resume=resume, **options)


def open_run_folder(out: Path | None, protocol: str, model: BeadModel, input_text: str,
                    scene: dict, overwrite: bool = False, resume: bool = False,
                    plan: RunPlan | None = None, files: dict[str, str] | None = None) -> Path:
    """The run folder: ``out`` to resume from its checkpoint (``resume``), else a new one
    (:func:`write_run_folder`, with ``files``) with the run's ``plan`` in ``plan.json``."""
    if resume:
        return resume_folder(out)
    run_dir = write_run_folder(out, protocol, model, input_text, scene, overwrite=overwrite,
                               files=files)
    if plan is not None and mpi.is_root():
        plan.write(run_dir)
    return run_dir


def run_with_trajectory(engine: Engine, run_dir: Path, protocol: str,
                        trajectory: TrajectoryOutput, model: BeadModel, resume: bool = False,
                        **options) -> tuple[EngineResult, Path | None]:
    """:func:`run_folder`, then the run's trajectory converted
    (:func:`fabmd.results.trajectory.finalise`, every rank); a failed run keeps the frames
    up to the failure (``salvage``) and raises. Returns the engine's result and the
    trajectory file (None: none written)."""
    try:
        run = run_folder(engine, run_dir, protocol, resume, **options)
    except SimulationFailed:
        salvage(run_dir, paraview=trajectory.paraview, model=model)
        raise
    return run, finalise(run_dir, paraview=trajectory.paraview, model=model)


def overlap_summary(run_dir: Path, contact_model: ContactModel | None = None,
                    file: str = OVERLAP_FILE, warn: bool = True) -> dict:
    """Largest overlaps a run saw, from the file :func:`fabmd.scene.blocks.overlap_monitor` wrote.

    Returns ``max_overlap_ratio`` (overlap/d, fibre–fibre and tool), its two parts, the
    warning threshold and a ``warnings`` list (empty when all is well); issues an
    :class:`fabmd.errors.OverlapWarning` past ``contact_model.overlap_warning`` (rank 0).
    Empty dict when the run had no monitor. Call it on rank 0 (where the file is read).
    """
    path = Path(run_dir) / file
    if not path.exists():
        return {}
    raw = read_print_file(path)
    threshold = contact_model.overlap_warning if contact_model else TOOL_OVERLAP_WARNING
    pair = raw["pair_overlap_ratio"]
    tool = raw["tool_overlap_ratio"]
    worst_pair = float(pair.max()) if pair.size else 0.0
    worst_tool = float(tool.max()) if tool.size else 0.0
    worst = max(worst_pair, worst_tool)
    messages = []
    if worst > threshold:
        step = int(raw["step"][np.argmax(np.maximum(pair, tool))])
        messages.append(f"largest overlap {worst:.3g} d (step {step}) is above the warning "
                        f"limit {threshold:g} d: contact too soft for these loads; raise the "
                        f"contact normal_stiffness_pa or load less")
        if warn and mpi.is_root():
            warnings.warn(messages[-1], OverlapWarning, stacklevel=2)
    return {"max_overlap_ratio": worst, "max_pair_overlap_ratio": worst_pair,
            "max_tool_overlap_ratio": worst_tool, "overlap_warning_ratio": threshold,
            "overlap_samples": int(pair.size), "warnings": messages}
