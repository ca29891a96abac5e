"""The table's rows kept packed (one string a row) until their lines are made, and the
positions' texts made once for a run of equal matrices: the same lines as
:func:`table_lines` and :func:`position_text` make."""

from __future__ import annotations

import numpy as np
import pytest

from gadgetctl.cli.monitor_text import (
    COLUMNS,
    PackedRows,
    PositionTexts,
    position_text,
    table_lines,
)

ROWS = [
    ["W0", "device", "waveform_device", "running", "10.0", "0.17", "0", "12.5", "0.30", "x"],
    ["P0", "proxy", "position_proxy -> W0[0]", "running", "10.0", "", "", "12.5", "", "pos"],
    ["a\x1bname\n", "proxy", "t\tab", "faulted", "-", "", "", "-", "", "bad \x00 value\u202e"],
    ["long" * 12, "alias", "alias -> P0", "stupefied", "-", "", "", "-", "", ""],
]


@pytest.mark.parametrize("last_free", [True, False])
def test_packed_rows_make_the_lines_of_table_lines(last_free):
    packed = PackedRows(COLUMNS, last_free=last_free)
    packed.add(ROWS[:2])
    packed.add(ROWS[2:])  # added a chunk at a time: the widths of every chunk count
    expected = list(table_lines(COLUMNS, [list(r) for r in ROWS], last_free=last_free))
    assert list(packed.lines()) == expected
    assert "\\x1b" in expected[3] and "\\x00" in expected[3]  # escaped, not a separator
    assert packed.rows == []  # given up as the lines were made


def test_packed_rows_with_a_short_row():
    packed = PackedRows(("A", "B", "C"))
    packed.add([["one"], ["x", "yy", "zzz"]])
    assert list(packed.lines()) == list(table_lines(("A", "B", "C"), [["one"], ["x", "yy", "zzz"]]))


def pose(x: float) -> np.ndarray:
    m = np.eye(4)
    m[0, 3] = x
    return m


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"quaternion": True},
        {"length_unit": "centimeters"},
        {"pose": "euler"},
        {"pose": "matrix"},
    ],
)
def test_position_texts_are_position_text(options):
    texts = PositionTexts(**options)
    for matrix in (pose(1.0), pose(1.0), pose(2.0), pose(1.0), np.full((4, 4), np.nan)):
        assert texts.text(matrix) == position_text(matrix, **options)


def test_equal_matrices_make_one_text():
    texts = PositionTexts()
    first = texts.text(pose(0.5))
    assert texts.text(pose(0.5)) is first
    assert texts.made == 1
    texts.text(pose(-0.0))
    texts.text(pose(0.0))  # equal numbers, other bytes: a text of its own, the same one
    assert texts.made == 3
    texts.text([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])  # not an array: made
    assert texts.made == 4


def test_position_texts_remember_only_a_few():
    texts = PositionTexts()
    for i in range(PositionTexts.MOST * 3):
        texts.text(pose(float(i)))
    assert len(texts._texts) <= PositionTexts.MOST
    assert texts.made == PositionTexts.MOST * 3
