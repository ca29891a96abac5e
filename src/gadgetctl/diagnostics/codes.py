"""The catalog of diagnostic codes.

Each category keeps its codes in its own module under ``gadgetctl.diagnostics.catalog``
as a ``CODES`` list; this module joins them. ``gadgetctl explain CODE`` reads it.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from functools import cache

from gadgetctl.diagnostics.levels import Category, Severity

CATALOG_MODULES = ("xml", "schema", "definition", "config", "driver")


@dataclass(frozen=True, slots=True)
class Code:
    """A diagnostic code of the catalog: its category, default severity and explanation."""

    code: str
    category: Category
    severity: Severity
    title: str
    description: str
    example: str = ""
    fix: str = ""


@cache
def catalog() -> dict[str, Code]:
    codes: dict[str, Code] = {}
    for name in CATALOG_MODULES:
        module = importlib.import_module(f"gadgetctl.diagnostics.catalog.{name}")
        for entry in module.CODES:
            if entry.code in codes:
                raise RuntimeError(f"diagnostic code {entry.code} defined twice")
            codes[entry.code] = entry
    return codes


def lookup(code: str) -> Code:
    try:
        return catalog()[code]
    except KeyError:
        raise KeyError(f"unknown diagnostic code {code!r}") from None
