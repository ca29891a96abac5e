"""VRPN wire format: the cookie, the 24-byte message header, 8-byte framing and system messages.

Everything is big-endian. A message is a header (length, seconds, microseconds, sender id,
type id, sequence number) followed by its payload, padded to a multiple of 8 bytes; the
length word counts the header and the *unpadded* payload. Negative type ids are system
messages (descriptions of senders, types and the UDP channel).

Decoders here are bounded: a header is checked before any payload is waited for, and a
message longer than the C++ receive buffer allows is a :class:`FramingError` (the C++ peer
drops the connection for it, and so do the connection classes of this package).
"""

from __future__ import annotations

import ipaddress
import struct
import time
from typing import NamedTuple

DEFAULT_PORT = 3883
MAGIC = b"vrpn: ver. 07.38"
MAGIC_LEN = 16
COOKIE_SIZE = 24
ACCEPTED_MAJOR = b"vrpn: ver. 07."
ALIGN = 8
HEADER_SIZE = 24
#: The largest padded payload a C++ receiver accepts (its buffer is 64,008 bytes).
MAX_PADDED_PAYLOAD = 64008
#: The largest whole message a C++ sender writes (its TCP output buffer is 64,000 bytes).
MAX_SEND_MESSAGE = 64000
#: The largest UDP datagram either side sends.
MAX_DATAGRAM = 1472
#: Names of senders and types: the C++ receiver refuses descriptions longer than 100 bytes.
MAX_DESCRIPTION_PAYLOAD = 100
MAX_NAME = MAX_DESCRIPTION_PAYLOAD - 5
#: Senders and types per side (C++ ``vrpn_MAX_SENDERS`` / ``vrpn_MAX_TYPES``).
MAX_IDS = 2000

# System message type ids.
SENDER_DESCRIPTION = -1
TYPE_DESCRIPTION = -2
UDP_DESCRIPTION = -3
LOG_DESCRIPTION = -4
DISCONNECT_MESSAGE = -5
#: A system type at or below this breaks the connection on a C++ peer.
FATAL_SYSTEM_TYPE = -2000

_HEADER = struct.Struct(">IiiiiI")
_UINT32 = struct.Struct(">I")


class FramingError(ValueError):
    """A message that cannot be framed: the connection it came on must be dropped."""


class Message(NamedTuple):
    """One received message. ``sender``/``type`` are names once the ids are translated."""

    type_id: int
    sender_id: int
    sec: int
    usec: int
    payload: bytes
    sender: str | None = None
    type: str | None = None
    received: float = 0.0  # local wall-clock time of arrival (time.time())
    report: object = None  # the decoded payload, when the receiver decodes (see codecs)

    @property
    def timestamp(self) -> float:
        """The sender's timestamp as Unix seconds."""
        return self.sec + self.usec * 1e-6


def padded(length: int) -> int:
    """``length`` rounded up to the next multiple of 8."""
    return (length + ALIGN - 1) & ~(ALIGN - 1)


