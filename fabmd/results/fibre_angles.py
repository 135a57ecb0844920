"""The fibre shear angle of a zone, frame by frame, from a run folder's ``trajectory.h5``.

The zone is the set of beads that start (first frame) in an in-plane rectangle;
the angle is :func:`fabmd.analysis.zone_shear_angle_deg` (mean in-plane axes of
two families, 90° minus the angle between them across the sector that holds the
direction the test stretches). The picture-frame and bias-extension tests report
it beside their kinematic (closed-form) shear angle.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.trajectory_file import TRAJECTORY_FILE


def fibre_shear_angles(run_dir: Path, centre, half_size, reference_deg: float = 45.0,
                       families: tuple[str, str] = ("warp", "weft")
                       ) -> tuple[np.ndarray, np.ndarray]:
    """(steps, shear angle [deg]) of the beads that start in ``centre ± half_size`` [m],
    one value per frame of ``run_dir/trajectory.h5`` (frames where a family has no
    segment in the zone are left out; empty arrays without a trajectory)."""
    from ..analysis import FabricFrame, zone_mask, zone_shear_angle_deg

    path = Path(run_dir) / TRAJECTORY_FILE
    if not path.exists():
        return np.zeros(0), np.zeros(0)
    steps, angles = [], []
    zone = None
    for frame in FabricFrame.iter_trajectory(path):
        if zone is None:  # the zone follows the beads that were in it at the start
            zone = zone_mask(frame.positions, centre, half_size)
        gamma = zone_shear_angle_deg(frame, zone, families, reference_deg)
        if gamma is not None:
            steps.append(frame.step)
            angles.append(gamma)
    return np.asarray(steps), np.asarray(angles)
