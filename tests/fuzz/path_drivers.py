"""Path targets of the drivers, through the input manager: floods of mutated datagrams to each
UDP driver (``udp.*``) and mutated byte streams on a pty to each serial driver
(``serial.*``), in the target's own process. Loopback and ptys only.

Inputs: the parser targets' seeds of the driver (emulator records and conformance fixtures'
bytes, :mod:`fuzz.targets`), mutated by :func:`fuzz.inputs.generate`; a serial driver reads
its emulator's own stream, each write mutated now and then, with junk and bursts between.

Checks, each a failure of the run:

- nothing faults with an internal error: a device's fault whose reason is a Python error
  (IndexError, RecursionError, struct.error...: not a modelled driver error or an OS
  error), an exception in any thread, a log record with a traceback; a UDP device must not
  fault at all (bad datagrams are counted, never a fault);
- nothing goes uncounted: after each burst every datagram sent is read or dropped by the
  kernel, each read one judged decoded or bad, once (the datagram ledger);
- nothing grows: the process's resident memory stays within ``GROWTH_CAP`` of its memory after
  the warm-up; one frame (``InputManager.update``) takes at most ``FRAME_CAP`` seconds; a burst
  is accounted for within ``ACCOUNT_CAP`` seconds.
"""

from __future__ import annotations

import builtins
import contextlib
import importlib
import logging
import re
import socket
import tempfile
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from fuzz.inputs import arbitrary, generate, mutate
from fuzz.memory import MB, PeakWatch
from fuzz.paths import CapExceeded, PathFailure, Run, path_target

REPO = Path(__file__).resolve().parents[2]
DRIVERS = REPO / "drivers"
LOOPBACK = "127.0.0.1"

#: resident memory a driver target may add after its warm-up
GROWTH_CAP = 64 * MB
#: seconds of warm-up before the memory baseline is taken (at most a quarter of the run)
WARM_UP = 3.0
#: seconds one frame of the input manager may take
FRAME_CAP = 2.0
#: the same for a serial driver: a frame that retries a device's start includes its setup
#: with the device (PinchGlove's is bounded at 6 s, the others' shorter)
SERIAL_FRAME_CAP = 10.0
#: seconds within which every datagram of a burst must be accounted for
ACCOUNT_CAP = 10.0
#: bursts sent however short the time (a loaded machine's slow start still floods)
MIN_BURSTS = 3
#: frames a serial target runs however short the time
MIN_FRAMES = 20
#: the largest datagram sent (UDP's limit on loopback is 65,507 bytes)
MAX_DATAGRAM = 65_000

#: Python's own exceptions, less the OS errors (a line that hangs up is a modelled fault)
INTERNAL_ERRORS = {
    name
    for name, value in vars(builtins).items()
    if isinstance(value, type) and issubclass(value, BaseException)
    and not issubclass(value, OSError)
} | {"error"}  # fmt: skip

DRIVER_CAPS = (
    f"memory: the process's VmRSS at most {GROWTH_CAP // MB} MB over its memory after the "
    "warm-up; time: one frame at most {frame:g} s"
)


def internal_error(reason: str | None) -> bool:
    """Whether a device's fault reason (``Type: message``) is a Python error, not a modelled one."""
    if not reason:
        return False
    head = reason.split(":", 1)[0].strip()
    return head in INTERNAL_ERRORS


#: warnings Python shows on stderr by default (the others are hidden unless asked for)
_SILENT_WARNINGS = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


