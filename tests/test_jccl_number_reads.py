"""Numbers read from property texts as VR Juggler's run time reads them (a C++ stream, strtol),
the same whether a text is read for the first time or again (reads are remembered)."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from gadgetctl.jccl import access
from gadgetctl.jccl.access import read_float, read_int

CASES = [
    ("10", 10, 10.0),
    (" -1.5e2 ", -1, -150.0),
    ("+.5", 0, 0.5),
    ("-0", 0, -0.0),
    ("3x", 3, 3.0),
    ("x3", 0, 0.0),
    ("", 0, 0.0),
    ("nan", 0, 0.0),
    ("inf", 0, 0.0),
    ("1_000", 1, 1.0),
    ("9" * 30, 2**63 - 1, float("9" * 30)),
    ("-" + "9" * 30, -(2**63), float("-" + "9" * 30)),
    ("0" * 25 + "42", 42, 42.0),  # plain digits: leading zeros count for nothing
    ("9" * 18, int("9" * 18), float("9" * 18)),
    ("1" * 19, int("1" * 19), float("1" * 19)),
    ("9" * 19, 2**63 - 1, float("9" * 19)),
    ("9" * 20, 2**63 - 1, float("9" * 20)),  # beyond a long: saturated
    ("9223372036854775808", 2**63 - 1, 9223372036854775808.0),
]


def test_reads_follow_the_stream_rules_the_first_time_and_again():
    for text, integer, number in CASES:
        for _ in range(2):  # read, then read from what was remembered
            assert read_int(text) == integer and type(read_int(text)) is int
            got = read_float(text)
            assert got == number and type(got) is float
            assert str(got) == str(number)  # -0.0 stays negative


@given(st.text(alphabet="0123456789+-.eE x_", max_size=40))
def test_a_remembered_read_is_the_read(text: str):
    first_int, first_float = read_int(text), read_float(text)
    assert read_int(text) == first_int and read_float(text) == first_float
    assert access._read_int(text) == first_int  # the uncached reading


@given(st.text(alphabet="0123456789", min_size=1, max_size=40))
def test_plain_digits_read_as_strtol_reads_them(text: str):
    assert read_int(text) == access._read_int(text) == min(int(text), 2**63 - 1)


def test_what_is_remembered_is_bounded():
    for i in range(3 * access._READ_MOST):
        read_int(str(i))
        read_float(f"{i}.5")
    assert len(access._READ_INTS) <= access._READ_MOST
    assert len(access._READ_FLOATS) <= access._READ_MOST
    long_text = "1" * (access._READ_LONGEST + 1)
    read_int(long_text)
    assert long_text not in access._READ_INTS
