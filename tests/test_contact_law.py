"""Within-family law: same-family fibres follow the yarn's compaction law itself (nonlinear,
hard core past the packing limit), crossings keep the stiff contact (ContactModel docstring,
"Within-family law"; fabmd.model.bundle_contact)."""

import math
import tomllib
import warnings

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError, OverlapWarning, QuasiStaticWarning
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.bundle_contact import BundleContact
from fabmd.model.compaction import GLASS_BUNDLE, PACKING_LIMIT
from fabmd.model.contact import WITHIN_FAMILY_TABLE, ContactModel, default_stiffness_pa
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.common import run_folder, write_run_folder
from fabmd.scene import blocks
from fabmd.scene.energy import UNMEASURED_NOTE, ContactPower, balance
from fabmd.scene.templates import render

# one virtual fibre of a 600 tex glass yarn of 7, d of the plain-weave example
AREA = 600e-6 / 2540 / 7
D = 0.333e-3  # touches at Vf 0.351 in a hexagonal bundle (the law starts at 0.30)
FIBRE = VirtualFibre(GLASS, AREA, D)
LAW = BundleContact(GLASS_BUNDLE, AREA, D)


def law_contact(**kw) -> ContactModel:
    return ContactModel(friction=0.3, within_family_law=LAW, **kw)


def beads_for(spacing_ratio: float, length: float):
    b = bead_parameters(FIBRE, Discretisation(spacing_ratio))
    n = round(length / b.bond_length_m)
    return bead_parameters(FIBRE, Discretisation(spacing_ratio), bond_length_m=length / n), n


def chains(axes, types, spacing_ratio: float, box_lo, box_hi, periodic=(True, True, True),
           registers=None, diameter=D):
    """Periodic fibres along x (length 2 d), one per (y, z) in ``axes``; ``registers``: each
    fibre's bead offset along x as a fraction of l0 (default 0: all in register)."""
    length = 2 * D
    b, n = beads_for(spacing_ratio, length)
    k = len(axes)
    shifts = np.zeros(k) if registers is None else np.asarray(registers, float)
    pos = np.vstack([np.column_stack([b.bond_length_m * (np.arange(n) + u), np.full(n, y),
                                      np.full(n, z)]) for (y, z), u in zip(axes, shifts,
                                                                           strict=True)])
    ring = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    model = BeadModel(positions=pos, diameters=diameter, masses=b.mass_kg,
                      atom_types=np.repeat(np.asarray(types), n),
                      fibre_ids=np.repeat(np.arange(1, k + 1), n),
                      bonds=np.vstack([ring + i * n for i in range(k)]), bond_types=1,
                      family_names=("warp", "weft")[:max(types)],
                      bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "fibre",
                                                b.axial_stiffness_n)],
                      fibre_yarn=np.ones(k, np.int64), yarns=[Yarn("y", "warp")],
                      box_lo=np.array([0.0, *box_lo]), box_hi=np.array([length, *box_hi]),
                      periodic=periodic)
    return model, b


#: rows × columns of the hexagonal bundle; its fibres sit at random registers, as in a yarn
HEX_SIDE = 8


def hex_bundle(g: float, spacing_ratio: float = 0.5):
    """A periodic hexagonal lattice of 8 × 8 fibres at axis spacing g (six neighbours each),
    every fibre at its own register (a fixed random permutation of 64 offsets)."""
    h = math.sqrt(3) / 2 * g
    axes = [(i * g + 0.5 * g * (j % 2), j * h) for j in range(HEX_SIDE) for i in range(HEX_SIDE)]
    registers = np.random.default_rng(0).permutation(HEX_SIDE**2) / HEX_SIDE**2
    return chains(axes, (1,) * len(axes), spacing_ratio, (-0.25 * g, -0.5 * h),
                  ((HEX_SIDE - 0.25) * g, (HEX_SIDE - 0.5) * h), registers=registers)


def pair_of_fibres(r: float, spacing_ratio: float, types=(1, 1)):
    """Two parallel fibres with axes ``r`` apart along y (periodic in x only)."""
    return chains([(0.0, 0.0), (r, 0.0)], types, spacing_ratio, (-2 * D, -2 * D),
                  (2 * D + r, 2 * D), periodic=(True, False, False))


#: registers of the fibre pairs whose mean is the force per length of two parallel fibres
PAIR_REGISTERS = np.arange(16) / 16


