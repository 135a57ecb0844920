"""Export a fabric state for composite analysis (pure numpy, SI).

From the virtual fibres of a state (e.g. a crimp run's ``crimped.data``):

* :func:`reconstruct_yarns` — per yarn a centreline, a smoothed fibre envelope, the fibre
  direction and the yarn fibre volume fraction at stations (periodic yarns stay periodic);
* :func:`voxelise` — a voxel mesh: yarn id (0 = matrix), fibre direction, fibre volume
  fraction per voxel; :func:`write_vtu`, :func:`write_abaqus` (element sets per yarn and
  matrix, ``*Distribution``/``*Orientation``, periodic node sets);
* :func:`yarn_surface`, :func:`write_surfaces` — closed yarn surfaces (STL, VTU) and
  :func:`interpenetration_report`;
* :func:`export_state` — all of it for one state, checked against the bead model
  (``fabmd export DIR``)::

    from fabmd.export import export_state, load_state

    model, _ = load_state("runs/crimp")
    summary = export_state(model, "runs/crimp/export")
    summary["fibre_volume_fraction"]    # voxels vs beads
"""

from .checks import bead_fibre_volume_fraction, bead_tangents, direction_errors, domain
from .state import default_voxel_size_m, export_state, load_state, voxel_grid
from .surfaces import (
    enclosed_volume,
    interpenetration_report,
    watertight,
    write_surfaces,
    yarn_surface,
)
from .voxel import VoxelGrid, VoxelMesh, locate, voxelise
from .writers import periodic_node_sets, read_distribution, write_abaqus, write_vtu
from .yarns import YarnGeometry, reconstruct_yarn, reconstruct_yarns

__all__ = [
    "VoxelGrid",
    "VoxelMesh",
    "YarnGeometry",
    "bead_fibre_volume_fraction",
    "bead_tangents",
    "default_voxel_size_m",
    "direction_errors",
    "domain",
    "enclosed_volume",
    "export_state",
    "interpenetration_report",
    "load_state",
    "locate",
    "periodic_node_sets",
    "read_distribution",
    "reconstruct_yarn",
    "reconstruct_yarns",
    "voxel_grid",
    "voxelise",
    "watertight",
    "write_abaqus",
    "write_surfaces",
    "write_vtu",
    "yarn_surface",
]
