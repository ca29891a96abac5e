"""Terminal input of the live monitor: key sequences to Gadgeteer key codes, mouse reports,
and the raw mode that must always be restored."""

from __future__ import annotations

import os
import pty
import termios

import pytest

from gadgetctl.cli.monitor_terminal import PIXELS_PER_CELL, KeyDecoder, RawTerminal, char_event
from gadgetctl.input.keys import Key, Modifier

SHIFT, CTRL, ALT = Modifier.SHIFT, Modifier.CTRL, Modifier.ALT


def keys(data: bytes, moment: float = 0.0) -> list[tuple[Key, tuple[Modifier, ...]]]:
    decoder = KeyDecoder()
    events = decoder.feed(data, moment) + decoder.flush(moment + 1.0)
    return [(e.key, e.modifiers) for e in events if e.kind == "key"]


@pytest.mark.parametrize(
    ("typed", "expected"),
    [
        (b"a", [(Key.KEY_A, ())]),
        (b"Z", [(Key.KEY_Z, (SHIFT,))]),
        (b"7", [(Key.KEY_7, ())]),
        (b" ", [(Key.KEY_SPACE, ())]),
        (b"\r", [(Key.KEY_RETURN, ())]),
        (b"\t", [(Key.KEY_TAB, ())]),
        (b"\x7f", [(Key.KEY_BACKSPACE, ())]),
        (b",.", [(Key.KEY_COMMA, ()), (Key.KEY_PERIOD, ())]),
        (
            b"<>",
            [(Key.KEY_COMMA, (SHIFT,)), (Key.KEY_PERIOD, (SHIFT,))],
        ),  # as an X11 input window: unshifted key + SHIFT
        (b"!", [(Key.KEY_1, (SHIFT,))]),
        (b"\x01", [(Key.KEY_A, (CTRL,))]),
        (b"\x1bx", [(Key.KEY_X, (ALT,))]),
        (b"\x1b", [(Key.KEY_ESC, ())]),
        (
            b"\x1b[A\x1b[B\x1b[C\x1b[D",
            [(Key.KEY_UP, ()), (Key.KEY_DOWN, ()), (Key.KEY_RIGHT, ()), (Key.KEY_LEFT, ())],
        ),
        (b"\x1bOA", [(Key.KEY_UP, ())]),
        (b"\x1b[1;2C", [(Key.KEY_RIGHT, (SHIFT,))]),
        (b"\x1b[1;5A", [(Key.KEY_UP, (CTRL,))]),
        (b"\x1bOP\x1b[15~\x1b[24~", [(Key.KEY_F1, ()), (Key.KEY_F5, ()), (Key.KEY_F12, ())]),
        (
            b"\x1b[5~\x1b[6~\x1b[H\x1b[3~",
            [(Key.KEY_PRIOR, ()), (Key.KEY_NEXT, ()), (Key.KEY_HOME, ()), (Key.KEY_DELETE, ())],
        ),
    ],
)
def test_terminal_sequences_become_key_codes(typed, expected):
    assert keys(typed) == expected


def test_a_sequence_split_across_reads_is_joined_and_a_lone_escape_waits():
    decoder = KeyDecoder()
    assert decoder.feed(b"\x1b", 0.0) == []
    assert decoder.flush(0.01) == []  # maybe the rest of a sequence is on its way
    events = decoder.feed(b"[A", 0.02)
    assert [(e.key, e.modifiers) for e in events] == [(Key.KEY_UP, ())]
    assert decoder.feed(b"\x1b", 1.0) == []
    assert [e.key for e in decoder.flush(1.1)] == [Key.KEY_ESC]


def test_utf8_split_across_reads_and_unknown_characters():
    decoder = KeyDecoder()
    assert decoder.feed("é".encode()[:1], 0.0) == []
    assert decoder.feed("é".encode()[1:] + b"b", 0.0)[-1].key is Key.KEY_B
    assert char_event("é") is None


def test_mouse_reports_become_buttons_motion_and_wheel():
    decoder = KeyDecoder()
    events = decoder.feed(
        b"\x1b[<0;10;5M\x1b[<32;12;4M\x1b[<0;12;4m\x1b[<65;12;4M\x1b[<18;12;4M", 0.0
    )
    summary = [(e.kind, e.key, e.pressed, e.dx, e.dy, e.direction, e.modifiers) for e in events]
    assert summary == [
        ("button", Key.MOUSE_BUT1, True, 0.0, 0.0, None, ()),
        ("move", None, True, 2.0 * PIXELS_PER_CELL, -1.0 * PIXELS_PER_CELL, None, ()),
        ("button", Key.MOUSE_BUT1, False, 0.0, 0.0, None, ()),
        ("scroll", None, True, 0.0, 0.0, "down", ()),
        ("button", Key.MOUSE_BUT3, True, 0.0, 0.0, None, (CTRL,)),
    ]


def test_raw_terminal_restores_the_mode_even_after_an_error():
    master, slave = pty.openpty()
    try:
        before = termios.tcgetattr(slave)
        with (
            open(slave, closefd=False) as stdin,
            open(os.devnull, "w") as stdout,
            pytest.raises(RuntimeError),
            RawTerminal(stdin, stdout) as terminal,
        ):
            raw = termios.tcgetattr(slave)
            assert (
                not raw[3] & termios.ECHO
                and not raw[3] & termios.ICANON
                and not raw[3] & termios.ISIG
            )
            os.write(master, b"q\x1b[A")
            assert terminal.read() == b"q\x1b[A"
            assert terminal.read() == b""  # never waits
            raise RuntimeError("boom")
        assert termios.tcgetattr(slave) == before
    finally:
        os.close(master)
        os.close(slave)
