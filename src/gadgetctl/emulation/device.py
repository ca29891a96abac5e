"""A serial device on a pseudo-terminal: what every serial emulator shares.

:class:`PtyDeviceEmulator` owns the pty (and its optional symlink), a thread that reads the
driver's commands and sends records at ``rate`` a second, pausing, hanging up once the
driver has read what was sent, and the console lines (a driver opening and closing the
line, the scenario ending). A device emulator adds only its protocol:

* :meth:`~PtyDeviceEmulator.on_byte` (or :meth:`~PtyDeviceEmulator.on_bytes`) for what the
  driver writes;
* :meth:`~PtyDeviceEmulator.sending` (whether a record is wanted now: streaming on, a poll
  waiting) and :meth:`~PtyDeviceEmulator.emit` (write one record, or hang up);
* :meth:`~PtyDeviceEmulator.on_open` for what the device says at power-up.

:func:`pty_parser` and :func:`run_pty` are the command line every serial emulator's
``main`` shares (``--port`` link, ``--disconnect-after``, where-to-point lines).
"""

from __future__ import annotations

import argparse
import os
import select
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType
from typing import ClassVar, TypeVar

from gadgetctl.emulation.clients import OpenWatch, openers
from gadgetctl.emulation.command import (
    STANDARD_SCENARIOS,
    check_settings,
    emulator_parser,
    run,
)
from gadgetctl.emulation.console import Console
from gadgetctl.emulation.endpoints import PseudoTerminal

Self = TypeVar("Self", bound="PtyDeviceEmulator")