def split_time(timestamp: float | None = None) -> tuple[int, int]:
    """Unix seconds as the (seconds, microseconds) pair of a header."""
    if timestamp is None:
        timestamp = time.time()
    sec = int(timestamp // 1)
    usec = round((timestamp - sec) * 1e6)
    if usec >= 1_000_000:
        sec, usec = sec + 1, usec - 1_000_000
    return ((sec + 2**31) % 2**32) - 2**31, usec  # int32 on the wire (wraps in 2038)


def pack_message(
    type_id: int,
    sender_id: int,
    payload: bytes = b"",
    timestamp: float | None = None,
    *,
    sec: int | None = None,
    usec: int = 0,
    sequence: int = 0,
) -> bytes:
    """One framed message: header, payload and zero padding."""
    if sec is None:
        sec, usec = split_time(timestamp)
    n = len(payload)
    pad = padded(n) - n
    return (
        _HEADER.pack(HEADER_SIZE + n, sec, usec, sender_id, type_id, sequence)
        + payload
        + (b"\0" * pad)
    )


def check_header(length: int) -> int:
    """The padded payload size of a message whose length word is ``length``."""
    if length < HEADER_SIZE:
        raise FramingError(f"message length {length} is shorter than a header")
    body = padded(length - HEADER_SIZE)
    if body > MAX_PADDED_PAYLOAD:
        raise FramingError(f"message too long ({length} bytes)")
    return body


class Block(NamedTuple):
    """Messages of one sender and type left framed, not unpacked: each starts (its header)
    at one of ``offsets`` in ``data``; ``sender`` and ``type`` are their names. A consumer
    unpacks a whole read's worth at once (numpy, say) for far less per message."""

    data: bytes
    offsets: list[int]
    sender: str
    type: str
    received: float


#: What :func:`split_messages` sets apart: (sender id, type id) -> ((sender name, type name),
#: the exact message length such a message must have).
BulkIds = dict[tuple[int, int], tuple[tuple[str, str], int]]
_INT32 = struct.Struct(">i")
#: One per length of a bulk type (tracker reports: two lengths), made when first needed.
_RUN_STRUCTS: dict[int, struct.Struct] = {}


def _run_struct(length: int) -> struct.Struct:
    """A whole message of ``length`` bytes: the header and the first payload word (a
    tracker report's sensor), the rest skipped."""
    found = _RUN_STRUCTS.get(length)
    if found is None:
        found = _RUN_STRUCTS[length] = struct.Struct(f">IiiiiIi{length - HEADER_SIZE - 4}x")
    return found


def split_messages(
    data: bytes | bytearray, pos: int, end: int, received: float, bulk: BulkIds
) -> tuple[int, list[Message], dict[tuple[str, str], list[int]]]:
    """Frame the whole messages of ``data[pos:end]``: the offset after the last one, the
    messages (payloads copied), and the offsets of those whose (sender, type) ids are in
    ``bulk``, per (sender, type) names. Bulk types are tracker reports (the payload starts
    with the sensor): one of another length or with a negative sensor is left a message, for
    the receiver's own checks. From the first system message on, every message is a message
    (the names it describes apply to what follows). Raises :class:`FramingError` on a bad
    header."""
    unpack = _HEADER.unpack_from
    sensor_of = _INT32.unpack_from
    new = tuple.__new__
    out: list[Message] = []
    found: dict[tuple[str, str], list[int]] = {}
    while end - pos >= HEADER_SIZE:
        length, sec, usec, sender, type_id, _seq = unpack(data, pos)
        body = (length - HEADER_SIZE + ALIGN - 1) & ~(ALIGN - 1)  # check_header, inlined
        if length < HEADER_SIZE or body > MAX_PADDED_PAYLOAD:
            check_header(length)  # raises
        if end - pos - HEADER_SIZE < body:
            break
        wanted = bulk.get((sender, type_id)) if bulk else None
        if (
            wanted is not None
            and length == wanted[1]
            and sensor_of(data, pos + HEADER_SIZE)[0] >= 0
        ):
            offsets = found.get(wanted[0])
            if offsets is None:
                offsets = found[wanted[0]] = []
            following = pos + length
            if (
                length % ALIGN  # padded: no run of back-to-back messages of this length
                or following + length > end
                or data[following : following + 4] != data[pos : pos + 4]
                or data[following + 12 : following + 20] != data[pos + 12 : pos + 20]
            ):  # a lone one (a tracker's pose, velocity and acceleration alternate)
                offsets.append(pos)
                pos += HEADER_SIZE + body
                continue
            # a run of reports of this sender and type (a tracker tick), read at once
            run = _run_struct(length)
            stop = pos + (end - pos) // length * length
            count = 0
            for fields in run.iter_unpack(memoryview(data)[pos:stop]):
                if (
                    fields[0] != length
                    or fields[3] != sender
                    or fields[4] != type_id
                    or fields[6] < 0
                ):
                    break
                count += 1
            offsets.extend(range(pos, pos + count * length, length))
            pos += count * length
            continue
        if type_id < 0:
            bulk = {}  # the descriptions to come change what the ids mean
        start = pos + HEADER_SIZE
        payload = bytes(data[start : start + length - HEADER_SIZE])
        out.append(new(Message, (type_id, sender, sec, usec, payload, None, None, received, None)))
        pos += HEADER_SIZE + body
    return pos, out, found


class StreamDecoder:
    """Splits a TCP byte stream into messages; holds at most one unfinished message."""

    __slots__ = ("_buf",)

    def __init__(self) -> None:
        self._buf = bytearray()

    @property
    def pending(self) -> int:
        return len(self._buf)

    def feed_split(
        self, data: bytes, received: float, bulk: BulkIds
    ) -> tuple[list[Message], dict[tuple[str, str], list[int]], bytes]:
        """As :meth:`feed`, with the messages of ``bulk`` left framed (see
        :func:`split_messages`): the messages, the bulk offsets per (sender, type) names,
        and the bytes those offsets point into."""
        buf = self._buf
        if buf:
            buf += data
            whole = bytes(buf)
        else:
            whole = data
        pos, out, found = split_messages(whole, 0, len(whole), received, bulk)
        if pos < len(whole):
            self._buf = bytearray(whole[pos:])
        else:
            self._buf = bytearray()
        return out, found, whole

    def feed(self, data: bytes, received: float = 0.0) -> list[Message]:
        """Messages completed by ``data``; raises :class:`FramingError` on a bad header."""
        buf = self._buf
        buf += data
        out: list[Message] = []
        pos, end = 0, len(buf)
        unpack = _HEADER.unpack_from
        new = tuple.__new__
        view = memoryview(buf)
        try:
            while end - pos >= HEADER_SIZE:
                length, sec, usec, sender, type_id, _seq = unpack(buf, pos)
                body = check_header(length)
                if end - pos - HEADER_SIZE < body:
                    break
                start = pos + HEADER_SIZE
                payload = bytes(view[start : start + length - HEADER_SIZE])
                out.append(
                    new(Message, (type_id, sender, sec, usec, payload, None, None, received, None))
                )
                pos = start + body
        finally:
            view.release()
        if pos:
            del buf[:pos]
        return out


def decode_datagram(data: bytes, received: float = 0.0) -> list[Message]:
    """The messages of one UDP datagram; raises :class:`FramingError` if any is malformed."""
    out: list[Message] = []
    pos, end = 0, len(data)
    while pos < end:
        if end - pos < HEADER_SIZE:
            raise FramingError(f"{end - pos} stray bytes after the last message of a datagram")
        length, sec, usec, sender, type_id, _seq = _HEADER.unpack_from(data, pos)
        body = check_header(length)
        start = pos + HEADER_SIZE
        if end - start < length - HEADER_SIZE:
            raise FramingError("message cut off at the end of a datagram")
        out.append(
            Message(
                type_id,
                sender,
                sec,
                usec,
                bytes(data[start : start + length - HEADER_SIZE]),
                None,
                None,
                received,
            )
        )
        pos = start + body
    return out


# -- the cookie -------------------------------------------------------------------------------


def make_cookie(magic: bytes = MAGIC, log_mode: int = 0) -> bytes:
    """The 24 bytes each side writes first: magic, two spaces, the log-mode digit, NULs."""
    if not 0 <= log_mode <= 3:
        raise ValueError("log mode must be 0 to 3")
    return magic[:MAGIC_LEN] + b"  " + str(log_mode).encode() + b"\0" * 5


class CookieError(ValueError):
    """The peer's cookie is refused (another major version, or not VRPN at all)."""


def check_cookie(cookie: bytes) -> str:
    """The peer's version (``"07.38"``) if its cookie is acceptable; else :class:`CookieError`."""
    if len(cookie) < COOKIE_SIZE:
        raise CookieError("cookie cut short")
    magic = bytes(cookie[:MAGIC_LEN])
    if not magic.startswith(ACCEPTED_MAJOR):
        shown = magic.decode("ascii", "replace").rstrip("\0")
        raise CookieError(f"not a VRPN 07 peer (cookie {shown!r})")
    version = magic[len(b"vrpn: ver. ") :].decode("ascii", "replace")
    log_digit = cookie[MAGIC_LEN + 2 : MAGIC_LEN + 3]
    if log_digit not in (b"0", b"1", b"2", b"3"):
        raise CookieError(f"bad log-mode byte {log_digit!r} in cookie")
    return version


# -- system messages --------------------------------------------------------------------------


def description_payload(name: str) -> bytes:
    """Payload of a sender or type description: uint32 length with NUL, name, NUL."""
    raw = name.encode("latin-1")
    if len(raw) > MAX_NAME or b"\0" in raw:
        raise ValueError(f"VRPN name {name!r} is longer than {MAX_NAME} bytes or holds a NUL")
    return _UINT32.pack(len(raw) + 1) + raw + b"\0"


def pack_description(kind: int, ident: int, name: str) -> bytes:
    """A SENDER_DESCRIPTION or TYPE_DESCRIPTION message for ``ident`` → ``name``."""
    return pack_message(kind, ident, description_payload(name))


def decode_description(payload: bytes) -> str:
    """The name in a description; :class:`FramingError` (connection dropped) when malformed."""
    if len(payload) > MAX_DESCRIPTION_PAYLOAD:
        raise FramingError(
            f"description of {len(payload)} bytes (at most {MAX_DESCRIPTION_PAYLOAD})"
        )
    if len(payload) < 5:
        raise FramingError("description too short")
    (n,) = _UINT32.unpack_from(payload, 0)
    if n < 1 or 4 + n > len(payload):
        raise FramingError(f"description name length {n} does not fit its payload")
    raw = payload[4 : 4 + n]
    return raw.split(b"\0", 1)[0].decode("latin-1")


def pack_udp_description(ip: str, port: int) -> bytes:
    """UDP_DESCRIPTION: the port travels in the sender field, the IPv4 address as text."""
    return pack_message(UDP_DESCRIPTION, port, ip.encode("ascii") + b"\0")


def decode_udp_description(message: Message) -> tuple[str, int]:
    """(ip, port) from a UDP_DESCRIPTION; :class:`ValueError` when not a usable address."""
    text = message.payload.split(b"\0", 1)[0].decode("ascii", "replace")
    ip = str(ipaddress.IPv4Address(text))
    port = message.sender_id
    if not 1 <= port <= 65535:
        raise ValueError(f"UDP port {port} out of range")
    return ip, port


def pack_disconnect() -> bytes:
    return pack_message(DISCONNECT_MESSAGE, 0)


# -- the lob (UDP connection request) ---------------------------------------------------------


def lob_request(ip: str, port: int) -> bytes:
    """The datagram asking a server to call back ``ip:port`` over TCP."""
    return f"{ip} {port}".encode("ascii") + b"\0"


class LobError(ValueError):
    """A connection-request datagram a server must ignore."""


def parse_lob(data: bytes) -> tuple[str, int]:
    """(host, port) of a connection request, checked as the C++ server does (and bounded)."""
    text = bytes(data[:199]).split(b"\0", 1)[0]
    parts = text.split(b" ")
    if len(parts) != 2 or not parts[0] or not parts[1].isdigit() or len(parts[1]) > 5:
        raise LobError("not 'HOST PORT'")
    host, port = parts[0].decode("ascii", "replace"), int(parts[1])
    if not all(c.isascii() and (c.isalnum() or c == ".") for c in host):
        raise LobError(f"bad host {host!r}")
    if not 1024 <= port <= 65535:
        raise LobError(f"bad port {port}")
    return host, port
