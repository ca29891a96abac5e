"""Offsets in a document's text and the line/character positions editors use.

Positions count UTF-16 code units by default, as the protocol says, or code points when
the client agreed to UTF-32. Line starts are found once per text (a 16 MB document is
indexed in one pass, and each conversion looks at one line only).
"""

from __future__ import annotations

from bisect import bisect_right


class LineIndex:
    def __init__(self, text: str, *, utf16: bool = True) -> None:
        self.text = text
        self.utf16 = utf16
        starts = [0]
        find = text.find
        at = find("\n")
        while at >= 0:
            starts.append(at + 1)
            at = find("\n", at + 1)
        self.starts = starts

    def position(self, offset: int) -> tuple[int, int]:
        """(line, character), both 0-based, of ``offset``."""
        offset = max(0, min(offset, len(self.text)))
        line = bisect_right(self.starts, offset) - 1
        start = self.starts[line]
        if not self.utf16:
            return line, offset - start
        prefix = self.text[start:offset]
        if prefix.isascii():
            return line, len(prefix)
        return line, len(prefix.encode("utf-16-le")) // 2

    def offset(self, line: int, character: int) -> int:
        """The offset of a (line, character) position, clamped to the text."""
        if line < 0:
            return 0
        if line >= len(self.starts):
            return len(self.text)
        start = self.starts[line]
        end = self.starts[line + 1] - 1 if line + 1 < len(self.starts) else len(self.text)
        if not self.utf16:
            return min(start + max(character, 0), end)
        units = 0
        at = start
        while at < end and units < character:
            units += 2 if ord(self.text[at]) > 0xFFFF else 1
            at += 1
        return at

    def at_line_column(self, line: int | None, column: int | None) -> int:
        """The offset of a 1-based line and column as diagnostics and locations give them
        (columns in characters); a missing column is the line's first non-blank character."""
        if not line:
            return 0
        row = min(line, len(self.starts)) - 1
        start = self.starts[row]
        if column:
            return min(start + column - 1, len(self.text))
        end = self.starts[row + 1] if row + 1 < len(self.starts) else len(self.text)
        stripped = self.text[start:end]
        return start + len(stripped) - len(stripped.lstrip())