class PtyDeviceEmulator:
    """The device's side of a serial line on a pty pair; subclass it with the protocol.

    ``sent`` lists what each good record carried (the subclass appends), ``commands`` what
    the driver asked, ``dropped_bytes`` what the pty refused; ``disconnected`` is set once
    the ``disconnect`` scenario has hung up; ``console`` has the event lines."""

    #: The device's name on the console and in the thread's name.
    DEVICE: ClassVar[str] = "device"
    SCENARIOS: ClassVar[tuple[str, ...]] = STANDARD_SCENARIOS
    #: Seconds after a write before the pty's reader queue shows the bytes for sure (the
    #: kernel's flip buffer moves them a moment later).
    SETTLE: ClassVar[float] = 0.05
    #: Records sent at most in one turn of the loop when it fell behind.
    BURST: ClassVar[int] = 1
    #: How far behind the schedule may fall before records are skipped (seconds; None: one
    #: record's time, math.inf: never skip, send them all in bursts).
    CATCH_UP: ClassVar[float | None] = None
    #: Longest wait of the loop for the driver's bytes (seconds).
    POLL: ClassVar[float] = 0.05
    READ_SIZE: ClassVar[int] = 4096

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 100.0,
        *,
        disconnect_after: int = 20,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
        drain: float = 0.0,
    ) -> None:
        check_settings(scenario, self.SCENARIOS, rate)
        self.scenario = scenario
        self.rate = rate
        self.disconnect_after = disconnect_after
        #: seconds the hang-up waits for the driver to read what was sent
        self.linger = linger
        #: seconds stop() waits for the driver to read what was sent (a pty drops it on close)
        self.drain = drain
        self.link = Path(link) if link is not None else None
        self.address = ""
        self.commands: list[bytes] = []
        self.sent: list = []
        self.dropped_bytes = 0
        self.disconnected = threading.Event()
        #: set while records are wanted (streaming on; the subclass decides what that means)
        self.streaming = threading.Event()
        #: while True nothing is sent (a benchmark counts what was sent)
        self.paused = False
        #: clients (opens of the line) seen now
        self.clients = 0
        self.console = Console()
        self._pty = PseudoTerminal(self.link)
        self._watch: OpenWatch | None = None
        self._emit_lock = threading.Lock()
        self._written_at = 0.0
        self._next_due = 0.0
        self._hangup_due: float | None = None
        self._quiet = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- life cycle -----------------------------------------------------------------------

    def start(self: Self) -> Self:
        if self._thread is None:
            self.address = self._pty.open().address
            self._watch = OpenWatch(self.address)  # after our own open: only drivers count
            self.on_open()
            self._stop.clear()
            self._quiet.clear()
            name = f"{self.DEVICE.lower()}-emulator"
            self._thread = threading.Thread(target=self._run, name=name, daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Send nothing more, give a reading driver up to ``drain`` seconds to read what was
        sent, then close the pty and remove the link."""
        self._quiet.set()
        deadline = time.monotonic() + self.drain
        while self.draining() and time.monotonic() < deadline:
            time.sleep(0.005)
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._pty.close()
        if self._watch is not None:
            self._watch.close()
            self._watch = None

    def __enter__(self: Self) -> Self:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    def pause(self) -> None:
        """Send nothing more; returns once a record being sent is out, so ``sent`` is final."""
        with self._emit_lock:
            self.paused = True
        self.console.stopped_sending("paused")

    # -- writing --------------------------------------------------------------------------

    def send_raw(self, data: bytes) -> None:
        """Write bytes to the driver as they are (for tests)."""
        self.write(data)

    def write(self, data: bytes) -> None:
        self._written_at = time.monotonic()
        self.dropped_bytes += len(data) - self._pty.write(data)

    def unread(self) -> int:
        """Bytes sent that the driver has not read yet."""
        return self._pty.unread()

    def all_read(self) -> bool:
        """The driver has read (or its open discarded) everything sent, trusted once
        :attr:`SETTLE` seconds have passed since the last write."""
        return time.monotonic() - self._written_at >= self.SETTLE and not self.unread()

    # -- the scenario's end ---------------------------------------------------------------

    def draining(self) -> bool:
        """Whether stop() still waits: a driver has the records flowing and has not read
        them all."""
        return self.streaming.is_set() and not self.all_read()

    def probe_taken(self) -> bool:
        """For a device that talks without being asked: what :meth:`on_open` wrote is gone,
        read by a driver or discarded by its open, so a driver is there."""
        return self.all_read()

    def hang_up_once_read(self) -> bool:
        """Hang up once the driver has read what was sent, or ``linger`` seconds after the
        first call; False while still waiting (call again later)."""
        now = time.monotonic()
        if self._hangup_due is None:
            self._hangup_due = now + self.linger
        if not self.all_read() and now < self._hangup_due:
            return False
        self.hang_up()
        return True

    def hang_up(self) -> None:
        """Close the line now (the driver sees it go) and say so."""
        self.console.stopped_sending(f"hung up the line after {len(self.sent)} records")
        self.disconnected.set()
        self.streaming.clear()
        self._pty.hang_up()
        if self.clients:
            self.clients = 0
            self.console.client_disconnected(self.address, "line hung up")

    def begin_sending(self) -> None:
        """Records are wanted from now on, the first one at once (never faster than ``rate``)."""
        if not self.streaming.is_set():
            self._next_due = max(self._next_due, time.monotonic())
            self.streaming.set()

    # -- the protocol: what a device emulator overrides ------------------------------------

    def on_open(self) -> None:
        """The pty is open: send what the device says at power-up."""

    def on_bytes(self, data: bytes) -> None:
        for value in data:
            self.on_byte(value)

    def on_byte(self, value: int) -> None:
        """One byte from the driver."""

    def sending(self) -> bool:
        """Whether a record is wanted now (streaming on, a poll waiting)."""
        return self.streaming.is_set()

    def emit(self) -> None:
        """Write the next record (or hang up); called at ``rate`` while :meth:`sending`."""

    # -- the loop -----------------------------------------------------------------------------

    def _run(self) -> None:
        watch = self._watch
        while not self._stop.is_set() and self._pty.master >= 0:
            wait = self.POLL
            if self.sending():
                wait = max(0.0, min(wait, self._next_due - time.monotonic()))
            master = self._pty.master
            try:
                fds = [master] + ([watch.fileno()] if watch is not None and watch.available else [])
                ready, _, _ = select.select(fds, [], [], wait)
                if watch is not None and watch.fileno() in ready:
                    self._count_clients(*watch.poll())
                if master in ready:
                    self.on_bytes(os.read(master, self.READ_SIZE))
                with self._emit_lock:
                    self._send_due()
            except OSError:
                break

    def _send_due(self) -> None:
        period = 1.0 / self.rate
        catch_up = period if self.CATCH_UP is None else self.CATCH_UP
        for _ in range(self.BURST):
            now = time.monotonic()
            if self.paused or self._quiet.is_set() or self._pty.master < 0:
                return
            if not self.sending() or now < self._next_due:
                return
            self._next_due = max(self._next_due + period, now - catch_up)
            self.emit()

    def _count_clients(self, opens: int, closes: int) -> None:
        before = self.clients
        self.clients = max(0, before + opens - closes)
        if closes:  # merged events miscount: once a close is told, /proc is exact
            left = openers(self.address, frozenset({(os.getpid(), self._pty.slave)}))
            if left >= 0:
                self.clients = left
        elif opens:
            self.clients = max(self.clients, 1)
        if before == 0 and self.clients:
            self.console.client_connected(f"{self.address} opened")
        elif before and self.clients == 0:
            self.console.client_disconnected(f"{self.address} closed")


# -- the command line ---------------------------------------------------------------------------


def pty_parser(
    prog: str,
    description: str,
    *,
    default_link: str,
    rate: float,
    rate_help: str,
    disconnect_after: int,
    disconnect_help: str = "records before hang-up",
    scenarios: Sequence[str] = STANDARD_SCENARIOS,
    default_scenario: str = "motion",
) -> argparse.ArgumentParser:
    """:func:`emulator_parser` with ``--port`` (the link to make) and ``--disconnect-after``."""
    parser = emulator_parser(
        prog,
        description,
        scenarios=scenarios,
        default_scenario=default_scenario,
        rate=rate,
        rate_help=rate_help,
    )
    plugin = prog.split(".")[0]
    parser.add_argument(
        "--port",
        default=default_link,
        help=f"symlink to create pointing at the pty (default {default_link}, where "
        f"drivers/{plugin}/example.jconf looks; '' for none)",
    )
    parser.add_argument(
        "--disconnect-after", type=int, default=disconnect_after, help=disconnect_help
    )
    return parser


def run_pty(
    emulator: PtyDeviceEmulator,
    *,
    title: str,
    element: str,
    duration: float | None,
    property_name: str = "port",
    detail: str = "",
) -> int:
    """Run ``emulator`` (:func:`run`), printing where it is and how to point an ``element``
    at it; the ``disconnect`` scenario ends the run once the line is hung up."""

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        what = f"{emulator.scenario}, {detail}" if detail else emulator.scenario
        print(f"{title} emulator ({what}) on {emulator.address}", flush=True)
        tag = property_name
        print(f"point the {element} element at it: <{tag}>{where}</{tag}>", flush=True)

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=duration, announce=announce, check=check)


__all__ = [
    "STANDARD_SCENARIOS",
    "PtyDeviceEmulator",
    "pty_parser",
    "run_pty",
]
