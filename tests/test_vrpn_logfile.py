"""VRPN log files (reference section 11), from bytes built by hand and from LogWriter."""

from __future__ import annotations

import io
import struct

import pytest
from vrpn_peers import COOKIE

from gadgetctl.vrpn import LogFormatError, LogReader, LogWriter, codecs


def record(type_id: int, sender: int, payload: bytes, sec: int = 100, usec: int = 0) -> bytes:
    return struct.pack(">iiiiii", type_id, sender, sec, usec, len(payload), 0) + payload


def name(text: str) -> bytes:
    return struct.pack(">I", len(text) + 1) + text.encode() + b"\0"


def handmade_log() -> bytes:
    return (
        COOKIE[:20]
        + b"\x13\x37\xbe\xef"  # bytes 20-23 may be garbage in outgoing logs
        + record(-1, 3, name("Tracker0"))
        + record(-2, 7, name(codecs.TRACKER_POS_QUAT))
        + record(7, 3, codecs.encode_pose(0, (1.0, 2.0, 3.0)), 100, 500000)
        + record(9, 3, b"undescribed type")
        + record(-5, 0, b"")  # disconnect: names are forgotten
        + record(7, 3, codecs.encode_pose(0, (9.0, 9.0, 9.0)))
        + record(-1, 0, name("Button0"))
        + record(-2, 0, name(codecs.BUTTON_CHANGE))
        + record(0, 0, codecs.encode_button_change(1, 1), 101)
    )


def test_reader_rebuilds_names_across_disconnects():
    reader = LogReader(io.BytesIO(handmade_log()))
    messages = list(reader)
    assert reader.version == "07.38"
    assert [(m.sender, m.type) for m in messages] == [
        ("Tracker0", codecs.TRACKER_POS_QUAT),
        ("Button0", codecs.BUTTON_CHANGE),
    ]
    assert messages[0].report.position == (1.0, 2.0, 3.0)
    assert messages[0].timestamp == 100.5
    assert messages[1].report == codecs.ButtonChange(1, 1)
    assert (reader.disconnects, reader.undescribed, reader.records, reader.truncated) == (
        1,
        2,
        9,
        False,
    )


def test_truncated_file_ends_cleanly():
    data = handmade_log()
    for cut in (len(data) - 3, len(data) - 20, len(COOKIE) + 5):
        reader = LogReader(io.BytesIO(data[:cut]))
        list(reader)
        assert reader.truncated


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "no VRPN cookie"),
        (b"PK\x03\x04" + b"\0" * 40, "no VRPN cookie"),
        (b"vrpn: ver. 08.00  0" + b"\0" * 5, "08.00"),
        (b"vrpn: ver. 03.99  0" + b"\0" * 5, "03.99"),
        (COOKIE + struct.pack(">iiiiii", 5, 0, 0, 0, 2**31 - 1, 0), "length"),
        (COOKIE + struct.pack(">iiiiii", 5, 0, 0, 0, -8, 0), "length"),
        (COOKIE + record(-1, 5000, name("x")), "id 5000"),
        (COOKIE + record(-1, 0, struct.pack(">I", 90) + b"abc"), "description"),
    ],
)
def test_bad_logs_raise_a_located_error(data, message):
    with pytest.raises(LogFormatError, match=message):
        list(LogReader(io.BytesIO(data)))


def test_old_versions_are_read():
    data = b"vrpn: ver. 04.00  0" + b"\0" * 5 + record(-1, 0, name("A"))
    assert LogReader(io.BytesIO(data)).version == "04.00"


def test_writer_round_trip(tmp_path):
    path = tmp_path / "session.vrpn"
    with LogWriter(path) as log:
        log.write("Tracker0", codecs.TRACKER_POS_QUAT, codecs.encode_pose(2, (0.1, 0.2, 0.3)), 5.0)
        log.write("Analog0", codecs.ANALOG_CHANNEL, codecs.encode_analog([0.5]), 5.5)
        log.write("Tracker0", codecs.TRACKER_POS_QUAT, codecs.encode_pose(2, (0.4, 0.5, 0.6)), 6.0)
    assert path.read_bytes()[:24] == COOKIE
    with LogReader(path) as reader:
        got = [(m.sender, m.timestamp, m.report) for m in reader]
    assert got == [
        ("Tracker0", 5.0, codecs.TrackerPose(2, (0.1, 0.2, 0.3), (0.0, 0.0, 0.0, 1.0))),
        ("Analog0", 5.5, codecs.AnalogChannels((0.5,))),
        ("Tracker0", 6.0, codecs.TrackerPose(2, (0.4, 0.5, 0.6), (0.0, 0.0, 0.0, 1.0))),
    ]
