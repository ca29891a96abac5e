"""Monitor records: the NDJSON encoding round-trips every kind and stays one line per record."""

from __future__ import annotations

import json
import math
import random
from enum import IntEnum, StrEnum

import numpy as np
import pytest

from gadgetctl.monitor.records import (
    FORMAT_NAME,
    EndRecord,
    FrameDevice,
    FrameRecord,
    HeaderRecord,
    MarkerRecord,
    RecordFormatError,
    SampleRecord,
    StatsRecord,
    UnknownRecordType,
    decode_line,
    decode_record,
    encode_record,
    encode_samples,
    encode_value,
)

POSITION = [
    [1.0, 0.0, 0.0, 0.125],
    [0.0, 0.0, -1.0, 1.6],
    [0.0, 1.0, 0.0, -0.3],
    [0.0, 0.0, 0.0, 1.0],
]
GLOVE = [[0.1 * f + 0.01 * j for j in range(4)] for f in range(6)]

ONE_OF_EACH = [
    SampleRecord("Wand", "analog", 0, 12.5, 0.5019607843137255, 128),
    SampleRecord("Wand", "digital", 3, 12.5, 1, 1),
    SampleRecord("WandButtonProxy", "digital", 0, 12.5, 3, 3),
    SampleRecord("Head", "position", 0, 12.501, POSITION, POSITION),
    SampleRecord("Glove", "glove", 1, 12.502, GLOVE, GLOVE),
    SampleRecord("Glove", "gesture", 0, 12.502, 7, 7),
    SampleRecord("Voice", "command", 0, 12.6, 2, 2),
    SampleRecord("Voice", "string", 0, 12.6, 'say "hi"\nnaïve ☃', 'say "hi"\nnaïve ☃'),
    SampleRecord("Joystick", "hat", 0, 12.7, 4, 4),
]


def roundtrip(records):
    text = encode_samples(records)
    lines = text.split("\n")
    assert lines[-1] == "" and len(lines) == len(records) + 1, "one line per record"
    return [decode_line(line) for line in lines[:-1]]


def test_every_kind_round_trips():
    assert roundtrip(ONE_OF_EACH) == ONE_OF_EACH


def test_lines_are_standard_json_with_version_and_type():
    for line in encode_samples(ONE_OF_EACH).splitlines():
        obj = json.loads(line)
        assert obj["v"] == 1 and obj["type"] == "sample"
        assert set(obj) <= {"v", "type", "device", "kind", "unit", "timestamp", "value", "raw"}


def test_raw_is_written_only_when_it_differs():
    analog, digital = (json.loads(line) for line in encode_samples(ONE_OF_EACH[:2]).splitlines())
    assert analog["raw"] == 128 and "raw" not in digital
    assert decode_record(digital).raw == 1


def test_floats_round_trip_exactly():
    rng = random.Random(7)
    values = [rng.uniform(-1e3, 1e3) for _ in range(2000)] + [
        5e-324,
        1.7976931348623157e308,
        -0.0,
        1e16,
        1e-7,
        0.1 + 0.2,
        2.0**0.5,
        123456789.0,
    ]
    records = [
        SampleRecord("A", "analog", 0, 1000.0 + i * 1e-3 + rng.random() * 1e-6, v, v)
        for i, v in enumerate(values)
    ]
    back = roundtrip(records)
    for ours, theirs in zip(records, back, strict=True):
        assert theirs.value == ours.value and theirs.timestamp == ours.timestamp
        assert math.copysign(1.0, theirs.value) == math.copysign(1.0, ours.value)
    matrices = [[[rng.random() for _ in range(4)] for _ in range(4)] for _ in range(100)]
    positions = [SampleRecord("P", "position", 0, 1.0 + i, m, m) for i, m in enumerate(matrices)]
    assert roundtrip(positions) == positions


def test_non_finite_values_use_the_python_json_tokens():
    record = SampleRecord("A", "analog", 0, 1.0, math.nan, math.inf)
    line = encode_samples([record])
    assert '"value":NaN' in line and '"raw":Infinity' in line
    back = decode_line(line)
    assert math.isnan(back.value) and back.raw == math.inf
    nested = [[1.0, -math.inf], [math.nan, 2]]
    assert encode_value(nested) == "[[1.0,-Infinity],[NaN,2]]"


def test_numpy_tuples_and_other_types_encode_as_json():
    m = np.arange(16, dtype=np.float64).reshape(4, 4) / 3
    record = SampleRecord("P", "position", 0, np.float64(2.5), m, (np.int64(5), True, None))
    back = decode_line(encode_samples([record]))
    assert back.value == m.tolist() and back.timestamp == 2.5
    assert back.raw == [5, True, None]
    assert encode_value(np.float32(0.5)) == "0.5"
    assert encode_value([np.float64(0.1), 2]) == "[0.1,2]"
    assert encode_value(False) == "false"


