"""Benchmarks of VRPN (issue 11): `VRPN_drv` ingesting from gadgetctl's server, and `serve`
fanning out to many clients. Both run `gadgetctl serve` as a separate process on loopback.

1. Ingest: a 32-sensor tracker at 1 kHz (32,000 pose reports/s) plus 16 buttons, read over
   direct TCP by VRPN_drv inside the input manager; targets: 0 reports lost. Printed: the
   driver thread's share of a core and its CPU per report, against a raw-socket reader of
   the same stream (framing only, no decoding) as baseline, measured in the same run.
2. Fan-out: 100 waveform devices at 1 kHz (100,000 pose reports/s) served to 8 raw TCP
   clients (each in its own process); targets: 0 lost on TCP, sample-to-client latency p99
   <= 2 ms. Printed: latency p50/p99 (sample time in the message header to the client's
   receipt), the CPU of serve, messages per second per client; and for reference the floor of
   the latency under the run's load: the same readers reading the C sender of 6 (as many
   sensors as devices), whose messages are stamped as they are sent, with no frame to wait for
   (a sample waits up to a frame period, 1 ms, for serve's next frame). Targets (issue 27
   goal 2): also serve's CPU <= 30 % of a core.
2b. The same fan-out with the other core busy (``--part fanout-busy``, part of ``all``): a
   process spins on every core but one while it runs; the same targets (issue 27 goal 2:
   "also with the other core busy"), and the C sender's floor under the same load.

3. Breakdown (``--part breakdown``, not part of ``all``): the fan-out with serve's service run
   in this process, to say where a sample's time goes: per frame, its age when the frame
   began (the oldest and the newest sample), the frame's update and gathering, the rest of
   the frame (feeding, framing, queueing, the first write to every client), the frame period,
   and the clients' latency as in 2; with the CPU of the frame thread and of the clients.

4. Flood (``--part flood``, not part of ``all``): the fan-out without, then with one more
   client pinging at 3 MB/s (issue 24 item 4); the other clients' latency with the flood
   against without.

5. Hostile (``--part hostile``, not part of ``all``): serve's memory while a client describes
   ever-new sender names, against its memory without it (issue 24: within 2x).

6. C sender (``--part csender``, part of ``all``): serve fanning out 4 tracker sensors at 1 kHz
   to 8 raw clients, against a C program sending the same messages (``vrpn_csender.c``, built
   with the system's compiler), each run twice alternately; target (issue 27): at most 2x.
   For reference, the least Python program sending the same messages
   (``vrpn_pysender.py``): what any Python sender pays before it computes anything.

Run: python bench/bench_vrpn.py [--seconds 5] [--part ingest|fanout|fanout-busy|breakdown|flood|hostile|csender] [--devices 100] [--clients 8]
[--walking-clients]

The fan-out clients keep what they receive with its receipt time and walk it after the run
(``--walking-clients``: as it arrives, as before): 8 clients walking every recv with numpy
took about half a core of the two the test machine has, which serve then did not have.
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import multiprocessing
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from common import REPO, Report

from gadgetctl.vrpn import codecs
from gadgetctl.vrpn.wire import (
    COOKIE_SIZE,
    HEADER_SIZE,
    SENDER_DESCRIPTION,
    TYPE_DESCRIPTION,
    make_cookie,
    pack_description,
    pack_message,
    padded,
)

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
   <elements>
{body}   </elements>
</configuration>
"""
_HEADER = struct.Struct(">IiiiiI")
#: Issue 27 goal 2: serve's share of a core fanning out 100 devices at 1 kHz to 8 clients.
FANOUT_CPU_TARGET = 30.0
TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int, tid: int | None = None) -> float:
    """CPU (user + system) of a process, or of one of its threads, from /proc."""
    path = f"/proc/{pid}/task/{tid}/stat" if tid else f"/proc/{pid}/stat"
    fields = Path(path).read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


class Served:
    def __init__(self, config: Path, *extra: str) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "gadgetctl",
                "serve",
                str(config),
                "--port",
                "0",
                "--format",
                "json",
                *extra,
            ],
            cwd=REPO,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        first = json.loads(self.process.stdout.readline())
        self.port = first["port"]
        self.names = first["names"]
        self.events: list[dict] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.events.append(json.loads(line))

    def cpu(self) -> float:
        return cpu_seconds(self.process.pid)

    def wait_disconnects(self, count: int, timeout: float = 30.0) -> list[dict]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            gone = [e for e in self.events if e["event"] == "disconnected"]
            if len(gone) >= count:
                return gone
            time.sleep(0.05)
        raise RuntimeError("clients did not disconnect")

    def stop(self) -> None:
        self.process.send_signal(signal.SIGINT)
        self.process.wait(30)
        self._reader.join(5)


