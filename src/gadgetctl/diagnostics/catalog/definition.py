"""Diagnostic codes of the `definition` category."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.model import Category, Severity

C = Category.DEFINITION
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = []
