"""The terminal side of the live monitor: raw keyboard input, mouse reporting, and the
translation of terminal key sequences into Gadgeteer key codes.

Terminals report characters and escape sequences, not key presses and releases: each
keystroke becomes a press and release of the matching ``key_modifier_pair`` key code, with
the modifiers it was typed with, as Gadgeteer's X11 input window does (the unshifted key
plus SHIFT: ``A`` is SHIFT+KEY_A and, on a US layout, ``>`` is SHIFT+KEY_PERIOD). Mouse
buttons, motion (one character cell counts as :data:`PIXELS_PER_CELL` pixels) and the wheel
come from SGR mouse reporting (xterm mode 1003 + 1006).
"""

from __future__ import annotations

import codecs
import os
import re
import select
import sys
import termios
from dataclasses import dataclass
from typing import TextIO

from gadgetctl.input.keys import Key, Modifier

PIXELS_PER_CELL = 10
ESCAPE_TIMEOUT = 0.05  # a lone ESC not followed by a sequence within this time is the Esc key
MOUSE_ON = "\x1b[?1003h\x1b[?1006h"
MOUSE_OFF = "\x1b[?1003l\x1b[?1006l"

_LETTERS = {chr(ord("a") + i): Key[f"KEY_{chr(ord('A') + i)}"] for i in range(26)}
_DIGITS = {str(d): Key[f"KEY_{d}"] for d in range(10)}
_PLAIN = {
    " ": Key.KEY_SPACE,
    ",": Key.KEY_COMMA,
    ".": Key.KEY_PERIOD,
    "/": Key.KEY_SLASH,
    ";": Key.KEY_SEMICOLON,
    "'": Key.KEY_APOSTROPHE,
    "[": Key.KEY_BRACKET_LEFT,
    "]": Key.KEY_BRACKET_RIGHT,
    "\\": Key.KEY_BACKSLASH,
    "-": Key.KEY_MINUS,
    "=": Key.KEY_EQUAL,
    "`": Key.KEY_QUOTE_LEFT,
    "\t": Key.KEY_TAB,
    "\r": Key.KEY_RETURN,
    "\n": Key.KEY_RETURN,
    "\x7f": Key.KEY_BACKSPACE,
    "\x08": Key.KEY_BACKSPACE,
}
#: Shifted characters of a US layout: the unshifted key, typed with SHIFT.
_SHIFTED = {
    "!": Key.KEY_1,
    "@": Key.KEY_2,
    "#": Key.KEY_3,
    "$": Key.KEY_4,
    "%": Key.KEY_5,
    "^": Key.KEY_6,
    "&": Key.KEY_7,
    "*": Key.KEY_8,
    "(": Key.KEY_9,
    ")": Key.KEY_0,
    "_": Key.KEY_MINUS,
    "+": Key.KEY_EQUAL,
    "{": Key.KEY_BRACKET_LEFT,
    "}": Key.KEY_BRACKET_RIGHT,
    "|": Key.KEY_BACKSLASH,
    ":": Key.KEY_SEMICOLON,
    '"': Key.KEY_APOSTROPHE,
    "<": Key.KEY_COMMA,
    ">": Key.KEY_PERIOD,
    "?": Key.KEY_SLASH,
    "~": Key.KEY_QUOTE_LEFT,
}
_CSI_LETTERS = {
    "A": Key.KEY_UP,
    "B": Key.KEY_DOWN,
    "C": Key.KEY_RIGHT,
    "D": Key.KEY_LEFT,
    "H": Key.KEY_HOME,
    "F": Key.KEY_END,
    "P": Key.KEY_F1,
    "Q": Key.KEY_F2,
    "R": Key.KEY_F3,
    "S": Key.KEY_F4,
}
_CSI_TILDE = {
    1: Key.KEY_HOME,
    2: Key.KEY_INSERT,
    3: Key.KEY_DELETE,
    4: Key.KEY_END,
    5: Key.KEY_PRIOR,
    6: Key.KEY_NEXT,
    7: Key.KEY_HOME,
    8: Key.KEY_END,
    11: Key.KEY_F1,
    12: Key.KEY_F2,
    13: Key.KEY_F3,
    14: Key.KEY_F4,
    15: Key.KEY_F5,
    17: Key.KEY_F6,
    18: Key.KEY_F7,
    19: Key.KEY_F8,
    20: Key.KEY_F9,
    21: Key.KEY_F10,
    23: Key.KEY_F11,
    24: Key.KEY_F12,
    25: Key.KEY_F13,
    26: Key.KEY_F14,
    28: Key.KEY_F15,
    29: Key.KEY_F16,
    31: Key.KEY_F17,
    32: Key.KEY_F18,
    33: Key.KEY_F19,
    34: Key.KEY_F20,
}
_CSI = re.compile(r"\x1b\[([0-9;?]*)([A-Za-z~])")
_SGR_MOUSE = re.compile(r"\x1b\[<(\d+);(\d+);(\d+)([Mm])")
_SS3 = re.compile(r"\x1bO([A-Za-z])")
_MOUSE_BUTTONS = {0: Key.MOUSE_BUT1, 1: Key.MOUSE_BUT2, 2: Key.MOUSE_BUT3}
_WHEEL = {64: "up", 65: "down", 66: "left", 67: "right"}


