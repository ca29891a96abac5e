"""validate's diagnostics as the editor shows them: a range for each finding, the hint and
where to read more as related text, the severity in the protocol's terms (plain data; the
server turns it into lsprotocol objects)."""

from __future__ import annotations

import re
from dataclasses import dataclass

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.lsp.text import LineIndex

_WORD = re.compile(r"[^\s<>]+")
#: How far a tag's range is looked for (a finding on a huge tag is shown on its start).
MAX_TAG_SCAN = 4096

#: The protocol's DiagnosticSeverity numbers.
SEVERITIES = {Severity.ERROR: 1, Severity.WARNING: 2, Severity.INFO: 3}


@dataclass(frozen=True)
class Finding:
    diagnostic: Diagnostic
    start: int
    end: int

    @property
    def explain(self) -> str:
        return f"gadgetctl explain {self.diagnostic.code}"

    @property
    def described(self) -> str:
        """What the code means, in the catalog's words, and where to read more."""
        from gadgetctl.diagnostics.codes import lookup

        code = self.diagnostic.code
        return f"{code}: {lookup(code).title} (`{self.explain}` describes it with an example)"


def token_end(text: str, start: int) -> int:
    """The end of what a finding at ``start`` points at: a whole tag, or a word."""
    if start >= len(text):
        return start
    line_end = text.find("\n", start)
    line_end = len(text) if line_end < 0 else line_end
    if text[start] == "<":
        close = text.find(">", start, start + MAX_TAG_SCAN)
        return close + 1 if close >= 0 else max(line_end, start + 1)
    match = _WORD.match(text, start)
    if match:
        return match.end()
    return min(start + 1, max(line_end, start + 1))


def findings(diagnostics: list[Diagnostic], index: LineIndex) -> list[Finding]:
    found = []
    for diagnostic in diagnostics:
        start = index.at_line_column(diagnostic.line, diagnostic.column)
        found.append(Finding(diagnostic, start, token_end(index.text, start)))
    return found
