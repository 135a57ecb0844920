"""Protocols behind ``fabmd test picture-frame|bias-extension|periodic-tension|periodic-shear``.

The ``fabmd test`` command (scene file loading, ``tension``) connects here through
:func:`run_protocol`: a protocol name, the coupon (or periodic cell) as a bead
model, and the protocol's settings as a plain dict (e.g. the ``[test]`` table of a
scene file: ``{"max_shear_angle_deg": 55, "contact": {"friction": 0.2}}``).
Nested tables become the objects they describe (``contact`` → ContactModel,
``time_step`` → TimeStep, ``relax`` → QuasiStatic); lists become tuples; unknown
keys are refused with the list of the known ones.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..errors import InputError

#: protocol name on the command line -> (module in fabmd.protocols, class name)
PROTOCOLS: dict[str, tuple[str, str]] = {
    "picture-frame": ("picture_frame", "PictureFrame"),
    "bias-extension": ("bias_extension", "BiasExtension"),
    "periodic-tension": ("periodic", "PeriodicTension"),
    "periodic-shear": ("periodic", "PeriodicShear"),
}


def protocol_class(name: str):
    """The protocol class of a command-line name."""
    import importlib

    if name not in PROTOCOLS:
        raise InputError(f"test protocol must be one of {', '.join(sorted(PROTOCOLS))}, "
                         f"got {name!r}")
    module, cls = PROTOCOLS[name]
    return getattr(importlib.import_module(f"fabmd.protocols.{module}"), cls)


def _nested():
    from ..model.beads import TimeStep
    from ..model.contact import ContactModel
    from ..scene.quasi_static import QuasiStatic

    return {"contact": ContactModel, "time_step": TimeStep, "relax": QuasiStatic}


def build_protocol(name: str, settings: dict | None = None):
    """The protocol object ``name`` with ``settings`` (validated when built)."""
    cls = protocol_class(name)
    settings = dict(settings or {})
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = set(settings) - fields
    if unknown:
        raise InputError(f"unknown setting(s) {sorted(unknown)} for {name}; known: "
                         f"{', '.join(sorted(fields))}")
    nested = _nested()
    for key, value in list(settings.items()):
        if key in nested and isinstance(value, dict):
            sub = nested[key]
            known = {f.name for f in dataclasses.fields(sub)}
            bad = set(value) - known
            if bad:
                raise InputError(f"unknown setting(s) {sorted(bad)} in {name}.{key}; known: "
                                 f"{', '.join(sorted(known))}")
            settings[key] = sub(**value)
        elif isinstance(value, list):
            settings[key] = tuple(value)
    try:
        return cls(**settings)
    except TypeError as exc:  # a wrong type the validators did not name
        raise InputError(f"{name}: {exc}") from None


def run_protocol(name: str, coupon_model, settings: dict | None, out: Path | None, engine=None,
                 overwrite: bool = False, check_rate: bool = False):
    """Run test ``name`` on ``coupon_model`` (a coupon, or a periodic cell for the
    ``periodic-*`` tests); returns the protocol's result (``run_dir``, ``curve``,
    ``summary``)."""
    test = build_protocol(name, settings)
    return test.run(coupon_model, out=out, engine=engine, overwrite=overwrite,
                    check_rate=check_rate)


def summary_line(name: str, summary: dict) -> str:
    """A one-line report of a finished test (for the command line)."""
    eb = (summary.get("energy_balance") or {}).get("relative_error")
    ke = summary.get("max_kinetic_to_strain_energy")
    parts = [f"{name}: {summary.get('n_beads')} beads, {summary.get('steps')} steps"]
    if summary.get("wall_s") is not None:
        parts.append(f"{summary['wall_s']:.1f} s")
    for key, label, unit in (
            ("initial_shear_stiffness_n_m_per_rad", "initial shear stiffness", "N/m/rad"),
            ("locking_angle_deg", "locking angle", "deg"),
            ("initial_stiffness_n_m_per_width", "initial stiffness", "N/m"),
            ("initial_stiffness_n_m", "initial stiffness", "N/m"),
            ("max_force_n", "max force", "N")):
        if summary.get(key) is not None:
            parts.append(f"{label} {summary[key]:.4g} {unit}")
    if ke is not None:
        parts.append(f"KE/U <= {ke:.3g}")
    if eb is not None:
        parts.append(f"energy balance {100 * eb:.2f} %")
    return "; ".join(parts)
