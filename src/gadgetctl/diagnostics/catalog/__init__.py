"""Diagnostic codes, one module per category."""
