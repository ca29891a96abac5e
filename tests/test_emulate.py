"""`gadgetctl emulate`: each bundled emulator run for real in a subprocess, and something
reading real data from where it says (a FIFO, a UDP port, a pty, a TCP port); Ctrl-C,
unknown names, plug-ins without an emulator, --list and option pass-through."""

from __future__ import annotations

import json
import os
import re
import selectors
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest
import serial

from conftest import write

pytestmark = pytest.mark.timeout(60)

JS_EVENT = struct.Struct("<IhBB")
JS_EVENT_INIT, JS_EVENT_BUTTON, JS_EVENT_AXIS = 0x80, 0x01, 0x02
BIRDNET_HEADER = struct.Struct(">HH4sBBBBHH")
MSG_WAKE_UP, RSP_WAKE_UP = 10, 20


class Emulation:
    """``gadgetctl ARGS`` in a subprocess, with its output read under timeouts."""

    def __init__(self, *args: str | Path) -> None:
        """``args`` start with the command: ``Emulation("emulate", "DTrack_drv", ...)``."""
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "gadgetctl", *map(str, args)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
        )
        self.output = ""

    def wait_for(self, pattern: str, timeout: float = 15.0) -> re.Match[str]:
        """Read stdout until ``pattern`` matches; fails on timeout or end of output."""
        regex = re.compile(pattern)
        deadline = time.monotonic() + timeout
        with selectors.DefaultSelector() as selector:
            selector.register(self.proc.stdout, selectors.EVENT_READ)
            while (match := regex.search(self.output)) is None:
                left = deadline - time.monotonic()
                assert left > 0, (
                    f"no {pattern!r} within {timeout} s; output so far: {self.output!r}"
                )
                if selector.select(left):
                    chunk = os.read(self.proc.stdout.fileno(), 4096)
                    assert chunk, (
                        f"emulator ended: {self.output!r} {self.proc.stderr.read().decode()!r}"
                    )
                    self.output += chunk.decode()
        return match

    def interrupt(self, timeout: float = 10.0) -> tuple[int, str]:
        """Ctrl-C, then its exit status and stderr."""
        self.proc.send_signal(signal.SIGINT)
        return self.finish(timeout)

    def finish(self, timeout: float = 15.0) -> tuple[int, str]:
        try:
            out, err = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.communicate(timeout=5)
            raise
        self.output += out.decode()
        return self.proc.returncode, err.decode()

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate(timeout=5)


@pytest.fixture
def emulate():
    started: list[Emulation] = []

    def run(*args: str | Path) -> Emulation:
        started.append(Emulation("emulate", *args))
        return started[-1]

    yield run
    for emulation in started:
        emulation.close()


# -- each bundled emulator, read for real ---------------------------------------------------


def test_joystick_fifo_delivers_js_events(emulate, tmp_path):
    fifo = tmp_path / "js0"
    emulation = emulate(
        "LinuxJoydev_drv", "--path", fifo, "--duration", "3", "--buttons", "4", "--axes", "2"
    )
    address = emulation.wait_for(r"<port_name>(.+)</port_name>").group(1)
    assert address == str(fifo)
    fd = os.open(address, os.O_RDONLY | os.O_NONBLOCK)
    data = b""
    try:
        deadline = time.monotonic() + 10
        with selectors.DefaultSelector() as selector:
            selector.register(fd, selectors.EVENT_READ)
            while len(data) < 8 * 8 and time.monotonic() < deadline:
                if selector.select(0.5):
                    try:
                        data += os.read(fd, 4096)
                    except BlockingIOError:
                        pass
    finally:
        os.close(fd)
    events = [JS_EVENT.unpack_from(data, i) for i in range(0, len(data) - len(data) % 8, 8)]
    assert len(events) >= 8, data
    # the kernel's order: one INIT event per button, then per axis, then live events
    assert [(e[2], e[3]) for e in events[:6]] == [
        *((JS_EVENT_INIT | JS_EVENT_BUTTON, n) for n in range(4)),
        *((JS_EVENT_INIT | JS_EVENT_AXIS, n) for n in range(2)),
    ]
    assert all(not e[2] & JS_EVENT_INIT for e in events[6:])
    assert emulation.finish() == (0, "")


def test_dtrack_sends_frames_to_the_given_udp_port(emulate):
    receiver = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        receiver.bind(("127.0.0.1", 0))
        receiver.settimeout(10)
        port = receiver.getsockname()[1]
        emulation = emulate("dtrack", "--port", port, "--duration", "3", "--rate", "50")
        assert emulation.wait_for(r"<receive_port>(\d+)</receive_port>").group(1) == str(port)
        datagram, sender = receiver.recvfrom(20000)
    finally:
        receiver.close()
    assert sender[0] == "127.0.0.1"
    lines = datagram.decode("ascii").split("\r\n")
    assert lines[0].startswith("fr ") and any(line.startswith("6d") for line in lines)
    assert emulation.finish()[0] == 0


def test_pinch_glove_answers_on_the_printed_pty(emulate, tmp_path):
    link = tmp_path / "pinchglove"
    emulation = emulate("PINCH_GLOVE", "--port", link, "--duration", "10")
    where = emulation.wait_for(r"<port>(.+)</port>").group(1)
    assert where == str(link) and os.path.realpath(link).startswith("/dev/pts/")
    with serial.Serial(where, 9600, timeout=5) as line:
        line.write(b"CL")  # the driver's first start-up query: left glove version
        reply = line.read_until(b"\x8f")
    assert reply == b"\x82PG-L 1.1\x8f"
    code, err = emulation.interrupt()
    assert code == 0 and "Traceback" not in err


