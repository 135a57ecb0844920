"""The compaction test's platen speed, from the fabric's through-thickness wave speed (SI).

Why not a fraction of the fibres' axial wave speed: the load crosses a soft fabric through
its thickness far more slowly than it runs along a fibre. While it crosses, the platens
differ by about the pressure a wave of the platen speed v carries into a layer of
impedance ρ_f·c_t, so the top/bottom mismatch that the verdict judges
(``quasi_static_at_pressure``) is, at a pressure p,

    m ≈ ρ_f·c_t·v / p = (v / c_t) · K_t / p,      c_t = sqrt(K_t / ρ_f),

ρ_f the fabric's density [kg/m³] (areal density over thickness), K_t its through-thickness
tangent modulus dp/dε [Pa]. The platen speed that holds m at a target at the lowest reported
pressure p_low is therefore the fraction m·p_low/K_t of c_t:

    v = m · p_low / (ρ_f · c_t) = (m · p_low / K_t) · c_t.

m falls above p_low at that speed (ρ_f·c_t grows more slowly than p), so one speed serves
every reported pressure.

K_t, from the yarn compaction law the contact realises (:mod:`fabmd.model.bundle_contact`):
a fabric that thins as its yarns compact at constant width has Vf ∝ 1/h, so
K_t = Vf·dp/dVf = n·k·E·Vf^n = n·(p + k·E·Vf_s^n), with Vf_s = max(Vf0, Vf_touch) (the law as
realised is shifted to 0 where the virtual fibres touch). Of several families the stiffest
is taken (the slower speed). Chosen over a modulus measured on the fly because it is known
before the run (speed, steps and refusal stated before LAMMPS starts) and the input stays a
plain constant-speed ramp. Checked on Twintex cells (benchmarks/RESULTS.md "Compaction
speed"): where the law acts through the thickness (19 fibres per yarn in two rows) the
measured mismatch was 0.25 of this prediction at 4.14 and 10 kPa and 0.85 at 100 kPa; where
it does not (7 fibres in one row: only the stiff crossings carry the load across) it was 7×
the prediction at 4.14 kPa — so a run whose reported thickness fails its verdict runs again
at the speed the measured mismatch asks for (:func:`fabmd.protocols.compaction.
rerun_speed_fraction`).

The pace. At a constant speed the lowest reported pressure sets the speed for the whole
travel, yet most of the travel is at high pressure, where m at that speed is far below its
target (m ∝ ρ_f·c_t/p falls as p grows). With ``speed_schedule = "pressure"`` the platen
moves at v0·φ(p), p the lower of the two platens' pressures over the last output interval
(the pressure the load has carried across the fabric) and

    φ(p) = (p / p0) · sqrt((p0 + T) / (p + T)),   T = k·E·Vf_s^n,  clipped to [1, MAX_PACE],

which holds the predicted mismatch m(p) = ρ_f·c_t(p)·v0·φ(p)/p at its value at p0 for
every p ≥ p0 (:func:`pace_factor`). On the plain-weave example's cell the estimate
(:func:`estimated_steps`) is 1.47 M steps to 200 kPa and back against 13.1 M at the constant
speed.

Without a law (solid-rod contact) the fabric's stiffness comes
from its crossings' geometry, which no contact parameter predicts (a hexagonal bundle of
solid-rod contacts would be 200× stiffer than the measured plain-weave cell): the speed
stays the fraction ``FALLBACK_SPEED_FRACTION`` of the fibres' axial wave speed, and the
per-pressure verdict judges it.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..model.bead_model import BeadModel
from ..model.beads import BeadParameters
from ..model.contact import ContactModel

#: the pressure schedule's largest speed over the base speed
MAX_PACE = 100.0
#: the platen speed over the fibres' axial wave speed where no compaction law is known
FALLBACK_SPEED_FRACTION = 5e-6
#: travel before both platens carry the load, over the starting gap, for the step estimate
#: (the platens start on the settled fabric's outermost surfaces: measured under 1 µm on
#: the crimped Twintex and plain-weave cells)
APPROACH_FRACTION = 0.02


def axial_wave_speed_m_s(beads: list[BeadParameters]) -> float:
    """The slowest axial wave speed of the model's fibres [m/s]."""
    return min(b.wave_speed_m_s for b in beads)


