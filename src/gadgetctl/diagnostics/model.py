"""Diagnostic records: one finding, with code, severity, category and location."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from gadgetctl.diagnostics.codes import lookup
from gadgetctl.diagnostics.levels import Category, Severity

__all__ = ["Category", "Diagnostic", "Severity", "exit_code_for", "sort_key"]


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One finding. ``line`` and ``column`` are 1-based; either may be unknown."""

    code: str
    severity: Severity
    category: Category
    path: str | None
    line: int | None
    column: int | None
    message: str
    hint: str | None = None

    @classmethod
    def make(
        cls,
        code: str,
        message: str,
        path: str | None = None,
        line: int | None = None,
        column: int | None = None,
        *,
        hint: str | None = None,
        severity: Severity | None = None,
    ) -> Diagnostic:
        """Build a diagnostic whose category and default severity come from the catalog."""
        entry = lookup(code)
        return cls(
            code=code,
            severity=severity or entry.severity,
            category=entry.category,
            path=path,
            line=line,
            column=column,
            message=message,
            hint=hint,
        )

    def to_dict(self) -> dict[str, object]:
        return {
            "code": self.code,
            "severity": self.severity.value,
            "category": self.category.value,
            "path": self.path,
            "line": self.line,
            "column": self.column,
            "message": self.message,
            "hint": self.hint,
        }

    @property
    def location(self) -> str:
        """``path:line:col`` with unknown parts left out."""
        parts = [self.path or "<input>"]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)


def sort_key(d: Diagnostic) -> tuple:
    return (d.path or "", d.line or 0, d.column or 0, d.code)


def exit_code_for(diagnostics: Iterable[Diagnostic], *, strict: bool = False) -> int:
    """0 when clean, 1 when any error (or, with ``strict``, any warning) was found."""
    for d in diagnostics:
        if d.severity is Severity.ERROR or (strict and d.severity is Severity.WARNING):
            return 1
    return 0