def pairs_in_registers(r: float, spacing_ratio: float):
    """16 pairs of parallel fibres ``r`` apart along y, stacked 3 d apart in z: the second
    fibre of pair j (molecule 2j + 2) sits at register j/16 of the first."""
    axes, registers = [], []
    for j, u in enumerate(PAIR_REGISTERS):
        axes += [(0.0, 3 * D * j), (r, 3 * D * j)]
        registers += [0.0, u]
    top = 3 * D * len(PAIR_REGISTERS)
    return chains(axes, (1,) * len(axes), spacing_ratio, (-2 * D, -2 * D), (2 * D + r, top),
                  periodic=(True, False, False), registers=registers)


def probe(tmp_path, name, model, contact, b, measure: list[str], engine=None):
    """One step without an integrator (the beads stay put); the values of ``measure``."""
    dt = 0.25 * b.critical_time_step_s(contact.stability_stiffness_n_per_m([b]))
    text = "\n".join([
        blocks.setup(model, "probe", "model.data", dt), blocks.bonds(model),
        blocks.contact(model, contact, [b]), *measure,
        "run             1   # no integrator: the beads stay where they were placed",
        render("finish", final_data="final.data")])
    run_dir = write_run_folder(tmp_path / name, "probe", model, text, {},
                               files=blocks.contact_files(contact, [b]))
    run_folder(engine or Engine(progress=False), run_dir, "probe")
    return [float(v) for v in (run_dir / "out.txt").read_text().split()[-2:]]


PRESSURE = ["compute         pv all pressure NULL virial",
            "fix             out all ave/time 1 1 1 c_pv[2] c_pv[3] file out.txt format ' %.15g'"]
# y force on the second fibre (atoms of molecule 2) and the potential energy of the pairs
FORCE = ["group           second molecule 2",
         "compute         fy second reduce sum fy",
         "compute         epair all pe pair",
         "fix             out all ave/time 1 1 1 c_fy c_epair file out.txt format ' %.15g'"]
# the same over the second fibres of every pair (pairs_in_registers)
FORCE_PAIRS = [FORCE[0].replace("molecule 2", f"molecule 2:{2 * len(PAIR_REGISTERS)}:2"),
               *FORCE[1:]]


def test_law_contact_is_checked_and_rendered():
    b, _ = beads_for(0.5, 2 * D)
    c = law_contact()
    assert c.split and c.pair_style() == "hybrid/overlay"
    # the linear part: the steepest line under the pair force down to the core (per pair)
    kn_cross = default_stiffness_pa([b]) * b.bond_length_m
    k_lin = c.within_family_stiffness_n_per_m([b])
    r = np.linspace(LAW.core_spacing_m(kn_cross / b.bond_length_m), D, 500)[:-1]
    under = LAW.pair_force_n(r, b.bond_length_m, kn_cross / b.bond_length_m) - k_lin * (D - r)
    assert under.min() == pytest.approx(0.0, abs=1e-6 * k_lin * D) and under.max() > 0
    # the time step: the pair's steepest tangent, the core's k_n plus the law's own (1.05×)
    assert c.stability_stiffness_n_per_m([b]) == pytest.approx(1.05 * kn_cross, rel=0.01)
    with pytest.raises(InputError, match="not both"):
        ContactModel(within_family_law=LAW, within_family_stiffness_pa=1e5)
    with pytest.raises(InputError, match="hooke"):
        ContactModel(normal="hertz", within_family_law=LAW)
    with pytest.raises(InputError, match="bundle_contact.area_m2"):
        BundleContact(GLASS_BUNDLE, -1.0, D)
    with pytest.raises(InputError, match="packing limit"):
        BundleContact(GLASS_BUNDLE, AREA, 0.2e-3)
    model, b = hex_bundle(0.9 * D)
    text = blocks.contact(model, c, [b])
    assert "pair_style      hybrid/overlay granular table linear 4000" in text
    assert "pair_coeff      1 1 granular hooke" in text
    assert f"pair_coeff      1 1 table {WITHIN_FAMILY_TABLE} WITHIN_FAMILY" in text
    table = blocks.contact_files(c, [b])[WITHIN_FAMILY_TABLE]
    assert "\nWITHIN_FAMILY\nN 4000 R " in table
    # the pair_coeff cutoff lies just inside the table's end, never past it (a 19-fibre
    # Twintex yarn's d = 0.000293465655655 m was rounded up past it by 10-digit formatting:
    # LAMMPS stopped), nor on it (test_the_plain_weave_with_the_law_crimps)
    for law in (LAW, BundleContact(GLASS_BUNDLE, 0.6 * 0.000293465655655**2,
                                   0.000293465655655)):
        m, _ = chains([(0.0, 0.0)], (1,), 0.5, (-D, -D), (D, D), diameter=law.diameter_m)
        rendered = blocks.contact(m, ContactModel(friction=0.3, within_family_law=law), [b])
        cutoff = float(rendered.split("WITHIN_FAMILY ")[1].split()[0])
        end = float(law.table_text(b.bond_length_m, 1e9).split(" R ")[1].split()[1])
        assert law.diameter_m * (1 - 2e-9) < cutoff < end == pytest.approx(law.diameter_m)
    assert blocks.contact_files(ContactModel(), [b]) == {}
    # the energy column is the integral of the force column (LAMMPS checks it too)
    rows = np.array([ln.split() for ln in table.splitlines()[5:]], float)
    r, e, f = rows[:, 1], rows[:, 2], rows[:, 3]
    assert np.all(f >= -1e-9 * f.max()) and f[-1] == 0 and e[-1] == 0
    close = np.isclose(-np.gradient(e, r), f, rtol=1e-3, atol=1e-9)
    # all but a few rows at the core's kink and where the fibres touch (the register-
    # averaged force starts as sqrt(d − r) there, ~1e-7 of the table's largest force)
    assert close.mean() > 0.997


