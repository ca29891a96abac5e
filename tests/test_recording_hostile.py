"""Recordings with fields of the wrong type or units beyond any device: bad records, found by
the fuzz campaign (``make fuzz``), end in a diagnostic or a skipped record, never a crash."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gadgetctl.monitor.recording import RecordingError, read_recording
from gadgetctl.monitor.records import MAX_UNITS

pytestmark = pytest.mark.timeout(60)
HEADER = {"v": 1, "type": "header", "format": "gadgetctl-recording", "created": "now"}


def recording(tmp_path: Path, *records: dict, header: dict | None = None) -> Path:
    path = tmp_path / "hostile.ndjson"
    lines = [header or HEADER, *records]
    path.write_text("".join(json.dumps(r) + "\n" for r in lines))
    return path


def sample(unit: int, t: float, value: float = 0.5) -> dict:
    return {
        "v": 1,
        "type": "sample",
        "device": "W",
        "kind": "analog",
        "unit": unit,
        "timestamp": t,
        "value": value,
    }


@pytest.mark.parametrize("wall_time", ["x", [], {}, None, "1.5"])
def test_a_header_field_of_the_wrong_type_is_not_a_recording(tmp_path, wall_time, cli) -> None:
    path = recording(tmp_path, sample(0, 1.0), header={**HEADER, "wall_time": wall_time})
    with pytest.raises(RecordingError, match="invalid header: field 'wall_time'"):
        read_recording(path)
    result = cli("replay", path, "--summary")
    assert result.exit_code == 2 and "Traceback" not in result.stderr
    assert "invalid header" in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_end_counts_of_the_wrong_type_are_a_malformed_record(tmp_path) -> None:
    end = {
        "v": 1,
        "type": "end",
        "timestamp": 2.0,
        "reason": "closed",
        "samples": 1,
        "markers": "many",
        "frames": [1],
    }
    source = read_recording(recording(tmp_path, sample(0, 1.0), end))
    records = list(source.records)
    assert len(records) == 1
    assert [(p.line, p.severity) for p in source.problems] == [(3, "error")]
    assert "field 'markers'" in source.problems[0].message


@pytest.mark.parametrize("unit", [-1, MAX_UNITS, 100_000_000, 2**62])
def test_a_unit_beyond_any_device_is_a_malformed_record(tmp_path, unit, cli) -> None:
    path = recording(tmp_path, sample(0, 1.0), sample(unit, 1.05), sample(1, 1.1, 0.25))
    source = read_recording(path)
    assert [r.unit for r in source.records] == [0, 1]
    assert [p.line for p in source.problems] == [3] and "unit" in source.problems[0].message
    # the replay goes on with the good samples, in bounded memory
    result = cli("replay", path, "--format", "ndjson", "--duration", "1", "--speed", "100")
    assert result.exit_code == 0, result.stderr
    values = [json.loads(line) for line in result.stdout.splitlines()]
    units = {r["unit"] for r in values if r.get("type") == "sample" and r.get("device") == "W"}
    assert units == {0, 1}


def test_a_sample_value_beyond_any_float_is_summarised(tmp_path, cli) -> None:
    path = tmp_path / "big.ndjson"
    path.write_text(
        json.dumps(HEADER)
        + "\n"
        + json.dumps(sample(0, 1.0)).replace('"value": 0.5', '"value": ' + "9" * 400)
        + "\n"
        + json.dumps(sample(0, 1.1))
        + "\n"
    )
    result = cli("replay", path, "--summary", "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["samples"] == 2
