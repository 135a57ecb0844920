"""Bead-chain ripple: F_t/F_n of a fibre sliding across another against the spacing ratio s/d.

Runs the sliding protocol (μ = 0.3, Hooke, E softened to 1 GPa: the load is a fixed
fraction of E·A, so the ratio does not depend on E) for several s/d and prints the
mean of F_t/F_n over whole bead periods, its bias against μ, and the ripple along
the slide (min, max, standard deviation), beside the closed form of a rigid sphere
sliding quasi-statically over a chain of spheres:

    F_t/F_n = tan(atan μ + α),  sin α_max = s/(2d),
    mean = (d/s)·∫ tan(atan μ + α) cos α dα over [−α_max, α_max]
         ≈ μ·(1 + (1 + μ²)·α_max²/3).

Cost of a run at fixed physical size and loading ∝ (beads) × (steps) ∝ (d/s)²
(the stable time step is proportional to the bead spacing).

    python benchmarks/ripple.py [--ratios 1 0.75 0.5 0.33 0.25] [--mu 0.3] [--write]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import table, update_section  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.model.beads import Discretisation  # noqa: E402
from fabmd.model.contact import ContactModel  # noqa: E402
from fabmd.model.material import GLASS, FibreMaterial, VirtualFibre  # noqa: E402
from fabmd.protocols.sliding import Sliding  # noqa: E402


def sphere_on_chain(mu: float, spacing_ratio: float) -> tuple[float, float, float]:
    """(mean, min, max) of F_t/F_n for a rigid sphere sliding over a chain of spheres."""
    a_max = math.asin(spacing_ratio / 2)
    phi = math.atan(mu)
    a = np.linspace(-a_max, a_max, 20001)
    f = np.tan(phi + a) * np.cos(a)
    mean = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(a)) / spacing_ratio)
    return mean, math.tan(phi - a_max), math.tan(phi + a_max)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ratios", type=float, nargs="+", default=[1.0, 0.75, 0.5, 0.33, 0.25])
    parser.add_argument("--mu", type=float, default=0.3)
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    args = parser.parse_args()

    fibre = VirtualFibre.solid(FibreMaterial(1e9, GLASS.density_kg_m3, "glass, softened"),
                               0.1e-3)
    root = Path(tempfile.mkdtemp(prefix="fabmd-ripple-"))
    rows = []
    for sd in args.ratios:
        test = Sliding(fibre=fibre, contact=ContactModel(friction=args.mu),
                       discretisation=Discretisation(spacing_ratio=sd))
        s = test.run(root / f"sd{sd:g}", Engine(progress=False)).summary
        mean, lo, hi = sphere_on_chain(args.mu, sd)
        rows.append([sd, s["measured_ratio"], 100 * (s["measured_ratio"] / args.mu - 1),
                     100 * (mean / args.mu - 1), s["ratio_min"], s["ratio_max"], lo, hi,
                     s["ratio_std"], (0.5 / sd) ** 2, s["wall_s"]])
        print(f"  s/d = {sd:g}: mean {s['measured_ratio']:.4f}, "
              f"{s['ratio_min']:.3f} .. {s['ratio_max']:.3f}", flush=True)
    header = ["s/d", "mean Ft/Fn", "bias %", "sphere-on-chain bias %", "min", "max",
              "sphere min", "sphere max", "std", "cost vs s/d=0.5", "wall s"]
    body = (f"Fibre pulled across a fibre (`fabmd.protocols.sliding`), μ = {args.mu:g}, Hooke "
            f"contact, E = 1 GPa (ratio independent of E), F_n = 10⁻³·E·A, "
            f"{Sliding().periods} bead periods averaged.\n\n" + table(header, rows))
    body += (
        "\n\nThe mean follows the sphere-on-chain closed form: bias ≈ (1 + μ²)·asin²(s/2d)/3. "
        "Default `Discretisation.spacing_ratio` = 0.5: the mean F_t/F_n is a couple of per "
        "cent above μ (inside the 5 % of `fabmd validate sliding`), s/d = 0.75 already misses "
        "it, and halving the bias (s/d = 0.33) costs 2.3× the run time. The ripple of a single "
        "contact is large at any practical s/d (±s/(2d) in F_t/F_n), but it has the bead "
        "period, so it averages out over the many contacts of a yarn.")
    print(body)
    if args.write:
        update_section("Bead-chain ripple", body, "python benchmarks/ripple.py --write")


if __name__ == "__main__":
    main()
