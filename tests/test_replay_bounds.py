"""`gadgetctl replay` of hostile recordings (issue 24): a far unit, a header claiming huge unit
counts or a VRPN log with a far sensor never widens what is replayed (REPLAY_UNITS); what is
left out is one line on stderr."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gadgetctl.monitor.records import MAX_UNITS, REPLAY_UNITS
from gadgetctl.vrpn import LogWriter, codecs

pytestmark = pytest.mark.timeout(60)
HEADER = {"v": 1, "type": "header", "format": "gadgetctl-recording", "created": "now"}


def sample(unit: int, t: float, kind: str = "analog") -> dict:
    value: object = (
        0.5 if kind == "analog" else [[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    )
    return {"v": 1, "type": "sample", "device": "W", "kind": kind, "unit": unit, "timestamp": t, "value": value}  # fmt: skip


def write_recording(path: Path, records: list[dict], header: dict | None = None) -> Path:
    path.write_text("".join(json.dumps(r) + "\n" for r in [header or HEADER, *records]))
    return path


def replayed(cli, path: Path) -> tuple[set[int], list[str]]:
    """The units of W the replay wrote, and its stderr lines."""
    result = cli("replay", path, "--format", "ndjson", "--speed", "100", "--duration", "5")
    assert result.exit_code == 0, result.stderr
    assert "Traceback" not in result.stderr
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    units = {r["unit"] for r in lines if r.get("type") == "sample" and r.get("device") == "W"}
    return units, result.stderr.strip().splitlines()


@pytest.mark.parametrize(("unit", "kind"), [(REPLAY_UNITS, "position"), (MAX_UNITS - 1, "analog")])
def test_a_sample_of_a_far_unit_is_skipped_and_said(tmp_path, cli, unit, kind) -> None:
    records = [sample(0, 1 + 0.01 * i, kind) for i in range(3)]
    records += [sample(unit, 1.031, kind)] + [sample(1, 1.04 + 0.01 * i, kind) for i in range(3)]
    units, stderr = replayed(cli, write_recording(tmp_path / "far.ndjson", records))
    assert units == {0, 1}  # not every unit up to the far one in each later instant
    assert len(stderr) == 1
    assert f"1 sample of units beyond {REPLAY_UNITS - 1} skipped" in stderr[0]


def test_the_last_unit_within_the_limit_is_replayed(tmp_path, cli) -> None:
    records = [sample(0, 1.0), sample(REPLAY_UNITS - 1, 1.01), sample(0, 1.02)]
    units, stderr = replayed(cli, write_recording(tmp_path / "wide.ndjson", records))
    assert units == set(range(REPLAY_UNITS)) and stderr == []


@pytest.mark.parametrize(
    ("kind", "claimed"), [("analog", 65536), ("analog", REPLAY_UNITS), ("position", 2)]
)
def test_a_header_claiming_more_units_than_its_samples_is_said(tmp_path, cli, kind, claimed):
    """Claimed units only padded every instant: 1,024 glove units claimed by a 17 KB file
    made 33 MB of output (found by make fuzz's replay.recording)."""
    elements = {"W": {"element": "device", "type": "x", "kinds": [kind], "units": {kind: claimed}}}  # fmt: skip
    header = {**HEADER, "info": {"elements": elements}}
    records = [sample(0, 1 + 0.01 * i, kind) for i in range(5)]
    units, stderr = replayed(cli, write_recording(tmp_path / "claims.ndjson", records, header))
    assert units == {0}
    assert len(stderr) == 1 and f"claims {claimed} {kind} units of 'W'" in stderr[0]
    assert "the 1 its samples hold are replayed" in stderr[0]


def test_a_vrpn_log_with_a_far_sensor_replays_the_near_ones(tmp_path, cli) -> None:
    path = tmp_path / "far.vrpn"
    with LogWriter(path) as log:
        for i in range(20):
            sensor = 65535 if i == 3 else 0
            pose = codecs.encode_pose(sensor, (0.01 * i, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
            log.write("Tracker0", codecs.TRACKER_POS_QUAT, pose, 1_700_000_000.0 + 0.01 * i)
    result = cli("replay", path, "--format", "ndjson", "--speed", "100", "--duration", "5")
    assert result.exit_code == 0, result.stderr
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    units = [r["unit"] for r in lines if r.get("type") == "sample"]
    assert set(units) == {0} and len(units) == 19
    stderr = result.stderr.strip().splitlines()
    assert (
        len(stderr) == 1 and f"1 tracker reports of sensors beyond {REPLAY_UNITS - 1}" in stderr[0]
    )


# -- timestamps and nesting (issue 24 item 11) -------------------------------------------------


@pytest.mark.parametrize("second", [1e308, 1e9])
def test_a_huge_pause_is_shortened_and_said(tmp_path, cli, second) -> None:
    path = write_recording(tmp_path / "pause.ndjson", [sample(0, 0.5), sample(0, second)])
    result = cli("replay", path, "--format", "ndjson", "--duration", "0.5")
    assert result.exit_code == 0, result.stderr
    notes = [line for line in result.stderr.splitlines() if "pause" in line]
    assert len(notes) == 1 and "Traceback" not in result.stderr
    assert "1 pause longer than 10 s of replay shortened to 10 s" in notes[0]


def test_a_vrpn_log_with_a_long_pause_says_its_pause(tmp_path, cli) -> None:
    # (A log starting at time 0 no longer pauses at all: a VRPN message of time 0 has no
    # time, and takes the time of the first timed one; tests/test_vrpn_replay.py.)
    path = tmp_path / "pause.vrpn"
    with LogWriter(path) as log:
        for i in range(5):
            pose = codecs.encode_pose(0, (0.01 * i, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
            log.write("Tracker0", codecs.TRACKER_POS_QUAT, pose, 1.7e9 + (1000 if i else 0) + i)
    result = cli("replay", path, "--format", "ndjson", "--duration", "0.5")
    assert result.exit_code == 0, result.stderr
    assert "1 pause longer than 10 s of replay shortened to 10 s" in result.stderr


def test_a_header_nested_beyond_json_is_not_a_recording(tmp_path, cli) -> None:
    path = tmp_path / "deep.ndjson"
    header = json.dumps(HEADER)[:-1] + ', "info": {"x": ' + "[" * 200_000 + "]" * 200_000 + "}}"
    path.write_text(header + "\n" + json.dumps(sample(0, 1.0)) + "\n")
    result = cli("replay", path, "--format", "ndjson")
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        f"gadgetctl: error: {path}: not a gadgetctl recording "
        "(the header nests deeper than JSON is read)"
    ]