def test_motion_star_accepts_a_client_on_the_printed_port(emulate):
    emulation = emulate("MotionStar_drv", "--port", "0", "--duration", "10")
    match = emulation.wait_for(r"<address>(.+)</address> <server_port>(\d+)</server_port>")
    host, port = match.group(1), int(match.group(2))
    assert host == "127.0.0.1"
    with socket.create_connection((host, port), timeout=5) as client:
        client.sendall(BIRDNET_HEADER.pack(1, 0, b"\0" * 4, MSG_WAKE_UP, 0, 3, 0, 0, 0))
        reply = b""
        while len(reply) < BIRDNET_HEADER.size:
            chunk = client.recv(BIRDNET_HEADER.size - len(reply))
            assert chunk, "the emulator closed the connection"
            reply += chunk
    assert BIRDNET_HEADER.unpack(reply)[3] == RSP_WAKE_UP
    code, err = emulation.interrupt()
    assert code == 0 and "Traceback" not in err


# -- Ctrl-C, names, pass-through ------------------------------------------------------------


@pytest.mark.parametrize(
    ("driver", "args", "ready"),
    [
        ("LinuxJoydev_drv", ("--path", "{tmp}/js0"), "Press Ctrl-C"),
        ("DTrack_drv", ("--port", "{udp}"), "Press Ctrl-C"),
        (
            "OptiTrack_drv",
            ("--port", "{udp}", "--group", "", "--command-port", "0"),
            "Press Ctrl-C",
        ),
        ("TUIO_drv", ("--port", "{udp}"), "Press Ctrl-C"),
        ("ElexolEther24_drv", ("--port", "0"), "Press Ctrl-C"),
        ("PinchGlove_drv", ("--port", "{tmp}/pinch"), "<port>"),
        ("MotionStar_drv", ("--port", "0"), "<server_port>"),
    ],
)
def test_ctrl_c_ends_cleanly(emulate, tmp_path, driver, args, ready):
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sink.bind(("127.0.0.1", 0))
        values = {"tmp": tmp_path, "udp": sink.getsockname()[1]}
        emulation = emulate(driver, *(a.format(**values) for a in args))
        emulation.wait_for(re.escape(ready))
        code, err = emulation.interrupt()
    finally:
        sink.close()
    assert code == 0, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err


def test_unknown_driver_exits_2_with_a_suggestion(cli):
    result = cli("emulate", "DTrak_drv")
    assert result.exit_code == 2
    assert result.stderr.startswith("gadgetctl: error: no driver plug-in named 'DTrak_drv'")
    assert (
        "did you mean DTrack_drv" in result.stderr and len(result.stderr.strip().splitlines()) == 1
    )


def test_plugin_without_emulator_exits_2(cli, tmp_path):
    write(
        tmp_path / "Quiet_drv" / "__init__.py",
        "GADGETCTL_API_VERSION = 1\n\ndef register(registry):\n    pass\n",
    )
    result = cli("emulate", "--driver-path", tmp_path, "quiet_drv")
    assert result.exit_code == 2
    assert "Quiet_drv" in result.stderr and "ships no emulator" in result.stderr
    assert "DTrack_drv" in result.stderr  # the ones that do


def test_list_shows_the_bundled_emulators(cli):
    result = cli("emulate", "--list")
    assert result.exit_code == 0
    for name in (
        "LinuxJoydev_drv",
        "DTrack_drv",
        "PinchGlove_drv",
        "MotionStar_drv",
        "OptiTrack_drv",
        "TUIO_drv",
        "ElexolEther24_drv",
    ):
        assert name in result.stdout
    listed = json.loads(cli("emulate", "--list", "--format", "json").stdout)["emulators"]
    dtrack = next(e for e in listed if e["plugin"] == "DTrack_drv")
    assert dtrack["element_types"] == ["dtrack"] and dtrack["path"].endswith(
        "DTrack_drv/emulator.py"
    )


def test_options_after_driver_go_to_the_emulator(cli):
    result = cli("emulate", "DTrack_drv", "--help")
    assert result.exit_code == 0
    assert "--command-port" in result.stdout and "--wait-for-start" in result.stdout
    bad = cli("emulate", "LinuxJoydev_drv", "--no-such-option")
    assert bad.exit_code == 2 and "unrecognized arguments: --no-such-option" in bad.stderr


def test_missing_driver_name(cli):
    result = cli("emulate")
    assert result.exit_code == 2 and "emulate --list" in result.stderr


def test_emulator_is_loaded_by_path_without_register(cli, tmp_path):
    plugin = tmp_path / "Odd_drv"
    write(
        plugin / "__init__.py",
        "GADGETCTL_API_VERSION = 1\nraise RuntimeError('__init__ must not run')\n\n"
        "def register(registry):\n    raise RuntimeError('register must not run')\n",
    )
    write(plugin / "protocol.py", "GREETING = 'odd device ready'\n")
    write(
        plugin / "emulator.py",
        '"""An odd emulator."""\nfrom .protocol import GREETING\n\n\n'
        "def main(argv):\n    print(GREETING, *argv)\n    return 0\n",
    )
    result = cli("emulate", "--driver-path", tmp_path, "Odd_drv", "--x", "1")
    assert result.exit_code == 0, result.stderr
    assert result.stdout == "odd device ready --x 1\n"
    assert "Odd_drv" not in {name.split(".")[0] for name in sys.modules}


def test_emulator_that_fails_to_import(cli, tmp_path):
    write(tmp_path / "Bad_drv" / "__init__.py", "GADGETCTL_API_VERSION = 1\n")
    write(tmp_path / "Bad_drv" / "emulator.py", "import no_such_module_anywhere\n")
    result = cli("emulate", "--driver-path", tmp_path, "Bad_drv")
    assert result.exit_code == 2
    assert "No module named 'no_such_module_anywhere'" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
