"""The shared serial-device emulator base (`gadgetctl.emulation.device`) over a real pty:
commands in, records out at a rate, pause, the disconnect scenario's hang-up once the driver
has read everything, the console lines for a driver opening and closing the line, and the
clean-up of the link (issue 14 clean-up, issue 16 item 3)."""

from __future__ import annotations

import contextlib
import errno
import os
import select
import time

import pytest

from gadgetctl.emulation import Console, OpenWatch, PtyDeviceEmulator, pty_parser
from gadgetctl.emulation.clients import openers
from gadgetctl.input.testing import wait_until

pytestmark = pytest.mark.timeout(60)


class Counter(PtyDeviceEmulator):
    """A toy device: ``s`` starts streaming ``#<n>;`` records, ``h`` stops them."""

    DEVICE = "Counter"

    def on_byte(self, value: int) -> None:
        self.commands.append(bytes([value]))
        if value == ord("s"):
            self.begin_sending()
        elif value == ord("h"):
            self.streaming.clear()

    def emit(self) -> None:
        if self.scenario == "disconnect" and len(self.sent) >= self.disconnect_after:
            self.hang_up_once_read()
            return
        self.sent.append(len(self.sent))
        self.write(f"#{len(self.sent) - 1};".encode())


@pytest.fixture
def made():
    emulators: list[PtyDeviceEmulator] = []
    yield emulators
    for emulator in emulators:
        emulator.stop()


def open_line(address: str) -> int:
    return os.open(address, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)


def read_until(fd: int, done, timeout: float = 10.0) -> bytes:
    """Read ``fd`` until ``done(data)`` or end of the line (EOF, EIO); fails on timeout."""
    data = b""
    deadline = time.monotonic() + timeout
    while not done(data):
        left = deadline - time.monotonic()
        assert left > 0, f"timed out with {data!r}"
        ready, _, _ = select.select([fd], [], [], left)
        if not ready:
            continue
        try:
            chunk = os.read(fd, 4096)
        except BlockingIOError:
            continue
        except OSError as exc:
            if exc.errno == errno.EIO:  # the master side hung up
                break
            raise
        if not chunk:
            break
        data += chunk
    return data


def records(data: bytes) -> list[int]:
    return [int(part[1:]) for part in data.split(b";") if part.startswith(b"#")]


def test_commands_start_records_at_the_rate_in_order(made) -> None:
    emulator = Counter("motion", 200.0)
    made.append(emulator)
    emulator.start()
    fd = open_line(emulator.address)
    try:
        assert emulator.sent == []  # nothing before the device is asked
        os.write(fd, b"s")
        data = read_until(fd, lambda d: len(records(d)) >= 20)
        assert records(data)[:20] == list(range(20))
        assert emulator.commands[0] == b"s"
        os.write(fd, b"h")
        assert wait_until(lambda: not emulator.streaming.is_set())
    finally:
        os.close(fd)


def test_pause_makes_sent_final_and_says_so(made) -> None:
    emulator = Counter("motion", 500.0)
    made.append(emulator)
    emulator.start()
    fd = open_line(emulator.address)
    try:
        os.write(fd, b"s")
        data = read_until(fd, lambda d: len(records(d)) >= 5)
        emulator.pause()
        count = len(emulator.sent)
        more = bytearray()

        def drain() -> None:
            with contextlib.suppress(BlockingIOError):
                more.extend(os.read(fd, 4096))

        # all read and nothing written for a while: sending has stopped (at 500/s it would not)
        assert wait_until(emulator.all_read, timeout=10, step=drain)
        assert len(emulator.sent) == count
        assert records(data + bytes(more)) == list(range(count))
        assert "scenario stopped sending: paused" in emulator.console.lines
    finally:
        os.close(fd)


def test_disconnect_scenario_hangs_up_once_everything_was_read(made) -> None:
    emulator = Counter("disconnect", 300.0, disconnect_after=12, linger=5.0)
    made.append(emulator)
    emulator.start()
    fd = open_line(emulator.address)
    try:
        assert wait_until(lambda: emulator.clients == 1)
        os.write(fd, b"s")
        data = read_until(fd, lambda d: False, timeout=15)  # until the hang-up
    finally:
        os.close(fd)
    assert records(data) == list(range(12))  # nothing lost to the hang-up
    assert emulator.disconnected.is_set()
    # the driver may see the line go before the emulator's thread has said it
    gone = f"client disconnected: {emulator.address} (line hung up)"
    assert wait_until(lambda: gone in emulator.console.lines)
    assert emulator.console.lines == [
        f"client connected: {emulator.address} opened",
        "scenario stopped sending: hung up the line after 12 records",
        gone,
    ]


def test_console_says_when_a_driver_opens_and_closes_the_line(made) -> None:
    emulator = Counter("idle", 50.0)
    made.append(emulator)
    said: list[str] = []
    emulator.console.sink = said.append
    emulator.start()
    assert emulator.console.lines == []  # the emulator's own open does not count
    first = open_line(emulator.address)
    assert wait_until(lambda: said == [f"client connected: {emulator.address} opened"])
    second = open_line(emulator.address)  # a second opener is the same connection
    os.close(first)
    assert wait_until(lambda: emulator.clients == 1)  # one left: still connected
    os.close(second)
    assert wait_until(lambda: len(said) == 2)
    assert said[1] == f"client disconnected: {emulator.address} closed"


def test_link_is_made_and_removed_and_bad_settings_are_refused(tmp_path, made) -> None:
    link = tmp_path / "ttyCounter"
    emulator = Counter("idle", 10.0, link=link)
    made.append(emulator)
    with emulator:
        assert os.path.realpath(link) == emulator.address
        assert emulator.address.startswith("/dev/pts/")
    assert not os.path.lexists(link)
    with pytest.raises(ValueError, match="unknown scenario 'dance'"):
        Counter("dance")
    with pytest.raises(ValueError, match="rate must be positive"):
        Counter("idle", 0.0)


def test_open_watch_counts_opens_and_closes(tmp_path) -> None:
    path = tmp_path / "device"
    path.write_bytes(b"")
    watch = OpenWatch(path)
    seen = [0, 0]

    def gather() -> None:
        opens, closes = watch.poll()
        seen[0] += opens
        seen[1] += closes

    try:
        assert watch.available and watch.poll() == (0, 0)
        with open(path, "rb"):
            assert wait_until(lambda: seen == [1, 0], step=gather)
            assert openers(path) == 1
        assert wait_until(lambda: seen == [1, 1], step=gather)
        assert openers(path) == 0
    finally:
        watch.close()
    assert watch.poll() == (0, 0)  # closed: inert


def test_console_says_a_stop_once() -> None:
    console = Console()
    console.stopped_sending("paused")
    console.stopped_sending("hung up")
    assert console.lines == ["scenario stopped sending: paused"]


def test_pty_parser_has_the_serial_options() -> None:
    parser = pty_parser(
        "Counter_drv.emulator",
        "Emulate a counter.",
        default_link="/tmp/counter",
        rate=50.0,
        rate_help="records per second",
        disconnect_after=7,
    )
    args = parser.parse_args(["--scenario", "garbage", "--port", ""])
    assert (args.scenario, args.port, args.disconnect_after, args.rate) == ("garbage", "", 7, 50.0)
    assert "drivers/Counter_drv/example.jconf" in parser.format_help()
