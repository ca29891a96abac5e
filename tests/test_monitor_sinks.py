"""Sinks: what a session's recorders get, and when (monitor/sinks.py), read back from the
NDJSON streams the recorders wrote."""

from __future__ import annotations

import io

import pytest

from gadgetctl.monitor.recording import Recorder
from gadgetctl.monitor.records import (
    EndRecord,
    FrameDevice,
    FrameRecord,
    HeaderRecord,
    MarkerRecord,
    SampleRecord,
    StatsRecord,
    StatusRecord,
    decode_line,
    encode_samples,
)
from gadgetctl.monitor.sinks import FRAME, MARKER, SAMPLES, Sinks

pytestmark = pytest.mark.timeout(30)


def clock() -> float:
    return 50.0


def records(stream: io.BytesIO) -> list:
    return [decode_line(line) for line in stream.getvalue().decode().splitlines()]


def stream_sinks(*per_frame: bool) -> tuple[Sinks, list[io.BytesIO]]:
    sinks = Sinks()
    streams = []
    for each in per_frame:
        stream = io.BytesIO()
        streams.append(stream)
        sinks.add(
            lambda info, stream=stream: Recorder.to_stream(stream, info, clock=clock),
            per_frame=each,
        )
    return sinks, streams


SAMPLE = SampleRecord("W0", "analog", 0, 10.0, 0.5, 0.5)
FRAME_RECORD = FrameRecord(3, 10.0, {"W0": FrameDevice(1, {"analog": {0: 0.5}})})


def test_records_wait_for_the_header_and_go_out_in_order_to_the_sinks_that_want_them() -> None:
    sinks, (samples_out, frames_out) = stream_sinks(False, True)
    assert sinks and len(sinks) == 2 and not sinks.is_open
    text = encode_samples([SAMPLE])
    sinks.emit(SAMPLES, {"matrix": text}, 1)
    sinks.emit(MARKER, MarkerRecord("tap", 10.1), 0)
    sinks.emit(FRAME, {"matrix": FRAME_RECORD}, 0)
    assert samples_out.getvalue() == frames_out.getvalue() == b""  # nothing before the header
    assert sinks.samples_written == 0

    sinks.open({"devices": ["W0"]})
    assert sinks.is_open and len(sinks.recorders) == 2
    written = records(samples_out)
    assert isinstance(written[0], HeaderRecord)
    assert written[1:] == [SAMPLE, MarkerRecord("tap", 10.1)]  # no frame record
    framed = records(frames_out)
    assert isinstance(framed[0], HeaderRecord)
    assert framed[1:] == [MarkerRecord("tap", 10.1), FRAME_RECORD]  # no sample record
    assert sinks.samples_written == 1

    sinks.emit(SAMPLES, {"matrix": text}, 1)  # open: out at once
    assert records(samples_out)[-1] == SAMPLE
    assert sinks.samples_written == 2


def test_a_status_is_written_when_it_changes_only() -> None:
    sinks, (out,) = stream_sinks(False)
    sinks.open({})
    sinks.note_statuses(1.0, [("W0", "device", "waveform_device", "running", None)])
    sinks.note_statuses(2.0, [("W0", "device", "waveform_device", "running", None)])
    sinks.note_statuses(3.0, [("W0", "device", "waveform_device", "faulted", "it broke")])
    statuses = [r for r in records(out) if isinstance(r, StatusRecord)]
    assert [(r.timestamp, r.state, r.reason) for r in statuses] == [
        (1.0, "running", None),
        (3.0, "faulted", "it broke"),
    ]


def test_close_writes_the_final_statistics_and_the_end_of_every_open_sink() -> None:
    sinks, streams = stream_sinks(False, True)
    sinks.open({})
    final = {"W0": {"samples": 5}}
    sinks.close("duration", final, 60.0)
    for stream in streams:
        written = records(stream)
        assert isinstance(written[-2], StatsRecord) and written[-2].devices["W0"]["samples"] == 5
        assert isinstance(written[-1], EndRecord) and written[-1].reason == "duration"
    assert all(recorder.closed for recorder in sinks.recorders)
    sinks.close("again", None, 61.0)  # closed sinks are left alone
    assert records(streams[0])[-1].reason == "duration"
