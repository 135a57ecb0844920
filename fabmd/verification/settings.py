"""``--set KEY=VALUE`` settings shared by the checks: refuse unknown keys, build the fibre."""

from __future__ import annotations

from ..errors import InputError
from ..model.material import GLASS, FibreMaterial, VirtualFibre


def check_known(settings: dict[str, float], allowed: tuple[str, ...], check: str) -> None:
    """One line naming the unknown keys and the allowed ones."""
    unknown = set(settings) - set(allowed)
    if unknown:
        raise InputError(f"unknown setting(s) {sorted(unknown)} for {check}; "
                         f"allowed: {', '.join(allowed)}")


def fibre_from(settings: dict[str, float], modulus_pa: float, name: str) -> VirtualFibre:
    """A solid glass virtual fibre (default diameter 0.1 mm) with the settings' modulus,
    density and diameter."""
    get = settings.get
    material = FibreMaterial(get("modulus_pa", modulus_pa),
                             get("density_kg_m3", GLASS.density_kg_m3), name)
    return VirtualFibre.solid(material, get("diameter_m", 0.1e-3))
