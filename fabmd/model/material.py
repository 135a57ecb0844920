"""Re-export: materials live beside the geometry (:mod:`fabmd.geometry.material`)."""

from ..geometry.material import CARBON, GLASS, FibreMaterial, VirtualFibre  # noqa: F401
