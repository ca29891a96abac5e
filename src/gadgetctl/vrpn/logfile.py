"""VRPN log files (``.vrpn``): what a VRPN connection writes with ``-li``/``-lo`` logging.

A log starts with the writer's 24-byte cookie (versions 04.00 to 07.xx are read; bytes 20-23
are not checked). Then one record per message: six big-endian int32 (type, sender, seconds,
microseconds, payload length, a historical 0) and the payload, unpadded. Sender and type
descriptions are logged too, so :class:`LogReader` rebuilds the names as it goes; a
DISCONNECT record (type -5) clears them, as the next connection describes its names anew.

Reading is bounded: a record length beyond a message's maximum is a :class:`LogFormatError`
naming the byte offset, and a file cut off inside its last record ends the reading with
``truncated`` set instead of raising.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from .codecs import CodecError, decode
from .wire import (
    COOKIE_SIZE,
    DISCONNECT_MESSAGE,
    MAX_IDS,
    MAX_PADDED_PAYLOAD,
    SENDER_DESCRIPTION,
    TYPE_DESCRIPTION,
    FramingError,
    Message,
    decode_description,
    description_payload,
    make_cookie,
    split_time,
)

_RECORD = struct.Struct(">iiiiii")


class LogFormatError(ValueError):
    """The file is not a readable VRPN log; ``offset`` is where reading stopped."""

    def __init__(self, message: str, offset: int) -> None:
        super().__init__(f"byte {offset}: {message}")
        self.offset = offset


def check_log_cookie(cookie: bytes) -> str:
    """The writer's version (``"07.38"``); :class:`LogFormatError` unless 04.00 to 07.xx."""
    if len(cookie) < COOKIE_SIZE or not cookie.startswith(b"vrpn: ver. "):
        raise LogFormatError("not a VRPN log file (no VRPN cookie)", 0)
    version = cookie[11:16].decode("ascii", "replace")
    try:
        major, minor = (int(p) for p in version.split("."))
    except ValueError:
        raise LogFormatError(f"unreadable log version {version!r}", 11) from None
    if not 4 <= major <= 7 or not 0 <= minor <= 99:
        raise LogFormatError(f"log version {version} is not readable (04.00 to 07.xx are)", 11)
    return version


class LogReader:
    """Iterates the user messages of a VRPN log, names resolved and payloads decoded."""

    def __init__(self, source: str | Path | BinaryIO) -> None:
        if isinstance(source, (str, Path)):
            self._file: BinaryIO = open(source, "rb")  # noqa: SIM115 - closed by close()
            self._owned = True
        else:
            self._file, self._owned = source, False
        self.version = check_log_cookie(self._file.read(COOKIE_SIZE))
        self.senders: dict[int, str] = {}
        self.types: dict[int, str] = {}
        self.offset = COOKIE_SIZE
        self.truncated = False
        self.records = 0
        self.disconnects = 0
        self.bad_reports = 0
        self.undescribed = 0

    def close(self) -> None:
        if self._owned:
            self._file.close()

    def __enter__(self) -> LogReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __iter__(self) -> Iterator[Message]:
        read = self._file.read
        while True:
            head = read(_RECORD.size)
            if not head:
                return
            if len(head) < _RECORD.size:
                self.truncated = True
                return
            type_id, sender, sec, usec, length, _slot = _RECORD.unpack(head)
            if not 0 <= length <= MAX_PADDED_PAYLOAD:
                raise LogFormatError(f"record length {length} out of range", self.offset)
            payload = read(length)
            if len(payload) < length:
                self.truncated = True
                return
            self.offset += _RECORD.size + length
            self.records += 1
            if type_id < 0:
                self._system(type_id, sender, payload)
                continue
            type_name = self.types.get(type_id)
            if type_name is None:
                self.undescribed += 1
                continue
            try:
                report = decode(type_name, payload)
            except CodecError:
                self.bad_reports += 1
                continue
            yield Message(
                type_id,
                sender,
                sec,
                usec,
                payload,
                self.senders.get(sender),
                type_name,
                0.0,
                report,
            )

    def _system(self, type_id: int, ident: int, payload: bytes) -> None:
        if type_id in (SENDER_DESCRIPTION, TYPE_DESCRIPTION):
            if not 0 <= ident < MAX_IDS:
                raise LogFormatError(f"description of id {ident}", self.offset)
            try:
                name = decode_description(payload)
            except FramingError as exc:
                raise LogFormatError(str(exc), self.offset) from None
            (self.senders if type_id == SENDER_DESCRIPTION else self.types)[ident] = name
        elif type_id == DISCONNECT_MESSAGE:
            self.disconnects += 1
            self.senders.clear()
            self.types.clear()


class LogWriter:
    """Writes a VRPN log file (the format :class:`LogReader` reads)."""

    def __init__(self, target: str | Path | BinaryIO) -> None:
        if isinstance(target, (str, Path)):
            self._file: BinaryIO = open(target, "wb")  # noqa: SIM115 - closed by close()
            self._owned = True
        else:
            self._file, self._owned = target, False
        self._file.write(make_cookie())
        self._senders: dict[str, int] = {}
        self._types: dict[str, int] = {}

    def record(
        self, type_id: int, sender: int, payload: bytes, timestamp: float | None = None
    ) -> None:
        sec, usec = split_time(timestamp)
        self._file.write(_RECORD.pack(type_id, sender, sec, usec, len(payload), 0) + payload)

    def _id(self, table: dict[str, int], kind: int, name: str) -> int:
        ident = table.get(name)
        if ident is None:
            ident = table[name] = len(table)
            self.record(kind, ident, description_payload(name))
        return ident

    def write(
        self, sender: str, type_name: str, payload: bytes, timestamp: float | None = None
    ) -> None:
        """One message of ``sender`` and ``type_name``, describing either on first use."""
        s = self._id(self._senders, SENDER_DESCRIPTION, sender)
        t = self._id(self._types, TYPE_DESCRIPTION, type_name)
        self.record(t, s, payload, timestamp)

    def disconnect(self, timestamp: float | None = None) -> None:
        self.record(DISCONNECT_MESSAGE, 0, b"", timestamp)
        self._senders.clear()
        self._types.clear()

    def close(self) -> None:
        if self._owned:
            self._file.close()
        else:
            self._file.flush()

    def __enter__(self) -> LogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
