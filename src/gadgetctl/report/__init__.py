"""Renderers for lists of diagnostics: text, json, github annotations and SARIF 2.1.0.

Each renderer returns a string; none touches the terminal.
"""

from __future__ import annotations

from collections.abc import Sequence

from gadgetctl.diagnostics import Diagnostic

FORMATS = ("text", "json", "github", "sarif")


def render(
    fmt: str,
    diagnostics: Sequence[Diagnostic],
    *,
    files_checked: int = 0,
    color: bool = False,
    hints: bool = True,
) -> str:
    if fmt == "text":
        from gadgetctl.report.text import render_text

        return render_text(diagnostics, files_checked=files_checked, color=color, hints=hints)
    if fmt == "json":
        from gadgetctl.report.json import render_json

        return render_json(diagnostics)
    if fmt == "github":
        from gadgetctl.report.github import render_github

        return render_github(diagnostics)
    if fmt == "sarif":
        from gadgetctl.report.sarif import render_sarif

        return render_sarif(diagnostics)
    raise ValueError(f"unknown format {fmt!r}")
