"""Diagnostics as GitHub Actions workflow commands (annotations)."""

from __future__ import annotations

from collections.abc import Sequence

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.safetext import printable

_LEVEL = {"error": "error", "warning": "warning", "info": "notice"}


def _escape_data(text: str) -> str:
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _escape_property(text: str) -> str:
    return _escape_data(text).replace(":", "%3A").replace(",", "%2C")


def format_annotation(d: Diagnostic) -> str:
    props = []
    if d.path:
        props.append(f"file={_escape_property(printable(d.path))}")
    if d.line is not None:
        props.append(f"line={d.line}")
    if d.column is not None:
        props.append(f"col={d.column}")
    props.append(f"title={_escape_property(d.code)}")
    # the one newline GitHub shows is ours, between message and hint; the texts' own are escaped
    message = printable(d.message) if not d.hint else f"{printable(d.message)}\n{printable(d.hint)}"
    return f"::{_LEVEL[d.severity.value]} {','.join(props)}::{_escape_data(message)}"


def render_github(diagnostics: Sequence[Diagnostic]) -> str:
    return "\n".join(format_annotation(d) for d in diagnostics)
