"""Recorder and read_recording: round trips, crash safety (real signals) and bad input."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap
import time
from collections import Counter

import pytest

from gadgetctl.monitor.recording import (
    Recorder,
    RecordingError,
    Terminated,
    raise_on_stop_signals,
    read_recording,
)
from gadgetctl.monitor.records import (
    EndRecord,
    FrameDevice,
    FrameRecord,
    MarkerRecord,
    SampleRecord,
    StatsRecord,
)

pytestmark = pytest.mark.timeout(60)


def samples(n, start=10.0, device="Wand"):
    return [
        SampleRecord(device, "analog", i % 2, start + i * 0.01, (i % 100) / 100, i % 100)
        for i in range(n)
    ]


class FakeClock:
    def __init__(self, now=100.0):
        self.now = now

    def __call__(self):
        return self.now


def read_all(path):
    recording = read_recording(path)
    return recording, list(recording.records)


def test_round_trip_of_a_session(tmp_path):
    path = tmp_path / "session.ndjson"
    frame = FrameRecord(1, 10.02, {"Wand": FrameDevice(2, {"analog": {0: 0.0, 1: 0.01}})})
    with Recorder(path, {"config": "wand.jconf", "devices": ["Wand"]}) as recorder:
        assert recorder.write_samples(samples(50)) == 50
        recorder.write_samples(iter(samples(10, start=11.0)))
        recorder.write_marker("tap", timestamp=10.5)
        recorder.write_frame(frame)
        recorder.write_stats({"Wand": {"count": 60}}, timestamp=11.2)
    recording, records = read_all(path)
    assert recording.header.info == {"config": "wand.jconf", "devices": ["Wand"]}
    assert records[:60] == samples(50) + samples(10, start=11.0)
    assert records[60:63] == [
        MarkerRecord("tap", 10.5),
        frame,
        StatsRecord(11.2, {"Wand": {"count": 60}}),
    ]
    end = records[-1]
    assert isinstance(end, EndRecord) and end.reason == "closed"
    assert (end.samples, end.markers, end.frames) == (60, 1, 1)
    assert recording.problems == []
    assert recorder.closed
    recorder.close()  # idempotent


def test_batches_are_on_disk_before_close(tmp_path):
    path = tmp_path / "live.ndjson"
    recorder = Recorder(path)
    try:
        recorder.write_samples(samples(5))
        _, records = read_all(path)
        assert records == samples(5)
    finally:
        recorder.close()


def test_single_samples_are_flushed_within_the_interval(tmp_path):
    clock = FakeClock()
    path = tmp_path / "single.ndjson"
    with Recorder(path, flush_interval=0.1, clock=clock) as recorder:
        batch = samples(3)
        recorder.write_sample(batch[0])
        clock.now += 0.05
        recorder.write_sample(batch[1])
        assert list(read_recording(path).records) == []  # still within 100 ms
        clock.now += 0.06
        recorder.write_sample(batch[2])
        assert list(read_recording(path).records) == batch
        recorder.write_sample(batch[0])
        recorder.write_marker("m")  # other records flush pending samples first
        assert list(read_recording(path).records) == [
            *batch,
            batch[0],
            MarkerRecord("m", clock.now),
        ]


def test_existing_files_are_kept_unless_overwrite(tmp_path):
    path = tmp_path / "taken.ndjson"
    path.write_text("precious\n")
    with pytest.raises(RecordingError, match="exists") as err:
        Recorder(path)
    assert err.value.exit_code == 2
    assert path.read_text() == "precious\n"
    with Recorder(path, overwrite=True) as recorder:
        recorder.write_samples(samples(1))
    assert read_all(path)[1][0] == samples(1)[0]


def test_unwritable_path_is_a_recording_error(tmp_path):
    with pytest.raises(RecordingError, match="cannot create"):
        Recorder(tmp_path / "missing-dir" / "x.ndjson")


@pytest.mark.parametrize(
    ("exc", "reason"),
    [(KeyboardInterrupt, "interrupted"), (Terminated, "terminated"), (RuntimeError, "error")],
)
def test_end_reason_follows_the_exception(tmp_path, exc, reason):
    path = tmp_path / "x.ndjson"
    with pytest.raises(exc), Recorder(path) as recorder:
        recorder.write_samples(samples(3))
        raise exc()
    records = read_all(path)[1]
    assert records[-1].reason == reason and records[-1].samples == 3


def test_writing_after_close_fails(tmp_path):
    recorder = Recorder(tmp_path / "x.ndjson")
    recorder.close()
    with pytest.raises(RecordingError, match="closed"):
        recorder.write_samples(samples(1))


# --------------------------------------------------------------------------- damaged files


def write_lines(path, lines, final_newline=True):
    path.write_bytes(("\n".join(lines) + ("\n" if final_newline else "")).encode())


def valid_recording(tmp_path, n=20):
    path = tmp_path / "good.ndjson"
    with Recorder(path, {"k": 1}) as recorder:
        recorder.write_samples(samples(n))
    return path


def test_truncated_last_line_is_ignored(tmp_path):
    path = valid_recording(tmp_path)
    lines = path.read_text().splitlines()[:-1]  # drop the end record, as after SIGKILL
    write_lines(path, [*lines, lines[-1][:37]], final_newline=False)  # a partial 21st sample
    recording, records = read_all(path)
    assert records == samples(20)
    assert [p.severity for p in recording.problems] == ["warning"]
    assert recording.problems[0].line == len(lines) + 1
    assert "truncated" in recording.problems[0].message


def test_a_complete_last_record_without_newline_is_kept(tmp_path):
    path = valid_recording(tmp_path, n=3)
    path.write_bytes(path.read_bytes().rstrip(b"\n"))
    recording, records = read_all(path)
    assert isinstance(records[-1], EndRecord) and recording.problems == []


def test_malformed_lines_are_reported_with_their_number(tmp_path):
    path = valid_recording(tmp_path, n=5)
    lines = path.read_text().splitlines()
    lines[2] = "this is not json"
    lines[3] = '{"v":1,"type":"sample","device":"Wand"}'
    lines.insert(4, "")
    lines.insert(5, '{"v":1,"type":"future-thing","x":1}')
    lines.insert(6, lines[0])  # a second header
    write_lines(path, lines)
    recording, records = read_all(path)
    assert [r for r in records if isinstance(r, SampleRecord)] == [samples(5)[i] for i in (0, 3, 4)]
    assert isinstance(records[-1], EndRecord)
    found = [(p.line, p.severity) for p in recording.problems]
    assert found == [(3, "error"), (4, "error"), (6, "info"), (7, "error")]
    assert str(recording.problems[0]).startswith("line 3: error: malformed record")


def test_interrupted_line_in_the_middle_is_a_warning(tmp_path):
    path = valid_recording(tmp_path, n=3)
    lines = path.read_text().splitlines()
    lines.insert(2, lines[2][:30])
    write_lines(path, lines)
    recording, records = read_all(path)
    assert len([r for r in records if isinstance(r, SampleRecord)]) == 3
    assert [(p.line, p.severity) for p in recording.problems] == [(3, "warning")]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "empty"),
        (b"\x89PNG\r\n\x1a\n\x00\x00binary", "not a gadgetctl recording"),
        (b'<?xml version="1.0"?>\n<configuration/>\n', "not a gadgetctl recording"),
        (b'{"v":1,"type":"sample","device":"A"}\n', "header"),
        (b'{"v":1,"type":"header","format":"something-else"}\n', "header"),
        (b'{"v":0,"type":"header","format":"gadgetctl-recording"}\n', "version"),
        (b'{"v":"1","type":"header","format":"gadgetctl-recording"}\n', "version"),
        (b'{"v":7,"type":"header","format":"gadgetctl-recording"}\n', "newer"),
        (b'{"v":1,"type":"header","format":"gadgetctl-recording","info":[]}\n', "info"),
        (b'{"v":1,"type":"header","format":"gadgetctl-rec', "ends inside its header"),
        (b"x" * 3_000_000, "not a gadgetctl recording"),
    ],
)
def test_files_that_are_not_recordings_raise(tmp_path, content, message):
    path = tmp_path / "bad.ndjson"
    path.write_bytes(content)
    with pytest.raises(RecordingError, match=message) as err:
        read_recording(path)
    assert err.value.exit_code == 2
    assert str(path) in str(err.value)


def test_missing_file_and_directory_raise(tmp_path):
    with pytest.raises(RecordingError, match="cannot read"):
        read_recording(tmp_path / "nope.ndjson")
    with pytest.raises(RecordingError, match="directory"):
        read_recording(tmp_path)


def test_records_are_read_lazily_and_problems_fill_up(tmp_path):
    path = valid_recording(tmp_path, n=3)
    lines = path.read_text().splitlines()
    lines.insert(3, "garbage")
    write_lines(path, lines)
    recording = read_recording(path)
    assert recording.problems == []
    list(recording.records)
    assert len(recording.problems) == 1


# --------------------------------------------------------------------------- real signals

CHILD = textwrap.dedent("""
    import sys
    from gadgetctl.monitor.records import SampleRecord
    from gadgetctl.monitor.recording import Recorder, Terminated, raise_on_stop_signals

    path, batch = sys.argv[1], int(sys.argv[2])
    matrix = [[1.0, 0.0, 0.0, 0.1], [0.0, 1.0, 0.0, 1.5], [0.0, 0.0, 1.0, -0.2], [0.0, 0.0, 0.0, 1.0]]
    t = 0.0
    try:
        with raise_on_stop_signals(), Recorder(path, {"child": True}) as recorder:
            announced = False
            while True:
                records = []
                for i in range(batch):
                    t += 0.001
                    records.append(SampleRecord("Wand", "analog", i % 4, t, (i % 256) / 255, i % 256))
                    records.append(SampleRecord("Head", "position", 0, t, matrix, matrix))
                recorder.write_samples(records)
                recorder.write_marker("batch", t)
                if not announced:
                    print("ready", flush=True)
                    announced = True
    except KeyboardInterrupt:
        sys.exit(130)
    except Terminated:
        sys.exit(143)