def test_enum_kinds_and_values_encode_as_plain_json():
    class Kind(StrEnum):
        DIGITAL = "digital"

    class State(IntEnum):
        TOGGLE_ON = 2

    record = SampleRecord("Button", Kind.DIGITAL, 0, 3.0, State.TOGGLE_ON, [State.TOGGLE_ON])
    back = decode_line(encode_samples([record]))
    assert (back.kind, back.value, back.raw) == ("digital", 2, [2])
    assert type(back.kind) is str and type(back.value) is int


@pytest.mark.parametrize("timestamp", [math.nan, math.inf, "1.0", None])
def test_bad_timestamps_are_refused(timestamp):
    with pytest.raises(ValueError, match="timestamp"):
        encode_samples([SampleRecord("A", "analog", 0, timestamp, 0.0, 0)])


def test_bad_unit_and_unencodable_value_are_refused():
    with pytest.raises(ValueError, match="unit"):
        encode_samples([SampleRecord("A", "analog", 1.5, 0.0, 0.0, 0)])
    with pytest.raises(TypeError, match="object"):
        encode_samples([SampleRecord("A", "analog", 0, 0.0, object(), 0)])


def test_device_names_are_escaped():
    record = SampleRecord('we"ird\\name\n', "analog", 0, 1.0, 0.25, 1)
    line = encode_samples([record])
    assert line.count("\n") == 1
    assert decode_line(line) == record


def test_rare_records_round_trip():
    frame = FrameRecord(
        42,
        99.5,
        {
            "Wand": FrameDevice(3, {"analog": {0: 0.5, 1: 0.25}, "digital": {0: 1}}),
            "Head": FrameDevice(1, {"position": {0: POSITION}}),
            "Idle": FrameDevice(0, {}),
        },
    )
    stats = StatsRecord(100.0, {"Wand": {"count": 10, "window_rate": 99.9, "p50_interval": None}})
    records = [
        MarkerRecord("start ☃", 12.0),
        frame,
        stats,
        EndRecord(101.0, "interrupted", 1000, 2, 60),
    ]
    for record in records:
        line = encode_record(record)
        assert line.endswith("\n") and line.count("\n") == 1
        assert json.loads(line)["v"] == 1
        assert decode_line(line) == record
    assert encode_record(ONE_OF_EACH[0]) == encode_samples(ONE_OF_EACH[:1])


def test_header_records_carry_format_and_clock_times():
    header = HeaderRecord.now(
        {"config": "x.jconf", "devices": ["Wand"], "n": np.int64(3)}, clock=lambda: 55.5
    )
    obj = json.loads(encode_record(header))
    assert obj["type"] == "header" and obj["format"] == FORMAT_NAME and obj["v"] == 1
    assert obj["monotonic"] == 55.5 and obj["clock"] == "monotonic"
    assert obj["created"].endswith("Z") and obj["generator"].startswith("gadgetctl ")
    back = decode_record(obj)
    assert back.info == {"config": "x.jconf", "devices": ["Wand"], "n": 3}


def test_unknown_fields_are_ignored():
    line = (
        '{"v":1,"type":"sample","device":"A","kind":"analog","unit":0,"timestamp":1.0,'
        '"value":0.5,"raw":7,"quality":"good","extra":{"x":[1]}}'
    )
    assert decode_line(line) == SampleRecord("A", "analog", 0, 1.0, 0.5, 7)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ('{"v":1,"type":"sample","device":"A","kind":"analog","unit":0,"timestamp":1.0}', "value"),
        (
            '{"v":1,"type":"sample","device":"A","kind":"analog","unit":true,"timestamp":1,"value":0}',
            "unit",
        ),
        ('{"v":1,"type":"marker","name":"m","timestamp":"soon"}', "timestamp"),
        ('{"v":1,"type":"marker","name":"m","timestamp":NaN}', "finite"),
        ('{"v":2,"type":"marker","name":"m","timestamp":1}', "newer"),
        ('{"type":"marker","name":"m","timestamp":1}', "'v'"),
        (
            '{"v":1,"type":"frame","frame":1,"timestamp":1,"devices":{"A":{"count":1,"values":{"analog":{"x":1}}}}}',
            "unit",
        ),
        ("[1, 2]", "object"),
        ('{"v":1,"type":"sample","device":"A"', "JSON"),
    ],
)
def test_malformed_records_raise_format_errors(line, message):
    with pytest.raises(RecordFormatError, match=message):
        decode_line(line)


def test_unknown_record_types_have_their_own_error():
    with pytest.raises(UnknownRecordType):
        decode_line('{"v":1,"type":"calibration","data":[]}')


def test_a_statistics_record_in_parts_is_the_record_in_one_piece():
    """Issue 27: the statistics of 10,000 devices are written in parts of about a megabyte;
    joined, they are exactly the line encode_record writes (and it decodes the same)."""
    from gadgetctl.monitor.records import (
        StatsRecord,
        decode_line,
        encode_record,
        encode_stats_parts,
    )

    devices = {
        f"Dev ice \u00e9{i}": {"count": i, "mean_rate": i / 3, "p99": None, "kinds": ["position"]}
        for i in range(2000)
    }
    record = StatsRecord(12.5, devices)
    parts = list(encode_stats_parts(record, size=10_000))
    assert len(parts) > 10 and all(p for p in parts)
    assert "".join(parts) == encode_record(record)
    assert decode_line("".join(parts)) == record
    empty = StatsRecord(1.0, {})
    assert "".join(encode_stats_parts(empty)) == encode_record(empty)
    with pytest.raises(ValueError):
        list(encode_stats_parts(StatsRecord(float("nan"), devices)))