# -------------------------------------------------------------------- raw-socket reader


class RawReader:
    """Reads a server's stream over direct TCP and walks the framing (no payload decoding):
    the cheapest correct reader, the baseline. Counts messages; keeps pose header times
    per sender for gap and latency analysis when ``poses`` is set."""

    def __init__(self, port: int, *, poses: bool = False, defer: bool = False) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=10)
        self.sock.sendall(make_cookie())
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
        self.messages = 0
        self.system = 0
        self.keep = poses
        self.pose_type: int | None = None
        self.type_names: dict[int, str] = {}
        self.times: list[np.ndarray] = []  # header times of pose messages (per chunk)
        self.senders: list[np.ndarray] = []
        self.latency: list[np.ndarray] = []
        #: Keep what arrives with its receipt time and walk it after the run (the same walk):
        #: a fan-out client then costs a recv per wakeup, not a numpy walk, and leaves the
        #: cores it shares with serve to serve (8 walking clients took half a core of two).
        self.defer = defer
        self._received: list[tuple[float, bytes]] = []

    def run(self, seconds: float) -> None:
        self._buf = bytearray()
        self._need_cookie = True
        end = time.monotonic() + seconds
        sock = self.sock
        sock.settimeout(0.5)
        keep = self._received.append if self.defer else None
        while time.monotonic() < end:
            try:
                data = sock.recv(1 << 20)
            except TimeoutError:
                continue
            if not data:
                break
            received = time.time()
            if keep is not None:
                keep((received, data))
            else:
                self._take(data, received)
        sock.close()
        received_list, self._received = self._received, []
        for received, data in received_list:
            self._take(data, received)

    def _take(self, data: bytes, received: float) -> None:
        buf = self._buf
        buf += data
        if self._need_cookie:
            if len(buf) < COOKIE_SIZE:
                return
            del buf[:COOKIE_SIZE]
            self._need_cookie = False
        self._buf = self._walk(buf, received)

    def _walk(self, buf: bytearray, received: float) -> bytearray:
        pos, end = 0, len(buf)
        unpack = _HEADER.unpack_from
        pose_size = HEADER_SIZE + 64
        while end - pos >= HEADER_SIZE:
            if self.pose_type is not None and self.keep:
                # a run of pose messages: read their headers at once
                most = (end - pos) // pose_size
                words = np.frombuffer(buf, dtype=">u4", count=most * 22, offset=pos).reshape(
                    most, 22
                )
                fits = (words[:, 0] == pose_size) & (words[:, 4] == self.pose_type)
                count = most if fits.all() else int(np.argmin(fits))
                if count:
                    words = np.frombuffer(buf, dtype=">i4", count=count * 22, offset=pos).reshape(
                        count, 22
                    )
                    stamps = words[:, 1] + words[:, 2] * 1e-6
                    self.times.append(stamps)
                    self.senders.append(words[:, 3].copy())
                    self.latency.append(received - stamps)
                    self.messages += count
                    pos += count * pose_size
                    continue
            length, _sec, _usec, sender, type_id, _ = unpack(buf, pos)
            body = padded(length - HEADER_SIZE)
            if end - pos - HEADER_SIZE < body:
                break
            if type_id < 0:
                self.system += 1
                if type_id == -2:
                    (n,) = struct.unpack_from(">I", buf, pos + HEADER_SIZE)
                    name = bytes(buf[pos + HEADER_SIZE + 4 : pos + HEADER_SIZE + 3 + n]).decode()
                    self.type_names[sender] = name
                    if name == codecs.TRACKER_POS_QUAT:
                        self.pose_type = sender
            self.messages += 1
            pos += HEADER_SIZE + body
        return buf[pos:]

    def lost_poses(self, rate: float) -> int:
        """Pose reports missing between each sender's first and last one (the waveform
        samples are exactly 1/rate apart)."""
        if not self.times:
            return 0
        times, senders = np.concatenate(self.times), np.concatenate(self.senders)
        lost = 0
        for sender in np.unique(senders):
            t = times[senders == sender]
            lost += max(0, round((t.max() - t.min()) * rate) + 1 - len(t))
        return lost


# -------------------------------------------------------------------- 1. ingest


def ingest_config(rate: float) -> str:
    paths = "".join(
        f"<position_path>{('circle', 'spin', 'figure_eight')[i % 3]}</position_path>"
        for i in range(32)
    )
    periods = "".join(f"<button_period>{0.05 + 0.01 * i:g}</button_period>" for i in range(16))
    body = (
        f'      <waveform_device name="Tracker32" version="1"><rate>{rate:g}</rate>'
        f"<event_period>0.0</event_period>{paths}</waveform_device>\n"
        f'      <waveform_device name="Buttons16" version="1"><rate>{rate:g}</rate>'
        f"<event_period>0.0</event_period>{periods}</waveform_device>\n"
    )
    return HEAD.format(body=body)


def receiver_config(port: int) -> str:
    body = (
        f'      <input_manager name="Input Manager" version="2"><driver>VRPN_drv</driver></input_manager>\n'
        f'      <vrpn name="Ingest" version="3"><tracker_server>Tracker32@tcp://127.0.0.1:{port}</tracker_server>'
        f"<button_server>Buttons16@tcp://127.0.0.1:{port}</button_server><analog_server></analog_server>"
        f"<tracker_count>32</tracker_count><button_count>16</button_count><analog_count>0</analog_count></vrpn>\n"
    )
    return HEAD.format(body=body)


def ingest(report: Report, seconds: float, tmp: Path) -> None:
    from gadgetctl.input.manager import InputManager

    rate = 1000.0
    config = tmp / "ingest.jconf"
    config.write_text(ingest_config(rate))
    served = Served(config)
    try:
        # baseline: the raw reader in a thread of its own, its CPU from /proc
        reader = RawReader(served.port, poses=True)
        measured: list[float] = []

        def run() -> None:  # the reader's own thread: its CPU time, measured in it
            cpu0, wall0 = time.thread_time(), time.perf_counter()
            reader.run(seconds)
            measured.extend((time.thread_time() - cpu0, time.perf_counter() - wall0))

        thread = threading.Thread(target=run)
        thread.start()
        thread.join()
        raw_cpu, raw_wall = measured
        raw_rate = reader.messages / seconds
        gone = served.wait_disconnects(1)[-1]
        # lost: what serve could not queue for this client (it did not read fast enough), and
        # gaps in the header times of what arrived
        raw_lost = gone["dropped"] + reader.lost_poses(rate)

        # VRPN_drv in the input manager, frames at 60 Hz in this thread
        receiver = tmp / "receiver.jconf"
        receiver.write_text(receiver_config(served.port))
        manager, configuration = InputManager.from_files([receiver])
        manager.configure(configuration)
        device = manager.device("Ingest")
        deadline = time.monotonic() + 10
        while device.counters.get("messages", 0) == 0 and time.monotonic() < deadline:
            manager.update()
            time.sleep(0.01)
        sampler = next(t for t in threading.enumerate() if t.name == "gadgetctl-sample-Ingest")
        start_messages = device.counters.get("messages", 0)
        cpu0, wall0 = cpu_seconds(os.getpid(), sampler.native_id), time.perf_counter()
        manager.run(60.0, duration=seconds)
        drv_cpu = cpu_seconds(os.getpid(), sampler.native_id) - cpu0
        drv_wall = time.perf_counter() - wall0
        received = device.counters.get("messages", 0)
        manager.shutdown()
        gone = served.wait_disconnects(2)[-1]
        drv_lost = gone["dropped"]  # by TCP the rest arrives: what serve had to drop is lost
        drv_reports = received - start_messages
    finally:
        served.stop()
    print(f"  32 sensors + 16 buttons at {rate:g} Hz over direct TCP, {seconds:g} s per reader")
    report.figure("raw reader: messages per second", raw_rate, "msg/s")
    report.figure("raw reader: reports lost", raw_lost, "reports", target=0)
    report.figure("raw reader: share of a core", raw_cpu / raw_wall * 100, "%")
    report.figure("raw reader: CPU per report", raw_cpu / max(1, reader.messages) * 1e6, "us")
    report.figure("VRPN_drv: reports per second", drv_reports / drv_wall, "msg/s")
    report.figure("VRPN_drv: reports lost", drv_lost, "reports", target=0)
    report.figure("VRPN_drv: share of a core (its sampling thread)", drv_cpu / drv_wall * 100, "%")
    report.figure("VRPN_drv: CPU per report", drv_cpu / max(1, drv_reports) * 1e6, "us")
    report.ratio(
        "VRPN_drv CPU per report / raw reader",
        drv_cpu / max(1, drv_reports),
        raw_cpu / max(1, reader.messages),
    )


# -------------------------------------------------------------------- 2. fan-out