def test_the_contact_follows_the_law_and_has_a_hard_core():
    b, _ = beads_for(0.5, 2 * D)
    k_cross = default_stiffness_pa([b])
    core = LAW.core_spacing_m(k_cross)
    # glass: the core is the packing limit (the law's tangent is far below k_cross there)
    assert core == pytest.approx(LAW.packing_spacing_m)
    assert LAW.vf_at(core) == pytest.approx(PACKING_LIMIT)
    r = np.array([0.99, 0.9, 0.8, 0.7]) * D
    q = LAW.line_force_n_per_m(r, k_cross)
    p = math.sqrt(3) * q / r  # the bundle's pressure (virial)
    vf = LAW.vf_at(r)
    law = np.array([GLASS_BUNDLE.pressure_pa(v) for v in vf]) - LAW.touching_pressure_pa
    assert p == pytest.approx(law, rel=1e-12)
    # past the core: linear with the crossing stiffness, so the stable step is unchanged
    q1, q2 = LAW.line_force_n_per_m(np.array([core - 1e-7, core - 2e-7]), k_cross)
    assert (q2 - q1) / 1e-7 == pytest.approx(k_cross, rel=1e-6)
    # the scene key: within_family = { law = ..., form = "law" }
    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"] = {"friction": 0.3, "within_family": {"law": "glass", "form": "law"}}
    scene = parse_scene(data)
    assert scene.contact.within_family_law.law == GLASS_BUNDLE
    assert scene.contact.within_family_stiffness_pa is None
    data["contact"]["within_family"]["form"] = "cubic"
    with pytest.raises(InputError, match=r"\[contact.within_family\] form must be one of"):
        parse_scene(data)
    data["contact"]["within_family"] = {"law": "glass", "form": "law",
                                        "reference_pressure_pa": "100 kPa"}
    with pytest.raises(InputError, match="reference_pressure_pa applies to form"):
        parse_scene(data)
    data["contact"]["within_family"] = {"law": "glass"}  # default: the linear secant
    assert parse_scene(data).contact.within_family_law is None


@pytest.mark.lammps
@pytest.mark.parametrize("pressure", [1e4, 1e5, 3e5])
def test_a_hexagonal_bundle_compacts_as_the_law(tmp_path, pressure):
    """(a) A periodic hexagonal bundle of one family at the spacing where the law gives
    ``pressure``: LAMMPS's virial pressure is that pressure (1 %; 1.5 % at 10 kPa, where
    64 random registers sample the bumpiest overlaps), and the Vf it implies is the
    bundle's (2 %). The law realised is shifted to 0 where the virtual fibres touch (Vf
    0.351 > the law's 0.30): Vf = law(p + p(Vf_touch))."""
    g = LAW.spacing_at(pressure)
    model, b = hex_bundle(g)
    pyy, pzz = probe(tmp_path, "bundle", model, law_contact(), b, PRESSURE)
    for p in (pyy, pzz):
        assert p == pytest.approx(pressure, rel=0.015 if pressure < 5e4 else 0.01)
        assert LAW.volume_fraction(p) == pytest.approx(LAW.vf_at(g), rel=0.02)