def encode_statuses(records) -> str:
    """Status records as one text: their parts of the default size, joined."""
    from gadgetctl.monitor.records import encode_status_parts

    return "".join(encode_status_parts(records))


def test_status_records_in_one_batch_are_each_record_as_encode_record_writes_it():
    """Issue 27: a session's start writes a status record per element (20,000 for 10,000
    devices and their proxies) with each distinct timestamp and status encoded once; the text
    is exactly encode_record's, record by record, whatever the names, states and timestamps."""
    from gadgetctl.monitor.records import StatusRecord

    class Kind(StrEnum):
        DEVICE = "device"

    records = [
        StatusRecord(12.5, "W0", "device", "waveform_device", "running", None),
        StatusRecord(12.5, "P0", "proxy", "position_proxy", "active", None),
        StatusRecord(12.5, 'Wand "é☃"\n', Kind.DEVICE, "waveform_device", "running", None),
        StatusRecord(12.5, "Gone", None, "", "removed", "no longer configured"),
        StatusRecord(13.0, "W0", "device", "waveform_device", "faulted", 'port "x" \u00e9'),
        StatusRecord(13, "Int", "device", "waveform_device", "running", None),  # an int time
        StatusRecord(1e-300, "Tiny", "alias", "alias", "stupefied", "its proxy 'p'"),
    ]
    rng = random.Random(5)
    records += [rng.choice(records[:5]) for _ in range(200)]
    assert encode_statuses(records) == "".join(encode_record(r) for r in records)
    assert [decode_line(line) for line in encode_statuses(records).splitlines()] == records
    assert encode_statuses([]) == ""
    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValueError):
            encode_statuses([StatusRecord(bad, "W0", "device", "t", "running")])


def test_status_records_in_parts_are_the_records_in_one_piece():
    """Issue 27 goal 3: a session's status records are written a megabyte of them at a time;
    each part holds whole lines, and joined they are the text in one piece."""
    from gadgetctl.monitor.records import StatusRecord, encode_status_parts

    records = [
        StatusRecord(12.5 + i // 700, f"W\u00e9{i}", "device", "waveform_device", "running")
        for i in range(2000)
    ] + [StatusRecord(13, "Int", "device", "waveform_device", "faulted", 'port "x"')]
    parts = list(encode_status_parts(records, size=10_000))
    assert len(parts) > 10 and all(p.endswith("\n") for p in parts)
    assert "".join(parts) == encode_statuses(records)
    assert "".join(parts) == "".join(encode_record(r) for r in records)
    assert len(list(encode_status_parts(records[:5], 0))) == 5  # 0: a line each
    assert list(encode_status_parts([])) == []


def test_a_header_record_in_parts_is_the_record_in_one_piece():
    """Issue 27 goal 3: a session's header (an entry per element: megabytes for 10,000
    devices and their proxies) is encoded a part at a time; joined, the parts are exactly the
    line encode_record writes, whatever the info holds (keys json converts, empty dicts,
    escapes, non-finite numbers, values it writes through its default)."""
    from gadgetctl.monitor.records import HeaderRecord, encode_header_parts

    elements = {
        f'W \u00e9"{i}': {"element": "device", "kinds": ["position"], "units": {"position": 1}}
        for i in range(2000)
    }
    elements["A"] = {"element": "device", "min": -0.0, "max": float("inf")}
    shared = {"element": "device", "kinds": ["hat"], "units": {"hat": 2}}
    elements.update((f"S{i}", shared) for i in range(50))  # one entry of alike devices
    elements["after"] = {"element": "proxy", "device": "S1", "unit": 0}
    infos = [
        {"config": ["a.jconf"], "devices": list(elements), "elements": elements},
        {"elements": {}, "frame_rate": 60.0, "selection": [], "pose": "euler"},
        {"numbered": {1: "one", "two": (2, 2)}, "array": np.arange(3)},
        {},
    ]
    for info in infos:
        record = HeaderRecord("2026-01-01T00:00:00.000000Z", 1.5, 2.25, "gadgetctl 0", info)
        whole = encode_record(record)
        for size in (1, 300, 10_000, 1 << 20):
            parts = list(encode_header_parts(record, size))
            assert all(parts) and "".join(parts) == whole
        assert decode_line(whole).info.keys() == info.keys()
    record = HeaderRecord("c", 1.0, 2.0, "g", {3: "int key"})  # json makes it "3"
    assert "".join(encode_header_parts(record)) == encode_record(record)
    parts = list(encode_header_parts(HeaderRecord("c", 1.0, 2.0, "g", infos[0]), 10_000))
    assert len(parts) > 10
