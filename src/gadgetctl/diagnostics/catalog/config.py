"""Diagnostic codes of the `config` category."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.model import Category, Severity

C = Category.CONFIG
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = []
