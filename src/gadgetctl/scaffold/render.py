"""A small template language for the files ``gadgetctl scaffold`` writes.

Templates are files under ``templates/``. Lines whose first non-blank characters are a
directive choose what is kept, then :class:`string.Template` fills in ``$name`` and
``${name}`` (``$$`` is a dollar sign):

``%if EXPR`` / ``%elif EXPR`` / ``%else`` / ``%end``
    keep the lines of the first branch whose EXPR holds. EXPR combines flag names with
    ``and``, ``or``, ``not`` and parentheses; an unknown flag is an error, not false.
``%include NAME``
    the lines of the template ``NAME`` (processed with the same flags).
``%# text``
    a comment for the template's reader, dropped.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from functools import cache
from importlib import resources
from string import Template

_DIRECTIVE = re.compile(r"^\s*%(#|(?:if|elif|else|end|include)\b)\s*(.*?)\s*$")
_TOKEN = re.compile(r"\s*(\(|\)|[A-Za-z_][A-Za-z0-9_]*)")


class TemplateError(Exception):
    """A template that is wrong (a bug of gadgetctl, never of the user's request)."""


@cache
def template_text(name: str) -> str:
    """The text of ``templates/NAME`` as shipped in the package."""
    return resources.files(__package__).joinpath("templates", name).read_text(encoding="utf-8")


def evaluate(expression: str, flags: Mapping[str, bool], where: str = "") -> bool:
    """The value of ``expression`` (names, and, or, not, parentheses) under ``flags``."""
    tokens: list[str] = []
    pos = 0
    while pos < len(expression):
        match = _TOKEN.match(expression, pos)
        if match is None:
            if expression[pos:].strip():
                raise TemplateError(f"{where}: cannot read condition {expression!r}")
            break
        tokens.append(match.group(1))
        pos = match.end()
    index = 0

    def peek() -> str | None:
        return tokens[index] if index < len(tokens) else None

    def take() -> str:
        nonlocal index
        if index >= len(tokens):
            raise TemplateError(f"{where}: condition {expression!r} ends too early")
        index += 1
        return tokens[index - 1]

    def either() -> bool:
        value = both()
        while peek() == "or":
            take()
            value = both() or value
        return value

    def both() -> bool:
        value = negation()
        while peek() == "and":
            take()
            value = negation() and value
        return value

    def negation() -> bool:
        if peek() == "not":
            take()
            return not negation()
        token = take()
        if token == "(":
            value = either()
            if take() != ")":
                raise TemplateError(f"{where}: unbalanced parentheses in {expression!r}")
            return value
        if token not in flags:
            raise TemplateError(f"{where}: unknown flag {token!r} in {expression!r}")
        return bool(flags[token])

    result = either()
    if index != len(tokens):
        raise TemplateError(f"{where}: cannot read condition {expression!r}")
    return result


def select_lines(name: str, flags: Mapping[str, bool], depth: int = 0) -> list[str]:
    """The lines of template ``name`` that its directives keep (not yet substituted)."""
    if depth > 8:
        raise TemplateError(f"{name}: %include nested too deeply")
    kept: list[str] = []
    # One entry per open %if: (this branch is kept, an earlier branch was taken, parent kept)
    stack: list[tuple[bool, bool, bool]] = []
    active = True
    for number, line in enumerate(template_text(name).splitlines(keepends=True), start=1):
        where = f"{name}:{number}"
        match = _DIRECTIVE.match(line)
        if match is None:
            if active:
                kept.append(line)
            continue
        directive, argument = match.groups()
        if directive == "#":
            continue
        if directive == "if":
            value = active and evaluate(argument, flags, where)
            stack.append((value, value, active))
            active = value
        elif directive in ("elif", "else"):
            if not stack:
                raise TemplateError(f"{where}: %{directive} without %if")
            _current, taken, parent = stack[-1]
            if directive == "else":
                value = parent and not taken
            else:
                value = parent and not taken and evaluate(argument, flags, where)
            stack[-1] = (value, taken or value, parent)
            active = value
        elif directive == "end":
            if not stack:
                raise TemplateError(f"{where}: %end without %if")
            _current, _taken, active = stack.pop()
        elif active:  # include
            kept.extend(select_lines(argument, flags, depth + 1))
    if stack:
        raise TemplateError(f"{name}: {len(stack)} %if without %end")
    return kept


def render(name: str, flags: Mapping[str, bool], values: Mapping[str, object]) -> str:
    """Template ``name`` with its directives applied and ``values`` filled in."""
    text = "".join(select_lines(name, flags))
    try:
        return Template(text).substitute({k: str(v) for k, v in values.items()})
    except (KeyError, ValueError) as err:
        raise TemplateError(f"{name}: {type(err).__name__}: {err}") from None
