"""Where bundled data (schemas, definitions, drivers, examples) lives.

In an installed wheel it sits in ``gadgetctl/_data``; in a source checkout (and an
editable install) it is the repository's top-level folders.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


@cache
def data_root() -> Path:
    installed = _PACKAGE_DIR / "_data"
    if installed.is_dir():
        return installed
    return _PACKAGE_DIR.parents[1]


def schemas_dir() -> Path:
    return data_root() / "schemas"


def definitions_dir() -> Path:
    return data_root() / "definitions"


def drivers_dir() -> Path:
    return data_root() / "drivers"


def examples_dir() -> Path:
    return data_root() / "examples"
