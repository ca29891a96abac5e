"""Numbers a device or file sends print in bounded width (issue 24 item 17): a coordinate of
1e308 was 309 digits in the live view, the table, events and the replay summary."""

from __future__ import annotations

import json
import math
import re
import warnings

import numpy as np
import pytest

from gadgetctl.cli.monitor_text import glove_text, number, position_text
from gadgetctl.monitor.events import pose_text
from gadgetctl.safetext import FIXED_LIMIT, fixed

pytestmark = [pytest.mark.timeout(60), pytest.mark.filterwarnings("error")]
HUGE = np.array([[1.0, 0, 0, 1e308], [0, 1, 0, -1e300], [0, 0, 1, 0.5], [0, 0, 0, 1]])
LONGEST_NUMBER = 15  # "+999999999.999" and "-1.000e+308" fit
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]\d+)?")


def longest_number(text: str) -> int:
    return max(len(m) for m in NUMBER.findall(text))


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (1e308, "+1.000e+308"),
        (-1e300, "-1.000e+300"),
        (FIXED_LIMIT * 0.999, "+999000000.000"),
        (FIXED_LIMIT, "+1.000e+09"),
        (0.5, "+0.500"),
        (math.inf, "+inf"),
        (-math.inf, "-inf"),
    ],
)
def test_fixed_switches_to_an_exponent_at_the_limit(value, text) -> None:
    assert fixed(value, 3, sign=True) == text


def test_positions_and_poses_stay_narrow() -> None:
    texts = [position_text(HUGE), position_text(HUGE, "centimeters", quaternion=True)]
    texts += [pose_text(HUGE, pose) for pose in ("euler", "quaternion", "matrix")]
    for text in texts:
        assert len(text) < 160 and longest_number(text) <= LONGEST_NUMBER, text
    assert position_text(HUGE).startswith("x +1.000e+308 y -1.000e+300 z +0.500 m")


def test_analog_values_and_glove_angles_stay_narrow_without_warnings() -> None:
    assert number(1e308) == "1.000e+308"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning went to stderr
        text = glove_text(np.full((6, 4), 1e308))
    assert text.startswith("thumb inf/inf/inf/inf") and len(text) < 160


def _recording(tmp_path) -> str:
    header = {"v": 1, "type": "header", "format": "gadgetctl-recording", "created": "now"}
    records = [header] + [
        {"v": 1, "type": "sample", "device": "W", "kind": "position", "unit": 0,
         "timestamp": 1 + 0.1 * i, "value": HUGE.tolist()}
        for i in range(3)
    ]  # fmt: skip
    path = tmp_path / "huge.ndjson"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    return str(path)


@pytest.mark.parametrize("view", [["--summary"], ["--format", "table", "--speed", "10"]])
def test_the_table_and_the_summary_stay_narrow(tmp_path, cli, view) -> None:
    result = cli("replay", _recording(tmp_path), *view)
    assert result.exit_code == 0, result.stderr
    assert "+1.000e+308" in result.stdout
    assert longest_number(result.stdout) <= LONGEST_NUMBER
    assert max(len(line) for line in result.stdout.splitlines()) < 200