class Witness:
    """Exceptions in threads, log records with a traceback and warnings that would reach
    stderr (numpy's on hostile numbers, issue 24 items 6 and 13) while the path runs."""

    def __init__(self) -> None:
        self.errors: list[str] = []

    @contextlib.contextmanager
    def watching(self) -> Iterator[Witness]:
        old_hook = threading.excepthook

        def hook(args: threading.ExceptHookArgs) -> None:
            self.errors.append(
                f"{args.exc_type.__name__} in thread {args.thread.name if args.thread else '?'}: {args.exc_value}"
            )

        class Handler(logging.Handler):
            def emit(inner, record: logging.LogRecord) -> None:
                if record.exc_info or record.levelno >= logging.CRITICAL:
                    self.errors.append(f"log {record.name}: {record.getMessage()[:300]}")

        def show(message, category, filename, lineno, file=None, line=None) -> None:
            if not issubclass(category, _SILENT_WARNINGS):
                self.errors.append(
                    f"{category.__name__} on stderr: {message} ({filename}:{lineno})"
                )

        handler = Handler(logging.WARNING)
        threading.excepthook = hook
        logging.getLogger().addHandler(handler)
        old_show = warnings.showwarning
        warnings.showwarning = show
        try:
            yield self
        finally:
            warnings.showwarning = old_show
            threading.excepthook = old_hook
            logging.getLogger().removeHandler(handler)

    def check(self) -> None:
        if self.errors:
            raise PathFailure(f"internal error: {self.errors[0]}")


@contextlib.contextmanager
def manager_of(
    driver: str, body: str | None = None, text: str | None = None, *, retry: float | None = None
) -> Iterator:
    """A running input manager of one configuration (``body``: elements for ``driver``;
    ``text``: a whole file), shut down at the end. Without ``retry`` (seconds between
    retries of a device that failed to start) nothing may be left pending."""
    from gadgetctl.input import InputManager, ManagerOptions
    from gadgetctl.input.testing.configs import configuration

    with tempfile.TemporaryDirectory(prefix="gadgetctl-fuzz-") as tmp:
        path = Path(tmp) / "fuzz.jconf"
        path.write_text(text if text is not None else configuration(driver, body or ""))
        options = ManagerOptions(retry_interval=retry, entry_points=False)
        manager, loaded = InputManager.from_files([path], options=options)
        try:
            manager.configure(loaded)
            pending = [(p.name, p.message) for p in manager.pending()]
            if pending and retry is None:
                raise PathFailure(f"the configuration is pending: {pending}")
            yield manager
        finally:
            manager.shutdown()


class Frames:
    """Runs frames of ``manager``, each against the time cap, and watches memory and faults."""

    def __init__(self, run: Run, manager, memory: PeakWatch, witness: Witness, udp: bool) -> None:
        self.run = run
        self.manager = manager
        self.memory = memory
        self.witness = witness
        self.udp = udp
        self.frame_cap = FRAME_CAP if udp else SERIAL_FRAME_CAP
        self.baseline: int | None = None
        self.warm_until = run.started + min(WARM_UP, run.seconds / 4)

    def frame(self) -> None:
        began = time.monotonic()
        self.manager.update()
        self.run.check_time(
            "a frame of the input manager", time.monotonic() - began, self.frame_cap
        )
        self.run.count("frames")
        self.check()

    def check(self) -> None:
        self.witness.check()
        for name, device in self.manager.devices.items():
            if internal_error(device.error):
                raise PathFailure(f"{name} faulted with an internal error: {device.error}")
            if self.udp and device.faults:
                raise PathFailure(f"{name} faulted on datagrams: {device.error}")
        self.memory.sample()
        now = time.monotonic()
        if self.baseline is None:
            if now >= self.warm_until:
                self.baseline = self.memory.last
                self.memory.reset()
                self.run.memory("baseline_mb", self.baseline)
                self.run.memory("peak_mb", self.baseline)
            return
        self.run.memory("peak_mb", self.memory.peak)
        self.run.check_memory(
            "the driver's process", self.memory.peak, self.baseline, lambda b: b + GROWTH_CAP
        )

    def until(self, done: Callable[[], bool], cap: float, what: str) -> None:
        began = time.monotonic()
        while not done():
            if time.monotonic() - began > cap:
                raise CapExceeded(f"time cap exceeded: {what} not within {cap:g} s")
            self.frame()
            time.sleep(0.001)


def _no_peer_timeout(manager) -> None:
    for device in manager.devices.values():
        if hasattr(device, "peer_timeout"):
            device.peer_timeout = 3600.0  # a flood of bad datagrams is no silence


# -- UDP drivers ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class UdpCase:
    driver: str
    #: the elements for a device named "D" (its port, or the board's address, given)
    element: Callable[[int], str]
    seeds: Callable[[], list[bytes]]


