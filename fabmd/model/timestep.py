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


def fibre_transit_s(model) -> float:
    """Time an axial wave takes along the model's longest fibre [s]: its bead count ×
    √(m/k) of the stiffest-per-mass bead kind (the crimp's ramp, the preload ramp and the
    release count their durations in these transits)."""
    import math

    import numpy as np

    longest = int(np.bincount(model.fibre_ids).max())
    return longest * max(math.sqrt(b.mass_kg / b.spring_n_per_m)
                         for b in model_bead_parameters(model))


def berendsen_modulus_pa(model) -> float:
    """The modulus guess [Pa] a Berendsen box control of a periodic fabric cell is given:
    a hundredth of all fibres' E·A over the cell's section. A crimped fabric is far softer
    in-plane than its fibres, and a guess above its modulus relaxes slowly (a tenth left a
    fifth of the Twintex cell's tension after ten time constants); one far below it would
    overshoot."""
    lx, ly, lz = (model.box_hi - model.box_lo).tolist()
    ea = max(bt.bond_axial_stiffness_n for bt in model.bond_type_table)
    return 0.01 * max(model.n_fibres, 1) * ea / (min(lx, ly) * lz)