def fanout_config(devices: int, rate: float) -> str:
    body = "".join(
        f'      <waveform_device name="Wave {i}" version="1"><rate>{rate:g}</rate>'
        f"<seed>{i}</seed><event_period>0.0</event_period>"
        f"<position_path>circle</position_path></waveform_device>\n"
        for i in range(devices)
    )
    return HEAD.format(body=body)


def _client(port: int, seconds: float, rate: float, results, defer: bool = True) -> None:
    reader = RawReader(port, poses=True, defer=defer)
    reader.run(seconds)
    latency = np.concatenate(reader.latency) if reader.latency else np.empty(0)
    results.put(
        {
            "messages": reader.messages,
            "lost": reader.lost_poses(rate),
            "latency": latency[len(latency) // 10 :],
        }
    )  # the first tenth: the connection's start


def _hostile_connection(port: int, setup: bytes = b"") -> socket.socket:
    """A direct TCP connection to serve that sent the cookie and ``setup``, and whose
    incoming bytes a thread of its own reads and discards."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    sock.sendall(make_cookie() + setup)

    def discard() -> None:
        try:
            while sock.recv(1 << 20):
                pass
        except OSError:
            pass

    threading.Thread(target=discard, daemon=True).start()
    return sock


def _flooder(port: int, seconds: float, rate: float, sender: str, results) -> None:
    """A hostile client (issue 24 item 4): pings from a served sender at ``rate`` bytes per
    second (as fast as serve takes them when it takes fewer), reading and discarding the
    pongs (the worst case for serve: every pong is written)."""
    sock = _hostile_connection(
        port,
        pack_description(SENDER_DESCRIPTION, 0, sender)
        + pack_description(TYPE_DESCRIPTION, 0, codecs.PING),
    )
    port_of = sock.getsockname()[1]
    ping = pack_message(0, 0, b"", 0.0)
    step = 0.01
    chunk = ping * max(1, int(rate * step) // len(ping))
    sent = 0
    end = time.monotonic() + seconds
    due = time.monotonic()
    try:
        while time.monotonic() < end:
            sock.sendall(chunk)
            sent += len(chunk)
            due += step
            time.sleep(max(0.0, due - time.monotonic()))
    finally:
        sock.close()
    results.put({"flooded": sent, "client": f"127.0.0.1:{port_of}"})


def c_sender(tmp: Path) -> Path | None:
    """bench/vrpn_csender.c built in ``tmp`` with the system's C compiler (None without one)."""
    import shutil

    binary = tmp / "vrpn_csender"
    if binary.exists():
        return binary
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        return None
    subprocess.run(
        [compiler, "-O2", "-o", str(binary), str(Path(__file__).with_name("vrpn_csender.c"))],
        check=True,
    )
    return binary


def c_sender_latency(
    tmp: Path, seconds: float, sensors: int, clients: int, rate: float
) -> np.ndarray | None:
    """Send-to-receive latencies (ms) of the C sender's messages (time-stamped as they are
    sent) read by the fan-out's readers: what the readers' own scheduling costs, with no
    frame to wait for; None without a C compiler."""
    binary = c_sender(tmp)
    if binary is None:
        return None
    sender = subprocess.Popen(
        [str(binary), str(clients), str(sensors), f"{rate:g}", f"{seconds + 30:g}"],
        stdout=subprocess.PIPE,
        text=True,
    )
    context = multiprocessing.get_context("fork")
    results = context.Queue()
    try:
        port = int(sender.stdout.readline())
        procs = [
            context.Process(target=_client, args=(port, seconds, rate, results))
            for _ in range(clients)
        ]
        for p in procs:
            p.start()
        outcomes = [results.get(timeout=seconds + 60) for _ in procs]
        for p in procs:
            p.join(30)
    finally:
        sender.kill()
        sender.wait(10)
    return np.concatenate([o["latency"] for o in outcomes]) * 1000


@contextlib.contextmanager
def other_cores_busy() -> Iterator[int]:
    """One process spinning on each core but one while the block runs (issue 27 goal 2:
    "also with the other core busy"); yields how many."""
    spinners = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"])
        for _ in range(max(1, (os.cpu_count() or 2) - 1))
    ]
    try:
        yield len(spinners)
    finally:
        for spinner in spinners:
            spinner.kill()
        for spinner in spinners:
            spinner.wait(10)


