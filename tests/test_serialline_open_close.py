"""SerialLine.open_with() and close(farewell), the start and end of the serial standalone
drivers' connections (Flock, IBox, Wanda; LineDriver's Fastrak, IS-900, 3D mouse)."""

from __future__ import annotations

import os

import pytest

from gadgetctl.emulation import PseudoTerminal
from gadgetctl.input.testing import wait_until
from gadgetctl.transport.serialline import SerialLine, SerialLineLost

pytestmark = pytest.mark.timeout(20)


class Gone(ConnectionError):
    """A driver's own lost-line error."""


def received(pty: PseudoTerminal) -> bytes:
    """What the driver side wrote so far (read from the master, without blocking)."""
    got = b""
    while True:
        try:
            chunk = os.read(pty.master, 1024)
        except BlockingIOError:
            return got
        if not chunk:
            return got
        got += chunk


def test_open_with_sets_the_device_up_once() -> None:
    calls: list[bool] = []
    with PseudoTerminal() as pty:
        line = SerialLine(pty.address, poll_interval=0.005)
        line.open_with(lambda: calls.append(line.is_open), Gone)
        line.open_with(lambda: calls.append(line.is_open), Gone)  # open already: nothing
        assert calls == [True] and line.is_open
        line.close()
        assert not line.is_open


@pytest.mark.parametrize(
    ("error", "raised", "message"),
    [
        (SerialLineLost("serial line lost: gone"), Gone, "serial line lost: gone"),  # the driver's
        (ValueError("no answer"), ValueError, "no answer"),  # as it is
    ],
)
def test_a_failed_set_up_closes_the_line(error, raised, message) -> None:
    def setup() -> None:
        raise error

    with PseudoTerminal() as pty:
        line = SerialLine(pty.address, poll_interval=0.005)
        with pytest.raises(raised) as caught:
            line.open_with(setup, Gone)
        assert type(caught.value) is raised and str(caught.value) == message
        assert caught.value is error or caught.value.__cause__ is error
        assert not line.is_open


def test_a_port_that_cannot_be_opened_is_the_drivers_error(tmp_path) -> None:
    line = SerialLine(str(tmp_path / "no-such-tty"))
    with pytest.raises(Gone, match="cannot open"):
        line.open_with(lambda: None, Gone)
    assert not line.is_open


def test_close_writes_the_farewell_first() -> None:
    with PseudoTerminal() as pty:
        line = SerialLine(pty.address, poll_interval=0.005).open()
        line.close(farewell=b"END")
        assert not line.is_open
        got = b""

        def more() -> None:
            nonlocal got
            got += received(pty)

        assert wait_until(lambda: got == b"END", step=more), got
        line.close(farewell=b"END")  # closed already: nothing written, no error
        more()
        assert got == b"END"


def test_a_farewell_on_a_hung_up_line_is_no_error() -> None:
    with PseudoTerminal() as pty:
        line = SerialLine(pty.address, poll_interval=0.005).open()
        pty.hang_up()
        line.close(farewell=b"END")
        assert not line.is_open
