"""Path targets of VRPN: a hostile client against a real ``gadgetctl serve`` process, and a
hostile server against ``gadgetctl monitor vrpn:NAME@127.0.0.1:PORT`` (lob mode: its TCP call
back and its UDP channel). Loopback only, ports the OS picks, every process killed at the end.

The hostile peer's bytes come from :func:`hostile_chunk`: the parser targets' VRPN seeds
mutated, garbage, oversized headers, ever-new sender and type names under ids within the
protocol's 0-1999 (issue 24 item 1), floods of pings, reports for huge sensor ids and text
with terminal control bytes.
"""

from __future__ import annotations

import contextlib
import os
import select
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

from fuzz.inputs import arbitrary, mutate
from fuzz.memory import PeakWatch
from fuzz.paths import CapExceeded, PathFailure, Run, path_target

REPO = Path(__file__).resolve().parents[2]
LOOPBACK = "127.0.0.1"

#: serve with one hostile client: at most this many times its memory without it
SERVE_MEMORY_FACTOR = 2.0
#: a well-behaved client of serve gets a report at least this often during the attack (s)
SERVE_ANSWER_CAP = 5.0
#: monitor vrpn: with a hostile server: at most this many times its memory with a plain one
MONITOR_MEMORY_FACTOR = 2.0
#: hostile chunks sent however short the time (a loaded machine's slow start still attacks)
MIN_CHUNKS = 30
#: seconds past its time a target may still wait for its peer to connect
CONNECT_CAP = 30.0
#: seconds a process may take to stop (serve after SIGTERM, monitor after its --duration)
EXIT_CAP = 20.0
#: stderr a command may write in one run (bytes): a peer must not fill the terminal
STDERR_CAP = 256 * 1024
#: bytes from a peer that must never reach a terminal as they are (issue 24 item 6)
RAW_CONTROLS = [b"\x1b", b"\x07", b"\r", b"\x9b"]

SERVE_CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="fuzz">
   <elements>
      <waveform_device name="Waves" version="1">
         <rate>200.0</rate><event_period>0.0</event_period><button_period>0.2</button_period>
         <position_path>circle</position_path><position_path>circle</position_path>
      </waveform_device>
   </elements>
