"""The ``replay.recording`` path target of ``make fuzz`` (tests/fuzz/path_replay.py): its checks
fail a replay past a cap, and the recordings it makes hostile are the kinds issue 24 found."""

from __future__ import annotations

import random

import pytest

from fuzz.memory import MB
from fuzz.path_replay import GROWTH_CAP, OUTPUT_CAP, _check, _hostile
from fuzz.paths import CapExceeded, PathFailure, Run

pytestmark = pytest.mark.timeout(60)
CALM = {"status": 0, "peak": 50 * MB, "written": 1000, "stderr": "", "seconds": 3.0, "killed": ""}


@pytest.mark.parametrize(
    ("change", "error", "words"),
    [
        ({"peak": 50 * MB + GROWTH_CAP + MB}, CapExceeded, "memory cap exceeded"),
        ({"killed": f"wrote more than {OUTPUT_CAP // MB} MB"}, CapExceeded, "output cap"),
        ({"killed": "still running 33 s after it began"}, CapExceeded, "time or output cap"),
        ({"stderr": "gadgetctl: internal error: ValueError: x\n"}, PathFailure, "failed inside"),
        ({"stderr": "Traceback (most recent call last):\n"}, PathFailure, "failed inside"),
        ({"stderr": "note\n" * 201}, PathFailure, "lines on stderr"),
        ({"status": -9}, PathFailure, "exited with status -9"),
    ],
)
def test_a_replay_past_a_cap_fails_the_run(change, error, words) -> None:
    run = Run(random.Random(0), 10.0)
    _check(run, CALM, 50 * MB)  # within every cap
    with pytest.raises(error, match=words):
        _check(run, CALM | change, 50 * MB)


def test_the_hostile_recordings_are_of_every_kind() -> None:
    rng = random.Random(3)
    made = [_hostile(rng) for _ in range(200)]
    heads = [data.split(b"\n", 1)[0] for data in made]
    assert any(b'"units": {' in head for head in heads)  # a header's unit claims
    assert any(b'"unit": 65535' in data for data in made)  # a far unit
    assert any(b'"timestamp": 1e+308' in data for data in made)  # a huge timestamp
    assert any(data.count(b"[") > 100_000 for data in made)  # a header nested deep
