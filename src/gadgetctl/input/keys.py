"""Key codes of the keyboard/mouse device: the values of the ``key_modifier_pair`` enumeration.

The numbers are those written in configurations (``<key>KEY_A</key>`` reads as 19) and the
positions in Gadgeteer's ``gadget::Keys``. Mouse buttons keep the definition's spelling
(``MOUSE_BUT1``), where the C++ enum says ``MBUTTON1``.
"""

from __future__ import annotations

from enum import IntEnum


class Key(IntEnum):
    KEY_NONE = 0
    KEY_UP = 1
    KEY_DOWN = 2
    KEY_LEFT = 3
    KEY_RIGHT = 4
    KEY_SHIFT = 5
    KEY_CTRL = 6
    KEY_ALT = 7
    KEY_COMMAND = 8
    KEY_1 = 9
    KEY_2 = 10
    KEY_3 = 11
    KEY_4 = 12
    KEY_5 = 13
    KEY_6 = 14
    KEY_7 = 15
    KEY_8 = 16
    KEY_9 = 17
    KEY_0 = 18
    KEY_A = 19
    KEY_B = 20
    KEY_C = 21
    KEY_D = 22
    KEY_E = 23
    KEY_F = 24
    KEY_G = 25
    KEY_H = 26
    KEY_I = 27
    KEY_J = 28
    KEY_K = 29
    KEY_L = 30
    KEY_M = 31
    KEY_N = 32
    KEY_O = 33
    KEY_P = 34
    KEY_Q = 35
    KEY_R = 36
    KEY_S = 37
    KEY_T = 38
    KEY_U = 39
    KEY_V = 40
    KEY_W = 41
    KEY_X = 42
    KEY_Y = 43
    KEY_Z = 44
    KEY_ESC = 45
    MOUSE_POSX = 46
    MOUSE_NEGX = 47
    MOUSE_POSY = 48
    MOUSE_NEGY = 49
    MOUSE_BUT1 = 50
    MOUSE_BUT2 = 51
    MOUSE_BUT3 = 52
    MOUSE_BUT4 = 53
    MOUSE_BUT5 = 54
    MOUSE_BUT6 = 55
    MOUSE_BUT7 = 56
    MOUSE_BUT8 = 57
    MOUSE_BUT9 = 58
    NO_MBUTTON = 59
    MOUSE_SCROLL_UP = 60
    MOUSE_SCROLL_DOWN = 61
    MOUSE_SCROLL_LEFT = 62
    MOUSE_SCROLL_RIGHT = 63
    KEY_TAB = 64
    KEY_BACKTAB = 65
    KEY_BACKSPACE = 66
    KEY_RETURN = 67
    KEY_ENTER = 68
    KEY_INSERT = 69
    KEY_DELETE = 70
    KEY_PAUSE = 71
    KEY_PRINT = 72
    KEY_SYSREQ = 73
    KEY_HOME = 74
    KEY_END = 75
    KEY_PRIOR = 76
    KEY_NEXT = 77
    KEY_CAPS_LOCK = 78
    KEY_NUM_LOCK = 79
    KEY_SCROLL_LOCK = 80
    KEY_F1 = 81
    KEY_F2 = 82
    KEY_F3 = 83
    KEY_F4 = 84
    KEY_F5 = 85
    KEY_F6 = 86
    KEY_F7 = 87
    KEY_F8 = 88
    KEY_F9 = 89
    KEY_F10 = 90
    KEY_F11 = 91
    KEY_F12 = 92
    KEY_F13 = 93
    KEY_F14 = 94
    KEY_F15 = 95
    KEY_F16 = 96
    KEY_F17 = 97
    KEY_F18 = 98
    KEY_F19 = 99
    KEY_F20 = 100
    KEY_F21 = 101
    KEY_F22 = 102
    KEY_F23 = 103
    KEY_F24 = 104
    KEY_F25 = 105
    KEY_F26 = 106
    KEY_F27 = 107
    KEY_F28 = 108
    KEY_F29 = 109
    KEY_F30 = 110
    KEY_F31 = 111
    KEY_F32 = 112
    KEY_F33 = 113
    KEY_F34 = 114
    KEY_F35 = 115
    KEY_SUPER_L = 116
    KEY_SUPER_R = 117
    KEY_MENU = 118
    KEY_HYPER_L = 119
    KEY_HYPER_R = 120
    KEY_HELP = 121
    KEY_SPACE = 122
    KEY_ANY = 123
    KEY_EXCLAM = 124
    KEY_QUOTE_DBL = 125
    KEY_NUMBER_SIGN = 126
    KEY_DOLLAR = 127
    KEY_PERCENT = 128
    KEY_AMPERSAND = 129
    KEY_APOSTROPHE = 130
    KEY_PAREN_LEFT = 131
    KEY_PAREN_RIGHT = 132
    KEY_ASTERISK = 133
    KEY_PLUS = 134
    KEY_COMMA = 135
    KEY_MINUS = 136
    KEY_PERIOD = 137
    KEY_SLASH = 138
    KEY_COLON = 139
    KEY_SEMICOLON = 140
    KEY_LESS = 141
    KEY_EQUAL = 142
    KEY_GREATER = 143
    KEY_QUESTION = 144
    KEY_AT = 145
    KEY_BRACKET_LEFT = 146
    KEY_BACKSLASH = 147
    KEY_BRACKET_RIGHT = 148
    KEY_ASCII_CIRCUM = 149
    KEY_UNDERSCORE = 150
    KEY_QUOTE_LEFT = 151
    KEY_BRACE_LEFT = 152
    KEY_BAR = 153
    KEY_BRACE_RIGHT = 154
    KEY_ASCII_TILDE = 155


class Modifier(IntEnum):
    """The ``modifier_key`` of a key binding."""

    ANY = -1
    NONE = 0
    SHIFT = 5
    CTRL = 6
    ALT = 7
    COMMAND = 8


MODIFIER_KEYS: tuple[Key, ...] = (Key.KEY_SHIFT, Key.KEY_CTRL, Key.KEY_ALT, Key.KEY_COMMAND)
MOUSE_BUTTONS: tuple[Key, ...] = tuple(Key[f"MOUSE_BUT{n}"] for n in range(1, 10))


def key_from_name(name: str) -> Key:
    """``KEY_A``, ``a``, ``A`` or ``19`` -> :class:`Key`; raises ``ValueError`` otherwise."""
    text = name.strip()
    if text.lstrip("-").isdigit():
        return Key(int(text))
    upper = text.upper()
    for candidate in (upper, f"KEY_{upper}"):
        if candidate in Key.__members__:
            return Key[candidate]
    raise ValueError(f"unknown key {name!r}")