@dataclass(frozen=True, slots=True)
class TermEvent:
    """One thing the user did: ``kind`` is key, button, move or scroll.

    ``text`` is the character typed for plain keys (the monitor's own keys and the marker
    prompt use it); ``modifiers`` lists the modifiers held (SHIFT, CTRL, ALT).
    """

    kind: str
    key: Key | None = None
    modifiers: tuple[Modifier, ...] = ()
    text: str | None = None
    pressed: bool = True
    dx: float = 0.0
    dy: float = 0.0
    direction: str | None = None


def _modifiers(code: int) -> tuple[Modifier, ...]:
    """xterm's modifier parameter (1 + shift 1, alt 2, ctrl 4)."""
    bits = max(0, code - 1)
    found = []
    if bits & 1:
        found.append(Modifier.SHIFT)
    if bits & 2:
        found.append(Modifier.ALT)
    if bits & 4:
        found.append(Modifier.CTRL)
    return tuple(found)


def char_event(char: str, extra: tuple[Modifier, ...] = ()) -> TermEvent | None:
    """The key event of one typed character (None for characters without a key code)."""
    if char in _LETTERS:
        return TermEvent("key", _LETTERS[char], extra, char)
    if "A" <= char <= "Z":
        return TermEvent("key", _LETTERS[char.lower()], (Modifier.SHIFT, *extra), char)
    if char in _DIGITS:
        return TermEvent("key", _DIGITS[char], extra, char)
    if char in _PLAIN:
        return TermEvent("key", _PLAIN[char], extra, char)
    if char in _SHIFTED:
        return TermEvent("key", _SHIFTED[char], (Modifier.SHIFT, *extra), char)
    code = ord(char)
    if 1 <= code <= 26:  # Ctrl+letter (Tab, Return and Backspace were taken above)
        return TermEvent("key", _LETTERS[chr(ord("a") + code - 1)], (Modifier.CTRL, *extra), char)
    if char == "\x1b":
        return TermEvent("key", Key.KEY_ESC, extra, char)
    return None