def fanout(
    report: Report,
    seconds: float,
    tmp: Path,
    devices: int = 100,
    clients: int = 8,
    defer: bool = True,
    flood: float = 0.0,
    condition: str = "",
) -> dict[str, float]:
    """The fan-out (with ``flood``, a client pinging at that many bytes per second too);
    returns the latency percentiles and serve's share of a core. ``condition`` (such as
    "the other core busy") is added to the labels of the figures with targets."""
    rate = 1000.0
    during = f" ({condition})" if condition else ""
    config = tmp / "fanout.jconf"
    config.write_text(fanout_config(devices, rate))
    served = Served(config)
    context = multiprocessing.get_context("fork")
    results = context.Queue()
    flooded = context.Queue()
    try:
        procs = [
            context.Process(target=_client, args=(served.port, seconds, rate, results, defer))
            for _ in range(clients)
        ]
        if flood:
            procs.append(
                context.Process(
                    target=_flooder, args=(served.port, seconds, flood, served.names[0], flooded)
                )
            )
        for p in procs:
            p.start()
        time.sleep(0.5)
        cpu0, wall0 = served.cpu(), time.perf_counter()
        time.sleep(max(0.1, seconds - 1.0))
        serve_cpu, wall = served.cpu() - cpu0, time.perf_counter() - wall0
        outcomes = [results.get(timeout=seconds + 60) for _ in range(clients)]
        flooder = flooded.get(timeout=seconds + 60) if flood else {"flooded": 0, "client": ""}
        for p in procs:
            p.join(30)
        gone = served.wait_disconnects(len(procs))
    finally:
        served.stop()
    gone = [e for e in gone if e["client"] != flooder["client"]]  # the readers' losses
    sent = flooder["flooded"]
    latency = np.concatenate([o["latency"] for o in outcomes]) * 1000
    dropped = sum(e["dropped"] for e in gone)
    lost = sum(o["lost"] for o in outcomes) + dropped
    per_client = np.mean([o["messages"] for o in outcomes]) / seconds
    print(
        f"  {devices} waveform devices at {rate:g} Hz ({devices * rate:,.0f} pose reports/s) to {clients} "
        f"TCP clients, {seconds:g} s"
        + (f", a client flooding pings at {flood / 1e6:g} MB/s" if flood else "")
    )
    if flood:
        stopped = next((e for e in served.events if e["event"] == "stopped"), {})
        counters = stopped.get("counters", {})
        report.figure("flooder: pings sent (serve took them at)", sent / seconds / 1e6, "MB/s")
        report.figure(
            "serve: passes with the input budget used", counters.get("input_deferred", 0), ""
        )
    report.figure(f"reports lost over TCP (all clients){during}", lost, "reports", target=0)
    report.figure("messages per second per client", per_client, "msg/s")
    report.figure("sample-to-client latency p50", float(np.percentile(latency, 50)), "ms")
    report.figure(
        f"sample-to-client latency p99{during}",
        float(np.percentile(latency, 99)),
        "ms",
        target=2.0,
    )
    # the flood's figures say what a flooding client costs; its CPU target is the fan-out's
    report.figure(
        f"CPU of serve{during}",
        serve_cpu / wall * 100,
        "% of a core",
        target=None if flood else FANOUT_CPU_TARGET,
    )
    report.figure(
        "serve CPU per report per client", serve_cpu / (per_client * clients * wall) * 1e6, "us"
    )
    if not flood:
        # the floor of the latency figures under this run's load: the same readers reading
        # a C sender that sends each message as it stamps it (no frame period to wait for,
        # where a sample waits up to a frame, 1 ms, for serve's next frame)
        floor = c_sender_latency(tmp, seconds, devices, clients, rate)
        if floor is not None and len(floor):
            report.figure(
                "C sender, the same readers: send-to-receive latency p99 (the floor)",
                float(np.percentile(floor, 99)),
                "ms",
            )
    return {
        "p50": float(np.percentile(latency, 50)),
        "p99": float(np.percentile(latency, 99)),
        "cpu": serve_cpu / wall * 100,
    }


def flooded(report: Report, seconds: float, tmp: Path, devices: int, clients: int) -> None:
    """The fan-out without, then with a client flooding pings at 3 MB/s (issue 24 item 4):
    the other clients' latency with the flood against without, in the same run."""
    calm = fanout(report, seconds, tmp, devices, clients)
    stormy = fanout(report, seconds, tmp, devices, clients, flood=3e6)
    report.ratio("latency p50 with the flooder / without", stormy["p50"], calm["p50"])
    report.ratio("latency p99 with the flooder / without", stormy["p99"], calm["p99"])
    report.ratio("serve CPU with the flooder / without", stormy["cpu"], calm["cpu"])


