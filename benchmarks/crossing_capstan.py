"""Capstan over a crossing fibre: a bead chain pulled over another bead chain, at several s/d.

    python benchmarks/crossing_capstan.py [--quick]

Fibre A (diameter d, E·A, tension T_in held at one end) wraps by an angle θ over fibre B,
a fixed straight bead chain of the same diameter crossing it at 90° (B along z, A in the
x–y plane at height z0 over B's bead lattice); the other end of A is pulled along its
straight part, so A slides over B. For a smooth fibre the belt-friction equation gives
T_out/T_in = exp(μθ). The bead chains make the crossing bumpy (the kink of A sits on one
bead at a time when θ·d < s); the question it answers (benchmarks/RESULTS.md "Crossing
friction: where the coarse excess comes from"): does a fibre slide through a crossing
harder at s/d 0.5 than at 0.25 and 0.125, i.e. does the bead spacing set the friction a
crimped fibre meets where it crosses another?

Contact as fabmd's default fibre–fibre contact (``ContactModel``'s coefficients): Hooke
k_n = k'·l0 with k' = 0.4·E·A/d², k_t = 2/7·k_n, normal damping 0.3 of critical
(tangential half), μ = 0.3, no rotation (``fix nve``), beads of one fibre do not touch.
Pull at 3 % of the transverse wave speed sqrt(T_in/λ) after a load ramp; the ratio is
averaged over the second half of a 3 d pull.
B's registers: z0 = 0, l0/4 and l0/2 (A over a bead of B, between, in the groove).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from fabmd.engine.library import new_instance
from fabmd.model.beads import BeadParameters
from fabmd.model.contact import ContactModel
from fabmd.scene.loading import SmoothStartSpeed

D = 1e-4  # fibre diameter [m]
E = 1e9  # modulus [Pa] (the force ratios do not depend on it)
RHO = 2540.0
AREA = math.pi * D * D / 4
EA = E * AREA
MU = 0.3
LOAD = 1e-3 * EA  # T_in [N]


def path(theta: float, straight: float, spacing: float) -> tuple[np.ndarray, float]:
    """Bead centres of A: a straight part, an arc of radius d over B's axis, a straight part
    (load end first). Returns (points, bead spacing used)."""
    a0, a1 = math.pi / 2 + theta / 2, math.pi / 2 - theta / 2
    arc = theta * D
    total = 2 * straight + arc
    n = max(3, round(total / spacing))
    s = np.linspace(0.0, total, n + 1)
    pts = []
    start = np.array([math.cos(a0), math.sin(a0)]) * D
    t_in = np.array([math.sin(a0), -math.cos(a0)])  # tangent along the path at the arc start
    end = np.array([math.cos(a1), math.sin(a1)]) * D
    t_out = np.array([math.sin(a1), -math.cos(a1)])
    for u in s:
        if u < straight:
            p = start - t_in * (straight - u)
        elif u <= straight + arc:
            a = a0 - (u - straight) / D
            p = np.array([math.cos(a), math.sin(a)]) * D
        else:
            p = end + t_out * (u - straight - arc)
        pts.append(p)
    return np.array(pts), total / n


def _loading(pts: np.ndarray, ramp: float, speed: float) -> list[str]:
    """The load T_in on A's first bead (ramped over ``ramp`` s), the pull of its last bead
    (smooth start over ``ramp`` once the load is on, then ``speed``), and T_out as
    ``v_tout``. Both ramps are fabmd's own smooth start (:class:`SmoothStartSpeed`)."""
    t_load = (pts[0] - pts[1]) / np.linalg.norm(pts[0] - pts[1])
    t_pull = (pts[-1] - pts[-2]) / np.linalg.norm(pts[-1] - pts[-2])
    pull = SmoothStartSpeed(speed, ramp)
    return ["group load_end id 1", f"group pulled id {len(pts)}",
             "group free subtract A pulled",
             "variable t equal time",
             f"variable ramp equal \"{SmoothStartSpeed(1.0, ramp).lammps_ramp('t')}\"",
             f"variable lx equal {LOAD * t_load[0]}*v_ramp",
             f"variable ly equal {LOAD * t_load[1]}*v_ramp",
             f"variable tp equal \"(v_t>{ramp})*(v_t-{ramp})\"",
             f"variable u equal \"{pull.lammps_displacement('tp')}\"",
             f"variable v equal \"{pull.lammps_velocity('tp')}\"",
             f"variable ux equal {t_pull[0]}*v_u", f"variable uy equal {t_pull[1]}*v_u",
             f"variable vx equal {t_pull[0]}*v_v", f"variable vy equal {t_pull[1]}*v_v",
             "variable zero equal 0.0",
             "fix integrate free nve",
             "fix pull pulled move variable v_ux v_uy v_zero v_vx v_vy v_zero",
             "fix load load_end addforce v_lx v_ly 0.0",
             "fix planar A setforce NULL NULL 0.0",
             "compute fp pulled reduce sum fx fy",
             f"variable tout equal \"-(c_fp[1]*{t_pull[0]}+c_fp[2]*{t_pull[1]})\"",
             "thermo_style custom step v_tout", "thermo 100000"]