""")


@pytest.mark.timeout(30)
@pytest.mark.parametrize("delay", [0.05, 0.3])
@pytest.mark.parametrize(
    ("signum", "returncode", "reason"),
    [
        (signal.SIGINT, 130, "interrupted"),
        (signal.SIGTERM, 143, "terminated"),
        (signal.SIGKILL, -signal.SIGKILL, None),
    ],
)
def test_killed_writer_leaves_a_readable_recording(tmp_path, signum, returncode, reason, delay):
    path = tmp_path / "killed.ndjson"
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path), "2000"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline() == "ready\n", child.stderr.read()
        time.sleep(delay)
        child.send_signal(signum)
        child.wait(timeout=10)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == returncode, child.stderr.read()
    recording, records = read_all(path)
    assert recording.header.info == {"child": True}
    # at most a cut-off record, reported as a warning
    assert len(recording.problems) <= 1 and all(p.severity == "warning" for p in recording.problems)
    written = [r for r in records if isinstance(r, SampleRecord)]
    assert len(written) >= 4000
    # whole records only: each sample time has its two records (Wand, Head), once each; but
    # SIGKILL can end a large write anywhere, so the newest time may have lost its second one
    per_stamp = Counter(r.timestamp for r in written)
    newest = max(per_stamp)
    assert all(n == 2 for t, n in per_stamp.items() if t != newest), per_stamp.most_common(3)
    assert per_stamp[newest] in (1, 2) and (per_stamp[newest] == 2 or signum == signal.SIGKILL)
    ends = [r for r in records if isinstance(r, EndRecord)]
    if reason is None:
        assert ends == []
    else:
        assert len(ends) == 1 and records[-1] is ends[0]
        assert ends[0].reason == reason
        # an interrupt between a write and its bookkeeping may leave one batch uncounted
        assert 0 <= len(written) - ends[0].samples <= 4000
    for line in path.read_bytes().splitlines()[:-1]:  # every complete line is one JSON object
        if line.strip():
            assert isinstance(json.loads(line), dict)


def test_raise_on_stop_signals_restores_handlers():
    before_int, before_term = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    with raise_on_stop_signals():
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        with pytest.raises(Terminated):
            signal.raise_signal(signal.SIGTERM)
    assert signal.getsignal(signal.SIGINT) is before_int
    assert signal.getsignal(signal.SIGTERM) is before_term


def test_a_large_header_and_statistics_are_written_as_their_whole_lines(tmp_path):
    """Issue 27 goal 3: the header, the status records and the statistics of a large session
    go out in parts; the file holds each as the one line encode_record makes of it."""
    from gadgetctl.monitor.records import StatusRecord, decode_line, encode_record

    path = tmp_path / "large.ndjson"
    names = [f"W{i}" for i in range(30_000)]  # more than a megabyte of header and statistics
    info = {
        "devices": names,
        "elements": {n: {"element": "device", "kinds": ["position"]} for n in names},
    }
    statuses = [StatusRecord(10.0, n, "device", "waveform_device", "running") for n in names]
    stats = {n: {"count": i, "mean_rate": i / 7} for i, n in enumerate(names)}
    with Recorder(path, info) as recorder:
        recorder.write_statuses(statuses)
        recorder.write_stats(stats, timestamp=11.0)
    lines = path.read_bytes().decode().splitlines(keepends=True)
    assert len(lines) == 1 + len(names) + 2
    header = decode_line(lines[0])
    assert header.info == info and encode_record(header) == lines[0]
    assert lines[1:-2] == [encode_record(s) for s in statuses]
    assert lines[-2] == encode_record(StatsRecord(11.0, stats))
    assert len(lines[0]) > 1 << 20 and len(lines[-2]) > 1 << 20


def test_statistics_that_fail_while_written_leave_a_line_close_ends(tmp_path):
    """The statistics are written as they are encoded: an entry that cannot be made after a
    megabyte went out leaves that line cut short, which close() ends; the reader reports and
    skips it, and reads the end record. A timestamp that cannot be encoded writes nothing."""

    class Failing(dict):
        def items(self):
            for i, item in enumerate(super().items()):
                if i == 20_000:
                    raise RuntimeError("statistics that cannot be read")
                yield item

    path = tmp_path / "cut.ndjson"
    stats = Failing({f"W{i}": {"count": i, "mean_rate": i / 7} for i in range(30_000)})
    with Recorder(path, {"devices": ["W0"]}) as recorder:
        with pytest.raises(ValueError):
            recorder.write_stats(stats, timestamp=float("nan"))
        assert path.read_bytes().count(b"\n") == 1  # the header alone
        with pytest.raises(RuntimeError):
            recorder.write_stats(stats, timestamp=11.0)
    recording, records = read_all(path)
    assert [type(r) for r in records] == [EndRecord]
    assert records[0].reason == "closed"
    assert [p.line for p in recording.problems] == [2]  # the cut line, skipped
