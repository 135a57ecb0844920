"""The facts a rendered fabric carries in ``BeadModel.info`` (JSON-able, SI; see
:func:`fabmd.model.fabric_model.render_loose` for the keys)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..describe import scene_dict
from ..geometry.fabric import FAMILY_AXIS, Fabric
from ..geometry.paths import YarnPath
from .bead_model import BeadModel
from .beads import Discretisation
from .overlap import ClosestApproach

if TYPE_CHECKING:  # fabric_model calls this module
    from .fabric_model import FamilyBeads

INFO_FORMAT = "fabmd-fabric"


def fabric_info(fabric: Fabric, disc: Discretisation, fams: dict[str, FamilyBeads],
                paths: list[YarnPath], model: BeadModel, approach: ClosestApproach | None,
                thickness: float, z_extent: tuple[float, float],
                cell_keys: list[str] | None = None) -> dict:
    """The JSON-able facts stored in ``BeadModel.info`` (see :func:`render_fabric`).

    ``fams`` holds every yarn spec by key (:func:`yarn_spec_beads`) and ``cell_keys``
    the key of each unit-cell yarn (default: ``fabric.cell_spec_keys()``).
    """
    if cell_keys is None:
        cell_keys = fabric.cell_spec_keys()
    table = fabric.yarn_spec_table()
    size = fabric.size_m
    crimp, mass = _loose_crimp_and_mass(fabric, fams, paths, cell_keys)
    per_family = _spec_facts(fams, table)
    pair = None
    if approach is not None and approach.i >= 0:
        pair = [model.yarns[model.yarn_ids[approach.i] - 1].name,
                model.yarns[model.yarn_ids[approach.j] - 1].name]
    bt_count = {f: sum(1 for bt in model.bond_type_table if bt.family == f)
                for f in model.family_names}
    straight = fabric.straight_areal_density_kg_m2()
    built = mass / (size[0] * size[1])
    datasheet = {
        "areal_density_kg_m2": fabric.areal_density_kg_m2,
        "areal_density_deviation": None if fabric.areal_density_kg_m2 is None
        else built / fabric.areal_density_kg_m2 - 1.0,
        "straight_areal_density_kg_m2": straight,
        "thickness_m": fabric.thickness_m,
        "thickness_pressure_pa": fabric.thickness_pressure_pa,
    }
    yarn_specs = {key: per_family.pop(key) for key in list(per_family) if ":" in key}
    for key, entry in yarn_specs.items():
        entry["yarns"] = [p.name for p in paths if cell_keys[p.cell_index] == key]
    packing = {fam: {"yarn_fibre_volume_fraction": spec.yarn_fibre_volume_fraction,
                     "filament_area_m2": spec.filament_area_m2,
                     "section_area_m2": spec.section.area_m2, "shape": spec.shape,
                     "width_m": spec.width_m, "height_m": spec.height_m,
                     "woven_width_m": fabric.woven_width_m.get(fam, spec.width_m)}
               for fam, spec in table.items()}
    return {
        "format": INFO_FORMAT,
        "datasheet": datasheet,
        "yarn_packing": packing,
        "architecture": _architecture(fabric),
        "unit_cell_m": list(fabric.unit_cell_m),
        "tiling": list(fabric.tiling),
        "fabric_size_m": list(size),
        "periodic": fabric.periodic,
        "yarns_per_unit_cell": fabric.yarns_per_unit_cell(),
        "yarn_axis": {f: FAMILY_AXIS[f] for f in model.family_names},
        "spacing_m": {f: fabric.spacing(f) for f in model.family_names},
        "count_per_m": {f: 1.0 / fabric.spacing(f) for f in model.family_names},
        "families": per_family,
        "yarn_specs": yarn_specs,
        "yarn_spec": [cell_keys[p.cell_index] for p in paths],
        "yarn_offset_m": [p.offset_m for p in paths],
        "yarn_level": [p.level for p in paths],
        "z_levels_m": fabric.levels(),
        "loose_thickness_m": thickness,
        "z_extent_m": list(z_extent),
        "thickness_measure": "extent of all beads including their radius",
        "crimp": crimp,
        "areal_density_kg_m2": mass / (size[0] * size[1]),
        "clearance_m": None if approach is None else approach.gap_m,
        "clearance_pair": pair,
        "requested_clearance_m": fabric.clearance_m,
        "lift_m": fabric.lift_m,
        "bond_types_per_family": bt_count,
        "discretisation": scene_dict(disc),
        "fabric": scene_dict(fabric),
    }


def _architecture(fabric: Fabric) -> dict:
    """The weave (matrix) or 3D architecture (layers, gaps, binder paths) as plain data."""
    arch = fabric.architecture
    if fabric.is_3d:
        return {"kind": "3d", "name": arch.name, "weft_layers": arch.weft_layers,
                "columns": arch.columns, "dents": arch.dents,
                "warp_gaps": list(arch.warp_gaps),
                "binder_paths": [[list(p) for p in dent] for dent in arch.binder_paths],
                "separate_binders": arch.separate_binders}
    return {"kind": "2d", "name": arch.name, "matrix": [list(r) for r in arch.matrix]}


def _centreline_length(path: YarnPath, step: float) -> float:
    pts = path.centreline(step)
    return float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())


def _loose_crimp_and_mass(fabric: Fabric, fams: dict[str, FamilyBeads],
                          paths: list[YarnPath], cell_keys: list[str]
                          ) -> tuple[dict[str, float], float]:
    """Loose centreline crimp per family and the tile's yarn mass [kg]."""
    table = fabric.yarn_spec_table()
    crimp: dict[str, float] = {}
    mass = 0.0
    for fam in fabric.specs():
        step = 0.25 * fams[fam].beads.bond_length_m
        shapes = {p.cell_index: p for p in paths if p.family == fam}
        ratio = {k: _centreline_length(p, step) / p.length_m for k, p in shapes.items()}
        crimp[fam] = float(np.mean(list(ratio.values())) - 1.0)
        # every yarn its own tex and its own shape's length
        mass += sum(table[cell_keys[p.cell_index]].linear_density_kg_m * p.length_m
                    * ratio[p.cell_index] for p in paths if p.family == fam)
    return crimp, mass


def _spec_facts(fams: dict[str, FamilyBeads], table: dict) -> dict[str, dict]:
    """Per yarn spec key: tex, fibres, section, fibre and bead sizes, E·A, the yarn's E·I,
    material."""
    per_family = {}
    for fam, fb in fams.items():
        spec = table[fam]
        per_family[fam] = {
            "linear_density_tex": spec.linear_density_tex, "n_fibres": spec.n_fibres,
            "width_m": spec.width_m, "height_m": spec.height_m,
            "fibre_diameter_m": fb.fibre.diameter_m, "fibre_area_m2": fb.fibre.area_m2,
            "bond_length_m": fb.beads.bond_length_m,
            "axial_stiffness_n": fb.fibre.axial_stiffness_n,
            "yarn_bending_stiffness_nm2": spec.yarn_bending_stiffness_nm2,
            "modulus_pa": spec.material.modulus_pa,
            "density_kg_m3": spec.material.density_kg_m3, "material": spec.material.name,
            "fill_fraction": spec.section.fill_fraction(spec.n_fibres),
        }
    return per_family
