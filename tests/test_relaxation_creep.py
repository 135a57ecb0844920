"""A relaxation that says "at rest" has reached rest: a fibre bent against its straight rest
shape, held at one end, is straight again when its relaxation stops.

The defect this guards against (stop 46, benchmarks/RESULTS.md "A relaxation that stops
while the fabric still creeps"): the relaxation's drag overdamps a slow bending mode, which
then creeps with forces per bead far below the stop's force scale (a fraction of a fibre
tension) and a kinetic energy far below its energy floor, so a damped run stops while the
fibre is still bent. The relaxation now goes on undamped after it (velocities zeroed when
the forces work against the motion) until nothing moves (stop 47, "A relaxation that waits
until nothing moves")."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from fabmd.model.bead_model import AngleType
from fabmd.model.beads import model_critical_time_step_s
from fabmd.model.bending import chain_triples
from fabmd.scene import blocks
from fabmd.scene.quasi_static import SETTLED_MESSAGE, QuasiStatic

from .fabrics import parallel_fibres


def _bent_chain():
    """One fibre, straight at rest, bent into an arc across y, with a bending term whose
    lowest mode is far slower than the relaxation's drag time (overdamped by it)."""
    chain = parallel_fibres(n=1, length_m=4e-3, diameter_m=0.5e-3, spacing_ratio=0.5)
    l0 = chain.bond_type_table[0].rest_length_m
    ei = 3e-8  # a hundredth of the solid fibre's E·A·d²/16, as the filaments' share is
    triples = chain_triples(chain)
    x = chain.positions[:, 0] - chain.positions[:, 0].min()
    bent = chain.positions.copy()
    bent[:, 1] += 0.2e-3 * (x / x.max()) ** 2  # tip 0.2 mm off the straight line
    return dataclasses.replace(chain, positions=bent, angles=triples,
                               angle_types=np.ones(len(triples), np.int64),
                               angle_type_table=[AngleType(ei / l0, "warp")])


@pytest.mark.lammps
def test_a_relaxation_does_not_stop_while_a_bent_fibre_creeps_back(tmp_path):
    from fabmd.engine.library import new_instance

    chain = _bent_chain()
    chain.save(tmp_path, "model")
    x = chain.positions[:, 0]
    held = np.flatnonzero(x < x.min() + 1.5 * chain.bond_type_table[0].rest_length_m)
    tip = int(np.argmax(x))
    ea = chain.bond_type_table[0].bond_axial_stiffness_n
    k = chain.bond_type_table[0].spring_n_per_m
    ref = 1e-3 * ea  # as the coupon's relaxation
    dt = 0.5 * model_critical_time_step_s(chain)
    relax = QuasiStatic(max_steps=400_000)
    lmp = new_instance(["-log", str(tmp_path / "log.lammps"), "-screen", "none"])
    try:
        lmp.commands_string("\n".join([
            blocks.setup(chain, "relax", str(tmp_path / "model.data"), dt),
            blocks.bonds(chain),
            f"pair_style zero {float(chain.diameters.max())}\npair_coeff * *",
            "group held id " + " ".join(str(i + 1) for i in held),
            "group free subtract all held",
            "fix integrate free nve",
            blocks.relax(chain, dt, "held", "free", relax, ref,
                         len(chain.bonds) * ref**2 / (2 * k)),
        ]))
        pos = np.array(lmp.gather_atoms("x", 1, 3)).reshape(-1, 3)
    finally:
        lmp.close()
    log = (tmp_path / "log.lammps").read_text()
    stop = re.search(SETTLED_MESSAGE + r" on step (\d+)", log)
    assert stop, "the relaxation did not come to rest within its steps"
    # the tip started 0.2 mm off the line of the held end (the rest shape is straight);
    # measured: the damped run alone stopped at 2,500 steps with the tip 0.183 mm off (its
    # largest force 1.4e-4 N against the limit 3.9e-4 N, KE/U 8.5e-5 against 1e-4); with the
    # undamped run after it the relaxation stops at 13,500 steps, 0.012 mm off (the line
    # through the two held beads, which sit on the bent shape, is itself 0.012 mm off there)
    held_line = chain.positions[held, 1].mean()
    offset = abs(pos[tip, 1] - held_line)
    assert offset < 0.02e-3, (f"stopped at step {stop.group(1)} with the tip still "
                              f"{offset * 1e3:.3f} mm off the straight line")


@pytest.mark.lammps
def test_a_coupon_whose_fibres_bend_says_its_rest_is_provisional(tmp_path):
    """A coupon with bending says, in a warning and in its summary, that its start state is
    provisional (cut free it warps out of its woven shape: stop 47); one without stays
    quiet."""
    import warnings

    from fabmd.engine import Engine
    from fabmd.errors import QuasiStaticWarning
    from fabmd.protocols.coupon import Coupon

    from .test_cohesion import _one_yarn

    plain = Coupon(length_m=6e-3, width_m=2.4e-3,
                   relax=QuasiStatic(max_steps=2_000, check_every=200))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        quiet = plain.run(_one_yarn(n_fibres=6), tmp_path / "plain",
                          engine=Engine(progress=False))
    assert quiet.summary["rest_note"] is None
    assert not any("fibres bend" in str(w.message) for w in caught)
    bent = dataclasses.replace(plain, bending_factor=0.01)
    with pytest.warns(QuasiStaticWarning, match="fibres bend"):
        result = bent.run(_one_yarn(n_fibres=6), tmp_path / "bent",
                          engine=Engine(progress=False))
    assert "provisional" in result.summary["rest_note"]


def test_the_motion_limit_of_a_relaxation_is_checked_when_it_is_built():
    from fabmd.errors import InputError

    with pytest.raises(InputError, match="motion_ratio"):
        QuasiStatic(motion_ratio=0.0)
    assert QuasiStatic().motion_ratio == 1e-4
