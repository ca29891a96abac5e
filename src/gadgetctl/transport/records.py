"""Finding fixed-size records in a byte stream that may carry junk, and counting what was
lost, for the serial drivers' standalone halves (imports nothing else from gadgetctl).

:class:`ResyncScanner` keeps the bytes of a record cut short until the rest comes, searches
for the next candidate head in one go (a junk run costs one search, not one step per byte),
asks the driver to decode each candidate, and counts: ``records`` decoded, ``bad_records``
runs of junk (a candidate that does not decode is junk too), ``skipped_bytes`` their bytes.

:class:`CarriedCounts` keeps such counters across reconnections: what the closed
connections counted plus what the open one counts now, read under one lock.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import ClassVar, Generic, TypeVar

R = TypeVar("R")


@dataclass
class ResyncScanner(Generic[R]):
    """A record scanner; a driver gives :attr:`HEAD` (the bytes a record starts with) or
    :meth:`find_head`, :meth:`record_size` (or :attr:`SIZE`) and :meth:`decode`."""

    #: The bytes every record starts with.
    HEAD: ClassVar[bytes] = b""
    #: Bytes of a record (head included).
    SIZE: ClassVar[int] = 0
    #: Bytes kept waiting at most (None: the record size bounds it already).
    MAX_BUFFER: ClassVar[int | None] = None

    buffer: bytearray = field(default_factory=bytearray, kw_only=True)
    records: int = field(default=0, kw_only=True)
    bad_records: int = field(default=0, kw_only=True)
    skipped_bytes: int = field(default=0, kw_only=True)
    _in_junk: bool = field(default=False, kw_only=True, repr=False)

    # -- what a driver gives ------------------------------------------------------------

    def find_head(self, buffer: bytearray, start: int) -> int:
        """Where the next candidate record starts at or after ``start`` (-1: nowhere)."""
        return buffer.find(self.HEAD, start)

    def record_size(self) -> int:
        return self.SIZE

    def restart_within(self, buffer: bytearray, start: int) -> int | None:
        """For a record still cut short at ``start``: where a later head inside it shows
        that it never will be whole (None: wait for the rest). Only protocols whose head
        cannot occur inside a record can tell."""
        return None

    def decode(self, record: bytes) -> R | None:
        """The record these bytes hold, or None when they are junk that looks like one."""
        raise NotImplementedError

    def complete(self, record: R, buffer: bytearray, end: int, quiet: bool) -> tuple[R, int] | None:
        """For a protocol whose records may carry optional trailing bytes: the record as
        finished by what follows it at ``end``, and how many more bytes it takes; None to
        wait for the bytes that tell (``quiet``: no more are coming now). By default a
        record is complete as decoded."""
        return record, 0

    # -- scanning -------------------------------------------------------------------------

    def feed(self, data: bytes, *, quiet: bool = False) -> list[R]:
        """Add bytes; return every complete valid record they finish, in order. ``quiet``
        says no more bytes are coming now (see :meth:`complete`)."""
        buf = self.buffer
        buf += data
        size = self.record_size()
        out: list[R] = []
        pos = 0
        while True:
            head = self.find_head(buf, pos)
            if head < 0:
                self.skip(len(buf) - pos)
                pos = len(buf)
                break
            self.skip(head - pos)
            pos = head
            if len(buf) - pos < size:
                cut = self.restart_within(buf, pos)
                if cut is None:
                    break  # cut short: the rest is still on its way
                self.skip(cut - pos)  # a head inside it: what came before was cut off
                pos = cut
                continue
            record = self.decode(bytes(buf[pos : pos + size]))
            if record is None:
                self.skip(1)  # not a head after all: look for the next one
                pos += 1
                continue
            finished = self.complete(record, buf, pos + size, quiet)
            if finished is None:
                break  # what follows it says how it ends: wait for that
            record, extra = finished
            out.append(record)
            self.records += 1
            self._in_junk = False
            pos += size + extra
        del buf[:pos]
        if self.MAX_BUFFER is not None and len(buf) > self.MAX_BUFFER:
            self.skip(len(buf))
            buf.clear()
        return out

    def skip(self, count: int) -> None:
        """Count ``count`` bytes of junk (a new run counts one bad record)."""
        if count <= 0:
            return
        self.skipped_bytes += count
        if not self._in_junk:
            self.bad_records += 1
            self._in_junk = True


class CarriedCounts:
    """Counters named ``names`` that survive reconnections: :meth:`attach` the open source (a
    standalone driver whose attributes are the counters), :meth:`detach` it when it closes
    (its counts are kept), read with :meth:`get` or :meth:`snapshot` from any thread."""

    def __init__(self, names: Iterable[str]) -> None:
        self._kept = dict.fromkeys(names, 0)
        self._source: object | None = None
        self._lock = threading.Lock()

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self._kept)

    def attach(self, source: object) -> None:
        with self._lock:
            self._source = source

    def detach(self) -> object | None:
        """Keep what the source counted and let it go; returns it."""
        with self._lock:
            source, self._source = self._source, None
            if source is not None:
                for name in self._kept:
                    self._kept[name] += int(getattr(source, name, 0))
            return source

    def get(self, name: str) -> int:
        with self._lock:
            live = int(getattr(self._source, name, 0)) if self._source is not None else 0
            return self._kept[name] + live

    def snapshot(self) -> dict[str, int]:
        with self._lock:
            source = self._source
            return {
                name: kept + (int(getattr(source, name, 0)) if source is not None else 0)
                for name, kept in self._kept.items()
            }


class ScannedDevice:
    """A standalone driver whose records come through ``self.scanner`` (a
    :class:`ResyncScanner`): a context manager (``open()`` on entry, ``close()`` on exit) with
    the scanner's counters as its own."""

    scanner: ResyncScanner

    def open(self) -> object:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self: D) -> D:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def records(self) -> int:
        return self.scanner.records

    @property
    def bad_records(self) -> int:
        return self.scanner.bad_records

    @property
    def skipped_bytes(self) -> int:
        return self.scanner.skipped_bytes


D = TypeVar("D", bound=ScannedDevice)


class CarriedCounters:
    """For a driver's wrapper whose standalone driver comes and goes: ``records``,
    ``bad_records``, ``skipped_bytes`` and ``counters`` over every connection, from
    ``self.counts`` (a :class:`CarriedCounts` the open driver is attached to)."""

    counts: CarriedCounts

    @property
    def records(self) -> int:
        """Records decoded."""
        return self.counts.get("records")

    @property
    def bad_records(self) -> int:
        """Runs of junk and malformed records skipped."""
        return self.counts.get("bad_records")

    @property
    def skipped_bytes(self) -> int:
        return self.counts.get("skipped_bytes")

    @property
    def counters(self) -> dict[str, int]:
        """The driver's health counters, reconnections included."""
        return self.counts.snapshot()


#: The counters of a scanning serial driver.
SCANNER_COUNTERS = ("records", "bad_records", "skipped_bytes")
