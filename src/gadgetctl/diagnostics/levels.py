"""How bad a finding is and which part of gadgetctl found it (no other imports, so the
code catalog and the Diagnostic model can both use them)."""

from __future__ import annotations

from enum import StrEnum


class Severity(StrEnum):
    ERROR = "error"
    WARNING = "warning"
    INFO = "info"

    @property
    def rank(self) -> int:
        return {"error": 0, "warning": 1, "info": 2}[self.value]


class Category(StrEnum):
    XML = "xml"
    SCHEMA = "schema"
    DEFINITION = "definition"
    CONFIG = "config"
    DRIVER = "driver"
