"""The stable time step of a bead model in contact: the one place it is derived.

Every protocol, ``fabmd build`` and the single-fibre checks ask
:func:`stable_time_step_s` (or :func:`critical_time_step_s` for the bound itself)
instead of writing out ``min(b.critical_time_step_s(k) for b in beads)``: the
bound of :meth:`~fabmd.model.beads.BeadParameters.critical_time_step_s` with the
stiffest *stability* stiffness of the contacts present (fibre–fibre contact and
tools), so a Hertz contact counts with its tangent stiffness at the warning overlap.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from ..errors import InputError
from .beads import BeadParameters, TimeStep, model_bead_parameters


def bead_list(beads) -> list[BeadParameters]:
    """Bead parameters of ``beads``: a :class:`~fabmd.model.bead_model.BeadModel`, one
    :class:`BeadParameters` or a sequence of them."""
    if isinstance(beads, BeadParameters):
        return [beads]
    if isinstance(beads, Sequence):
        return list(beads)
    return model_bead_parameters(beads)


def contact_stiffness_n_per_m(beads: Sequence[BeadParameters], contacts: Iterable) -> float:
    """Stiffest stability stiffness [N/m] of ``contacts`` (``ContactModel``/``ToolContact``
    objects; ``None`` entries are skipped); 0 without contact."""
    return max((c.stability_stiffness_n_per_m(list(beads)) for c in contacts if c is not None),
               default=0.0)


def critical_time_step_s(beads, contacts: Iterable = ()) -> float:
    """Smallest critical time step [s] of ``beads`` (a model, one bead kind or a list)
    touching the stiffest of ``contacts``."""
    beads = bead_list(beads)
    if not beads:
        raise InputError("model has no bond types: cannot derive a time step")
    kn = contact_stiffness_n_per_m(beads, contacts)
    return min(b.critical_time_step_s(kn) for b in beads)


def stable_time_step_s(beads, contacts: Iterable = (), policy: TimeStep | None = None) -> float:
    """The time step to run with [s]: ``policy`` (default :class:`TimeStep`) applied to
    :func:`critical_time_step_s`; raises ``InputError`` for an explicit step above it."""
    return (policy or TimeStep()).resolve(critical_time_step_s(beads, contacts))