</configuration>
"""


def gadgetctl(*args: str, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "NO_COLOR": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", *args], cwd=REPO, env=env, stdout=stdout, stderr=stderr
    )


@contextlib.contextmanager
def killed_at_end(process: subprocess.Popen) -> Iterator[subprocess.Popen]:
    try:
        yield process
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(10)


def check_stderr(what: str, text: bytes) -> None:
    if len(text) > STDERR_CAP:
        raise CapExceeded(f"{what} wrote {len(text):,} bytes to stderr, cap {STDERR_CAP:,}")
    if b"Traceback" in text or b"internal error" in text:
        raise PathFailure(f"{what}: internal error on stderr: {text[-1500:]!r}")
    for control in RAW_CONTROLS:
        if control in text:
            at = text.index(control)
            raise PathFailure(
                f"{what}: raw control byte {control!r} on stderr: {text[max(0, at - 120) : at + 40]!r}"
            )


# -- the hostile bytes ------------------------------------------------------------------------


class Peer:
    """What a hostile peer keeps between chunks: its name counter and described ids."""

    def __init__(self) -> None:
        self.names = 0


def _seeds() -> list[bytes]:
    from gadgetctl.vrpn import wire

    from fuzz.targets import _vrpn_seeds

    return [s[wire.COOKIE_SIZE :] if s.startswith(b"vrpn:") else s for s in _vrpn_seeds()]


def hostile_chunk(run: Run, peer: Peer, served: str) -> bytes:
    """One burst of hostile VRPN stream bytes (no cookie), ``served`` a device name the
    other side knows (pings name it)."""
    from gadgetctl.vrpn import codecs, wire

    rng = run.rng
    kind = rng.randrange(10)
    if kind <= 1:  # ever-new sender names under ids within 0..1999
        out = []
        for _ in range(rng.randint(50, 400)):
            peer.names += 1
            name = f"H{peer.names}" + "x" * rng.randrange(wire.MAX_NAME - 10)
            out.append(
                wire.pack_description(wire.SENDER_DESCRIPTION, rng.randrange(wire.MAX_IDS), name)
            )
        run.count("new_names", len(out))
        return b"".join(out)
    if kind == 2:  # ever-new type names
        out = []
        for _ in range(rng.randint(50, 400)):
            peer.names += 1
            out.append(
                wire.pack_description(
                    wire.TYPE_DESCRIPTION, rng.randrange(wire.MAX_IDS), f"T{peer.names}"
                )
            )
        run.count("new_names", len(out))
        return b"".join(out)
    if kind == 3:  # a flood of pings to a device the other side has
        sender, ping = rng.randrange(wire.MAX_IDS), rng.randrange(wire.MAX_IDS)
        head = wire.pack_description(wire.SENDER_DESCRIPTION, sender, served)
        head += wire.pack_description(wire.TYPE_DESCRIPTION, ping, codecs.PING)
        count = rng.randint(500, 5000)
        run.count("pings", count)
        return head + wire.pack_message(ping, sender) * count
    if kind == 4:  # reports for huge sensor ids, text with terminal controls
        sender, pose, text = 0, rng.randrange(wire.MAX_IDS), rng.randrange(wire.MAX_IDS)
        head = wire.pack_description(wire.SENDER_DESCRIPTION, sender, served)
        head += wire.pack_description(wire.TYPE_DESCRIPTION, pose, codecs.TRACKER_POS_QUAT)
        head += wire.pack_description(wire.TYPE_DESCRIPTION, text, codecs.TEXT_MESSAGE)
        sensor = rng.choice([1023, 1024, 65535, 2**31 - 1, -1, -(2**31)])
        body = struct.pack(">ii3d4d", sensor, 0, 1e308, -1e308, float("nan"), 0, 0, 0, 1)
        words = codecs.encode_text("\x1b[2J\x07\rhostile\x9b" * rng.randint(1, 40))[:1000]
        return head + (
            wire.pack_message(pose, sender, body) + wire.pack_message(text, sender, words)
        ) * rng.randint(1, 200)
    if kind == 5:  # garbage
        return arbitrary(rng, 8192)
    if kind == 6:  # an oversized or impossible header
        length = rng.choice([wire.HEADER_SIZE - 1, 0, 64_033, 1_000_000, 2**31, 2**32 - 1])
        return struct.pack(
            ">IiiiiI", length, 0, 0, rng.randrange(-5, 2000), rng.randrange(-5, 2000), 0
        ) + rng.randbytes(rng.randrange(4096))
    return mutate(rng, _seeds(), rng.choice([6, 24]))  # mutated valid streams


def hostile_datagram(run: Run) -> bytes:
    from gadgetctl.vrpn import wire

    return mutate(run.rng, _seeds(), 12)[: wire.MAX_DATAGRAM + run.rng.choice([0, 0, 200])]


def send_some(sock: socket.socket, data: bytes, timeout: float) -> bool:
    """Send ``data``; False when the peer closed or stopped reading for ``timeout`` s."""
    sock.settimeout(timeout)
    try:
        sock.sendall(data)
        return True
    except OSError:  # closed by the peer (garbage is refused), or it stopped reading
        return False


def drain(sock: socket.socket) -> bool:
    """Read what the peer sent (without waiting); False once it has closed."""
    sock.setblocking(False)
    try:
        while True:
            data = sock.recv(1 << 16)
            if not data:
                return False
    except BlockingIOError:
        return True
    except OSError:
        return False


# -- a hostile client against serve ------------------------------------------------------------


def _listening_port(serve: subprocess.Popen, timeout: float) -> int:
    import json

    assert serve.stdout is not None
    deadline = time.monotonic() + timeout
    text = b""
    while time.monotonic() < deadline:
        ready, _, _ = select.select([serve.stdout], [], [], 0.2)
        if ready:
            line = serve.stdout.readline()
            if not line:
                break
            text += line
            with contextlib.suppress(ValueError):
                event = json.loads(line)
                if event.get("event") == "listening":
                    return int(event["port"])
    raise PathFailure(f"serve did not start listening within {timeout:g} s: {text[-2000:]!r}")


class Watcher:
    """A well-behaved client of serve: when it last got a report."""

    def __init__(self, port: int) -> None:
        from gadgetctl.vrpn import VrpnClient

        self.client = VrpnClient(f"tcp://{LOOPBACK}:{port}", ["Waves"])
        self.last = time.monotonic()
        self.reports = 0
        self.longest = 0.0

    def pump(self) -> None:
        got = sum(1 for m in self.client.poll(0) if m.type == "vrpn_Tracker Pos_Quat")
        now = time.monotonic()
        if got:
            self.longest = max(self.longest, now - self.last)
            self.reports += got
            self.last = now

    def silent_for(self) -> float:
        return time.monotonic() - self.last


@path_target(
    "vrpn.serve_hostile_client",
    caps=(
        f"memory: serve's VmRSS with the hostile client at most {SERVE_MEMORY_FACTOR:g} x its "
        f"peak over 1 s with a well-behaved client only; time: that client gets a report at "
        f"least every {SERVE_ANSWER_CAP:g} s, serve stops within {EXIT_CAP:g} s of SIGTERM "
        "(exit 0, no traceback or raw control bytes on stderr)"
    ),
)
def _serve_hostile_client(run: Run) -> None:
    with tempfile.TemporaryDirectory(prefix="gadgetctl-fuzz-serve-") as tmp:
        config = Path(tmp) / "fuzz.jconf"
        config.write_text(SERVE_CONFIG)
        serve = gadgetctl(
            "serve", str(config), "--port", "0", "--bind", LOOPBACK, "--format", "json",
            stdout=subprocess.PIPE, stderr=open(Path(tmp) / "stderr", "wb"),  # noqa: SIM115
        )  # fmt: skip
        with killed_at_end(serve), PeakWatch(serve.pid) as memory:
            port = _listening_port(serve, 60.0)
            # its event lines (one per client that comes and goes) are read to the end, or
            # a full pipe would stop serve
            assert serve.stdout is not None
            events = threading.Thread(target=serve.stdout.read, name="serve events", daemon=True)
            events.start()
            watcher = Watcher(port)
            try:
                # the baseline: serve with a well-behaved client only, after its start-up
                warm = time.monotonic() + 2.0
                while time.monotonic() < warm:
                    watcher.pump()
                    time.sleep(0.005)
                if watcher.reports == 0:
                    raise PathFailure("serve sent a well-behaved client nothing in 2 s")
                memory.reset()
                calm = time.monotonic() + 1.0
                while time.monotonic() < calm:
                    watcher.pump()
                    time.sleep(0.005)
                baseline = memory.peak
                run.memory("baseline_mb", baseline)
                watcher.longest = 0.0
                _attack_serve(run, port, watcher, memory, baseline)
                run.figures["watcher_longest_gap_s"] = round(watcher.longest, 2)
            finally:
                watcher.client.close()
            run.memory("peak_mb", memory.peak)
            if serve.poll() is not None:
                raise PathFailure(f"serve ended during the attack (exit {serve.returncode})")
            serve.send_signal(signal.SIGTERM)
            began = time.monotonic()
            try:
                serve.wait(EXIT_CAP)
            except subprocess.TimeoutExpired:
                raise CapExceeded(
                    f"time cap exceeded: serve did not stop within {EXIT_CAP:g} s of SIGTERM"
                ) from None
            run.figures["stop_s"] = round(time.monotonic() - began, 2)
            events.join(10)
        check_stderr("serve", (Path(tmp) / "stderr").read_bytes())
        if serve.returncode != 0:
            raise PathFailure(f"serve exited {serve.returncode} after SIGTERM")


def _attack_serve(run: Run, port: int, watcher: Watcher, memory: PeakWatch, baseline: int) -> None:
    from gadgetctl.vrpn import wire

    peer = Peer()
    sock: socket.socket | None = None
    chunks = 0
    while run.left() > 0 or chunks < MIN_CHUNKS:
        chunks += 1
        if sock is None:
            sock = socket.create_connection((LOOPBACK, port), timeout=5)
            run.count("connections")
            if run.rng.randrange(20):  # now and then no cookie at all
                send_some(sock, wire.make_cookie(), 2.0)
        chunk = run.sent(hostile_chunk(run, peer, "Waves"))
        if not send_some(sock, chunk, 0.5) or not drain(sock):
            sock.close()
            sock = None
        watcher.pump()
        memory.sample()
        run.check_memory("serve", memory.peak, baseline, lambda b: int(b * SERVE_MEMORY_FACTOR))
        run.check_time(
            "a well-behaved client's wait for a report", watcher.silent_for(), SERVE_ANSWER_CAP
        )
    if sock is not None:
        sock.close()


# -- a hostile server against monitor vrpn: ----------------------------------------------------


class HostileServer:
    """A VRPN server on ``127.0.0.1:port`` (TCP and UDP, the port the OS picked for the UDP
    socket) that calls a lobbing client back and then sends what the target tells it."""

    def __init__(self) -> None:
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.udp.bind((LOOPBACK, 0))
        self.port = self.udp.getsockname()[1]
        self.session: socket.socket | None = None
        self.channel: tuple[str, int] | None = None  # the client's UDP channel
        self._decoder = None
        self._skip = 0  # bytes of the client's cookie still to pass over

    def close(self) -> None:
        self.udp.close()
        self.end_session()

    def end_session(self) -> None:
        if self.session is not None:
            self.session.close()
        self.session = None
        self.channel = None

    def poll(self, run: Run) -> None:
        """Answer a lob (a new session replaces the old one) and read the client's bytes."""
        from gadgetctl.vrpn import wire

        ready, _, _ = select.select(
            [self.udp] + ([self.session] if self.session else []), [], [], 0.002
        )
        if self.udp in ready:
            data, source = self.udp.recvfrom(2048)
            try:
                host, port = wire.parse_lob(data)
            except wire.LobError:
                return
            if host != LOOPBACK or source[0] != LOOPBACK:
                return  # never call back anything but loopback
            self.end_session()
            try:
                self.session = socket.create_connection((LOOPBACK, port), timeout=5)
            except OSError:
                return
            run.count("sessions")
            self.session.sendall(wire.make_cookie())
            self._decoder = wire.StreamDecoder()
            self._skip = wire.COOKIE_SIZE
        if self.session is not None and self.session in ready:
            try:
                data = self.session.recv(1 << 16)
            except OSError:
                data = b""
            if not data:
                self.end_session()
                return
            cut = min(self._skip, len(data))
            self._skip -= cut
            if data[cut:] and self._decoder is not None:
                try:
                    for message in self._decoder.feed(data[cut:]):
                        if message.type_id == wire.UDP_DESCRIPTION:
                            with contextlib.suppress(ValueError):
                                host, port = wire.decode_udp_description(message)
                                if host == LOOPBACK:
                                    self.channel = (host, port)
                except wire.FramingError:
                    self.end_session()

    def send(self, data: bytes) -> bool:
        if self.session is None:
            return False
        if not send_some(self.session, data, 0.5):
            self.end_session()
            return False
        return True

    def datagram(self, data: bytes) -> None:
        if self.channel is not None:
            with contextlib.suppress(OSError):
                self.udp.sendto(data, self.channel)