def _target_seeds(name: str) -> Callable[[], list[bytes]]:
    def seeds() -> list[bytes]:
        from fuzz.targets import TARGETS

        return TARGETS[name].seeds()

    return seeds


def _optitrack_element(port: int) -> str:
    return (
        f'<optitrack name="D" version="2"><port>{port}</port><natnet_version>4.1</natnet_version>'
        '<rigid_body><optitrack_rigid_body name="D B0" version="1"><body_index>1</body_index>'
        "</optitrack_rigid_body></rigid_body></optitrack>\n"
    )


UDP_CASES = {
    "udp.dtrack": UdpCase(
        "DTrack_drv",
        lambda port: f'<dtrack name="D" version="1"><receive_port>{port}</receive_port></dtrack>\n',
        _target_seeds("dtrack.datagram"),
    ),
    "udp.optitrack": UdpCase("Optitrack_drv", _optitrack_element, _target_seeds("natnet.frame")),
    "udp.tuio": UdpCase(
        "TUIO_drv",
        lambda port: (
            f'<TUIO_drv name="D" version="1"><points>10</points><port>{port}</port></TUIO_drv>\n'
        ),
        _target_seeds("tuio.datagram"),
    ),
}


def _udp_burst(run: Run, seeds: list[bytes]) -> list[bytes]:
    rng = run.rng
    burst = []
    for _ in range(rng.randint(1, 300)):
        kind = rng.randrange(50)
        data = arbitrary(rng, MAX_DATAGRAM) if kind == 0 else generate(rng, seeds)
        burst.append(run.sent(data[:MAX_DATAGRAM]))
    return burst


def _ledger_delta(before: dict[str, int], after: dict[str, int]) -> tuple[int, int, int]:
    """Datagrams read, dropped by the kernel and judged (decoded or bad) between two readings
    of a ledger's counters."""
    arrived = after["datagrams"] - before["datagrams"]
    dropped = after["kernel_dropped"] - before["kernel_dropped"]
    judged = (after["decoded"] + after["bad_datagrams"]) - (
        before["decoded"] + before["bad_datagrams"]
    )
    return arrived, dropped, judged


def _flood(
    run: Run, manager, device_name: str, send: Callable[[list[bytes]], None], seeds: list[bytes]
) -> None:
    """Bursts of mutated datagrams until the time is up, each accounted for in the ledger."""
    device = manager.device(device_name)
    ledger = device.datagram_ledger()
    if ledger is None:
        raise PathFailure(f"{device_name} keeps no datagram ledger")
    witness = Witness()
    with witness.watching(), PeakWatch() as memory:
        frames = Frames(run, manager, memory, witness, udp=True)
        bursts = 0
        while run.left() > 0 or bursts < MIN_BURSTS:
            bursts += 1
            before = ledger.counters()
            burst = _udp_burst(run, seeds)
            send(burst)

            def accounted(before=before, sent=len(burst)) -> bool:
                arrived, dropped, judged = _ledger_delta(before, ledger.counters())
                return arrived + dropped >= sent and judged >= arrived

            frames.until(
                accounted,
                ACCOUNT_CAP,
                f"{len(burst)} datagrams accounted for (read or dropped, each judged)",
            )
            after = ledger.counters()
            arrived, dropped, judged = _ledger_delta(before, after)
            if arrived + dropped != len(burst) or judged != arrived:
                raise PathFailure(
                    f"datagrams miscounted: {len(burst)} sent, {arrived} read, {dropped} dropped by "
                    f"the kernel, {judged} judged ({before} -> {after})"
                )
            run.count("decoded", after["decoded"] - before["decoded"])
            run.count("bad", after["bad_datagrams"] - before["bad_datagrams"])
            run.count("kernel_dropped", dropped)
        frames.check()


def _send_to(port: int) -> Callable[[list[bytes]], None]:
    def send(burst: list[bytes]) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for data in burst:
                tx.sendto(data, (LOOPBACK, port))

    return send


