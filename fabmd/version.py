"""fabmd's version, from the installed package's metadata (one place: pyproject.toml)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("fabmd")
except PackageNotFoundError:  # a source tree on sys.path without installing it
    __version__ = "0+unknown"
