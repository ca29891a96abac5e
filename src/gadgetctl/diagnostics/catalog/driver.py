"""Diagnostic codes of the `driver` category."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.model import Category, Severity

C = Category.DRIVER
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = []
