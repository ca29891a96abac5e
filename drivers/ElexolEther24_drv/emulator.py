"""An Elexol Ether I/O 24 board emulated on loopback UDP: the board's side of the protocol.

Knows nothing of gadgetctl's input manager (the command line comes from the shared emulator
scaffolding, :mod:`gadgetctl.emulation`). It listens on ``127.0.0.1:port`` only, answers port
reads (``'a'``-``'c'``) with the levels of its 24 lines, keeps port and register writes in
``writes``, and answers a unicast ``IO24`` with its identity (never broadcast).

Scenarios (the lines change ``rate`` times a second): ``idle`` (a fixed pattern), ``motion``
(the three ports count up), ``buttons`` (one line after the other goes high, 0 to 23),
``garbage`` (``motion``, and before each reply a datagram that is no reply: a wrong length or
an unknown port letter) and ``disconnect`` (answers for ``disconnect_after`` changes of the
lines, then closes).

Run ``python emulator.py --help`` (or ``gadgetctl emulate ElexolEther24_drv``) for the command line.
"""

from __future__ import annotations

import select
import socket
import sys
import threading
import time

from gadgetctl.emulation import Console, emulator_parser, run
from gadgetctl.emulation.command import ended
from gadgetctl.emulation.network import LOOPBACK, STANDARD_SCENARIOS, Peers
from gadgetctl.transport.udp import bind_named

SCENARIOS = STANDARD_SCENARIOS
IDLE_PATTERN = (0xA5, 0x0F, 0x81)
MAC = bytes([0x00, 0x0A, 0xBC, 0x12, 0x34, 0x56])


def port_values(step: int, scenario: str) -> tuple[int, int, int]:
    """The levels of ports A, B, C at ``step``."""
    if scenario == "idle":
        return IDLE_PATTERN
    if scenario == "buttons":
        line = step % 24
        return tuple((1 << (line % 8)) if line // 8 == p else 0 for p in range(3))  # type: ignore[return-value]
    return (step & 0xFF, (step >> 8) & 0xFF, (255 - step) & 0xFF)


class Ether24Emulator:
    """A board on ``127.0.0.1:port`` (0: chosen by the OS, see ``port`` after ``start``)."""

    def __init__(
        self,
        port: int = 2424,
        *,
        scenario: str = "buttons",
        rate: float = 20.0,
        disconnect_after: int = 10,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        if not 0 <= port < 65536:
            raise ValueError("port must be between 0 and 65535")
        self.port = port
        self.scenario = scenario
        self.rate = rate
        self.disconnect_after = disconnect_after
        self.writes: list[bytes] = []
        self.reads = 0
        self.garbage_sent = 0
        self.error: BaseException | None = None
        self.finished = threading.Event()
        self.console = Console()
        self._peers = Peers(self.console)
        self._sock: socket.socket | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._start = time.monotonic()

    @property
    def address(self) -> str:
        return f"{LOOPBACK}:{self.port}"

    def step(self) -> int:
        return int((time.monotonic() - self._start) * self.rate)

    def start(self) -> Ether24Emulator:
        if self._thread is not None:
            return self
        self._stop.clear()
        self.finished.clear()
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        bind_named(sock, LOOPBACK, self.port)
        self.port = sock.getsockname()[1]
        self._sock = sock
        self._start = time.monotonic()
        self._thread = threading.Thread(target=self._serve, name="ether24-emulator", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout: float = 2.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def __enter__(self) -> Ether24Emulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _serve(self) -> None:
        sock = self._sock
        assert sock is not None
        try:
            while not self._stop.is_set():
                step = self.step()
                if self.scenario == "disconnect" and step >= self.disconnect_after:
                    self.console.stopped_sending(f"stopped answering after {step} steps")
                    return
                if not select.select([sock], [], [], 0.01)[0]:
                    continue
                data, peer = sock.recvfrom(64)
                self._peers.heard(peer)
                self._answer(sock, data, peer, step)
        except OSError as exc:
            if not self._stop.is_set():
                self.error = exc
        finally:
            if self.scenario == "disconnect" and self._sock is not None:
                self._sock.close()
                self._sock = None
            self.finished.set()

    def _answer(self, sock: socket.socket, data: bytes, peer: tuple, step: int) -> None:
        if data == b"IO24":
            sock.sendto(b"IO24" + MAC + bytes([0x01, 0x05]), peer)
            return
        if len(data) == 1 and ord("a") <= data[0] <= ord("c"):
            port = data[0] - ord("a")
            self.reads += 1
            if self.scenario == "garbage":
                junk = b"Z\x00" if self.garbage_sent % 2 else b"A\x01\x02"
                sock.sendto(junk, peer)
                self.garbage_sent += 1
            value = port_values(step, self.scenario)[port]
            sock.sendto(bytes([ord("A") + port, value]), peer)
            return
        self.writes.append(data)


def main(argv: list[str] | None = None) -> int:
    """Command line: answer until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "ElexolEther24_drv.emulator",
        "Emulate an Elexol Ether I/O 24 board on loopback UDP.",
        scenarios=SCENARIOS,
        default_scenario="buttons",
        rate=20.0,
        rate_help="changes of the lines per second (default 20)",
    )
    parser.add_argument(
        "--port", type=int, default=2424, help="UDP port on 127.0.0.1 to listen on (default 2424)"
    )
    parser.add_argument("--disconnect-after", type=int, default=10, metavar="N")
    args = parser.parse_args(argv)
    try:
        emulator = Ether24Emulator(
            args.port,
            scenario=args.scenario,
            rate=args.rate,
            disconnect_after=args.disconnect_after,
        )
    except ValueError as exc:
        parser.error(str(exc))

    def announce() -> None:
        print(f"Ether I/O 24 emulator ({args.scenario}) listening on {emulator.address}")
        print(
            "Point the elexol_ether24 element at it: <config_method>static_ip</config_method> "
            f"<ip_address>{emulator.address}</ip_address>"
        )
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
