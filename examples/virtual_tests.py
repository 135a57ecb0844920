"""Picture frame, bias extension and periodic cells on a small crimped plain weave.

Reproduces the example table of the README section "Virtual tests: picture frame, bias
extension, periodic cells" (a minute or two on 2 cores):

    python examples/virtual_tests.py runs/virtual-tests

The fabric is the tiny hand-built plain weave of the tests (single-fibre yarns 0.5 mm
thick, 1 mm apart, E = 1 GPa), crimped by a 2 % rest-length shrink in a periodic cell.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fabmd.engine import Engine  # noqa: E402
from fabmd.protocols.bias_extension import BiasExtension  # noqa: E402
from fabmd.protocols.coupon import Coupon  # noqa: E402
from fabmd.protocols.crimp import Crimp  # noqa: E402
from fabmd.protocols.periodic import PeriodicShear, PeriodicTension  # noqa: E402
from fabmd.protocols.picture_frame import PictureFrame  # noqa: E402
from fabmd.protocols.tension import Tension  # noqa: E402
from fabmd.results.curves import tangent_intersection  # noqa: E402
from tests.fabrics import plain_weave_cell  # noqa: E402
from tests.test_bias_extension import braced_bias_net  # noqa: E402


def main(root: Path) -> dict:
    engine = Engine(progress=False)
    rows = {}

    def record(name, result, t0, **extra):
        s = result.summary
        rows[name] = {"n_beads": s["n_beads"], "steps": s["steps"],
                      "wall_s": round(time.perf_counter() - t0, 2),
                      "energy_balance_error": s["energy_balance"]["relative_error"],
                      "max_ke_over_strain_energy": s.get("max_kinetic_to_strain_energy"),
                      **extra}
        print(name, json.dumps(rows[name]))

    cell = Crimp(expansion={"warp": -0.02, "weft": -0.02}).run(
        plain_weave_cell(spacing_m=1e-3, gap=1.0), root / "crimp", engine=engine,
        overwrite=True).model

    # tension: periodic cell (held across) and coupons, relaxed free and clamped as woven
    t0 = time.perf_counter()
    r = PeriodicTension(max_strain_pct=2.0).run(cell, root / "periodic_tension", engine=engine,
                                                overwrite=True)
    record("periodic tension", r, t0,
           initial_stiffness_n_m_per_width=r.summary["initial_stiffness_n_m_per_width"])
    for label, relax in (("relaxed", True), ("as woven", False)):
        kw = {} if relax else {"relax": None}
        coupon = Coupon(length_m=12e-3, width_m=6e-3, **kw).run(
            cell, root / f"coupon_tension_{relax}", engine=engine, overwrite=True).model
        t0 = time.perf_counter()
        r = Tension(max_elongation_pct=2.0).run(coupon, root / f"tension_{relax}",
                                                engine=engine, overwrite=True)
        # the same slope definition as the periodic cell: 10-40 % of the strain range
        c = r.curve
        slope = tangent_intersection(c["elongation_pct"] / 100, c["force_per_width_n_m"],
                                     initial=(0.1, 0.4), final=0.2)["initial_slope"]
        record(f"coupon tension ({label})", r, t0, initial_stiffness_n_m_per_width=slope)

    # shear: periodic cell and picture frame (coupon clamped as woven; with and without mu)
    t0 = time.perf_counter()
    r = PeriodicShear(max_shear_angle_deg=45).run(cell, root / "periodic_shear", engine=engine,
                                                  overwrite=True)
    record("periodic shear", r, t0,
           initial_shear_stiffness_n_m_per_rad=r.summary["initial_shear_stiffness_n_m_per_rad"],
           locking_angle_deg=r.summary["locking_angle_deg"],
           normalised_force_at_angle_n_m=r.summary["normalised_force_at_angle_n_m"])
    square = Coupon(length_m=6e-3, width_m=6e-3, relax=None).run(
        cell, root / "coupon_square", engine=engine, overwrite=True).model
    from fabmd.model.contact import ContactModel

    for mu in (0.3, 0.0):
        t0 = time.perf_counter()
        r = PictureFrame(max_shear_angle_deg=60, contact=ContactModel(friction=mu)).run(
            square, root / f"picture_frame_mu{mu}", engine=engine, overwrite=True,
            check_rate=(mu == 0.3))
        s = r.summary
        record(f"picture frame (mu = {mu})", r, t0,
               initial_shear_stiffness_n_m_per_rad=s["initial_shear_stiffness_n_m_per_rad"],
               locking_angle_deg=s["locking_angle_deg"],
               normalised_force_at_angle_n_m=s["normalised_force_at_angle_n_m"],
               mean_frame_force_n=s["mean_frame_force_n"], max_frame_force_n=s["max_frame_force_n"],
               rate_check=s.get("rate_check"))

    # bias extension: the braced trellis net of the tests (the tiny weave slips apart)
    t0 = time.perf_counter()
    r = BiasExtension(max_shear_angle_deg=30, speed_fraction=5e-4).run(
        braced_bias_net(), root / "bias_extension", engine=engine, overwrite=True)
    f = r.summary["fibre_shear_angle"]
    record("bias extension (braced net)", r, t0,
           shear_kinematic_deg=[round(x, 1) for x in f["kinematic_deg"][::3]],
           shear_fibres_deg=[round(x, 1) for x in f["fibres_deg"][::3]])
    (root / "table.json").write_text(json.dumps(rows, indent=2, default=str))
    return rows


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "runs/virtual-tests"))
