"""What the ``fabmd`` command prints besides results: warnings as one line each."""

from __future__ import annotations

import sys
import warnings


def format_warning(message, category, filename=None, lineno=None, line=None) -> str:
    """``fabmd: warning: <message>`` on one line (no file, line or source)."""
    text = " ".join(str(message).split())
    return f"fabmd: warning: {text}\n"


def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A ``warnings.showwarning`` that prints :func:`format_warning` to stderr."""
    stream = file if file is not None else sys.stderr
    try:
        stream.write(format_warning(message, category))
    except (OSError, AttributeError):  # no stream to write to: nothing to do
        pass


def install_warning_format() -> None:
    """Print every Python warning the command issues as one ``fabmd: warning:`` line."""
    warnings.showwarning = show_warning
