"""Bounds on the language server's input: pygls reads a message's header lines and then as
many bytes as its ``Content-Length`` says, however many that is. A peer that announces
gigabytes (a broken client, or anyone on the machine who connects to ``--tcp``) made the
server reserve or buffer them. These readers stand between pygls and the stream and end the
session with one line instead."""

from __future__ import annotations

import asyncio
from concurrent.futures import Executor
from typing import BinaryIO

from gadgetctl.errors import GadgetctlError

#: The largest message body accepted: far beyond any configuration a client would send whole.
MAX_BODY = 64 << 20
#: The longest header line accepted (``Content-Length: ...``, ``Content-Type: ...``).
MAX_HEADER_LINE = 1024


LONG_HEADER = f"lsp: a header line is longer than {MAX_HEADER_LINE} bytes; the session ends"


class FramingError(GadgetctlError):
    """A message the server will not read: its header or announced body is over the limit."""


def body_length(size: int) -> int:
    """``size`` when a body of that many bytes may be read; :class:`FramingError` if not."""
    if size > MAX_BODY:
        shown = f"{size} bytes" if size < 10**15 else f"a number of {len(str(size))} digits"
        raise FramingError(
            f"lsp: a message announces {shown}, over the limit of {MAX_BODY >> 20} MiB; "
            "the session ends"
        )
    return size


def header_line(line: bytes) -> bytes:
    """``line`` when it is within the limit; :class:`FramingError` if not."""
    if len(line) > MAX_HEADER_LINE:
        raise FramingError(LONG_HEADER)
    return line


class BoundedStdinReader:
    """pygls's reader of standard input (lines and exact reads in a worker thread) with the
    limits above."""

    def __init__(self, stdin: BinaryIO, executor: Executor | None = None) -> None:
        self._stdin = stdin
        self._executor = executor

    async def readline(self) -> bytes:
        loop = asyncio.get_running_loop()
        line = await loop.run_in_executor(self._executor, self._stdin.readline, MAX_HEADER_LINE + 1)
        return header_line(line)

    async def readexactly(self, n: int) -> bytes:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self._executor, self._stdin.read, body_length(n))


class BoundedStreamReader:
    """An :class:`asyncio.StreamReader` (a ``--tcp`` client) with the limits above."""

    def __init__(self, reader: asyncio.StreamReader) -> None:
        self._reader = reader

    async def readline(self) -> bytes:
        try:
            line = await self._reader.readline()  # the partial line at the end, b"" after
        except ValueError:  # no line end within the stream's own limit (64 KiB)
            raise FramingError(LONG_HEADER) from None
        return header_line(line)

    async def readexactly(self, n: int) -> bytes:
        return await self._reader.readexactly(body_length(n))
