"""The presets against a refined reference on the example as shipped: run time and error.

Runs :mod:`fabmd.presets`' ``--fast``, default and ``--accurate`` discretisations of
``examples/plain_weave.toml`` and a reference (19 virtual fibres per yarn, s/d 0.5, half the
example's loading speed) with the runner of ``benchmarks/accuracy.py``: per discretisation
one crimp of the periodic cell, then a tension coupon of 3 x 1 cells (to the example's
elongation) and a picture frame of 2 x 2 cells (to the example's angle), each at the
example's ``speed_fraction`` times the preset's speed factor, one run after the other in
this process. Prints per preset the signed error of every report value against the
reference, the largest of them per test (tension: force at 4/5/6 %, past the coupon's
toe; picture frame: normalised force at 10/20/30/40 deg and the locking angle) and the run
time (crimp + both tests) and its ratio to the default's.

The reference is not converged in bead spacing (``benchmarks/RESULTS.md``, "Crimp pinned by
the loose height" and "Where the plain weave's convergence stands"): the errors are
distances to it, not to the fabric.

    python benchmarks/presets.py [--write] [--resume] [--root DIR]

``--write`` replaces the RESULTS section "Presets against the reference"; results go to
``benchmarks/presets.json`` as they come (``--resume`` keeps those already there).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import accuracy  # noqa: E402
from _results import table, update_section  # noqa: E402

from fabmd.presets import PRESETS  # noqa: E402

DATA = Path(__file__).resolve().parent / "presets.json"
COMMAND = "python benchmarks/presets.py --write"
#: the values whose largest error is a test's error: tension past the 3-cell coupon's toe
#: (about 2.4 %: RESULTS "Tension coupon length"), the picture frame's report angles
COMBINED = {"tension": ("F4%", "F5%", "F6%"),
            "picture_frame": ("F10°", "F20°", "F30°", "F40°", "locking")}
REFERENCE = accuracy.REFERENCE


def configs() -> dict[str, accuracy.Config]:
    """The presets' configurations and the reference, cheapest first."""
    out = {name: accuracy.preset_config(name) for name in PRESETS}
    out = dict(sorted(out.items(), key=lambda kv: (kv[1].n_fibres, -kv[1].spacing_ratio)))
    out["reference"] = REFERENCE
    return out


def _pct(value) -> str:
    return "–" if value is None else f"{100 * value:+.1f}"


def rows(data: dict) -> tuple[list[list], dict]:
    """Table rows (one per preset) and each preset's errors."""
    records = {r["label"]: r for r in data["records"]}
    ref = records[REFERENCE.label]
    default = records.get(accuracy.preset_config("default").label, ref)
    out, errors = [], {}
    for name, config in configs().items():
        if config.label not in records or name == "reference":
            continue
        r = records[config.label]
        e = accuracy.relative_errors(r, ref, COMBINED)
        errors[name] = e
        te, pe = e["tension"]["values"], e["picture_frame"]["values"]
        lock, lock_ref = r["picture_frame"]["values"]["locking"], \
            ref["picture_frame"]["values"]["locking"]
        out.append([name, config.label, r["crimp"]["beads"], f"{r['crimp']['crimp_pct']:.2f}",
                    f"{r['wall_s']:.0f}", f"{r['wall_s'] / default['wall_s']:.2f}",
                    " / ".join(_pct(te.get(f"F{s}%")) for s in (2, 3, 4, 5, 6)),
                    " / ".join(_pct(pe.get(f"F{a}°")) for a in (10, 20, 30, 40)),
                    "–" if lock is None or lock_ref is None else f"{lock - lock_ref:+.1f}",
                    f"{100 * e['tension']['combined']:.0f}",
                    f"{100 * e['picture_frame']['combined']:.0f}"])
    return out, errors


def reference_line(data: dict) -> str:
    ref = {r["label"]: r for r in data["records"]}[REFERENCE.label]
    t, p = ref["tension"]["values"], ref["picture_frame"]["values"]
    return (f"Reference **{REFERENCE.label}** ({ref['crimp']['beads']} beads per cell, crimp "
            f"{ref['crimp']['crimp_pct']:.2f} %, {ref['wall_s']:.0f} s): tension force per "
            "width at 2 / 3 / 4 / 5 / 6 % "
            + " / ".join(f"{t[f'F{s}%']:.4g}" for s in (2, 3, 4, 5, 6))
            + " N/m; picture frame F_norm at 10 / 20 / 30 / 40° "
            + " / ".join(f"{p[f'F{a}°']:.4g}" for a in (10, 20, 30, 40))
            + f" N/m, locking {p['locking']:.1f}°.")


def section(data: dict) -> str:
    body, _ = rows(data)
    speeds = data["base_speed"]
    return "\n".join([
        "Plain weave of `examples/plain_weave.toml` as shipped (the glass law within a family, "
        "staggered beads, 1 cN/tex weaving tension, whole-yarn clamps), discretised as each "
        "preset of `fabmd.presets` says; coupons tiled from its crimped periodic cell: tension "
        f"{accuracy.TENSION_CELLS[0]} × {accuracy.TENSION_CELLS[1]} cells (relieved, to the "
        f"example's elongation), picture frame {accuracy.FRAME_CELLS[0]} × "
        f"{accuracy.FRAME_CELLS[1]} cells. Loading at the example's speed (tension "
        f"{speeds['tension']:g}, picture frame {speeds['picture_frame']:g} of the fibre wave "
        "speed) × the preset's factor. One process, in-process LAMMPS on one core, one run "
        "after the other; run time = crimp + coupons + both tests (the machine was shared: "
        "compare the ratios). Whole study: "
        f"{data.get('study_wall_s', 0) / 60:.0f} min.",
        "",
        reference_line(data),
        "",
        "Errors are signed and relative to the reference (locking: difference in degrees); "
        "tension error = the largest of F at 4 / 5 / 6 % (past the coupon's toe; 2 and 3 % "
        "shown, in and at the end of the toe), frame error = the largest of F_norm at 10 / 20 "
        "/ 30 / 40° and the locking angle's relative error.",
        "",
        table(["preset", "discretisation", "beads per cell", "crimp %", "run s", "× default",
               "tension F 2 / 3 / 4 / 5 / 6 % error %", "frame F_norm 10 / 20 / 30 / 40° "
               "error %", "locking [°]", "tension error %", "frame error %"], body),
    ])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    parser.add_argument("--resume", action="store_true",
                        help="keep the configurations presets.json already holds")
    parser.add_argument("--replot", action="store_true", help="no runs: from presets.json")
    parser.add_argument("--root", type=Path, default=None, help="folder for the runs")
    args = parser.parse_args(argv)
    if args.replot:
        data = json.loads(DATA.read_text())
    else:
        root = args.root or Path(tempfile.mkdtemp(prefix="fabmd-presets-"))
        root.mkdir(parents=True, exist_ok=True)
        data = accuracy.run_study(list(configs().values()), DATA, args.resume, root)
    body = section(data)
    print(body)
    if args.write:
        update_section("Presets against the reference", body, COMMAND)
    return 0


if __name__ == "__main__":
    sys.exit(main())
