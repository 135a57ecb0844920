"""Fabric geometry (pure Python + numpy, no LAMMPS).

* :mod:`.weave` — 2D weave matrices (plain, twill, satin, basket, user matrix);
* :mod:`.architecture3d` — 3D woven layers and binder paths;
* :mod:`.section` — yarn cross-sections and the packing of virtual fibres in them;
* :mod:`.paths` — yarn centrelines and virtual-fibre paths;
* :mod:`.fabric` — :class:`~.fabric.Fabric`, the complete description of a fabric;
* :mod:`.overrides` — other yarn specs for some yarns or layers of a family.

Axes: warp (and binder) yarns run along x, weft yarns along y, z is the thickness.
Rendering a fabric into beads lives in :mod:`fabmd.model.fabric_model`.
"""

from .architecture3d import Architecture3D
from .fabric import Fabric, YarnSpec
from .overrides import YarnOverride
from .section import Section
from .weave import Weave

__all__ = ["Architecture3D", "Fabric", "Section", "Weave", "YarnOverride", "YarnSpec"]
