"""Hostile peers on `gadgetctl serve`'s TCP and UDP ports (loopback): garbage, oversized
messages, bad lobs, 1,000 connects and disconnects, a client that stops reading, a client
flooding pings. Serve goes
on serving a well-behaved client throughout, counts what it refused, and exits cleanly."""

from __future__ import annotations

import os
import signal
import socket
import struct

import pytest

from gadgetctl.input.testing import wait_until
from gadgetctl.vrpn import VrpnClient
from gadgetctl.vrpn.codecs import PING
from gadgetctl.vrpn.wire import (
    SENDER_DESCRIPTION,
    TYPE_DESCRIPTION,
    make_cookie,
    pack_description,
    pack_message,
)

from conftest import write
from serve_process import ServeProcess

FLOOD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="flood">
   <elements>
      <waveform_device name="Flood" version="1">
         <rate>2000.0</rate><event_period>0.0</event_period>
         {paths}
      </waveform_device>
      <waveform_device name="Buttons" version="1">
         <rate>100.0</rate><event_period>0.0</event_period><button_period>0.2</button_period>
      </waveform_device>
   </elements>
</configuration>
"""


class Watcher:
    """A well-behaved client: counts the tracker reports it reads."""

    def __init__(self, port: int) -> None:
        self.client = VrpnClient(f"tcp://127.0.0.1:{port}", ["Flood", "Buttons"])
        self.poses = 0

    def pump(self) -> None:
        self.poses += sum(1 for m in self.client.poll(0.005) if m.type == "vrpn_Tracker Pos_Quat")

    def progresses(self, amount: int = 2000, timeout: float = 30.0) -> None:
        """Wait until ``amount`` more reports arrived (serve still serves this client)."""
        target = self.poses + amount
        wait_until(lambda: (self.pump(), self.poses >= target)[1], timeout=timeout)
        assert self.client.state == "connected"


def connect(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.settimeout(5)
    return sock


@pytest.mark.timeout(240)
def test_serve_survives_hostile_peers_and_exits_cleanly(tmp_path):
    paths = "".join("<position_path>circle</position_path>" for _ in range(8))
    config = write(tmp_path / "flood.jconf", FLOOD.format(paths=paths))
    with ServeProcess(config, "--client-buffer", "65536") as serve:
        port = serve.port
        watcher = Watcher(port)
        try:
            assert watcher.client.wait_connected(10)
            watcher.progresses()

            # a client that stops reading (its receive window as small as the OS allows)
            stalled = socket.socket()
            stalled.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            stalled.connect(("127.0.0.1", port))
            stalled.sendall(make_cookie())
            wait_until(
                lambda: sum(e["event"] == "connected" for e in serve.events) >= 2, timeout=20
            )

            # garbage bytes instead of a cookie, a cookie then garbage, an oversized message
            rng = os.urandom
            for payload in (
                rng(100_000),
                make_cookie() + rng(50_000),
                make_cookie() + struct.pack(">IiiiiI", 1_000_000, 0, 0, 0, 5, 0) + rng(4096),
                make_cookie() + pack_message(-1, 3, struct.pack(">I", 5000) + b"x" * 5000),
                b"vrpn: ver. 08.00  0\0\0\0\0\0",
            ):
                sock = connect(port)
                try:
                    sock.sendall(payload)
                except OSError:
                    pass  # serve may drop it while we still write: that is the point
                sock.close()
            watcher.progresses()

            # UDP: garbage and oversized datagrams, lobs with bad hosts and ports
            udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            closed = socket.socket()
            closed.bind(("127.0.0.1", 0))
            closed_port = closed.getsockname()[1]
            closed.close()  # nothing listens there: the call-back fails
            datagrams = [
                rng(1400),
                rng(60_000),
                make_cookie(),
                b"",
                b"evil-host.example 40000\0",
                b"127.0.0.1 80\0",
                b"127.0.0.1 70000\0",
                b"127.0.0.1 -5\0",
                b"10.9.8.7 40000\0",
                b"127.0.0.1 abc\0",
                b"\xff\xfe 4000\0",
                b"127.0.0.1 4000 extra\0",
                b"1" * 5000 + b" 4000\0",
                f"127.0.0.1 {closed_port}\0".encode(),
            ]
            for _ in range(20):
                for datagram in datagrams:
                    udp.sendto(datagram, ("127.0.0.1", port))
            udp.close()
            watcher.progresses()

            # a client flooding pings (240 KB at once): served within its budget per pass
            flooder = connect(port)
            flooder.sendall(
                make_cookie()
                + pack_description(SENDER_DESCRIPTION, 0, "Flood")
                + pack_description(TYPE_DESCRIPTION, 0, PING)
            )
            me = f"127.0.0.1:{flooder.getsockname()[1]}"
            assert wait_until(
                lambda: any(e["event"] == "connected" and e["client"] == me for e in serve.events),
                timeout=20,
            )
            flooder.sendall(pack_message(0, 0) * 10_000)
            watcher.progresses()
            flooder.close()

            # 1,000 connects and disconnects, half of them after a cookie
            for i in range(1000):
                sock = connect(port)
                if i % 2:
                    sock.sendall(make_cookie())
                sock.close()
            watcher.progresses()

            assert serve.alive()
        finally:
            watcher.client.close()
        code = serve.stop(signal.SIGTERM)
        stalled.close()
    assert code == 0, serve.stderr[-3000:]
    assert "Traceback" not in serve.stderr
    stopped = serve.events[-1]
    assert stopped["event"] == "stopped" and stopped["reason"] == "terminated"
    counters = stopped["counters"]
    assert counters.get("bad_lobs", 0) >= 1  # UDP: the kernel may drop some of the burst
    assert counters.get("callback_failures", 0) >= 1 or counters.get("handshake_timeouts", 0) >= 1
    assert counters.get("bad_cookies", 0) >= 2
    assert counters.get("oversized", 0) >= 1
    # the flood was read a budget at a time, the excess left for later passes (counted)
    assert counters.get("input_deferred", 0) >= 1
    assert counters.get("messages_deferred", 0) >= 1, counters
    # the stalled client lost messages (counted and shown); the watcher lost none
    leaving = [e for e in serve.events if e["event"] == "disconnected"]
    assert any(e["dropped"] > 0 for e in leaving)
    assert stopped["dropped"] > 0
    assert watcher.client.counts().get("drops", 0) == 0
