"""Yarn tension of a bead model: the state the crimp leaves the fabric in.

The tension of a harmonic fibre bond (E = K·(r − r0)²) is T = 2K·(r − r0) [N]
(positive: stretched). A virtual fibre's tension is the mean over its bonds, a yarn's
the sum over its fibres (the axial force through a cross-section of the yarn), and a
family's the mean over its yarns. In textile units: T/tex in cN/tex (1 cN/tex =
0.01 N per tex of the yarn's linear density), when the model knows the linear density
(a model built from a fabric does: ``info["families"][family]["linear_density_tex"]``).
Cohesion links between the fibres of a yarn are not fibres and are left out. (The
crimped measures' ``tension``, :func:`fabmd.results.measure.family_tension_n`, give the
mean and largest fibre tension; this adds the spread over yarns and cN/tex.)
"""

from __future__ import annotations

import numpy as np

from ..model.bead_model import BeadModel
from .measure import bond_tension_n


def yarn_tension(model: BeadModel) -> dict[str, dict]:
    """Tension per yarn family: ``yarn_n`` (mean over the family's yarns), ``yarn_min_n``,
    ``yarn_max_n``, ``fibre_n`` (mean per virtual fibre), ``cn_per_tex`` (None when the
    linear density is unknown), ``linear_density_tex``, ``yarns``."""
    if not model.n_bonds:
        return {}
    fibre_bonds = model.fibre_bond_mask()
    tension = bond_tension_n(model)[fibre_bonds]
    fibre_of_bond = model.fibre_ids[model.bonds[fibre_bonds, 0]]
    n_fibres = len(model.fibre_yarn)
    total = np.bincount(fibre_of_bond, weights=tension, minlength=n_fibres + 1)
    count = np.bincount(fibre_of_bond, minlength=n_fibres + 1)
    per_fibre = np.divide(total, count, out=np.zeros_like(total), where=count > 0)[1:]
    has_bonds = count[1:] > 0
    per_yarn = np.bincount(model.fibre_yarn[has_bonds], weights=per_fibre[has_bonds],
                           minlength=len(model.yarns) + 1)[1:]
    families = (model.info or {}).get("families", {})
    out = {}
    for fam in model.family_names:
        yarns = [k for k, y in enumerate(model.yarns) if y.family == fam]
        fibres = [f for f in range(n_fibres) if has_bonds[f]
                  and model.yarns[model.fibre_yarn[f] - 1].family == fam]
        if not yarns or not fibres:
            continue
        t_yarn = per_yarn[yarns]
        tex = families.get(fam, {}).get("linear_density_tex")
        mean = float(t_yarn.mean())
        out[fam] = {"yarn_n": mean, "yarn_min_n": float(t_yarn.min()),
                    "yarn_max_n": float(t_yarn.max()),
                    "fibre_n": float(per_fibre[fibres].mean()),
                    "cn_per_tex": 100.0 * mean / tex if tex else None,
                    "linear_density_tex": tex, "yarns": len(yarns)}
    return out


def tension_line(tensions: dict[str, dict]) -> str:
    """One line for the terminal: 'warp 3.1 N (0.52 cN/tex), weft ...'."""
    parts = []
    for fam, t in tensions.items():
        unit = f" ({t['cn_per_tex']:.3g} cN/tex)" if t.get("cn_per_tex") is not None else ""
        parts.append(f"{fam} {t['yarn_n']:.3g} N per yarn{unit}")
    return "yarn tension after crimp: " + (", ".join(parts) if parts else "none")
