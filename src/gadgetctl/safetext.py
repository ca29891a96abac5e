"""Making text from files, devices and peers safe to print.

Names, values and paths come from configurations, recordings and the network, and may hold
anything: an escape sequence retitles, clears or recolours a terminal, a newline splits one
diagnostic into two (and forges a ``::error`` line in a CI log), a bidirectional override
reorders what is shown. :func:`printable` shows every such character as an escape
(``\\n``, ``\\x1b``, ``\\x85``, ``\\u202e``), so one text always stays one line and prints
as itself. Every human or line-oriented output (text reports, GitHub annotations, config
show, graph text/dot/mermaid, monitor tables, the live view, replay summaries, error lines)
passes user text through it; JSON, NDJSON and SARIF keep the exact strings.
"""

from __future__ import annotations

import re

# C0 controls (newline, tab and ESC among them), DEL, C1 controls, the Unicode line and
# paragraph separators, and the bidirectional embedding, override and isolate controls.
_UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escape(match: re.Match[str]) -> str:
    char = match.group()
    named = _NAMED.get(char)
    if named is not None:
        return named
    code = ord(char)
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def is_printable(text: str) -> bool:
    """Whether :func:`printable` leaves ``text`` as it is (one search for the cells of a
    whole row joined, instead of one per cell)."""
    return not _UNSAFE.search(text)


def printable(text: str) -> str:
    """``text`` with every control character escaped: one line, no terminal effects."""
    if not _UNSAFE.search(text):
        return text
    return _UNSAFE.sub(_escape, text)


#: The largest magnitude written in fixed notation by :func:`fixed`: beyond it a number is
#: written with an exponent (a coordinate of 1e308 would take 309 digits), so a number's
#: text stays within about 15 characters, whatever a device or file sends.
FIXED_LIMIT = 1e9


def fixed(value: float, digits: int = 3, sign: bool = False) -> str:
    """``value`` with ``digits`` decimals (a ``+`` for positive ones with ``sign``), with an
    exponent from :data:`FIXED_LIMIT` on; ``nan`` and ``inf`` as Python writes them."""
    spec = f"{'+' if sign else ''}.{digits}{'e' if abs(value) >= FIXED_LIMIT else 'f'}"
    return format(value, spec)
