"""Benchmarks of `gadgetctl monitor` (issue 6).

1. 32 waveform devices at 1 kHz (2 analog, 2 digital and 1 position unit each, plus three
   proxies per device) monitored at 60 frames/s, once without a view (sampling and the
   session's data gathering only) and once with the live view refreshing every frame into
   a rich Console writing to a StringIO sized like a terminal. Targets: no sample lost in
   either run; the view costs at most 30 % of one core beyond the run without it.
2. `--format ndjson` into a file on the same 32 devices (160,000 sample records/s offered):
   records written per second, target >= 100,000, and no sample lost.
3. `--format events` on the same 32 devices (every button change, analog units beyond the
   default dead band of a noise channel, circle positions beyond 1 cm), written to
   /dev/null: no sample lost; at most 30 % of one core beyond the run without it.

Run: python bench/bench_monitor.py [--seconds 5] [--devices 32] [--rate 1000]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import io
import os
import tempfile
import time
from pathlib import Path

from common import Report

from gadgetctl.input.clock import now
from gadgetctl.input.manager import InputManager, ManagerOptions
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor.recording import Recorder
from gadgetctl.monitor.session import MonitorSession

DEVICE = """      <waveform_device name="Wave {i}" version="1">
         <rate>{rate}</rate>
         <seed>{i}</seed>
         <analog_waveform>sine</analog_waveform>
         <analog_waveform>noise</analog_waveform>
         <min>-1.0</min>
         <max>1.0</max>
         <button_period>0.5</button_period>
         <button_period>0.3</button_period>
         <position_path>circle</position_path>
         <event_period>0.0</event_period>
      </waveform_device>
      <position_proxy name="Wave {i} Position" version="1"><device>Wave {i}</device><unit>0</unit></position_proxy>
      <digital_proxy name="Wave {i} Button" version="1"><device>Wave {i}</device><unit>0</unit></digital_proxy>
      <analog_proxy name="Wave {i} Analog" version="1"><device>Wave {i}</device><unit>0</unit></analog_proxy>
"""
HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
   <elements>
"""
UNITS_PER_SAMPLE = 5
TERMINAL = (200, 50)


