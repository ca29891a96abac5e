"""The diagnostics model shared by every check in gadgetctl."""

from gadgetctl.diagnostics.codes import Code, catalog, lookup
from gadgetctl.diagnostics.model import Category, Diagnostic, Severity, exit_code_for, sort_key

__all__ = [
    "Category",
    "Code",
    "Diagnostic",
    "Severity",
    "catalog",
    "exit_code_for",
    "lookup",
    "sort_key",
]
