"""A serial line whose far end hangs up raises SerialLineLost from every call, whichever
syscall notices first (pyserial's tcsetattr on a timeout change answers termios.error)."""

from __future__ import annotations

import pytest

from gadgetctl.emulation import PseudoTerminal
from gadgetctl.transport.serialline import SerialLine, SerialLineLost

pytestmark = pytest.mark.timeout(20)


@pytest.mark.parametrize("call", ["read", "write", "discard_input"])
def test_a_hung_up_pty_raises_serial_line_lost(call: str) -> None:
    with PseudoTerminal() as pty, SerialLine(pty.address, poll_interval=0.005) as line:
        pty.write(b"x")
        assert line.read(2.0) == b"x"
        pty.hang_up()
        with pytest.raises(SerialLineLost, match="serial line lost"):
            for attempt in range(1000):  # varying timeouts: pyserial reconfigures the port
                if call == "read":
                    line.read(0.001 * (attempt % 7))
                elif call == "write":
                    line.write(b"?")
                else:
                    line.discard_input()
