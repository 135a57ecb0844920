"""Friction lever of one fibre crossing turned in place, at several bead spacings.

    python benchmarks/crossing_lever.py

Two straight bead chains of diameter d cross at 90° (A along x, B along y), pressed to an
overlap δ (per-crossing pair stiffness k_n ∝ l0², Hooke). B turns about the crossing's
normal; every bead pair in contact slides (full Coulomb sliding, μ = 1), its friction
force opposing the pair's tangential relative velocity. The resisting torque T over the
normal force N is the crossing's friction lever [d], averaged over the two chains'
registers. Question it answers (benchmarks/RESULTS.md "Bead register"): does a coarse
crossing turn harder than a fine one? (It does not: the lever is the same at every l0.)
"""

from __future__ import annotations

import numpy as np


def crossing_lever(spacing_ratio: float, overlap_ratio: float, registers: int = 16) -> float:
    """Register-averaged T / (μ·N) of one crossing turned in place, in fibre diameters."""
    d, l0 = 1.0, spacing_ratio
    gap = d - overlap_ratio
    k = np.arange(-(int(np.ceil(2 * d / l0)) + 2), int(np.ceil(2 * d / l0)) + 3) * l0
    torque = normal = 0.0
    for ra in (np.arange(registers) + 0.5) / registers:
        for rb in (np.arange(registers) + 0.5) / registers:
            a = np.column_stack([k + ra * l0, 0 * k, 0 * k])
            b = np.column_stack([0 * k, k + rb * l0, 0 * k + gap])
            sep = b[None, :, :] - a[:, None, :]
            r = np.linalg.norm(sep, axis=2)
            i, j = np.nonzero(r < d)
            if not len(i):
                continue
            n = sep[i, j] / r[i, j, None]
            force = l0 * l0 * (d - r[i, j])  # per-crossing k_n ∝ l0² (any constant)
            p = b[j]
            v = np.column_stack([-p[:, 1], p[:, 0], 0 * p[:, 0]])  # B turning about z
            vt = v - np.sum(v * n, axis=1)[:, None] * n
            speed = np.linalg.norm(vt, axis=1)
            moving = speed > 1e-12
            f = np.zeros_like(vt)
            f[moving] = -(force[moving] / speed[moving])[:, None] * vt[moving]
            torque -= float(np.sum(p[:, 0] * f[:, 1] - p[:, 1] * f[:, 0]))
            normal += float(np.sum(force * n[:, 2]))
    return torque / normal


def main():
    print("| δ/d | " + " | ".join(f"s/d {s}" for s in (0.5, 0.25, 0.125, 0.0625)) + " |")
    print("|---|---|---|---|---|")
    for overlap in (0.02, 0.05):
        levers = [crossing_lever(s, overlap) for s in (0.5, 0.25, 0.125, 0.0625)]
        print(f"| {overlap} | " + " | ".join(f"{v:.4f} d" for v in levers) + " |")


if __name__ == "__main__":
    main()