def _udp_runner(name: str, case: UdpCase) -> Callable[[Run], None]:
    def run_case(run: Run) -> None:
        from gadgetctl.input.testing.configs import free_udp_port

        port = free_udp_port()
        with manager_of(case.driver, case.element(port)) as manager:
            _no_peer_timeout(manager)
            _flood(run, manager, "D", _send_to(port), case.seeds())

    return run_case


for _name, _case in UDP_CASES.items():
    path_target(
        _name,
        caps=DRIVER_CAPS.format(frame=FRAME_CAP)
        + f"; every datagram read or dropped and judged within {ACCOUNT_CAP:g} s; no fault",
    )(_udp_runner(_name, _case))


@path_target(
    "udp.ether24",
    caps=DRIVER_CAPS.format(frame=FRAME_CAP)
    + f"; every reply read or dropped and judged within {ACCOUNT_CAP:g} s; no fault",
)
def _ether24(run: Run) -> None:
    """A board on loopback that answers nothing the driver asks and floods it with replies."""
    seeds = _target_seeds("ether24.reply")()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as board:
        board.bind((LOOPBACK, 0))
        board.settimeout(10.0)
        host, port = board.getsockname()
        body = (
            f'<elexol_ether24 name="D" version="1"><ip_address>{host}:{port}</ip_address>'
            "<config_method>static_ip</config_method></elexol_ether24>\n"
        )
        with manager_of("ElexolEther24_drv", body) as manager:
            _no_peer_timeout(manager)
            _request, driver_address = board.recvfrom(64)  # the driver's first write

            def send(burst: list[bytes]) -> None:
                board.setblocking(False)
                with contextlib.suppress(BlockingIOError):
                    while board.recv(4096):  # what the driver asked since
                        pass
                for data in burst:
                    board.sendto(data, driver_address)

            _flood(run, manager, "D", send, seeds)


@path_target(
    "udp.vrpn_drv",
    caps=DRIVER_CAPS.format(frame=FRAME_CAP)
    + f"; every datagram on its UDP channel read or dropped and judged within {ACCOUNT_CAP:g} s; no fault",
)
def _vrpn_drv(run: Run) -> None:
    """VRPN_drv connected to a library server that reports nothing; its UDP channel flooded."""
    from gadgetctl.vrpn import VrpnServer, wire

    from fuzz.targets import _vrpn_seeds

    seeds = [s[wire.COOKIE_SIZE :] if s.startswith(b"vrpn:") else s for s in _vrpn_seeds()]
    server = VrpnServer(LOOPBACK, 0)
    server.register_sender("Tracker0")
    server.start()
    stop = threading.Event()
    thread = threading.Thread(target=server.serve_forever, args=(stop, 0.02), daemon=True)
    thread.start()
    body = (
        f'<vrpn name="D" version="3"><tracker_server>Tracker0@{LOOPBACK}:{server.port}</tracker_server>'
        "<button_server></button_server><analog_server></analog_server>"
        "<tracker_count>2</tracker_count><button_count>0</button_count>"
        "<analog_count>0</analog_count><min>-1.0</min><max>1.0</max></vrpn>\n"
    )
    try:
        with manager_of("VRPN_drv", body) as manager:
            device = manager.device("D")

            def channel() -> socket.socket | None:
                clients = device._input.clients if device._input is not None else {}
                return next((c._udp_in for c in clients.values() if c._udp_in is not None), None)

            deadline = time.monotonic() + 15
            while channel() is None:
                if time.monotonic() > deadline:
                    raise PathFailure("VRPN_drv opened no UDP channel within 15 s")
                manager.update()
                time.sleep(0.005)
            udp = channel()
            assert udp is not None
            _flood(run, manager, "D", _send_to(udp.getsockname()[1]), seeds)
    finally:
        stop.set()
        thread.join(5)
        server.close()


# -- serial drivers --------------------------------------------------------------------------------