def ratio(spacing_ratio: float, theta: float, register: float, pull_d: float = 3.0,
          speed_fraction: float = 0.03, stiffness_factor: float = 1.0
          ) -> tuple[float, float, float]:
    """T_out/T_in over the second half of the pull: mean, and the lowest and highest of
    its means over 100-step chunks (the ripple as A's beads pass over B).
    ``stiffness_factor`` scales the contact's k' (a softer crossing)."""
    l0 = spacing_ratio * D
    pts, l0 = path(theta, 12 * D, l0)
    mass = RHO * AREA * l0
    kb = EA / l0  # bond spring [N/m]; LAMMPS harmonic K = kb/2
    contact = ContactModel(friction=MU, normal_stiffness_pa=stiffness_factor * 0.4 * EA / D**2)
    c = contact.pair_coefficients([BeadParameters(D, l0, mass, EA)])
    dt = 0.1 * 2 / math.sqrt((4 * kb + 6 * c["kn"]) / mass)
    lam = RHO * AREA
    speed = speed_fraction * math.sqrt(LOAD / lam)
    length = len(pts) * l0
    ramp = 2 * length / math.sqrt(LOAD / lam)
    pull_time = pull_d * D / speed
    z0 = register * l0
    nb = int(math.ceil(3 * D / l0))
    lmp = new_instance()
    cmds = ["units si", "atom_style hybrid sphere bond", "boundary f f f",
            "newton on", "comm_modify vel yes",
            f"region box block {-30 * D} {30 * D} {-30 * D} {30 * D} {-4 * D} {4 * D}",
            "create_box 2 box bond/types 1 extra/bond/per/atom 2 extra/special/per/atom 4",
            f"mass * {mass}"]
    for p in pts:
        cmds.append(f"create_atoms 1 single {p[0]} {p[1]} {z0}")
    for k in range(-nb, nb + 1):
        cmds.append(f"create_atoms 2 single 0.0 0.0 {k * l0}")
    n_a = len(pts)
    cmds += [f"group A id 1:{n_a}", "group B type 2",
             "set group A mol 1", "set group B mol 2",
             f"set group all diameter {D}",
             f"set group all density {mass / (math.pi * D**3 / 6)}",
             "bond_style harmonic", f"bond_coeff 1 {kb / 2} {l0}"]
    cmds += [f"create_bonds single/bond 1 {i} {i + 1}" for i in range(1, n_a)]
    cmds += [f"pair_style {contact.pair_style()} {c['kn']} {c['kt']} {c['gamman']} "
             f"{c['gammat']} {c['friction']} 1",
             "pair_coeff * *", "special_bonds lj 0 1 1",
             f"neighbor {0.2 * D} bin", "neigh_modify exclude molecule/intra all",
             "neigh_modify exclude type 2 2", f"timestep {dt}"]
    cmds += _loading(pts, ramp, speed)
    lmp.commands_list(cmds)
    chunk = 100  # the mean of each chunk of steps, averaged over the chunks
    half = chunk * round((ramp * 2 + pull_time / 2) / dt / chunk)
    lmp.command(f"run {half}")
    lmp.commands_list([f"fix avg all ave/time 1 {chunk} {chunk} v_tout",
                       "variable tavg equal f_avg"])
    means = []
    for k in range(round(pull_time / 2 / dt / chunk)):
        lmp.command(f"run {chunk} post no" + (" pre no" if k else ""))  # set the fix up once
        means.append(lmp.extract_variable("tavg"))
    lmp.close()
    means = np.array(means) / LOAD
    return float(np.mean(means)), float(means.min()), float(means.max())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="s/d 0.5 and 0.25, one angle")
    args = parser.parse_args()
    spacings = (0.5, 0.25) if args.quick else (0.5, 0.25, 0.125)
    angles = (0.3,) if args.quick else (0.3, math.pi / 2)
    print("| θ [rad] | s/d | register z0/l0 | T_out/T_in mean | min | max | exp(μθ) "
          "| mean excess over μθ | peak excess | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for theta in angles:
        exact = math.exp(MU * theta)
        for s in spacings:
            for reg in (0.0, 0.25, 0.5):
                t0 = time.perf_counter()
                mean, low, high = ratio(s, theta, reg)
                print(f"| {theta:.3f} | {s} | {reg} | {mean:.4f} | {low:.4f} | {high:.4f} | "
                      f"{exact:.4f} | {(mean - exact) / (exact - 1):+.1%} | "
                      f"{(high - exact) / (exact - 1):+.1%} | {time.perf_counter() - t0:.1f} |",
                      flush=True)


if __name__ == "__main__":
    main()
