"""Granular pair styles on the same bead system, timed side by side in one process.

A hexagonal bundle of virtual fibres (E-glass, d = 0.1 mm, s/d = 0.5) packed 0.3 %
into each other, with random bead velocities so that contacts press and slide,
runs the same number of steps with each style that carries fabmd's contact
physics:

* ``gran/hooke`` (no tangential history: carries no Coulomb friction, μ = 0 only),
* ``gran/hooke/history`` and ``gran/hertz/history`` (fabmd's defaults),
* ``granular`` with the same Hooke/Hertz + linear_history model (no /omp version),
* the ``gran/*`` styles again as ``/omp`` with 2 OpenMP threads,
* ``gran/hooke/history`` with fabmd's overlap monitor (its cost).

Printed: the Pair time and the whole loop time (best of ``--repeat``), both as
ratios to ``granular`` (hooke) on one thread; and, as a check that the styles
compared are the same physics, the largest force difference between
``gran/hooke/history`` and ``granular hooke ... linear_history`` on step 0.

    python benchmarks/pair_styles.py [--rings 4] [--beads 200] [--steps 300] [--repeat 3] [--write]
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import table, update_section  # noqa: E402

from fabmd.engine.library import new_instance  # noqa: E402
from fabmd.engine.script import logical_lines  # noqa: E402
from fabmd.model.bead_model import BeadModel, BondType, Yarn  # noqa: E402
from fabmd.model.beads import bead_parameters  # noqa: E402
from fabmd.model.contact import ContactModel  # noqa: E402
from fabmd.model.material import GLASS, VirtualFibre  # noqa: E402
from fabmd.scene import blocks  # noqa: E402

OVERLAP = 0.003


def bundle(rings: int, beads_per_fibre: int):
    """Hexagonal bundle of fibres along x, centres (1 − OVERLAP)·d apart."""
    b = bead_parameters(VirtualFibre.solid(GLASS, 0.1e-3))
    d, l0 = b.diameter_m, b.bond_length_m
    pitch = (1 - OVERLAP) * d
    centres = []
    for q in range(-rings, rings + 1):
        for r in range(-rings, rings + 1):
            if abs(q + r) <= rings:
                centres.append((pitch * (q + 0.5 * r), pitch * r * np.sqrt(3) / 2))
    n_f, n_b = len(centres), beads_per_fibre
    x = l0 * np.arange(n_b)
    pos = np.vstack([np.column_stack([x, np.full(n_b, y), np.full(n_b, z)])
                     for y, z in centres])
    first = np.arange(n_f)[:, None] * n_b
    chain = np.column_stack([np.arange(n_b - 1), np.arange(1, n_b)])
    bonds = np.vstack([first[i] + chain for i in range(n_f)])
    pad = 10 * d
    model = BeadModel(
        positions=pos, diameters=d, masses=b.mass_kg, atom_types=1,
        fibre_ids=np.repeat(np.arange(1, n_f + 1), n_b), bonds=bonds, bond_types=1,
        family_names=("fibre",),
        bond_type_table=[BondType(b.bond_coefficient, l0, "fibre", b.axial_stiffness_n)],
        fibre_yarn=np.ones(n_f, np.int64), yarns=[Yarn("bundle", "fibre")],
        box_lo=pos.min(axis=0) - pad, box_hi=pos.max(axis=0) + pad)
    return model, b


def pair_lines(style: str, contact: ContactModel, b) -> str:
    """``pair_style``/``pair_coeff`` for one of the compared styles (same physics)."""
    c = contact.pair_coefficients([b])
    k = f"{c['kn']:.10g} {c['kt']:.10g} {c['gamman']:.10g} {c['gammat']:.10g} {c['friction']:g} 1"
    if style.startswith("gran/"):
        text = f"pair_style {style} {k}\npair_coeff * *"
    else:
        # classic hertz multiplies Kt and both dampings by a = sqrt(delta R); granular's
        # 'viscoelastic' damping does the same for damping, its linear_history Kt does not
        # (Kt taken at the reference overlap here)
        kt, damping = c["kt"], "mass_velocity"
        if contact.normal == "hertz":
            kt *= np.sqrt(contact.reference_overlap * b.diameter_m ** 2 / 4)
            damping = "viscoelastic"
        text = (f"pair_style granular\npair_coeff * * {contact.normal} {c['kn']:.10g} "
                f"{c['gamman']:.10g} tangential linear_history {kt:.10g} "
                f"{c['gammat'] / c['gamman']:.10g} {c['friction']:g} damping {damping}")
    return text + "\nneigh_modify exclude molecule/intra all"


def input_text(model, b, contact, style, steps: int, monitor_every: int = 0) -> str:
    dt = 0.25 * b.critical_time_step_s(contact.normal_stiffness_n_per_m([b]))
    v = 1e-3 * GLASS.wave_speed_m_s
    monitor = blocks.overlap_monitor(model, contact, [b], every=monitor_every) \
        if monitor_every else ""
    return "\n".join([
        blocks.setup(model, "bench", "model.data", dt), blocks.bonds(model),
        pair_lines(style, contact, b),
        f"variable vx atom normal(0,{v},1)\nvariable vy atom normal(0,{v},2)\n"
        f"variable vz atom normal(0,{v},3)\nvelocity all set v_vx v_vy v_vz\n"
        "fix integrate all nve\nthermo 0", monitor,
        f"run {steps}",
    ])


def run(folder: Path, text: str, threads: int) -> tuple[float, float, np.ndarray]:
    """(pair time, loop time, forces after the run) of one input."""
    log = folder / "log.lammps"
    args = ["-log", str(log), "-screen", "none", "-nocite"]
    if threads > 1:
        args += ["-sf", "omp", "-pk", "omp", str(threads)]
    old = os.getcwd()
    os.chdir(folder)
    lmp = new_instance(args)
    try:
        for command in logical_lines(text):
            lmp.command(command)
        ids = lmp.numpy.extract_atom("id").copy()
        f = lmp.numpy.extract_atom("f")[np.argsort(ids)].copy()
    finally:
        lmp.close()
        os.chdir(old)
    out = log.read_text()
    loop = float(re.search(r"Loop time of ([\d.eE+-]+)", out.split("run ")[-1]).group(1))
    pair = float(re.search(r"^Pair\s*\|\s*[\d.eE+-]+\s*\|\s*([\d.eE+-]+)", out, re.M).group(1))
    return pair, loop, f


CONFIGS = [  # (label, style, normal, friction, threads[, overlap monitor every])
    ("granular hooke + linear_history", "granular", "hooke", 0.3, 1),
    ("granular hertz + linear_history", "granular", "hertz", 0.3, 1),
    ("gran/hooke (mu = 0 only)", "gran/hooke", "hooke", 0.0, 1),
    ("gran/hooke/history", "gran/hooke/history", "hooke", 0.3, 1),
    ("gran/hertz/history", "gran/hertz/history", "hertz", 0.3, 1),
    ("gran/hooke/history + overlap monitor every 100", "gran/hooke/history", "hooke", 0.3, 1,
     100),
    ("gran/hooke/history + overlap monitor every 20", "gran/hooke/history", "hooke", 0.3, 1,
     20),
    ("gran/hooke/omp, 2 threads (mu = 0)", "gran/hooke", "hooke", 0.0, 2),
    ("gran/hooke/history/omp, 2 threads", "gran/hooke/history", "hooke", 0.3, 2),
    ("gran/hertz/history/omp, 2 threads", "gran/hertz/history", "hertz", 0.3, 2),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rings", type=int, default=4, help="hexagonal rings of fibres")
    parser.add_argument("--beads", type=int, default=200, help="beads per fibre")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    args = parser.parse_args()

    model, b = bundle(args.rings, args.beads)
    root = Path(tempfile.mkdtemp(prefix="fabmd-pair-bench-"))
    model.save(root, stem="model")

    # same physics? gran/hooke/history against granular hooke, step 0
    c = ContactModel(friction=0.3)
    f_classic = run(root, input_text(model, b, c, "gran/hooke/history", 0), 1)[2]
    f_general = run(root, input_text(model, b, c, "granular", 0), 1)[2]
    same = float(np.abs(f_classic - f_general).max() / np.abs(f_classic).max())

    times = {}
    for label, style, normal, mu, threads, *every in CONFIGS:
        contact = ContactModel(friction=mu, normal=normal)
        text = input_text(model, b, contact, style, args.steps, *every)
        best = min((run(root, text, threads)[:2] for _ in range(args.repeat)),
                   key=lambda t: t[1])
        times[label] = best
        print(f"  {label:40s} pair {best[0]:.3f} s, loop {best[1]:.3f} s", flush=True)
    ref_pair, ref_loop = times[CONFIGS[0][0]]
    rows = [[label, threads, times[label][0], times[label][1], ref_pair / times[label][0],
             ref_loop / times[label][1]] for label, _s, _n, _m, threads, *_e in CONFIGS]
    header = ["style", "threads", "pair s", "loop s", "pair speed-up vs granular",
              "loop speed-up vs granular"]
    body = (f"{model.n_beads} beads in {model.n_fibres} fibres (hexagonal bundle, "
            f"{100 * OVERLAP:g} % overlap, random velocities), {args.steps} steps, "
            f"best of {args.repeat}; "
            f"speed-up = time of `granular` hooke on 1 thread / time.\n"
            f"Same physics: largest force difference gran/hooke/history vs granular hooke "
            f"linear_history on step 0: {same:.1e} of the largest force.\n\n"
            + table(header, rows))
    t = {label: times[label] for label in times}
    hh = t["gran/hooke/history"]
    body += (
        "\n\nChoice (`ContactModel.pair_style()`): `gran/hooke` when μ = 0 with Hooke "
        "contact (no tangential force, no history to store), else `gran/hooke/history` "
        "(Hertz: `gran/hertz/history`). `granular` carries the same physics at "
        f"{t[CONFIGS[0][0]][1] / hh[1]:.1f}× the loop time ({t[CONFIGS[0][0]][0] / hh[0]:.1f}× "
        "the pair time) and has no OpenMP version. The overlap monitor sampled every 100 "
        f"steps costs {100 * (t[CONFIGS[5][0]][1] / hh[1] - 1):.0f} % of the loop. "
        "Timings with 2 threads are noisy on a shared 2-core machine; rerun on a quiet one.")
    print(body)
    if args.write:
        update_section("Pair styles", body, "python benchmarks/pair_styles.py --write")


if __name__ == "__main__":
    main()