#: the serial drivers (an emulator on a pty) and the parser target whose seeds they also get
SERIAL_CASES = {
    "serial.dataglove": ("DataGlove_drv", "dataglove.packets"),
    "serial.ultraglove": ("DataGloveUltraWireless_drv", None),
    "serial.fastrak": ("Fastrak_drv", "fastrak.records"),
    "serial.flock": ("Flock_drv", "flock.records"),
    "serial.ibox": ("IBox_drv", "ibox.packets"),
    "serial.is900": ("IS900_drv", "is900.records"),
    "serial.pinchglove": ("PinchGlove_drv", "pinchglove.stream"),
    "serial.serialencoder": ("SerialEncoder_drv", "serialencoder.replies"),
    "serial.spaceball": ("SpaceBall_drv", "spaceball.records"),
    "serial.three_d_mouse": ("ThreeDMouse_drv", "three_d_mouse.reports"),
    "serial.wanda": ("Wanda_drv", "wanda.packets"),
}
_PTY_PORT = re.compile(r"<port>/tmp/gadgetctl-[^<]*</port>")


def pty_emulator_class(driver: str) -> type | None:
    """The driver's emulator class on a pty (a PtyDeviceEmulator), if it has one."""
    from gadgetctl.emulation.device import PtyDeviceEmulator

    module = importlib.import_module(f"{driver}.emulator")
    for value in vars(module).values():
        if (
            isinstance(value, type)
            and issubclass(value, PtyDeviceEmulator)
            and value is not PtyDeviceEmulator
            and value.__module__ == module.__name__
        ):
            return value
    return None


class Mutator:
    """Replaces an emulator's ``write``: some writes mutated, junk and bursts between, the
    parser target's seeds mutated now and then (its own random source: it runs in the
    emulator's thread)."""

    def __init__(self, run: Run, write: Callable[[bytes], None], seeds: list[bytes]) -> None:
        import random

        self.rng = random.Random(run.rng.getrandbits(64))
        self.run = run
        self.write = write
        self.seeds = seeds
        #: set: mutate (from the start in half the runs, the handshake too; else once the
        #: device runs)
        self.armed = threading.Event()
        if run.rng.randrange(2):
            self.armed.set()

    def __call__(self, data: bytes) -> None:
        if not self.armed.is_set():
            self.write(data)
            return
        rng = self.rng
        roll = rng.random()
        if roll < 0.25:
            data = mutate(rng, [data], 4)
        elif roll < 0.30:
            data = arbitrary(rng, 512) + data
        elif roll < 0.32:
            data = data * rng.randint(2, 60)
        elif roll < 0.37 and self.seeds:
            data = generate(rng, self.seeds)[:4096] + data
        self.run.sent(data)
        self.write(data)


def _serial_runner(driver: str, parser_target: str | None) -> Callable[[Run], None]:
    def run_case(run: Run) -> None:
        kind = pty_emulator_class(driver)
        if kind is None:
            raise PathFailure(f"{driver} has no pty emulator")
        seeds = _target_seeds(parser_target)() if parser_target else []
        scenario = "motion" if "motion" in kind.SCENARIOS else kind.SCENARIOS[0]
        emulator = kind(scenario)
        mutator = Mutator(run, emulator.write, seeds)
        emulator.write = mutator
        example = (DRIVERS / driver / "example.jconf").read_text()
        witness = Witness()
        with witness.watching(), emulator:
            text, found = _PTY_PORT.subn(f"<port>{emulator.address}</port>", example)
            if found != 1:
                raise PathFailure(f"{driver}/example.jconf has {found} pty ports, not one")
            with manager_of(driver, text=text, retry=0.5) as manager, PeakWatch() as memory:
                frames = Frames(run, manager, memory, witness, udp=False)
                while run.left() > 0 or run.figures.get("frames", 0) < MIN_FRAMES:
                    frames.frame()
                    if not mutator.armed.is_set() and not manager.pending():
                        mutator.armed.set()
                    time.sleep(0.002)
                run.count("pending_at_end", len(manager.pending()))
                for device in manager.devices.values():
                    run.count("faults", device.faults)
                    run.count("samples", device.store.total())
                frames.check()

    return run_case


for _name, (_driver, _parser) in SERIAL_CASES.items():
    path_target(
        _name, caps=DRIVER_CAPS.format(frame=SERIAL_FRAME_CAP) + "; no fault with an internal error"
    )(_serial_runner(_driver, _parser))
