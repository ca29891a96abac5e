"""Benchmarks of the embedded input manager.

1. 100 waveform devices at 1 kHz each (100,000 samples/s) with frames at 60 Hz: samples
   lost, sample-to-frame latency (p50/p99/max) and CPU use of the whole process, against
   the targets: no loss, p99 <= one frame period + 2 ms, <= 60 % of one core.
2. Position filtering of batched samples: 4x4 transforms per second through a chain of
   position filters with numpy, next to a per-sample Python loop as the baseline (target
   >= 1 million per second).

Run: python bench/bench_input.py [--seconds 10] [--devices 100] [--rate 1000]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager, ManagerOptions
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository

DEVICE = """      <waveform_device name="Wave {i}" version="1">
         <rate>{rate}</rate>
         <seed>{i}</seed>
         <analog_waveform>sine</analog_waveform>
         <analog_waveform>noise</analog_waveform>
         <button_period>0.5</button_period>
         <button_period>0.3</button_period>
         <position_path>circle</position_path>
         <position_filters>
            <position_transform_filter name="Offset" version="1">
               <pre_translate>0.0</pre_translate><pre_translate>0.1</pre_translate><pre_translate>0.0</pre_translate>
               <pre_rotation>0.0</pre_rotation><pre_rotation>90.0</pre_rotation><pre_rotation>0.0</pre_rotation>
               <custom_scale>1.0</custom_scale><device_units>Meters</device_units>
               <post_translate>0.0</post_translate><post_translate>0.0</post_translate><post_translate>0.0</post_translate>
               <post_rotation>0.0</post_rotation><post_rotation>0.0</post_rotation><post_rotation>0.0</post_rotation>
            </position_transform_filter>
         </position_filters>
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


def repository():
    return default_repository()  # the bundled definitions, waveform_device included