def configuration(devices: int, rate: float):
    text = (
        HEAD
        + "".join(DEVICE.format(i=i, rate=rate) for i in range(devices))
        + "   </elements>\n</configuration>\n"
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.jconf"
        path.write_text(text)
        return load_configuration([path])


class Run:
    """One monitored run: CPU seconds of the whole process, wall seconds, losses."""

    def __init__(
        self,
        devices: int,
        rate: float,
        seconds: float,
        *,
        view: bool = False,
        ndjson: Path | None = None,
        events: bool = False,
    ) -> None:
        manager = InputManager(default_repository(), ManagerOptions(retry_interval=None))
        session = MonitorSession(manager, configuration(devices, rate), rate=60.0)
        session.start()
        assert not manager.pending(), [p.message for p in manager.pending()]
        if ndjson is not None:
            session.add_sink(lambda info: Recorder(ndjson, info, overwrite=True, clock=now))
        sink = None
        if events:
            from gadgetctl.cli.monitor_run import EventPrinter, RunOptions

            sink = open(os.devnull, "w")  # noqa: SIM115 - closed below
            printer = EventPrinter(sink, RunOptions())
            session.add_consumer(printer)
        live = None
        if view:
            from rich.console import Console

            from gadgetctl.cli.monitor_live import LiveView

            width, height = TERMINAL
            console = Console(
                file=io.StringIO(),
                width=width,
                height=height,
                force_terminal=True,
                color_system="truecolor",
                legacy_windows=False,
            )
            live = LiveView(session, console, title="bench").__enter__()
        frames = 0
        wall0, cpu0 = time.perf_counter(), time.process_time()
        for _ in session.frames(duration=seconds):
            if live is not None:
                live.draw()
                if frames % 300 == 0:  # keep the StringIO from growing without bound
                    console.file.seek(0)
                    console.file.truncate()
            frames += 1
        self.cpu = time.process_time() - cpu0
        self.wall = time.perf_counter() - wall0
        if live is not None:
            live.__exit__(None, None, None)
        self.frames = frames
        stats = session.final_stats()
        self.samples = sum(int(s["samples"]) for s in stats.values())
        self.dropped = sum(int(s["dropped"]) for s in stats.values())
        self.max_gap = max((s["max_gap"] or 0.0) for s in stats.values())
        self.store_dropped = sum(d.store.dropped() for d in manager.devices.values())
        # a sample is lost when it never reached a frame: the count must match the rate
        spans = [(s["newest_timestamp"] - s["first_timestamp"]) * rate + 1 for s in stats.values()]
        self.missing = max(0, round(sum(spans)) - self.samples)
        self.written = (
            session.recorders[0].samples if ndjson is not None and session.recorders else 0
        )
        self.lines = printer.lines if events else 0
        if sink is not None:
            sink.close()
        session.close_sinks()
        manager.shutdown()

    @property
    def lost(self) -> int:
        return self.dropped + self.store_dropped + self.missing


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--devices", type=int, default=32)
    parser.add_argument("--rate", type=float, default=1000.0)
    args = parser.parse_args()
    report = Report()
    offered = args.devices * args.rate
    print(
        f"{args.devices} waveform devices at {args.rate:g} Hz ({offered:,.0f} samples/s, "
        f"{offered * UNITS_PER_SAMPLE:,.0f} unit values/s), frames at 60 Hz, {args.seconds:g} s per run"
    )

    base = Run(args.devices, args.rate, args.seconds)
    report.figure("without view: samples lost", base.lost, "samples", target=0)
    report.figure("without view: CPU of the process", base.cpu / base.wall * 100, "% of a core")
    viewed = Run(args.devices, args.rate, args.seconds, view=True)
    width, height = TERMINAL
    report.figure(
        f"live view ({width}x{height}, every frame): samples lost", viewed.lost, "samples", target=0
    )
    report.figure("live view: frames drawn per second", viewed.frames / viewed.wall, "frames/s")
    report.figure("live view: CPU of the process", viewed.cpu / viewed.wall * 100, "% of a core")
    extra = (viewed.cpu / viewed.wall - base.cpu / base.wall) * 100
    report.figure("live view: CPU beyond the run without view", extra, "% of a core", target=30)
    report.ratio("CPU with view / without", viewed.cpu / viewed.wall, base.cpu / base.wall)

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "monitor.ndjson"
        written = Run(args.devices, args.rate, args.seconds, ndjson=path)
        size = path.stat().st_size
    report.figure(
        "ndjson to a file: sample records written per second",
        written.written / written.wall,
        "samples/s",
        target=100_000,
        higher_is_better=True,
    )
    report.figure("ndjson to a file: samples lost", written.lost, "samples", target=0)
    report.figure(
        "ndjson to a file: CPU of the process", written.cpu / written.wall * 100, "% of a core"
    )
    report.figure(
        "ndjson to a file: records per CPU second (capacity)",
        written.written / written.cpu,
        "samples/s",
    )
    report.figure("ndjson to a file: bytes per record", size / max(1, written.written), "bytes")

    changes = Run(args.devices, args.rate, args.seconds, events=True)
    report.figure("events: samples lost", changes.lost, "samples", target=0)
    report.figure("events: lines written per second", changes.lines / changes.wall, "lines/s")
    report.figure("events: CPU of the process", changes.cpu / changes.wall * 100, "% of a core")
    extra = (changes.cpu / changes.wall - base.cpu / base.wall) * 100
    report.figure("events: CPU beyond the run without view", extra, "% of a core", target=30)
    report.exit()


if __name__ == "__main__":
    main()