class KeyDecoder:
    """Turns the bytes read from a terminal into :class:`TermEvent` objects."""

    def __init__(self) -> None:
        self._pending = ""
        self._pending_since: float | None = None
        self._mouse: tuple[int, int] | None = None
        self._decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")

    def feed(self, data: bytes, moment: float) -> list[TermEvent]:
        if not data:
            return []  # nothing new: a pending lone ESC keeps the time it arrived (see flush)
        self._pending += self._decoder.decode(data)
        events: list[TermEvent] = []
        self._parse(events, moment)
        return events

    def flush(self, moment: float) -> list[TermEvent]:
        """Events of a pending lone ESC whose sequence never came."""
        events: list[TermEvent] = []
        if (
            self._pending
            and self._pending_since is not None
            and moment - self._pending_since >= ESCAPE_TIMEOUT
        ):
            self._parse(events, moment, final=True)
        return events

    def _parse(self, events: list[TermEvent], moment: float, final: bool = False) -> None:
        buf = self._pending
        i = 0
        while i < len(buf):
            char = buf[i]
            if char != "\x1b":
                event = char_event(char)
                if event is not None:
                    events.append(event)
                i += 1
                continue
            rest = buf[i:]
            if len(rest) == 1:
                if final:
                    events.append(TermEvent("key", Key.KEY_ESC, (), "\x1b"))
                    i += 1
                    continue
                break  # wait: the rest of a sequence may come with the next read
            match = _SGR_MOUSE.match(rest)
            if match:
                events.extend(self._mouse_event(*match.groups()))
                i += match.end()
                continue
            match = _CSI.match(rest)
            if match:
                event = self._csi(match.group(1), match.group(2))
                if event is not None:
                    events.append(event)
                i += match.end()
                continue
            match = _SS3.match(rest)
            if match:
                key = _CSI_LETTERS.get(match.group(1))
                if key is not None:
                    events.append(TermEvent("key", key))
                i += match.end()
                continue
            if rest.startswith(("\x1b[", "\x1bO")) and not final:
                if re.fullmatch(r"\x1b(\[[<0-9;?]*|O)", rest):
                    break  # an unfinished sequence
                i += 2  # an unknown sequence: skip its introducer
                continue
            if rest[1] == "\x1b":
                events.append(TermEvent("key", Key.KEY_ESC, (), "\x1b"))
                i += 1
                continue
            event = char_event(rest[1], (Modifier.ALT,))  # ESC + character: Alt+character
            if event is not None:
                events.append(TermEvent(event.kind, event.key, event.modifiers, None))
            i += 2
        self._pending = buf[i:]
        self._pending_since = moment if self._pending else None

    @staticmethod
    def _csi(params: str, final: str) -> TermEvent | None:
        parts = [p for p in params.split(";") if p.isdigit()]
        numbers = [int(p) for p in parts]
        modifiers = _modifiers(numbers[1]) if len(numbers) >= 2 else ()
        if final == "~":
            key = _CSI_TILDE.get(numbers[0]) if numbers else None
            return TermEvent("key", key, modifiers) if key is not None else None
        if final == "Z":
            return TermEvent("key", Key.KEY_BACKTAB)
        key = _CSI_LETTERS.get(final)
        return TermEvent("key", key, modifiers) if key is not None else None

    def _mouse_event(self, code_text: str, x_text: str, y_text: str, kind: str) -> list[TermEvent]:
        code, x, y = int(code_text), int(x_text), int(y_text)
        modifiers = tuple(
            m
            for bit, m in ((4, Modifier.SHIFT), (8, Modifier.ALT), (16, Modifier.CTRL))
            if code & bit
        )
        events: list[TermEvent] = []
        previous = self._mouse
        self._mouse = (x, y)
        if previous is not None and (x, y) != previous:
            events.append(
                TermEvent(
                    "move",
                    dx=float((x - previous[0]) * PIXELS_PER_CELL),
                    dy=float((y - previous[1]) * PIXELS_PER_CELL),
                )
            )
        base = code & ~(4 | 8 | 16 | 32)
        if code & 32:  # motion, with or without a button held
            return events
        if base in _WHEEL:
            if kind == "M":
                events.append(TermEvent("scroll", direction=_WHEEL[base], modifiers=modifiers))
            return events
        button = _MOUSE_BUTTONS.get(base & 3)
        if button is not None:
            events.append(TermEvent("button", button, modifiers, pressed=kind == "M"))
        return events


class RawTerminal:
    """Raw keyboard input on ``stdin`` and mouse reporting on ``stdout``, always restored.

    Echo, line editing, signal keys (Ctrl-C arrives as a character) and flow control are
    turned off; output processing stays on. ``__exit__`` restores the saved mode whatever
    happened, and turns mouse reporting off.
    """

    def __init__(
        self, stdin: TextIO | None = None, stdout: TextIO | None = None, *, mouse: bool = True
    ) -> None:
        self.stdin = stdin or sys.stdin
        self.stdout = stdout or sys.stdout
        self.fd = self.stdin.fileno()
        self.mouse = mouse
        self._saved: list | None = None

    def __enter__(self) -> RawTerminal:
        self._saved = termios.tcgetattr(self.fd)
        mode = termios.tcgetattr(self.fd)
        mode[0] &= ~(termios.IXON | termios.ICRNL | termios.INLCR | termios.IGNCR)  # iflag
        mode[3] &= ~(termios.ICANON | termios.ECHO | termios.ISIG | termios.IEXTEN)  # lflag
        mode[6] = list(mode[6])
        mode[6][termios.VMIN] = 0
        mode[6][termios.VTIME] = 0
        try:
            termios.tcsetattr(self.fd, termios.TCSADRAIN, mode)
            if self.mouse:
                self.stdout.write(MOUSE_ON)
                self.stdout.flush()
        except BaseException:
            self.restore()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.restore()

    def restore(self) -> None:
        if self._saved is None:
            return
        try:
            if self.mouse:
                self.stdout.write(MOUSE_OFF)
                self.stdout.flush()
        finally:
            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
            self._saved = None

    def read(self) -> bytes:
        """Whatever has been typed, without waiting."""
        chunks = []
        while True:
            ready, _, _ = select.select([self.fd], [], [], 0)
            if not ready:
                break
            data = os.read(self.fd, 4096)
            if not data:
                break
            chunks.append(data)
        return b"".join(chunks)