def bench_throughput(devices: int, rate: float, seconds: float, frame_rate: float = 60.0) -> bool:
    text = (
        HEAD
        + "".join(DEVICE.format(i=i, rate=rate) for i in range(devices))
        + "   </elements>\n</configuration>\n"
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.jconf"
        path.write_text(text)
        configuration = load_configuration([path])
    manager = InputManager(repository(), ManagerOptions(retry_interval=None))
    configured = manager.configure(configuration)
    assert not manager.pending(), [p.message for p in manager.pending()]
    waves = [manager.device(f"Wave {i}") for i in range(devices)]
    period = 1.0 / rate
    frames_seen: list[
        tuple[np.ndarray, np.ndarray, np.ndarray]
    ] = []  # per frame: device, swap time, stamp

    def on_frame(_: InputManager) -> None:  # keep the frame loop's own work small; analyse later
        indices, swaps, parts = [], [], []
        for index, device in enumerate(waves):
            frame = device.store.frame(DeviceKind.POSITION)
            if frame:
                for chunk in frame.chunks:
                    parts.append(chunk.timestamps)
                    indices.append(index)
                    swaps.append(device.store.swapped_at)
        if parts:
            lengths = [len(p) for p in parts]
            frames_seen.append(
                (np.repeat(indices, lengths), np.repeat(swaps, lengths), np.concatenate(parts))
            )

    manager.update()  # warm-up frame, not measured
    measured_from = [d.next_index for d in waves]
    dropped_before = sum(d.store.dropped() for d in waves)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    usage0 = resource.getrusage(resource.RUSAGE_SELF)
    frames = manager.run(frame_rate, duration=seconds, on_frame=on_frame)
    wall = time.perf_counter() - wall0
    cpu = time.process_time() - cpu0
    usage1 = resource.getrusage(resource.RUSAGE_SELF)
    dropped = sum(d.store.dropped() for d in waves) - dropped_before
    produced = sum(d.next_index - start for d, start in zip(waves, measured_from, strict=True))
    manager.shutdown()

    device_of = np.concatenate([f[0] for f in frames_seen])
    swapped = np.concatenate([f[1] for f in frames_seen])
    stamps = np.concatenate([f[2] for f in frames_seen])
    total = len(stamps)
    latencies = [swapped - stamps]
    gaps = 0
    for index in range(devices):
        own = stamps[device_of == index]
        gaps += int(np.count_nonzero(np.abs(np.diff(own) - period) > period / 2))
    lat = np.concatenate(latencies) * 1000.0 if latencies else np.zeros(1)
    p50, p99, worst = np.percentile(lat, 50), np.percentile(lat, 99), lat.max()
    limit_latency = 1000.0 / frame_rate + 2.0
    core = cpu / wall
    rusage_core = ((usage1.ru_utime + usage1.ru_stime) - (usage0.ru_utime + usage0.ru_stime)) / wall
    print(
        f"throughput: {devices} waveform devices x {rate:g} Hz, frames at {frame_rate:g} Hz, {wall:.1f} s, "
        f"{configured} elements configured"
    )
    print(f"  frames run           {frames} ({frames / wall:.1f} per second)")
    print(
        f"  samples received     {total} ({total / wall:,.0f} per second; position kind, one per sample)"
    )
    print(f"  samples lost         {gaps} gaps, {dropped} dropped over the cap (target 0)")
    print(
        f"  latency p50/p99/max  {p50:.2f} / {p99:.2f} / {worst:.2f} ms  "
        f"(target p99 <= {limit_latency:.2f} ms, ratio {p99 / limit_latency:.2f})"
    )
    print(
        f"  CPU                  {core * 100:.1f} % of one core (getrusage {rusage_core * 100:.1f} %) "
        f"(target <= 60 %, ratio {core / 0.60:.2f})"
    )
    print(f"  produced vs received {produced} produced in the measured window")
    return gaps == 0 and dropped == 0 and p99 <= limit_latency and core <= 0.60


def bench_filters(samples: int = 200_000) -> bool:
    from gadgetctl.input.filters import FilterChain, PositionFilter
    from gadgetctl.input.transforms import euler_xyz_degrees, translation

    chain = FilterChain(
        (
            PositionFilter(
                "a",
                translation(0, 0.1, 0) @ euler_xyz_degrees(0, 90, 0),
                translation(0.02, 0, 0) @ euler_xyz_degrees(10, 0, 0),
                0.0254,
            ),
            PositionFilter("b", euler_xyz_degrees(0, 0, 5), np.eye(4), 1.0),
        )
    )
    rng = np.random.default_rng(1)
    matrices = np.tile(np.eye(4), (samples, 1, 1))
    matrices[:, :3, 3] = rng.random((samples, 3))
    chain.apply(matrices[:10])  # warm-up
    best = float("inf")
    for _ in range(5):
        start = time.perf_counter()
        result = chain.apply(matrices)
        best = min(best, time.perf_counter() - start)
    batched = samples / best
    loop_count = 20_000
    start = time.perf_counter()
    for i in range(loop_count):
        m = matrices[i]
        for f in chain.filters:
            m = f.apply(m)
        result[i] = m
    loop = loop_count / (time.perf_counter() - start)
    check = chain.apply(matrices[:5])
    sequential = matrices[:5]
    for f in chain.filters:
        sequential = f.apply(sequential)
    assert np.allclose(check, sequential)
    print(f"position filters: chain of {len(chain)} filters, batches of {samples:,} samples")
    print(
        f"  batched numpy        {batched / 1e6:.2f} M transforms/s (target >= 1.00 M/s, ratio {batched / 1e6:.2f})"
    )
    print(f"  per-sample loop      {loop / 1e6:.3f} M transforms/s (baseline)")
    print(f"  speed-up             x{batched / loop:.0f}")
    return batched >= 1e6


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--devices", type=int, default=100)
    parser.add_argument("--rate", type=float, default=1000.0)
    args = parser.parse_args(argv)
    ok = bench_filters()
    ok = bench_throughput(args.devices, args.rate, args.seconds) and ok
    print("all targets met" if ok else "TARGET MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
