"""Environment-variable expansion in paths, with the two syntaxes JCCL uses.

``${NAME}`` and ``$(NAME)`` are replaced by the variable's value. Unlike VR Juggler, an
undefined variable is reported (the caller gets its name) instead of silently becoming an
empty string, a value is not expanded a second time (so a self-referencing value cannot
loop), and an unterminated reference is left as written.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass

_REFERENCE = re.compile(r"\$\{([^}]*)\}|\$\(([^)]*)\)")


@dataclass(frozen=True, slots=True)
class Expansion:
    """A text with its variables expanded, and the names of those that were not set."""

    text: str
    undefined: tuple[str, ...] = ()


def expand(text: str, environ: Mapping[str, str] | None = None) -> Expansion:
    env = os.environ if environ is None else environ
    undefined: list[str] = []

    def replace(match: re.Match[str]) -> str:
        name = match.group(1) if match.group(1) is not None else match.group(2)
        if name in env:
            return env[name]
        undefined.append(name)
        return ""

    return Expansion(_REFERENCE.sub(replace, text), tuple(undefined))


def references(text: str) -> list[str]:
    """Names of the variables ``text`` refers to."""
    return [m.group(1) if m.group(1) is not None else m.group(2) for m in _REFERENCE.finditer(text)]
