"""Input fragments rendered from ``lammps_templates/`` for a bead model."""

from __future__ import annotations

from ..model.bead_model import BeadModel
from ..model.beads import BeadParameters
from ..model.contact import ContactModel
from .templates import fmt, render

#: neighbour skin as a fraction of the smallest bead diameter (LAMMPS-NOTES: ~0.2 d)
SKIN_FRACTION = 0.2
#: a bead that moves this fraction of the shortest bond per step is running away
SPEED_FRACTION = 0.1
#: a bond longer than this multiple of the longest rest length is running away
BOND_RUNAWAY = 1.5


def boundary_text(model: BeadModel) -> str:
    """LAMMPS ``boundary`` argument: p where periodic, else fixed (f)."""
    return " ".join("p" if p else "f" for p in model.periodic)


def neighbour_skin(model: BeadModel) -> float:
    """Neighbour skin [m]."""
    return SKIN_FRACTION * float(model.diameters.min())


def comm_cutoff(model: BeadModel) -> float:
    """Ghost cutoff [m]: covers contact (largest diameter + skin) and three bond lengths."""
    longest_bond = max((bt.rest_length_m for bt in model.bond_type_table), default=0.0)
    return max(float(model.diameters.max()) + neighbour_skin(model), 3.0 * longest_bond) * 1.01


def setup(model: BeadModel, protocol: str, data_file: str, time_step_s: float) -> str:
    """Units, atom style, box, beads, neighbour settings, time step."""
    return render("setup", protocol=protocol, boundary=boundary_text(model),
                  comm_cutoff=comm_cutoff(model), data_file=data_file,
                  skin=neighbour_skin(model), time_step=time_step_s)


def bonds(model: BeadModel, rest_length_scale: dict[int, float] | None = None) -> str:
    """``bond_style harmonic`` with one coefficient line per bond type (and angles)."""
    scale = rest_length_scale or {}
    lines = [f"bond_coeff      {i} {fmt(bt.coefficient)} "
             f"{fmt(bt.rest_length_m * scale.get(i, 1.0))}   # {bt.family}"
             for i, bt in enumerate(model.bond_type_table, start=1)]
    if model.angle_type_table and len(model.angles):
        angle = ["angle_style     cosine"]
        angle += [f"angle_coeff     {i} {fmt(at.coefficient)}   # {at.family}"
                  for i, at in enumerate(model.angle_type_table, start=1)]
        angle_block = "\n".join(angle)
    else:
        angle_block = "# no bending term in this scene"
    return render("bonds", bond_coeffs="\n".join(lines), angle_block=angle_block)


def guards(model: BeadModel, time_step_s: float, every: int = 100,
           max_rest_length_scale: float = 1.0) -> str:
    """Stability guards (see :mod:`fabmd.engine.diagnosis` for the causes)."""
    shortest = min((bt.rest_length_m for bt in model.bond_type_table),
                   default=float(model.diameters.min()))
    speed_limit = SPEED_FRACTION * shortest / time_step_s
    if model.n_bonds:
        longest = max(bt.rest_length_m for bt in model.bond_type_table)
        bond_guard = render("bond_guard", bond_limit=BOND_RUNAWAY * longest
                            * max_rest_length_scale, every=every)
    else:
        bond_guard = "# no bonds: no bond-stretch guard"
    return render("guards", speed_fraction=SPEED_FRACTION, speed_limit=speed_limit,
                  every=every, bond_guard=bond_guard)


def trajectory(every: int, *, velocities: bool = False, bond_forces: bool = True) -> str:
    """Outputs block: a trajectory frame every ``every`` steps (see
    :mod:`fabmd.scene.outputs`; put :func:`trajectory_final` after the last run and call
    :func:`fabmd.results.trajectory.finalise` on the run folder afterwards)."""
    from . import outputs

    return outputs.trajectory(every, velocities=velocities, bond_forces=bond_forces)


def trajectory_final(bond_forces: bool = True) -> str:
    """After the last run: the final step as the trajectory's last frame."""
    from . import outputs

    return outputs.trajectory_final(bond_forces)


def contact(model: BeadModel, contact_model: ContactModel | None,
            beads: list[BeadParameters]) -> str:
    """Fibre–fibre contact, or ``pair_style none`` when the scene needs none."""
    if contact_model is None:
        return render("contact_none")
    c = contact_model.pair_coefficients(beads)
    return render("contact_granular", normal=contact_model.normal,
                  style=contact_model.pair_style(), **c)