def fabric_density_kg_m3(model: BeadModel, area_m2: float, thickness_m: float) -> float:
    """ρ_f: the beads' mass over the cell's area [m²] and the fabric's thickness [m]."""
    return float(model.masses.sum()) / (area_m2 * thickness_m)


def law_stiffness_pa(contact: ContactModel) -> tuple[float, float] | None:
    """(n, k·E·Vf_s^n [Pa]) of the stiffest family law of ``contact``: K_t = n·(p + that);
    None without a within-family law."""
    laws = [law for _, law in contact.within_family_laws] or (
        [contact.within_family_law] if contact.within_family_law is not None else [])
    if not laws:
        return None
    best = None
    for b in laws:
        n = b.law.exponent
        vf_s = max(b.law.vf0, b.touching_vf)
        term = b.law.coefficient * b.law.modulus_pa * vf_s**n
        if best is None or n * term > best[0] * best[1]:
            best = (n, term)
    return best


def through_thickness_modulus_pa(contact: ContactModel, pressure_pa: float) -> float | None:
    """K_t = dp/dε [Pa] at ``pressure_pa`` [Pa] from the contact's compaction law (module
    docstring); None without one."""
    law = law_stiffness_pa(contact)
    if law is None:
        return None
    n, term = law
    return n * (pressure_pa + term)


def law_strain(contact: ContactModel, pressure_pa: float) -> float:
    """Through-thickness strain [-] the law gives from touching to ``pressure_pa`` [Pa]:
    ln(Vf/Vf_s) = ln((p + k·E·Vf_s^n) / (k·E·Vf_s^n)) / n (0 without a law)."""
    law = law_stiffness_pa(contact)
    if law is None:
        return 0.0
    n, term = law
    return math.log((pressure_pa + term) / term) / n


def platen_speed(contact: ContactModel, model: BeadModel, beads: list[BeadParameters],
                 area_m2: float, thickness_m: float, pressure_pa: float,
                 mismatch: float) -> dict:
    """The platen speed [m/s] that holds the predicted platen mismatch at ``mismatch`` at
    ``pressure_pa`` [Pa] (module docstring), with what it came from (JSON-able).

    ``thickness_m``: the fabric's thickness for its density (the starting gap) [m]."""
    c_axial = axial_wave_speed_m_s(beads)
    k_t = through_thickness_modulus_pa(contact, pressure_pa)
    if k_t is None:
        return {"platen_speed_m_s": FALLBACK_SPEED_FRACTION * c_axial,
                "speed_basis": "axial",
                "speed_note": f"no yarn compaction law in the contact: "
                              f"{FALLBACK_SPEED_FRACTION:g} of the fibres' axial wave speed "
                              f"{c_axial:.4g} m/s",
                "axial_wave_speed_m_s": c_axial}
    rho = fabric_density_kg_m3(model, area_m2, thickness_m)
    c_t = math.sqrt(k_t / rho)
    fraction = mismatch * pressure_pa / k_t
    return {"platen_speed_m_s": fraction * c_t, "speed_basis": "through_thickness",
            "speed_note": f"{fraction:.3g} of the fabric's through-thickness wave speed "
                          f"c_t = {c_t:.4g} m/s at {pressure_pa:g} Pa (K_t = {k_t:.4g} Pa, "
                          f"rho_f = {rho:.4g} kg/m3): predicted platen mismatch {mismatch:g}",
            "axial_wave_speed_m_s": c_axial, "through_thickness_modulus_pa": k_t,
            "fabric_density_kg_m3": rho, "through_thickness_wave_speed_m_s": c_t,
            "wave_speed_fraction": fraction, "speed_pressure_pa": pressure_pa}


