"""Human-readable diagnostics: ``path:line:col: severity CODE message`` and a summary."""

from __future__ import annotations

from collections.abc import Sequence

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.safetext import printable
from gadgetctl.wording import counted

_COLORS = {"error": "\x1b[1;31m", "warning": "\x1b[1;33m", "info": "\x1b[1;36m"}
_DIM, _BOLD, _RESET = "\x1b[2m", "\x1b[1m", "\x1b[0m"


def format_line(d: Diagnostic, *, color: bool = False) -> str:
    severity = d.severity.value
    location, message = printable(str(d.location)), printable(d.message)
    if color:
        return (
            f"{_BOLD}{location}{_RESET}: {_COLORS[severity]}{severity}{_RESET} "
            f"{_DIM}{d.code}{_RESET} {message}"
        )
    return f"{location}: {severity} {d.code} {message}"


def summary_line(diagnostics: Sequence[Diagnostic], files_checked: int) -> str:
    counts = {"error": 0, "warning": 0, "info": 0}
    for d in diagnostics:
        counts[d.severity.value] += 1
    affected = len({d.path for d in diagnostics})
    head = counted(files_checked, "file") + " checked"
    if not diagnostics:
        return f"{head}: no problems found"
    parts = [counted(counts["error"], "error"), counted(counts["warning"], "warning")]
    if counts["info"]:
        parts.append(counted(counts["info"], "note"))
    return f"{head}: {', '.join(parts)} in {counted(affected, 'file')}"


def render_text(
    diagnostics: Sequence[Diagnostic],
    *,
    files_checked: int = 0,
    color: bool = False,
    hints: bool = True,
) -> str:
    lines = []
    for d in diagnostics:
        lines.append(format_line(d, color=color))
        if hints and d.hint:
            lines.append(f"    hint: {printable(d.hint)}")
    lines.append(summary_line(diagnostics, files_checked))
    return "\n".join(lines)