def breakdown(
    report: Report,
    seconds: float,
    tmp: Path,
    devices: int = 100,
    clients: int = 8,
    defer: bool = True,
) -> None:
    """The fan-out of 2 with the service in this process, timed stage by stage."""
    import resource

    from gadgetctl.input.clock import now
    from gadgetctl.input.kinds import DeviceKind
    from gadgetctl.input.manager import InputManager
    from gadgetctl.serve.service import ServeOptions, ServeService

    rate = 1000.0
    config = tmp / "fanout.jconf"
    config.write_text(fanout_config(devices, rate))
    manager, configuration = InputManager.from_files([config])
    service = ServeService(manager, configuration, ServeOptions(port=0))
    service.prepare()
    # frame start, gathered, oldest and newest sample, this hook's own time, frame end
    rows: list[list[float]] = []
    feed_devices: list[str] = []

    def gathered(session, moment: float) -> None:  # runs first: after update and gathering
        done = now()
        oldest = newest = None
        count = 0  # the frame's samples, all devices together
        # devices whose frame is a window of their group's shared arrays: read there, as the
        # feed does (asking per device would make every store's frame, which serve does not)
        grouped: set[str] = set()
        for group in getattr(session.gathered, "groups", ()):
            windows = group.windows
            grouped.update(group.names)
            for slot in group.slots[windows.fresh[group.slots]].tolist():
                stamps = windows.arrays[slot][0]
                t0 = float(stamps[windows.starts[slot]])
                t1 = float(stamps[windows.stops[slot] - 1])
                count += int(windows.stops[slot] - windows.starts[slot])
                oldest = t0 if oldest is None else min(oldest, t0)
                newest = t1 if newest is None else max(newest, t1)
        for name in feed_devices:
            if name in grouped:
                continue
            frame = session.frame_samples(name).get(DeviceKind.POSITION)
            if frame:
                first, last = frame.chunks[0], frame.chunks[-1]
                t0 = first.timestamp if hasattr(first, "timestamp") else float(first.timestamps[0])
                t1 = last.timestamp if hasattr(last, "timestamp") else float(last.timestamps[-1])
                count += sum(
                    1 if hasattr(chunk, "timestamp") else len(chunk.timestamps)
                    for chunk in frame.chunks
                )
                oldest = t0 if oldest is None else min(oldest, t0)
                newest = t1 if newest is None else max(newest, t1)
        if oldest is not None:
            rows.append([moment, done, oldest, newest, count, now() - done])

    service.session.add_consumer(gathered)
    port = service.listen()
    feed_devices.extend(e.element for e in service.catalog if e.kind == "device")
    context = multiprocessing.get_context("fork")
    results = context.Queue()
    procs = [
        context.Process(target=_client, args=(port, seconds, rate, results, defer))
        for _ in range(clients)
    ]
    for p in procs:
        p.start()
    frames = 0
    try:
        time.sleep(0.3)
        cpu0, wall0 = time.thread_time(), time.perf_counter()
        for frame in service.frames(max(0.5, seconds - 0.5)):
            frames += 1
            if rows and rows[-1][0] == frame.timestamp:
                rows[-1].append(now())
        frame_cpu, wall = time.thread_time() - cpu0, time.perf_counter() - wall0
        frame_cpu -= sum(row[5] for row in rows)  # the measuring hook's own time
        outcomes = [results.get(timeout=seconds + 60) for _ in procs]
        for p in procs:
            p.join(30)
        dropped = service.server.dropped
    finally:
        service.close()
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    table = np.array([row for row in rows[len(rows) // 10 :] if len(row) == 7])
    start, done, oldest, newest, count, spent, end = table.T
    end = end - spent  # without the measuring hook's own time
    latency = np.concatenate([o["latency"] for o in outcomes]) * 1000

    def ms(values, label: str) -> None:
        values = np.asarray(values) * 1000
        print(
            f"  {label:<48} p50 {np.percentile(values, 50):7.3f}  "
            f"p99 {np.percentile(values, 99):7.3f} ms"
        )

    print(
        f"  {devices} waveform devices at {rate:g} Hz to {clients} TCP clients, serve in this "
        f"process: {frames / wall:.0f} frames/s, {np.mean(count) / devices:.2f} "
        "samples per device and frame"
    )
    ms(done - oldest, "age of a frame's oldest sample once gathered")
    ms(done - newest, "age of a frame's newest sample once gathered")
    ms(done - start, "update + gathering (publish, swap, tracks)")
    ms(end - done, "feed + framing + queueing + first write")
    ms(np.diff(start), "frame period")
    report.figure(
        "breakdown: sample-to-client latency p50", float(np.percentile(latency, 50)), "ms"
    )
    report.figure(
        "breakdown: sample-to-client latency p99", float(np.percentile(latency, 99)), "ms"
    )
    report.figure(
        "breakdown: reports missing at the clients", sum(o["lost"] for o in outcomes), "reports"
    )
    report.figure("breakdown: reports serve dropped (full client buffers)", dropped, "reports")
    report.figure("breakdown: frame thread CPU", frame_cpu / wall * 100, "% of a core")
    report.figure("breakdown: frame thread CPU per frame", frame_cpu / max(1, frames) * 1000, "ms")
    report.figure(
        f"breakdown: the {clients} clients' CPU together",
        (usage.ru_utime + usage.ru_stime) / seconds * 100,
        "% of a core",
    )


# -------------------------------------------------------------------- 6. against a C sender


def sensors_config(sensors: int, rate: float) -> str:
    paths = "".join("<position_path>circle</position_path>" for _ in range(sensors))
    body = (
        f'      <waveform_device name="Tracker0" version="1"><rate>{rate:g}</rate>'
        f"<event_period>0.0</event_period>{paths}</waveform_device>\n"
    )
    return HEAD.format(body=body)


def _readers_cpu(
    port: int, pid: int, clients: int, seconds: float, rate: float
) -> tuple[float, int]:
    """Share of a core ``pid`` takes while ``clients`` raw readers read it, and the messages
    each read (the least of them)."""
    context = multiprocessing.get_context("fork")
    results = context.Queue()
    procs = [
        context.Process(target=_client, args=(port, seconds, rate, results)) for _ in range(clients)
    ]
    for p in procs:
        p.start()
    time.sleep(0.5)
    cpu0, wall0 = cpu_seconds(pid), time.perf_counter()
    time.sleep(max(0.1, seconds - 1.0))
    used, wall = cpu_seconds(pid) - cpu0, time.perf_counter() - wall0
    outcomes = [results.get(timeout=seconds + 60) for _ in procs]
    for p in procs:
        p.join(30)
    return used / wall * 100, min(o["messages"] for o in outcomes)


def against_c(
    report: Report, seconds: float, tmp: Path, clients: int = 8, sensors: int = 4
) -> None:
    """serve's CPU fanning out ``sensors`` tracker sensors at 1 kHz to ``clients`` raw
    readers, against a C program sending the same messages (bench/vrpn_csender.c, built
    here with the system's C compiler), measured in the same run, twice each alternately;
    target (issue 27): at most 2x."""
    rate = 1000.0
    binary = c_sender(tmp)
    if binary is None:
        print("  no C compiler: the C sender cannot be built, nothing to compare")
        return
    config = tmp / "sensors.jconf"
    config.write_text(sensors_config(sensors, rate))
    c_runs, python_runs, serve_runs = [], [], []
    arguments = [str(clients), str(sensors), f"{rate:g}", f"{seconds + 30:g}"]
    python_sender = [sys.executable, str(Path(__file__).with_name("vrpn_pysender.py"))]
    for _ in range(2):
        for command, runs in (([str(binary)], c_runs), (python_sender, python_runs)):
            sender = subprocess.Popen([*command, *arguments], stdout=subprocess.PIPE, text=True)
            try:
                port = int(sender.stdout.readline())
                runs.append(_readers_cpu(port, sender.pid, clients, seconds, rate)[0])
            finally:
                sender.kill()
                sender.wait(10)
        served = Served(config)
        try:
            serve_runs.append(
                _readers_cpu(served.port, served.process.pid, clients, seconds, rate)[0]
            )
        finally:
            served.stop()
    c_cpu, python_cpu, serve_cpu = min(c_runs), min(python_runs), min(serve_runs)
    print(
        f"  {sensors} sensors at {rate:g} Hz to {clients} TCP clients, {seconds:g} s, "
        f"twice each (the lesser figure)"
    )
    report.figure("C sender: share of a core", c_cpu, "%")
    report.figure("least Python sender (bench/vrpn_pysender.py): share of a core", python_cpu, "%")
    report.figure("serve: share of a core", serve_cpu, "%")
    report.ratio("least Python sender / C sender (for reference)", python_cpu, c_cpu)
    report.ratio("serve / least Python sender (for reference)", serve_cpu, python_cpu)
    report.figure("serve / C sender", serve_cpu / c_cpu, "x", target=2.0)


# -------------------------------------------------------------------- 5. hostile memory


def rss_bytes(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    return 0


def _describer(port: int, seconds: float, results) -> None:
    """A hostile client (issue 24 item 1): sender descriptions that keep their ids within
    0..1999 but bring ever-new names of 90 characters, as fast as serve reads them."""
    sock = _hostile_connection(port)
    sent = 0
    number = 0
    end = time.monotonic() + seconds
    try:
        while time.monotonic() < end:
            batch = b"".join(
                pack_description(SENDER_DESCRIPTION, (number + i) % 2000, f"n{number + i:089d}")
                for i in range(1000)
            )
            number += 1000
            sock.sendall(batch)
            sent += 1000
    except OSError:
        pass
    finally:
        sock.close()
    results.put(sent)


def hostile_memory(report: Report, seconds: float, tmp: Path) -> None:
    """serve's memory (RSS) with one hostile client describing ever-new sender names for
    ``seconds``, against its memory with a well-behaved client only, in the same run;
    target (issue 24): within 2x."""
    rate = 1000.0
    config = tmp / "hostile.jconf"
    config.write_text(fanout_config(4, rate))
    served = Served(config)
    context = multiprocessing.get_context("fork")
    results, described = context.Queue(), context.Queue()
    try:
        reader = context.Process(target=_client, args=(served.port, 2 * seconds + 2, rate, results))
        reader.start()
        time.sleep(1.0)
        calm = 0
        for _ in range(5):  # with the reader served, before the hostile client
            calm = max(calm, rss_bytes(served.process.pid))
            time.sleep(0.1)
        hostile = context.Process(target=_describer, args=(served.port, seconds, described))
        hostile.start()
        peak = calm
        deadline = time.monotonic() + seconds + 1
        while time.monotonic() < deadline:
            peak = max(peak, rss_bytes(served.process.pid))
            time.sleep(0.1)
        names = described.get(timeout=60)
        hostile.join(30)
        results.get(timeout=seconds + 60)
        reader.join(30)
    finally:
        served.stop()
    print(
        f"  4 waveform devices at {rate:g} Hz to 1 client; a hostile client describing {names:,} new sender names in {seconds:g} s"
    )
    report.figure("serve RSS with the well-behaved client", calm / 1e6, "MB")
    report.figure("serve RSS, peak with the hostile client", peak / 1e6, "MB")
    report.figure("serve RSS hostile / calm", peak / calm, "x", target=2.0)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument(
        "--part",
        choices=(
            "ingest",
            "fanout",
            "fanout-busy",
            "breakdown",
            "flood",
            "hostile",
            "csender",
            "all",
        ),
        default="all",
    )
    parser.add_argument(
        "--devices", type=int, default=100, help="fan-out: waveform devices at 1 kHz"
    )
    parser.add_argument("--clients", type=int, default=8, help="fan-out: TCP clients")
    parser.add_argument(
        "--walking-clients",
        action="store_true",
        help="fan-out: clients walk what they receive as it arrives (numpy per recv, about "
        "half a core for 8 of them) instead of after the run",
    )
    args = parser.parse_args()
    print(
        f"load average before the run: {' '.join(f'{x:.2f}' for x in os.getloadavg())} "
        f"on {os.cpu_count()} cores (figures are shares of what this machine had left)"
    )
    report = Report()
    with tempfile.TemporaryDirectory() as tmp:
        if args.part in ("ingest", "all"):
            print("VRPN_drv ingest from gadgetctl serve")
            ingest(report, args.seconds, Path(tmp))
        the_fanout = functools.partial(
            fanout,
            report,
            args.seconds,
            Path(tmp),
            args.devices,
            args.clients,
            not args.walking_clients,
        )
        if args.part in ("fanout", "all"):
            print("serve fan-out")
            the_fanout()
        if args.part in ("fanout-busy", "all"):
            with other_cores_busy() as spinning:
                condition = "the other core busy" if spinning == 1 else f"{spinning} cores busy"
                print(f"serve fan-out, {condition} (a process spinning on it)")
                the_fanout(condition=condition)
        if args.part == "flood":
            print("serve fan-out, without and with a client flooding pings")
            flooded(report, args.seconds, Path(tmp), args.devices, args.clients)
        if args.part in ("csender", "all"):
            print("serve fan-out against a C sender of the same messages")
            against_c(report, args.seconds, Path(tmp), args.clients)
        if args.part == "hostile":
            print("serve's memory with a hostile client")
            hostile_memory(report, args.seconds, Path(tmp))
        if args.part == "breakdown":
            print("serve fan-out, where the time goes (serve in this process)")
            breakdown(
                report,
                args.seconds,
                Path(tmp),
                args.devices,
                args.clients,
                not args.walking_clients,
            )
    report.exit()


if __name__ == "__main__":
    main()