def pace_factor(pressure_pa, base_pressure_pa: float, law_pa: float):
    """φ(p) = (p/p0)·sqrt((p0 + T)/(p + T)) clipped to [1, :data:`MAX_PACE`] (module
    docstring): the platen speed over its base at the pressure ``pressure_pa`` [Pa]; p0 =
    ``base_pressure_pa`` [Pa], where the base speed holds the mismatch, T = ``law_pa`` =
    k·E·Vf_s^n [Pa] of the law (:func:`law_stiffness_pa`)."""
    p = np.maximum(np.asarray(pressure_pa, dtype=float), base_pressure_pa)
    phi = p / base_pressure_pa * np.sqrt((base_pressure_pa + law_pa) / (p + law_pa))
    return np.clip(phi, 1.0, MAX_PACE)


def pace_formula(pressure: str, base_pressure_pa: float, law_pa: float) -> str:
    """ln φ of :func:`pace_factor` as a LAMMPS equal-style formula of the variable
    ``pressure`` [Pa] (a name, e.g. ``v_pace_p``); p below p0 is taken as p0 first (no log
    of zero)."""
    p = f"(ternary({pressure}>{base_pressure_pa!r},{pressure},{base_pressure_pa!r}))"
    phi = f"({p}/{base_pressure_pa!r}*sqrt({base_pressure_pa + law_pa!r}/({p}+{law_pa!r})))"
    return f"ln(ternary({phi}>{MAX_PACE!r},{MAX_PACE!r},{phi}))"


def estimated_steps(contact: ContactModel, gap_m: float, max_travel_m: float,
                    max_pressure_pa: float, speed_m_s: float, time_step_s: float,
                    unload: bool, base_pressure_pa: float | None = None) -> dict:
    """A rough step count of the loading (and unloading) before LAMMPS starts: the travel
    is an approach of :data:`APPROACH_FRACTION` of the gap plus the law's strain to
    ``max_pressure_pa`` (none without a law), at most ``max_travel_m``. An upper estimate
    where the law is given: it counts the whole fabric compacting as its yarns do (the
    one-row Twintex cell compacted 0.3 % to 100 kPa, the law says 18 %).

    ``base_pressure_pa``: the pressure schedule's p0 (None: a constant speed); the law's
    strain is then travelled at ``speed_m_s``·φ(p) (:func:`pace_factor`), the approach at
    ``speed_m_s``. ``loading_steps``: the loading's share."""
    travel = min(max_travel_m, gap_m * (APPROACH_FRACTION + law_strain(contact,
                                                                        max_pressure_pa)))
    law = law_stiffness_pa(contact)
    if base_pressure_pa is None or law is None:
        loading = math.ceil(travel / speed_m_s / time_step_s)
    else:
        n, term = law
        approach = min(travel, gap_m * APPROACH_FRACTION)
        # the law's strain ε(p) = ln((p + T)/T)/n, up to what the travel leaves
        strain_max = (travel - approach) / gap_m
        p_max = term * (math.exp(n * strain_max) - 1.0)
        paced = 0.0
        if p_max > 0.0:
            p = np.geomspace(min(1e-3 * base_pressure_pa, p_max), p_max, 4001)
            strain = np.log((p + term) / term) / n
            slow = 1.0 / pace_factor(p, base_pressure_pa, term)  # trapezoid of dε/φ
            paced = float(strain[0] + np.sum(0.5 * (slow[1:] + slow[:-1]) * np.diff(strain)))
        loading = math.ceil((approach / gap_m + paced) * gap_m / speed_m_s / time_step_s)
    return {"estimated_travel_m": travel, "loading_steps": loading,
            "estimated_steps": loading * (2 if unload else 1)}


def check_steps(estimate: int, limit: int, speed: dict) -> None:
    """Refuse a run whose estimated steps exceed ``limit`` (one line: what, why, remedy)."""
    if estimate > limit:
        raise InputError(
            f"compaction: about {estimate:,} steps at the platen speed "
            f"{speed['platen_speed_m_s']:.3g} m/s ({speed['speed_note']}) > "
            f"compaction.step_limit = {limit:,}; "
            + ("raise" if speed["speed_basis"] == "set" else "set")
            + f" compaction.speed_fraction (platen speed over the fibres' axial wave speed "
            f"{speed['axial_wave_speed_m_s']:.4g} m/s) or raise step_limit")
