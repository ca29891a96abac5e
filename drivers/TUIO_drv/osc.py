"""Open Sound Control 1.0 packets, decoded with bounds: what a TUIO datagram is made of.
Knows nothing of gadgetctl; logs nothing and prints nothing (a packet is data, never text for
a terminal).

A packet is a message or a bundle. A message is an address string, a type tag string
(``,`` then one letter per argument) and the arguments; strings end in NUL and are padded with
NULs to 4 bytes. A bundle is ``#bundle``, an 8-byte time tag, then elements, each an int32
size (a positive multiple of 4) and that many bytes holding a message or a bundle.

Bounds: bundles nest at most :data:`MAX_DEPTH` deep and a packet holds at most
:data:`MAX_MESSAGES` messages; anything beyond, a size that does not fit, a type tag this
module does not know (it could not know the argument's length), a string that is not ASCII
or not terminated, makes the whole packet bad (:class:`OscError`), as no part of a packet
whose framing failed can be trusted.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

BUNDLE_HEAD = b"#bundle\x00"
#: Deepest nesting of bundles in one packet (the outermost bundle is depth 1).
MAX_DEPTH = 8
#: Most messages one packet may hold (a 64 KB datagram holds at most about 8,000).
MAX_MESSAGES = 8192

_I32 = struct.Struct(">i")
#: Type tags of numbers and how they are packed (big-endian).
_NUMBERS = {"i": _I32, "f": struct.Struct(">f"), "h": struct.Struct(">q"), "d": struct.Struct(">d")}
#: Type tags without data, and their values.
_CONSTANTS = {"T": True, "F": False, "N": None, "I": float("inf")}
#: Type tags with four bytes of data that TUIO never uses: kept as raw bytes.
_FOUR_BYTES = frozenset("crm")


class OscError(ValueError):
    """A packet that is not well-formed OSC 1.0 within the bounds."""


@dataclass(frozen=True, slots=True)
class OscMessage:
    address: str
    arguments: tuple[object, ...]


@dataclass(frozen=True, slots=True)
class OscBundle:
    """A bundle's messages in order, nested bundles flattened into their place; ``depth`` is
    the deepest nesting met."""

    messages: tuple[OscMessage, ...]
    depth: int


def _string(data: bytes, offset: int, end: int) -> tuple[str, int]:
    stop = data.find(b"\x00", offset, end)
    if stop < 0:
        raise OscError(f"string at byte {offset} has no terminating NUL")
    raw = data[offset:stop]
    if not raw.isascii():
        raise OscError(f"string at byte {offset} is not ASCII")
    after = (stop + 4) & ~3
    if after > end:
        raise OscError(f"string at byte {offset} runs past its element")
    return raw.decode("ascii"), after


def _fixed(data: bytes, offset: int, end: int, size: int) -> int:
    if offset + size > end:
        raise OscError(f"argument at byte {offset} runs past its element")
    return offset + size


def _message(data: bytes, offset: int, end: int) -> OscMessage:
    address, offset = _string(data, offset, end)
    if not address.startswith("/"):
        raise OscError(f"address {address[:40]!r} does not start with '/'")
    if offset == end:  # no type tags: an OSC 1.0 message without arguments
        return OscMessage(address, ())
    tags, offset = _string(data, offset, end)
    if not tags.startswith(","):
        raise OscError(f"type tags {tags[:40]!r} do not start with ','")
    arguments: list[object] = []
    for tag in tags[1:]:
        start = offset
        number = _NUMBERS.get(tag)
        if number is not None:
            offset = _fixed(data, offset, end, number.size)
            arguments.append(number.unpack_from(data, start)[0])
        elif tag in "sS":
            text, offset = _string(data, offset, end)
            arguments.append(text)
        elif tag == "t":
            offset = _fixed(data, offset, end, 8)
            arguments.append(data[start:offset])
        elif tag == "b":
            offset = _fixed(data, offset, end, 4)
            size = _I32.unpack_from(data, start)[0]
            if size < 0:
                raise OscError(f"blob at byte {start} has a negative size")
            blob_end = _fixed(data, offset, end, (size + 3) & ~3)
            arguments.append(data[offset : offset + size])
            offset = blob_end
        elif tag in _CONSTANTS:
            arguments.append(_CONSTANTS[tag])
        elif tag in _FOUR_BYTES:
            offset = _fixed(data, offset, end, 4)
            arguments.append(data[start:offset])
        else:
            raise OscError(f"type tag {tag!r} is not one this decoder reads")
    return OscMessage(address, tuple(arguments))


def decode_packet(data: bytes) -> OscBundle:
    """The messages of a packet (a bare message is a bundle of one, at depth 0); raises
    :class:`OscError` when it is not well-formed OSC within the bounds."""
    if not data.startswith(BUNDLE_HEAD):
        if len(data) % 4:
            raise OscError(f"a message of {len(data)} bytes is not a multiple of 4")
        return OscBundle((_message(data, 0, len(data)),), 0)
    if len(data) < 16:
        raise OscError("a bundle shorter than its head and time tag")
    messages: list[OscMessage] = []
    deepest = 1
    open_bundles = [(len(data), 1)]  # (end, depth) of the bundles being read, innermost last
    offset = 16  # after the head and the time tag
    while open_bundles:
        end, depth = open_bundles[-1]
        if offset == end:  # every element of this bundle read
            open_bundles.pop()
            continue
        if offset + 4 > end:
            raise OscError(f"bundle element size at byte {offset} runs past the bundle")
        size = _I32.unpack_from(data, offset)[0]
        offset += 4
        if size <= 0 or size % 4 or offset + size > end:
            raise OscError(f"bundle element of {size} bytes at byte {offset - 4} does not fit")
        if data.startswith(BUNDLE_HEAD, offset):
            if depth >= MAX_DEPTH:
                raise OscError(f"bundles nest deeper than {MAX_DEPTH}")
            if size < 16:
                raise OscError(f"a nested bundle of {size} bytes at byte {offset}")
            open_bundles.append((offset + size, depth + 1))
            deepest = max(deepest, depth + 1)
            offset += 16
            continue
        if len(messages) >= MAX_MESSAGES:
            raise OscError(f"more than {MAX_MESSAGES} messages in one packet")
        messages.append(_message(data, offset, offset + size))
        offset += size
    return OscBundle(tuple(messages), deepest)