def test_the_pair_force_scales_with_the_bead_spacing_squared():
    """F = l0²·f(ρ): the mean force per length over register is the law at every overlap
    for either spacing (64 registers, Python sums), with the bumpiness of one register
    shrinking as the overlap grows (module docstring's numbers)."""
    k_cross = default_stiffness_pa([beads_for(0.5, 2 * D)[0]])
    rho = np.linspace(0.65, 0.999, 50) * D
    assert LAW.pair_force_n(rho, 0.25 * D, k_cross) == pytest.approx(
        LAW.pair_force_n(rho, 0.5 * D, k_cross) / 4, rel=1e-12)
    for delta in (0.03, 0.1, 0.2, 0.33):
        h = (1 - delta) * D
        q = LAW.line_force_n_per_m(h, k_cross)
        for ratio in (0.5, 0.25):
            assert LAW.mean_line_force_n_per_m(h, ratio * D, k_cross) == pytest.approx(
                q, rel=0.005)
    h = 0.8 * D
    one = [LAW.mean_line_force_n_per_m(h, 0.5 * D, k_cross, register=u) for u in (0, 0.5)]
    assert 0.02 < abs(one[0] - one[1]) / LAW.line_force_n_per_m(h, k_cross) < 0.1


@pytest.mark.lammps
def test_two_parallel_fibres_carry_the_law_per_unit_length_at_either_spacing(tmp_path):
    """(b) Two parallel fibres pressed together, averaged over 16 registers: the law's force
    per unit length (≤ 2 %) at s/d 0.5 and 0.25 alike, from barely touching (δ = 0.03 d)
    to near the packing limit (0.33 d, about 300 kPa); one register alone carries what
    :meth:`BundleContact.mean_line_force_n_per_m` predicts for it (the bumpiness)."""
    k_cross = default_stiffness_pa([beads_for(0.5, 2 * D)[0]])
    per_length = {}
    for delta in (0.03, 0.2, 0.33):
        r = (1 - delta) * D
        q_law = LAW.line_force_n_per_m(r, k_cross)
        for ratio in (0.5, 0.25):
            model, b = pairs_in_registers(r, ratio)
            fy, _ = probe(tmp_path, f"pairs_{delta}_{ratio}", model, law_contact(), b,
                          FORCE_PAIRS)
            per_length[delta, ratio] = fy / (2 * D) / len(PAIR_REGISTERS) / q_law
    for delta in (0.03, 0.2, 0.33):
        assert per_length[delta, 0.5] == pytest.approx(1.0, rel=0.02), delta
        assert per_length[delta, 0.25] == pytest.approx(1.0, rel=0.02), delta
        assert per_length[delta, 0.25] == pytest.approx(per_length[delta, 0.5], rel=0.02)
    r = 0.8 * D
    model, b = pair_of_fibres(r, 0.5)
    fy, _ = probe(tmp_path, "in_register", model, law_contact(), b, FORCE)
    assert fy / (2 * D) == pytest.approx(LAW.mean_line_force_n_per_m(
        r, b.bond_length_m, k_cross, register=0.0), rel=1e-3)


@pytest.mark.lammps
@pytest.mark.slow
def test_the_plain_weave_with_the_law_crimps(tmp_path):
    """The shipped plain weave's cell with the law, crimped a little (``fabmd crimp``, ~10 s):
    its fibres are built touching at d to rounding, and with the cutoff on the table's end
    LAMMPS stopped at the first step ("Pair distance > table outer cutoff", measured)."""
    from fabmd.examples_dir import example_scene

    from .conftest import run_cli

    text = example_scene("plain_weave.toml").read_text()
    assert 'within_family = { law = "glass", form = "law" }' in text  # the example's own
    text = text.replace('target_tension = "1 cN/tex"\n', "")  # one crimp, not the search
    for key in ("target_crimp_pct = { warp = 1.5, weft = 1.5 }\n",
                'crimp_by = "loose_height"\n', "crimp_tolerance_pct = 0.05\n"):
        assert key in text
        text = text.replace(key, "")  # nor the loose height's
    text = text.replace("warp = -0.068, weft = -0.068", "warp = -0.02, weft = -0.02")
    assert "target_tension" not in text and "-0.02" in text
    scene = tmp_path / "law.toml"
    scene.write_text(text)
    done = run_cli("crimp", str(scene), "--form", "cell", "--out", str(tmp_path / "c"),
                   "--np", "1", "--quiet")
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "c" / "within_family.table").exists()


