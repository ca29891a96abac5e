"""Suggestions ("did you mean ...?"): the names closest to a mistyped one, for every command and check
that takes element, driver, definition, property or diagnostic code names.

Matching ignores case (``waveform stick`` finds ``Waveform Sticks``) and gives the
candidates as they are spelled.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from difflib import get_close_matches

CUTOFF = 0.6


def close_names(
    word: str, candidates: Iterable[str], *, n: int = 3, cutoff: float = CUTOFF
) -> list[str]:
    """Up to ``n`` candidates that look like ``word``, the closest first."""
    spelled: dict[str, str] = {}
    for candidate in candidates:
        spelled.setdefault(candidate.lower(), candidate)
    return [spelled[m] for m in get_close_matches(word.lower(), list(spelled), n=n, cutoff=cutoff)]


def did_you_mean(
    word: str,
    candidates: Iterable[str],
    *,
    n: int = 3,
    cutoff: float = CUTOFF,
    quote: Callable[[str], str] = repr,
) -> str | None:
    """``"did you mean 'a' or 'b'?"``, or None when nothing is close."""
    close = close_names(word, candidates, n=n, cutoff=cutoff)
    if not close:
        return None
    quoted = [quote(c) for c in close]
    listed = quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} or {quoted[-1]}"
    return f"did you mean {listed}?"


def with_suggestion(message: str, word: str, candidates: Iterable[str], **options: object) -> str:
    """``message`` followed by ``" (did you mean ...?)"`` when something is close."""
    suggestion = did_you_mean(word, candidates, **options)  # type: ignore[arg-type]
    return f"{message} ({suggestion})" if suggestion else message
