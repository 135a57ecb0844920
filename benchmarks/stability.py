"""Stability stress test: where do runs blow up, and how far inside is fabmd's time step?

Sweeps the time-step factor (as a fraction of fabmd's own critical time step,
which accounts for bonds, bending and contacts) for several stiffness contrasts
(contact against bond stiffness) and mass scalings, and the loading speed of a
tension test. For each case it finds the largest stable factor by bisection;
the margin is that boundary over fabmd's default factor (0.25).

    python benchmarks/stability.py            # prints the tables
    python benchmarks/stability.py --write    # and updates benchmarks/RESULTS.md
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _results import table, update_section  # noqa: E402
from fabrics import plain_weave_cell  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.errors import UnstableRun  # noqa: E402
from fabmd.model.beads import TimeStep  # noqa: E402
from fabmd.model.contact import ContactModel  # noqa: E402
from fabmd.protocols.coupon import Coupon  # noqa: E402
from fabmd.protocols.crimp import Crimp  # noqa: E402
from fabmd.protocols.fibre_tension import FibreTension  # noqa: E402
from fabmd.protocols.tension import Tension  # noqa: E402
from fabmd.scene.quasi_static import QuasiStatic  # noqa: E402

ENGINE = Engine(progress=False)
DEFAULT_FACTOR = 0.25


def stable(make, factor: float, root: Path) -> tuple[bool, str]:
    """Run the case at ``factor``; (stable?, cause)."""
    out = Path(tempfile.mkdtemp(dir=root))
    try:
        make(TimeStep(factor=factor, check=False), out / "run")
        return True, ""
    except UnstableRun as exc:
        return False, exc.cause


def boundary(make, root: Path, lo: float = DEFAULT_FACTOR, hi: float = 4.0,
             tol: float = 0.05) -> tuple[float, str, float]:
    """Largest stable factor in [lo, hi] by bisection: (factor, cause above it, seconds)."""
    t0 = time.perf_counter()
    ok, _ = stable(make, lo, root)
    if not ok:
        return 0.0, "unstable at the default", time.perf_counter() - t0
    ok, cause = stable(make, hi, root)
    if ok:
        return hi, "stable up to the sweep's end", time.perf_counter() - t0
    while hi - lo > tol * lo:
        mid = 0.5 * (lo + hi)
        ok, why = stable(make, mid, root)
        if ok:
            lo = mid
        else:
            hi, cause = mid, why
    return lo, cause, time.perf_counter() - t0


def chain_case(mass_scaling: float = 1.0):
    from fabmd.model.beads import Discretisation

    def make(step, out):
        FibreTension(length_m=3e-3, time_step=step, speed_fraction=1e-3,
                     discretisation=Discretisation(mass_scaling=mass_scaling)).run(out, ENGINE)
    return make


def crimp_case(stiffness_factor: float, mass_scaling: float = 1.0):
    loose = plain_weave_cell()
    if mass_scaling != 1.0:
        loose.masses = loose.masses * mass_scaling

    def make(step, out):
        Crimp(expansion={"warp": -0.1, "weft": -0.1}, time_step=step,
              contact=ContactModel(stiffness_factor=stiffness_factor),
              quasi_static=QuasiStatic(max_steps=20_000)).run(loose, out, ENGINE)
    return make


def speed_sweep(root: Path) -> list[list]:
    crimped = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(plain_weave_cell(),
                                                                root / "crimp", ENGINE)
    coupon = Coupon(length_m=16e-3, width_m=8e-3).run(crimped.model, root / "coupon", ENGINE)
    rows = []
    reference = None
    for fraction in (2.5e-5, 5e-5, 1e-4, 2e-4, 1e-3, 5e-3, 2e-2, 5e-2):
        t0 = time.perf_counter()
        try:
            r = Tension(speed_fraction=fraction).run(coupon.model, root / f"speed-{fraction:g}",
                                                     ENGINE)
            s = r.summary
            f1 = s["force_at_elongation_n"]["1"]
            if reference is None:
                reference = f1
            rows.append([f"{fraction:g}", "stable", s["max_kinetic_to_strain_energy"],
                         abs(f1 - reference) / reference, s["energy_balance"]["relative_error"],
                         time.perf_counter() - t0])
        except UnstableRun as exc:
            rows.append([f"{fraction:g}", f"unstable ({exc.cause})", "-", "-", "-",
                         time.perf_counter() - t0])
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    args = parser.parse_args()
    root = Path(tempfile.mkdtemp(prefix="fabmd-stability-"))
    cases = [
        ("bare chain (fibre tension), mass scaling 1", chain_case()),
        ("bare chain, mass scaling 100", chain_case(100.0)),
        ("plain-weave crimp, contact 0.01 x bond", crimp_case(0.01)),
        ("plain-weave crimp, contact 0.1 x bond (default)", crimp_case(0.1)),
        ("plain-weave crimp, contact 1 x bond", crimp_case(1.0)),
        ("plain-weave crimp, contact 10 x bond", crimp_case(10.0)),
        ("plain-weave crimp, contact 100 x bond", crimp_case(100.0)),
        ("plain-weave crimp, default contact, mass scaling 100", crimp_case(0.1, 100.0)),
    ]
    rows = []
    for name, make in cases:
        factor, cause, seconds = boundary(make, root)
        rows.append([name, factor, cause, factor / DEFAULT_FACTOR, seconds])
        print(rows[-1], flush=True)
    dt_table = table(["case", "largest stable factor (x fabmd dt_crit)", "failure above it",
                      "margin over the default 0.25", "sweep time [s]"], rows)
    speed_rows = speed_sweep(root)
    speed_table = table(["clamp speed / wave speed", "outcome", "max KE/U after start-up",
                         "force change at 1 % vs slowest", "energy balance error",
                         "run time [s]"], speed_rows)
    body = ("### Time-step factor (bisection to 5 %)\n\n" + dt_table
            + "\n\n### Loading speed (tension of a 16 x 8 mm plain-weave coupon, 512 beads)\n\n"
            + speed_table)
    print(body)
    if args.write:
        update_section("Stability boundary", body, "python benchmarks/stability.py --write")


if __name__ == "__main__":
    main()
