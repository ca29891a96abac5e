"""`gadgetctl emulate` says when a client connects and disconnects and when the scenario stops
sending, one plain line each (issue 16 item 3): over a pty (a driver opening and closing the
line, the disconnect scenario hanging up), TCP (accept and close), UDP (the first datagram of
a peer; the disconnect scenario closing its socket). Each emulator runs in a subprocess."""

from __future__ import annotations

import re
import socket

import pytest
import serial
from test_emulate import Emulation

pytestmark = pytest.mark.timeout(90)


@pytest.fixture
def emulate():
    started: list[Emulation] = []

    def run(*args: object) -> Emulation:
        started.append(Emulation("emulate", *map(str, args)))
        return started[-1]

    yield run
    for emulation in started:
        emulation.close()


def test_pty_emulator_says_a_driver_opening_and_closing_the_line(emulate, tmp_path) -> None:
    link = tmp_path / "fastrak"
    emulation = emulate("Fastrak_drv", "--port", link, "--scenario", "idle", "--duration", "60")
    where = emulation.wait_for(r"<port>(.+)</port>").group(1)
    pts = emulation.wait_for(r"emulator \(idle\) on (/dev/pts/\d+)").group(1)
    assert "client connected" not in emulation.output  # the emulator's own open is not one
    with serial.Serial(where, 9600, timeout=5):
        emulation.wait_for(re.escape(f"client connected: {pts} opened"))
    emulation.wait_for(re.escape(f"client disconnected: {pts} closed"))
    code, err = emulation.interrupt()
    assert code == 0 and "Traceback" not in err


def test_pty_disconnect_scenario_says_it_stopped_and_hung_up(emulate, tmp_path) -> None:
    link = tmp_path / "fastrak"
    emulation = emulate(
        "Fastrak_drv",
        "--port",
        link,
        "--scenario",
        "disconnect",
        "--disconnect-after",
        "4",
        "--duration",
        "60",
    )
    where = emulation.wait_for(r"<port>(.+)</port>").group(1)
    pts = emulation.wait_for(r"on (/dev/pts/\d+)").group(1)
    with serial.Serial(where, 9600, timeout=0.2) as line:
        emulation.wait_for(re.escape(f"client connected: {pts} opened"))
        line.write(b"fC")  # binary records, continuous output: the scenario starts
        got = b""
        with pytest.raises(OSError):  # the hang-up ends the reads (SerialException is one)
            while len(got) < 10_000:  # what waits only: a longer read loses it at the hang-up
                got += line.read(max(1, line.in_waiting))
    assert got.count(b"\r\n") == 4  # the four records, read before the line went
    emulation.wait_for(re.escape("scenario stopped sending: hung up the line after 4 records"))
    emulation.wait_for(re.escape(f"client disconnected: {pts} (line hung up)"))
    code, err = emulation.finish()
    assert code == 0 and "Traceback" not in err
    assert emulation.output.count("scenario stopped sending") == 1


def test_tcp_emulator_says_accept_and_close(emulate) -> None:
    emulation = emulate("MotionStar_drv", "--port", "0", "--duration", "60")
    port = int(emulation.wait_for(r"<server_port>(\d+)</server_port>").group(1))
    with socket.create_connection(("127.0.0.1", port), timeout=5) as client:
        me = "{}:{}".format(*client.getsockname())
        emulation.wait_for(re.escape(f"client connected: {me}"))
    emulation.wait_for(re.escape(f"client disconnected: {me} (closed by the client)"))
    code, err = emulation.interrupt()
    assert code == 0 and "Traceback" not in err


def test_udp_emulator_says_each_peers_first_datagram_once(emulate) -> None:
    emulation = emulate("ElexolEther24_drv", "--port", "0", "--duration", "60")
    host, port = emulation.wait_for(r"listening on (127\.0\.0\.1):(\d+)").groups()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer:
        peer.settimeout(5)
        peer.bind(("127.0.0.1", 0))
        me = "{}:{}".format(*peer.getsockname())
        for _ in range(3):
            peer.sendto(b"IO24", (host, int(port)))
            assert peer.recv(64).startswith(b"IO24")  # answered each time
        emulation.wait_for(re.escape(f"client connected: {me} (first datagram)"))
    code, err = emulation.interrupt()
    assert code == 0 and "Traceback" not in err
    assert emulation.output.count("client connected") == 1


def test_udp_disconnect_scenario_says_it_closed_its_socket(emulate) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.bind(("127.0.0.1", 0))
        port = sink.getsockname()[1]
        emulation = emulate(
            "DTrack_drv",
            "--port",
            port,
            "--scenario",
            "disconnect",
            "--disconnect-after",
            "3",
            "--rate",
            "50",
            "--duration",
            "60",
        )
        emulation.wait_for(re.escape("scenario stopped sending: closed the socket after 3 frames"))
        code, err = emulation.finish()
    assert code == 0 and "Traceback" not in err
