"""``fabmd validate sliding``: mean F_t/F_n of a fibre pulled across another against μ.

Cases: μ = 0.1 and 0.3 with the default Hooke contact, and μ = 0.3 with Hertz. The
fibres are softened to E = 1 GPa: the load is a fixed fraction of E·A, so the force
ratio does not depend on E (only the number of steps grows, as sqrt(E)). The mean
over whole bead periods must be within 5 % of μ; the ripple (min, max, std of
F_t/F_n along the slide) is reported: it comes from the bead-chain bumps.
"""

from __future__ import annotations

from pathlib import Path

from ..engine import Engine
from ..protocols.sliding import Sliding
from .cases import run_cases
from .settings import check_known, fibre_from

TOLERANCE = 0.05
#: (μ, normal model) of each case
CASES = ((0.1, "hooke"), (0.3, "hooke"), (0.3, "hertz"))
MODULUS_PA = 1e9
#: summary keys reported for each case
CASE_KEYS = ("mu", "normal", "pair_style", "measured_ratio", "rel_error", "ratio_min",
             "ratio_max", "ratio_std", "max_overlap_ratio", "steps")

SETTINGS = ("modulus_pa", "density_kg_m3", "diameter_m", "spacing_ratio", "load_strain",
            "speed_fraction", "stiffness_factor", "periods", "time_step_factor")


def from_settings(settings: dict[str, float], friction: float, normal: str) -> Sliding:
    """A :class:`Sliding` case with some defaults replaced (SI values)."""
    from ..model.beads import Discretisation, TimeStep
    from ..model.contact import ContactModel

    check_known(settings, SETTINGS, "sliding")
    get = settings.get
    fibre = fibre_from(settings, MODULUS_PA, "glass, softened")
    disc = Discretisation() if "spacing_ratio" not in settings else \
        Discretisation(spacing_ratio=settings["spacing_ratio"])
    contact = ContactModel(friction=friction, normal=normal,
                           stiffness_factor=get("stiffness_factor", 0.1))
    return Sliding(fibre=fibre, contact=contact, load_strain=get("load_strain", 1e-3),
                   periods=get("periods", 4), speed_fraction=get("speed_fraction", 0.02),
                   discretisation=disc, time_step=TimeStep(factor=get("time_step_factor", 0.25)))


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
