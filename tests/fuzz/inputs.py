"""Inputs for the fuzz targets: arbitrary bytes, grammar-made records, mutations of valid ones.

A mutation takes one valid input (a corpus file, an emulator's record) and applies a few edits
that hostile or damaged input is made of: flipped bits, bytes set, inserted, deleted or
duplicated, a slice of another valid input spliced in, numbers replaced by extreme ones (huge,
negative, thousands of digits, not finite) and tokens that break structure.

Everything is a function of a ``random.Random``: the campaign (``make fuzz``) calls them
directly, thousands of times a second, and :func:`strategy` hands them a random object that
hypothesis controls, so ``make test`` is deterministic and hypothesis can shrink a failure.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence

from hypothesis import strategies as st

#: Numbers and tokens that reach the edges of parsers.
INTERESTING = [
    b"0", b"-1", b"-0", b"1e309", b"-1e309", b"nan", b"inf", b"2147483647", b"2147483648",
    b"4294967295", b"4294967296", b"9223372036854775807", b"18446744073709551616",
    b"3000000", b"2000000", b"9" * 400, b"1" * 4301, b"0x10", b"1_000", b"\xc2\xb2", b"1.5",
    b".", b"-", b"[", b"]", b"[]", b"[[", b"]]", b"\r\n", b"\n", b"\0", b"\x80", b"\x8f",
    b"\xff", b"<", b">", b"</", b"/>", b"&", b"&amp;", b"&#0;", b'"', b"'", b"<!--", b"-->",
    b"<![CDATA[", b"<?", b"?>", b"<!DOCTYPE x [<!ENTITY e 'x'>]>", b"&e;", b"{", b"}", b"[1",
    b'{"v":1,', b'"type":"sample"', b"null", b"true", b"1e999", b"-1e999", b'"\\ud800"',
    b"$(HOME)", b"${UNDEFINED}", b"..", b"/", b"x" * 300, b"\xef\xbb\xbf", b"\xfe\xff",
]  # fmt: skip

_DIGITS = frozenset(b"0123456789")

Grammar = Callable[[random.Random], bytes]


def _number_spans(data: bytes | bytearray, rng: random.Random) -> tuple[int, int] | None:
    """A run of digits of ``data``, picked near a random place; None if there is none."""
    if not data:
        return None
    at = rng.randrange(len(data))
    for i in [*range(at, len(data)), *range(at)]:
        if data[i] in _DIGITS:
            start = end = i
            while start > 0 and data[start - 1] in _DIGITS:
                start -= 1
            while end < len(data) and data[end] in _DIGITS:
                end += 1
            return start, end
    return None


def mutate(rng: random.Random, seeds: Sequence[bytes], max_edits: int = 6) -> bytes:
    """One of ``seeds`` with 0 to ``max_edits`` hostile edits."""
    data = bytearray(rng.choice(seeds))
    for _ in range(rng.randint(0, max_edits)):
        kind = rng.randrange(9)
        size = len(data)
        at = rng.randint(0, size)
        if kind == 0 and size:  # flip a bit
            data[min(at, size - 1)] ^= 1 << rng.randrange(8)
        elif kind == 1 and size:  # set a byte
            data[min(at, size - 1)] = rng.randrange(256)
        elif kind == 2:  # insert random bytes
            data[at:at] = rng.randbytes(rng.randint(1, 16))
        elif kind == 3 and size:  # delete a run
            del data[at : at + rng.randint(1, 64)]
        elif kind == 4 and size:  # duplicate a run, a few times
            run = bytes(data[at : at + rng.randint(1, 256)])
            data[at:at] = run * rng.randint(1, 4)
        elif kind == 5:  # splice a slice of another seed
            other = rng.choice(seeds)
            start = rng.randint(0, len(other))
            data[at:at] = other[start : start + rng.randint(1, 512)]
        elif kind == 6:  # insert an interesting token
            data[at:at] = rng.choice(INTERESTING)
        elif kind == 7 and (span := _number_spans(data, rng)):  # replace a number
            data[span[0] : span[1]] = rng.choice(INTERESTING)
        elif kind == 8 and size:  # cut short
            del data[at:]
    return bytes(data)


def arbitrary(rng: random.Random, max_size: int = 2048) -> bytes:
    return rng.randbytes(rng.randint(0, max_size))


def generate(rng: random.Random, seeds: Sequence[bytes], grammar: Grammar | None = None) -> bytes:
    """One input: mostly mutated valid inputs, also arbitrary bytes and grammar-made ones."""
    kind = rng.randrange(8 if grammar else 6)
    if kind == 0:
        return arbitrary(rng)
    if kind <= 3:
        return mutate(rng, seeds)
    if kind <= 5:
        return mutate(rng, seeds, 24)
    made = grammar(rng)  # type: ignore[misc]
    return made if kind == 6 else mutate(rng, [made])


def strategy(seeds: Sequence[bytes], grammar: Grammar | None = None) -> st.SearchStrategy[bytes]:
    """The same inputs for hypothesis, plus its own arbitrary bytes (which it shrinks well)."""
    made = st.randoms(use_true_random=False).map(lambda rng: generate(rng, seeds, grammar))
    return st.one_of(st.binary(max_size=512), made)
