"""The diagnostics model shared by every check in gadgetctl."""

from gadgetctl.diagnostics.codes import Code, lookup
from gadgetctl.diagnostics.codes import catalog as all_codes
from gadgetctl.diagnostics.model import Category, Diagnostic, Severity, exit_code_for, sort_key

__all__ = [
    "Category",
    "Code",
    "Diagnostic",
    "Severity",
    "all_codes",
    "exit_code_for",
    "lookup",
    "sort_key",
]