def _plain_reports(sensors: int = 2) -> bytes:
    from gadgetctl.vrpn import codecs, wire

    return b"".join(
        wire.pack_message(0, 0, codecs.encode_pose(s, (0.1 * s, 0.2, 0.3))) for s in range(sensors)
    )


def _describe_tracker() -> bytes:
    from gadgetctl.vrpn import codecs, wire

    return wire.pack_description(wire.SENDER_DESCRIPTION, 0, "Tracker0") + wire.pack_description(
        wire.TYPE_DESCRIPTION, 0, codecs.TRACKER_POS_QUAT
    )


@path_target(
    "vrpn.monitor_hostile_server",
    caps=(
        f"memory: monitor's VmRSS at most {MONITOR_MEMORY_FACTOR:g} x its peak over 1 s of plain "
        f"reports from the same server; time: monitor ends within {EXIT_CAP:g} s of SIGINT "
        f"(exit 0 or 1), stderr under {STDERR_CAP // 1024} KB with no traceback or raw "
        "control bytes"
    ),
)
def _monitor_hostile_server(run: Run) -> None:
    server = HostileServer()
    with tempfile.TemporaryDirectory(prefix="gadgetctl-fuzz-monitor-") as tmp:
        stderr_path = Path(tmp) / "stderr"
        # ended by SIGINT (Ctrl-C) once the attack is over: however slowly it started, it
        # watches the whole attack; --duration only bounds it should the signal be lost
        duration = run.seconds + 120
        monitor = gadgetctl(
            "monitor", f"vrpn:Tracker0@{LOOPBACK}:{server.port}", "--duration", f"{duration:g}",
            "--format", "ndjson", stderr=open(stderr_path, "wb"),  # noqa: SIM115
        )  # fmt: skip
        try:
            with killed_at_end(monitor), PeakWatch(monitor.pid) as memory:
                _play_monitor(run, server, monitor, memory)
                run.memory("peak_mb", memory.peak)
                if monitor.poll() is not None:
                    raise PathFailure(
                        f"monitor ended during the attack (exit {monitor.returncode})"
                    )
                monitor.send_signal(signal.SIGINT)
                began = time.monotonic()
                while monitor.poll() is None and time.monotonic() - began < EXIT_CAP:
                    server.poll(run)  # keep answering while it ends
                if monitor.poll() is None:
                    raise CapExceeded(
                        f"time cap exceeded: monitor did not end within {EXIT_CAP:g} s of SIGINT"
                    )
                run.figures["stop_s"] = round(time.monotonic() - began, 2)
        finally:
            server.close()
        check_stderr("monitor", stderr_path.read_bytes())
        if monitor.returncode not in (0, 1):
            raise PathFailure(
                f"monitor exited {monitor.returncode}: {stderr_path.read_bytes()[-1500:]!r}"
            )


