"""``fabmd validate sliding``: mean F_t/F_n of a fibre pulled across another against μ.

Cases: μ = 0.1 and 0.3 with the default Hooke contact, and μ = 0.3 with Hertz. The
fibres are softened to E = 1 GPa: the load is a fixed fraction of E·A, so the force
ratio does not depend on E (only the number of steps grows, as sqrt(E)). The mean
over whole bead periods must be within 5 % of μ; the ripple (min, max, std of
F_t/F_n along the slide) is reported: it comes from the bead-chain bumps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..engine import Engine
from ..protocols.sliding import Sliding
from ..schema import unit
from .cases import run_cases
from .settings import FibreSettings, read

TOLERANCE = 0.05
#: (μ, normal model) of each case
CASES = ((0.1, "hooke"), (0.3, "hooke"), (0.3, "hertz"))
MODULUS_PA = 1e9
#: summary keys reported for each case
CASE_KEYS = ("mu", "normal", "pair_style", "measured_ratio", "rel_error", "ratio_min",
             "ratio_max", "ratio_std", "max_overlap_ratio", "steps")


@dataclass(frozen=True)
class Settings(FibreSettings):
    """What ``--set KEY=VALUE`` may change (SI; units as text accepted); see
    :class:`~fabmd.verification.settings.FibreSettings` for the fibres (here softened).

    Args:
        load_strain: normal load over E·A.
        stiffness_factor: the contact's stiffness factor.
        periods: bead periods slid.
    """

    modulus_pa: float = field(default=MODULUS_PA, metadata=unit("pressure"))
    speed_fraction: float = 0.02
    load_strain: float = 1e-3
    stiffness_factor: float = 0.1
    periods: float = 4


def from_settings(settings: dict, friction: float, normal: str) -> Sliding:
    """A :class:`Sliding` case with some defaults replaced (``--set`` values)."""
    from ..model.beads import Discretisation
    from ..model.contact import ContactModel

    s = read(Settings, settings, "sliding")
    contact = ContactModel(friction=friction, normal=normal,
                           stiffness_factor=s.stiffness_factor)
    return Sliding(fibre=s.fibre("glass, softened"), contact=contact,
                   load_strain=s.load_strain, periods=s.periods,
                   speed_fraction=s.speed_fraction,
                   discretisation=Discretisation(spacing_ratio=s.spacing_ratio),
                   time_step=s.time_step)


def check(out: Path | None = None, engine: Engine | None = None, overwrite: bool = False,
          settings: dict[str, float] | None = None) -> dict:
    """Run the sliding cases; each mean F_t/F_n must be within 5 % of μ."""
    settings = settings or {}
    tests = [from_settings(settings, mu, normal) for mu, normal in CASES]
    named = [(f"mu{t.contact.friction:g}-{t.contact.normal}", t) for t in tests]
    head = {"check": "sliding", "closed_form": "mean F_t/F_n = mu",
            "modulus_pa": tests[0].fibre.material.modulus_pa,
            "spacing_ratio": tests[0].discretisation.spacing_ratio}
    return run_cases("sliding", named, CASE_KEYS, head, TOLERANCE, out, engine, overwrite)
