"""Small helpers for the words of messages."""

from __future__ import annotations


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """``count`` with ``noun`` in the right number: ``1 file``, ``0 files``, ``2 proxies``
    (``plural`` for nouns that do not just take an ``s``)."""
    return f"{count} {noun if count == 1 else plural or noun + 's'}"


def article(word: str) -> str:
    """``a`` or ``an`` before ``word``, by its first letter (``an alias``, ``a proxy``,
    ``an int``); good enough for type and value names, which are not read aloud by letter."""
    return "an" if word[:1].lower() in "aeiou" and word[:1] else "a"


def with_article(word: str) -> str:
    """``word`` after its article: ``an alias``, ``a position_proxy``."""
    return f"{article(word)} {word}"
