"""Where a picture frame's work goes: fibre stretch, contact elastic energy, friction.

Reads a finished picture-frame run folder (``curve.csv``, ``trajectory.h5``,
``in.picture_frame``) and prints, cumulative from 0 deg at each angle: the external work [J],
the shares of bond (stretch) energy and contact work, the contact elastic energy
sum(Kn*delta^2/2) over the overlapping pairs of different fibres that touch the free fabric
(Hooke contact, from the trajectory's positions), the rest of the contact work (friction and
contact damping), the mean tension of the free fabric's bonds [N per virtual fibre], the sum
of the normal contact forces [N] and the free fabric's thickness (1-99 % z range plus a bead
diameter) [m], and for each fibre's free segment (its beads inside the clamps' inner edge)
the change of end-to-end distance and of path length [%] and its crimp (path / end-to-end
- 1) [%]: whether the fibres stretch because the frame pulls their ends apart or because
their crimp grows. Used for "Crimp tension and picture-frame force" in benchmarks/RESULTS.md.

    python benchmarks/picture_frame_energy.py RUN/picture_frame [--angles 10 20 30 40 49.9]
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import h5py
import numpy as np
from scipy.spatial import cKDTree  # scipy comes with MDAnalysis

NM = 1e-9  # trajectory.h5 stores lengths in nm


def frame_terms(run: Path) -> dict[str, np.ndarray]:
    """Per trajectory frame: step, contact elastic energy [J], sum of normal forces [N],
    mean free-bond tension [N], free thickness [m]."""
    text = (run / "in.picture_frame").read_text()
    kn = float(re.search(r"pair_style\s+gran/hooke\S*\s+(\S+)", text).group(1))  # N/m
    inner = re.search(r"region\s+inner block (.+?) INF INF", text).group(1)
    box = [float(v) for v in inner.split()]
    with h5py.File(run / "trajectory.h5") as f:
        x = f["particles/all/position/value"][:] * NM
        dia = f["particles/all/diameter"][:] * NM
        fibre = f["particles/all/fibre_id"][:]
        bonds = f["connectivity/bonds"][:]
        tension = f["observables/bond_force/value"][:]  # positive in tension
        steps = f["observables/bond_force/step"][:]
    free = ((x[0, :, 0] >= box[0]) & (x[0, :, 0] <= box[1])
            & (x[0, :, 1] >= box[2]) & (x[0, :, 1] <= box[3]))
    free_bond = free[bonds[:, 0]] & free[bonds[:, 1]]
    out = {k: [] for k in ("step", "contact_elastic_j", "normal_force_n", "tension_n",
                           "thickness_m", "end_to_end_m", "path_m")}
    # each fibre's free segment: beads of one fibre are consecutive in the model
    segments = []
    for fid in np.unique(fibre):
        idx = np.flatnonzero(fibre == fid)
        inside = idx[free[idx]]
        if len(inside) >= 3:
            segments.append((inside[0], inside[-1] + 1))
    for k in range(x.shape[0]):
        p = x[k]
        i, j = cKDTree(p).query_pairs(dia.max(), output_type="ndarray").T
        keep = (fibre[i] != fibre[j]) & (free[i] | free[j])  # clamp-clamp pairs are excluded
        i, j = i[keep], j[keep]
        delta = 0.5 * (dia[i] + dia[j]) - np.linalg.norm(p[i] - p[j], axis=1)
        delta = delta[delta > 0]
        z = p[free, 2]
        out["step"].append(steps[k])
        out["contact_elastic_j"].append(0.5 * kn * float(np.sum(delta**2)))
        out["normal_force_n"].append(kn * float(np.sum(delta)))
        out["tension_n"].append(float(np.mean(tension[k][free_bond])))
        out["thickness_m"].append(float(np.percentile(z, 99) - np.percentile(z, 1) + dia.max()))
        ends = np.array([np.linalg.norm(p[b - 1] - p[a]) for a, b in segments])
        paths = np.array([np.sum(np.linalg.norm(np.diff(p[a:b], axis=0), axis=1))
                          for a, b in segments])
        out["end_to_end_m"].append(ends)
        out["path_m"].append(paths)
    res = {k: np.asarray(v, float) for k, v in out.items()}
    e, s = res.pop("end_to_end_m"), res.pop("path_m")  # (frames, fibres)
    res["end_to_end_change_pct"] = 100 * np.mean(e / e[0] - 1, axis=1)
    res["path_change_pct"] = 100 * np.mean(s / s[0] - 1, axis=1)
    res["crimp_pct"] = 100 * np.mean(s / e - 1, axis=1)
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="picture_frame run folder")
    ap.add_argument("--angles", type=float, nargs="+", default=[10, 20, 30, 40, 49.9])
    a = ap.parse_args()
    c = np.genfromtxt(a.run / "curve.csv", delimiter=",", names=True)
    g = c["shear_angle_deg"]
    dt = float(re.search(r"timestep\s+(\S+)", (a.run / "in.picture_frame").read_text()).group(1))
    fr = frame_terms(a.run)
    g_frame = np.interp(fr["step"] * dt, c["time_s"], g)
    print("angle  work[J]  bonds  contact  contact-elastic  friction+damping  "
          "tension[N/fibre]  sum Fn[N]  thickness[mm]  free segments: end-to-end %  path %  "
          "crimp %")
    for ang in a.angles:
        w = np.interp(ang, g, c["external_work_j"])
        u = np.interp(ang, g, c["strain_energy_j"]) - c["strain_energy_j"][0]
        cw = np.interp(ang, g, c["contact_work_j"])
        ec = np.interp(ang, g_frame, fr["contact_elastic_j"]) - fr["contact_elastic_j"][0]
        print(f"{ang:5.1f}  {w:.4g}  {u / w:5.2f}  {cw / w:6.2f}  {ec / w:14.2f}  "
              f"{(cw - ec) / w:15.2f}  {np.interp(ang, g_frame, fr['tension_n']):15.2f}  "
              f"{np.interp(ang, g_frame, fr['normal_force_n']):9.0f}  "
              f"{np.interp(ang, g_frame, fr['thickness_m']) * 1e3:.3f}  "
              f"{np.interp(ang, g_frame, fr['end_to_end_change_pct']):+.3f}  "
              f"{np.interp(ang, g_frame, fr['path_change_pct']):+.3f}  "
              f"{np.interp(ang, g_frame, fr['crimp_pct']):.3f}")
    print(f"crimp of the free segments at the start: {fr['crimp_pct'][0]:.3f} %")


if __name__ == "__main__":
    main()
