"""``fabmd validate CHECK``: physics checks against closed form."""

from __future__ import annotations

import argparse

from .common import add_run_options, emit, engine_from

#: check name -> module in fabmd.verification
CHECKS = {
    "fibre-tension": "fibre_tension",
    "capstan": "capstan",
    "sliding": "sliding",
}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("check", choices=sorted(CHECKS), help="which check to run")
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a parameter of the check (SI, or text with a unit; "
                        "repeatable), e.g. --set spacing_ratio=0.25, --set diameter_m='0.1 mm',"
                        " --set time_step.factor=0.2")
    add_run_options(p)


def parse_settings(pairs: list[str]) -> dict:
    """``["a=1", "b=2 mm", "time_step.factor=0.2"]`` -> ``{"a": 1.0, "b": "2 mm",
    "time_step": {"factor": 0.2}}``: numbers as floats, other text as given (a quantity
    with its unit, read by the check's schema); a dot opens a sub-table. One-line errors."""
    from ..errors import InputError

    out: dict = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        key = key.strip()
        if not sep or not key or "" in key.split("."):
            raise InputError(f"--set expects KEY=VALUE (KEY may be table.key), got {pair!r}")
        *tables, last = key.split(".")
        where = out
        for name in tables:
            where = where.setdefault(name, {})
            if not isinstance(where, dict):
                raise InputError(f"--set {key}: {name} is a value, not a table")
        try:
            where[last] = float(value)
        except ValueError:
            where[last] = value.strip()
    return out


def run(args) -> int:
    import importlib

    module = importlib.import_module(f"fabmd.verification.{CHECKS[args.check]}")
    settings = parse_settings(args.set)
    result = module.check(out=args.out, engine=engine_from(args), overwrite=args.overwrite,
                          settings=settings)
    from .report import value_text

    lines = [f"{args.check}: {'PASSED' if result['passed'] else 'FAILED'}"]
    for key, value in result.items():
        if key not in ("check", "passed", "cases"):
            shown = value_text(key, value) if isinstance(value, int | float) else value
            lines.append(f"  {key:32s} {shown}")
    for case in result.get("cases", []):
        lines.append("  " + ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                                      for k, v in case.items()))
    emit(result, args.json, "\n".join(lines))
    return 0 if result["passed"] else 1
