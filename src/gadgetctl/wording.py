"""Small helpers for the words of messages."""

from __future__ import annotations


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """``count`` with ``noun`` in the right number: ``1 file``, ``0 files``, ``2 proxies``
    (``plural`` for nouns that do not just take an ``s``)."""
    return f"{count} {noun if count == 1 else plural or noun + 's'}"