@pytest.mark.lammps
def test_a_crossing_of_two_families_keeps_the_crossing_stiffness(tmp_path):
    """(c) The same pair of fibres, of two families: the crossing's k'·δ per unit length,
    no law (the table is on same-family type pairs only)."""
    delta = 0.01
    model, b = pair_of_fibres((1 - delta) * D, 0.5, types=(1, 2))
    c = law_contact()
    fy, evdwl = probe(tmp_path, "cross", model, c, b, FORCE)
    k_cross = c.normal_stiffness_n_per_m([b]) / b.bond_length_m
    assert fy / (2 * D) == pytest.approx(k_cross * delta * D, rel=1e-6)
    assert evdwl == 0.0  # no table energy between families
    same, b1 = pair_of_fibres((1 - delta) * D, 0.5)
    fy1, evdwl1 = probe(tmp_path, "same", same, c, b1, FORCE)
    assert fy1 / (2 * D) == pytest.approx(LAW.mean_line_force_n_per_m(
        (1 - delta) * D, b1.bond_length_m, k_cross, register=0.0), rel=1e-3)
    assert fy1 < 1e-3 * fy and evdwl1 > 0  # the table's (conservative) energy is evdwl


@pytest.mark.lammps
@pytest.mark.mpi
def test_the_law_gives_the_same_forces_on_two_mpi_ranks(tmp_path, mpirun):
    """(d) The run folder runs as ``mpirun lmp -in`` (the table beside the input), and two
    ranks give the pressure of one."""
    model, b = hex_bundle(LAW.spacing_at(1e5))
    one = probe(tmp_path, "one", model, law_contact(), b, PRESSURE,
                Engine(backend="standalone", progress=False))
    two = probe(tmp_path, "two", model, law_contact(), b, PRESSURE,
                Engine(backend="standalone", ranks=2, progress=False))
    assert one[0] == pytest.approx(1e5, rel=0.01)
    assert two == pytest.approx(one, rel=1e-9)


def test_the_energy_balance_says_not_measured_with_the_law():
    """(e) Under hybrid/overlay ``pair/local`` loses the tangential force of overlaid pairs
    (measured): the contact power is not sampled, the balance says so (no NaN)."""
    power = ContactPower(law_contact().pair_style())
    assert not power.measured
    assert "compute" not in ContactPower.commands("hybrid/overlay").replace("#", "")
    power(_FakeLammps(100))
    power(_FakeLammps(200))
    work = power.work_j(np.array([100, 150, 200]), 1e-7)
    one = np.array([0.0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error", QuasiStaticWarning)
        with pytest.raises(QuasiStaticWarning, match="within-family law"):
            balance(one, one, one, one, work)
    with pytest.warns(QuasiStaticWarning):
        terms = balance(one, one, one, one, work)
    assert terms["note"] == UNMEASURED_NOTE
    assert terms["contact_work_j"] is None and terms["relative_error"] is None


class _FakeLammps:
    def __init__(self, step: int):
        self.step = step

    def extract_global(self, name):
        assert name == "ntimestep"
        return self.step


@pytest.mark.lammps
@pytest.mark.slow
def test_the_example_cell_crimps_with_the_law_and_its_folder_holds_the_table(tmp_path):
    """The plain-weave cell with ``within_family = { law = "glass", form = "law" }``: the
    crimp's run folder holds the table beside the input, the crimp is quasi-static and no
    yarns pass through each other (−4.5 %: 1.336 mm, 0 flipped pairs)."""
    from fabmd.examples_dir import example_scene
    from fabmd.pipeline import run_crimp
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"] = {"friction": 0.3, "within_family": {"law": "glass", "form": "law"}}
    data["crimp"] = {"expansion": {"warp": -0.045, "weft": -0.045}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QuasiStaticWarning)
        warnings.simplefilter("error", OverlapWarning)  # the law's pairs reach its core
        result = run_crimp(parse_scene(data), tmp_path / "crimp",
                           Engine(progress=False, ranks=1), form="cell")
    folder = tmp_path / "crimp"
    assert (folder / WITHIN_FAMILY_TABLE).is_file()
    assert "hybrid/overlay granular table" in (folder / "in.crimp").read_text()
    s = result.summary
    assert s["quasi_static"] and s["pass_through"]["flipped_pairs"] == 0
    assert s["overlap"]["max_overlap_ratio"] < 0.1  # counted from the law's hard core
    # the tension at this level is not resolved: the same state (1.34 mm, 4.5 % crimp)
    # stopped quasi-static with +0.55 and −1.04 cN/tex at time steps 3 % apart
    assert abs(s["yarn_tension"]["warp"]["cn_per_tex"]) < 2.0
    assert 1.2e-3 < s["crimped"]["thickness_m"] < 1.45e-3  # measured 1.336 mm
