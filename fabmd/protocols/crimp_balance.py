"""Whether the crimp of a balanced fabric went into one family (crimp interchange): warp
and weft drawn alike that crimp far apart. The crimp stage of a balanced fabric has more
than one outcome, and the forces follow it (benchmarks/RESULTS.md "Crimp pinned by the
loose height")."""

from __future__ import annotations

import warnings
from pathlib import Path

#: warp and weft drawn alike (loose crimps within this relative difference) that crimp
#: to crimps this many times apart are reported as a crimp interchange
INTERCHANGE_LOOSE_TOLERANCE = 0.05
INTERCHANGE_RATIO = 1.5


def warn_interchange(run_dir: Path, summary: dict, stacklevel: int = 2) -> None:
    """Warn (``UserWarning``) where a crimp summary names a crimp interchange."""
    if summary.get("crimp_interchange"):
        warnings.warn(f"crimp in {run_dir}: {summary['crimp_interchange']}", UserWarning,
                      stacklevel=stacklevel + 1)


def crimp_interchange(loose: dict, crimped: dict) -> str | None:
    """A note where warp and weft were drawn alike but the crimp went into one of them
    (``fabric_measures`` of the loose and the crimped state), else None. The crimp stage
    of a balanced fabric has more than one outcome (benchmarks/RESULTS.md "Crimp pinned by
    the loose height": nineteen area-packed fibres crimped to 1.05 % warp / 2.10 % weft
    from loose yarns 0.8 mm high and to 2.49 / 0.89 % from 0.84 mm), and the forces follow
    the outcome."""
    c0, c1 = loose.get("crimp_pct") or {}, crimped.get("crimp_pct") or {}
    if not all(isinstance(d.get(f), int | float) for d in (c0, c1) for f in ("warp", "weft")):
        return None
    lo, hi = sorted((c0["warp"], c0["weft"]))
    a, b = sorted((c1["warp"], c1["weft"]))
    if hi <= 0 or hi - lo > INTERCHANGE_LOOSE_TOLERANCE * hi or a * INTERCHANGE_RATIO >= b:
        return None
    return (f"warp and weft were drawn alike (loose crimp {c0['warp']:.3g} / "
            f"{c0['weft']:.3g} %) but crimped to {c1['warp']:.3g} / {c1['weft']:.3g} %: the "
            f"crimp went into one family (crimp interchange, one of the crimp stage's "
            f"outcomes for a balanced fabric; a slightly different loose height can give the "
            f"other). If the fabric is balanced, give both crimps as targets: fabmd "
            f"calibrate with [calibrate] crimp_pct = {{ warp = ..., weft = ... }} and "
            f"crimp_by = \"loose_height\"")