def _play_monitor(
    run: Run, server: HostileServer, monitor: subprocess.Popen, memory: PeakWatch
) -> None:
    # plain reports until the client is connected and settled: the baseline
    plain_until: float | None = None
    baseline = 0
    described = None
    peer = Peer()
    chunks = 0
    while (run.left() > 0 or chunks < MIN_CHUNKS) and monitor.poll() is None:
        server.poll(run)
        if not baseline and run.left() < -CONNECT_CAP:
            raise CapExceeded(
                f"time cap exceeded: monitor was not connected and settled {CONNECT_CAP:g} s after the time was up"
            )
        if server.session is None:
            described = None
            continue
        if described is not server.session:
            server.send(_describe_tracker())
            described = server.session
        if plain_until is None:
            plain_until = time.monotonic() + 2.0
        now = time.monotonic()
        if now < plain_until:
            server.send(_plain_reports())
            time.sleep(0.01)
            if now > plain_until - 1.0 and not baseline:
                memory.reset()
                baseline = -1
            continue
        if baseline <= 0:
            baseline = memory.peak
            run.memory("baseline_mb", baseline)
        chunks += 1
        server.send(run.sent(hostile_chunk(run, peer, "Tracker0")) + _plain_reports())
        for _ in range(run.rng.randrange(20)):
            server.datagram(run.sent(hostile_datagram(run)))
        memory.sample()
        run.check_memory("monitor", memory.peak, baseline, lambda b: int(b * MONITOR_MEMORY_FACTOR))
    if not baseline:
        raise PathFailure("monitor never connected to the server")
