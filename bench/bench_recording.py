"""Issue 6 benchmark: writing monitor recordings (NDJSON) and keeping live statistics."""

from __future__ import annotations

import json
import random
import tempfile
from pathlib import Path

import numpy as np
from common import Report, median_time

from gadgetctl.monitor.recording import Recorder, read_recording
from gadgetctl.monitor.records import SampleRecord
from gadgetctl.monitor.stats import MonitorStats

BATCH = 1000


def wand_session(updates: int) -> list[SampleRecord]:
    """A tracked wand and head at 1 kHz: 4 axes, 6 buttons, 2 positions per update."""
    rng = random.Random(1)
    records = []
    for i in range(updates):
        t = 1000.0 + i / 1000.0 + rng.uniform(-5e-5, 5e-5)
        for axis in range(4):
            raw = rng.randrange(256)
            records.append(SampleRecord("Wand", "analog", axis, t, raw / 255, raw))
        for button in range(6):
            pressed = rng.randrange(2)
            records.append(SampleRecord("Wand", "digital", button, t, pressed, pressed))
        for name in ("Head", "WandPos"):
            m = [[rng.uniform(-1, 1) for _ in range(3)] + [rng.uniform(-2, 2)] for _ in range(3)]
            m.append([0.0, 0.0, 0.0, 1.0])
            records.append(SampleRecord(name, "position", 0, t, m, m))
    return records


def record_ours(path: Path, records: list[SampleRecord]) -> None:
    with Recorder(path, {"bench": True}, overwrite=True) as recorder:
        for i in range(0, len(records), BATCH):
            recorder.write_samples(records[i : i + BATCH])


def record_json_dumps(path: Path, records: list[SampleRecord]) -> None:
    """The baseline: json.dumps of a dict per record, the same batching and flushing."""
    with open(path, "wb") as f:
        for i in range(0, len(records), BATCH):
            lines = [
                json.dumps(
                    {
                        "v": 1,
                        "type": "sample",
                        "device": r.device,
                        "kind": r.kind,
                        "unit": r.unit,
                        "timestamp": r.timestamp,
                        "value": r.value,
                        "raw": r.raw,
                    }
                )
                for r in records[i : i + BATCH]
            ]
            f.write(("\n".join(lines) + "\n").encode())
            f.flush()


def read_all(path: Path) -> int:
    return sum(1 for _ in read_recording(path).records)


def stats_second(
    devices: int = 100, rate: int = 1000, batch: int = 10, snapshots: int = 10
) -> None:
    """One second of data from ``devices`` at ``rate`` Hz, fed in batches, with snapshots."""
    monitor = MonitorStats()
    stamps = np.arange(rate) / rate
    chunks = [stamps[i : i + batch] for i in range(0, rate, batch)]
    every = len(chunks) // snapshots
    names = [f"dev{d}" for d in range(devices)]
    for n, chunk in enumerate(chunks):
        for name in names:
            monitor.add_timestamps(name, chunk)
        if n % 2 == 1:  # ~ frames at 50 Hz for 10-sample batches at 1 kHz
            monitor.end_frame()
        if (n + 1) % every == 0:
            monitor.snapshot(float(chunk[-1]))


def main() -> None:
    report = Report()
    session = wand_session(20_000)
    by_kind = {
        kind: [r for r in session if r.kind == kind] for kind in ("analog", "digital", "position")
    }
    print(
        f"recording: {len(session)} samples (1 kHz wand: 4 analog, 6 digital, 2 positions "
        f"per update), batches of {BATCH}, flushed per batch"
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.ndjson"
        ours = median_time(lambda: record_ours(path, session), repeat=5)
        size = path.stat().st_size
        base = median_time(lambda: record_json_dumps(path, session), repeat=5)
        report.figure(
            "write mixed session",
            len(session) / ours,
            "samples/s",
            target=100_000,
            higher_is_better=True,
        )
        report.figure(
            "json.dumps per record, same batching (baseline)", len(session) / base, "samples/s"
        )
        report.ratio("speed-up over json.dumps", base, ours)
        for kind, records in by_kind.items():
            t = median_time(lambda records=records: record_ours(path, records), repeat=5)
            report.figure(f"write {kind} samples only", len(records) / t, "samples/s")
        record_ours(path, session)
        read = median_time(lambda: read_all(path), repeat=3)
        report.figure("read back (decode + validate)", len(session) / read, "records/s")
        report.figure("file size per sample", size / len(session), "bytes")
    cpu = median_time(stats_second, repeat=5)
    report.figure(
        "stats: 100 devices x 1 kHz, batches of 10, 10 snapshots/s",
        cpu * 100,
        "% of a core",
        target=10,
    )
    report.exit()


if __name__ == "__main__":
    main()
