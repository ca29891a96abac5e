"""VRPN client and server of gadgetctl against each other and against raw-socket peers,
over real loopback sockets."""

from __future__ import annotations

import socket
import struct
import time

import pytest
from vrpn_peers import COOKIE, RawServer, describe, frame, read_messages, running_server

from gadgetctl.input.testing import wait_until
from gadgetctl.vrpn import VrpnClient, codecs, wire

pytestmark = pytest.mark.timeout(60)


def collect(client: VrpnClient, until, timeout: float = 5.0) -> list:
    got: list = []
    wait_until(lambda: until(got), timeout, step=lambda: got.extend(client.poll(0.02)), pause=0)
    return got


def open_clients(server) -> int:
    return sum(1 for c in server.clients if c.state == "open")


@pytest.mark.parametrize("scheme", ["", "tcp://"])
def test_client_and_server_exchange_every_device_family(scheme):
    with running_server() as server:
        tracker = server.register_sender("Tracker0")
        pose = server.register_type(codecs.TRACKER_POS_QUAT)
        buttons = server.register_sender("Button0")
        change = server.register_type(codecs.BUTTON_CHANGE)
        with VrpnClient(f"{scheme}127.0.0.1:{server.port}", ["Tracker0", "Button0"]) as client:
            assert client.wait_connected(5), client.last_error
            assert wait_until(lambda: open_clients(server) == 1)
            assert client.server_version == "07.38"
            assert server.clients[0].mode == ("tcp" if scheme else "lob")
            # Lob clients announce a UDP channel and get unreliable reports there.
            # (the description may still be on its way: wait for it, never assume it)
            if not scheme:
                assert wait_until(lambda: server.clients[0].udp)
            pongs = collect(client, lambda g: sum(m.type == codecs.PONG for m in g) == 2)
            assert {m.sender for m in pongs if m.type == codecs.PONG} == {"Tracker0", "Button0"}
            assert server.clients[0].udp == (not scheme)  # all the client sent has arrived
            server.send(
                tracker,
                pose,
                codecs.encode_pose(1, (0.5, -1.0, 2.0)),
                reliable=False,
                timestamp=1000.25,
            )
            server.send(buttons, change, codecs.encode_button_change(2, 1))
            # A type registered while the client is connected is announced on the spot.
            analog = server.register_sender("Analog0")
            channel = server.register_type(codecs.ANALOG_CHANNEL)
            # (reliable: by UDP it could overtake the descriptions that still travel by TCP)
            server.send(analog, channel, codecs.encode_analog([0.5, -0.5]))
            got = collect(client, lambda g: len([m for m in g if m.type != codecs.PONG]) >= 3)
            reports = {m.type: m for m in got}
            pose_msg = reports[codecs.TRACKER_POS_QUAT]
            assert pose_msg.sender == "Tracker0"
            assert pose_msg.report == codecs.TrackerPose(1, (0.5, -1.0, 2.0), (0.0, 0.0, 0.0, 1.0))
            assert pose_msg.timestamp == pytest.approx(1000.25)
            assert 0 < time.time() - pose_msg.received < 60
            assert reports[codecs.BUTTON_CHANGE].report == codecs.ButtonChange(2, 1)
            assert reports[codecs.ANALOG_CHANNEL].report.channels == (0.5, -0.5)
            assert reports[codecs.ANALOG_CHANNEL].sender == "Analog0"
            assert set(client.announced) == {"Tracker0", "Button0", "Analog0"}


def test_client_reconnects_when_the_server_returns():
    with running_server() as server:
        port = server.port
        t = server.register_sender("Tracker0")
        client = VrpnClient(f"127.0.0.1:{port}", ["Tracker0"])
        assert client.wait_connected(5)
    # The server is gone: the client notices and keeps trying.
    collect(client, lambda g: client.state != "connected")
    assert client.drops == 1 and client.last_error
    with running_server(port=port) as server:
        t = server.register_sender("Tracker0")
        p = server.register_type(codecs.TRACKER_POS_QUAT)
        assert wait_until(lambda: open_clients(server) == 1, 5, step=lambda: client.poll(0.02))
        server.send(t, p, codecs.encode_pose(0, (1.0, 2.0, 3.0)))
        got = collect(client, lambda g: any(m.type == codecs.TRACKER_POS_QUAT for m in g))
        assert client.connects == 2
        assert any(
            m.report.position == (1.0, 2.0, 3.0) for m in got if m.type == codecs.TRACKER_POS_QUAT
        )
    client.close()


def test_a_stalled_client_loses_messages_but_never_blocks_the_others():
    with running_server(client_buffer=64 * 1024, socket_buffer=16384) as server:
        t = server.register_sender("Tracker0")
        p = server.register_type(codecs.TRACKER_POS_QUAT)
        stalled = socket.socket()
        stalled.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # before connecting
        stalled.connect(("127.0.0.1", server.port))
        stalled.sendall(COOKIE)  # and never reads again
        with VrpnClient(f"tcp://127.0.0.1:{server.port}", ["Tracker0"]) as client:
            assert client.wait_connected(5)
            assert wait_until(lambda: open_clients(server) == 2)
            # Batches the reader can hold, each awaited by the reader; the stalled peer's
            # buffer fills and then loses messages. Sending into a full buffer never waits
            # (if it did, this test would hang and time out).
            received: list = []
            batch, batches = 200, 30  # 88-byte messages: 0.5 MB in all
            for b in range(batches):
                for i in range(b * batch, (b + 1) * batch):
                    server.send(t, p, codecs.encode_pose(0, (float(i), 0.0, 0.0)), flush=False)
                n = (b + 1) * batch
                received.extend(
                    collect(
                        client,
                        lambda g, n=n: (
                            sum(m.type == codecs.TRACKER_POS_QUAT for m in received + g) >= n
                        ),
                    )
                )
            xs = [m.report.position[0] for m in received if m.type == codecs.TRACKER_POS_QUAT]
            assert xs == [float(i) for i in range(batch * batches)]
            by_mode = sorted(c.dropped for c in server.clients)
            assert (
                by_mode[0] == 0 and by_mode[1] > 0
            )  # the reader lost nothing, the stalled one lost
            assert server.dropped == by_mode[1]
        stalled.close()


def test_server_survives_hostile_peers_and_keeps_serving():
    with running_server(handshake_timeout=1.0) as server:
        t = server.register_sender("Tracker0")
        p = server.register_type(codecs.TRACKER_POS_QUAT)
        with VrpnClient(f"tcp://127.0.0.1:{server.port}", ["Tracker0"]) as good:
            assert good.wait_connected(5)
            addr = ("127.0.0.1", server.port)
            # Garbage instead of a cookie; a right cookie then an oversized header; a header
            # claiming 4 GB; a fatal system type; a malformed description.
            hostile = [
                b"GET / HTTP/1.0\r\n\r\n" + b"\xff" * 100,
                COOKIE + struct.pack(">IiiiiI", 64040, 0, 0, 0, 5, 0),
                COOKIE + struct.pack(">IiiiiI", 0xFFFFFFFF, 0, 0, 0, 5, 0),
                COOKIE + frame(-2001, 0),
                COOKIE + frame(-1, 0, struct.pack(">I", 5000) + b"abc\0"),
            ]
            for data in hostile:
                s = socket.create_connection(addr)
                s.sendall(data)
                s.settimeout(5)
                try:
                    while s.recv(65536):  # the server ends the connection
                        pass
                except ConnectionResetError:
                    pass
                s.close()
            # Bad lobs: garbage, a low port, a host other than the sender, an oversized datagram.
            udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            for data in (b"\x00\x01garbage", b"127.0.0.1 80\0", b"10.9.8.7 4000\0", b"9" * 1400):
                udp.sendto(data, addr)
            udp.close()
            # Many connects and disconnects, and one that says nothing.
            for _ in range(200):
                socket.create_connection(addr).close()
            silent = socket.create_connection(addr)
            assert wait_until(lambda: server.counters["bad_lobs"] == 4, 5)
            assert wait_until(lambda: server.counters["handshake_timeouts"] >= 1, 5)
            silent.close()
            counters = server.counters
            assert counters["bad_cookies"] >= 1
            assert counters["oversized"] == 2
            assert counters["bad_system_messages"] == 1
            assert counters["bad_descriptions"] == 1
            server.send(t, p, codecs.encode_pose(0, (7.0, 0.0, 0.0)))
            got = collect(good, lambda g: any(m.type == codecs.TRACKER_POS_QUAT for m in g))
            assert [m.report.position[0] for m in got if m.type == codecs.TRACKER_POS_QUAT] == [7.0]
            assert good.drops == 0


def test_raw_client_sees_the_handshake_the_reference_describes():
    with running_server() as server:
        server.register_sender("Tracker0")
        server.register_type(codecs.TRACKER_POS_QUAT)
        s = socket.create_connection(("127.0.0.1", server.port))
        s.sendall(COOKIE)
        s.settimeout(5)
        cookie = b""
        while len(cookie) < 24:
            cookie += s.recv(24 - len(cookie))
        assert cookie == COOKIE
        # Describe our sender and the ping type, then ping: the server answers with a pong
        # from its own id of that sender.
        s.sendall(describe(-1, 0, "Tracker0") + describe(-2, 0, codecs.PING) + frame(0, 0))
        msgs = read_messages(s, 1 + 4 + 1)
        senders = {i: wire.decode_description(p) for t, i, p in msgs if t == -1}
        types = {i: wire.decode_description(p) for t, i, p in msgs if t == -2}
        assert senders == {0: "Tracker0"}
        assert set(types.values()) >= {codecs.PING, codecs.PONG, codecs.TRACKER_POS_QUAT}
        user = [(t, i) for t, i, _ in msgs if t >= 0]
        assert user == [(next(k for k, v in types.items() if v == codecs.PONG), 0)]
        s.close()


def _hostile_script(kind: str):
    def script(conn: socket.socket, n: int) -> None:
        if kind == "wrong cookie":
            conn.sendall(b"vrpn: ver. 08.00  0\0\0\0\0\0")
        elif kind == "garbage":
            conn.sendall(bytes(range(256)) * 4)
        else:
            conn.sendall(COOKIE)
            conn.recv(24)
            if kind == "oversized":
                conn.sendall(struct.pack(">IiiiiI", 10_000_000, 0, 0, 0, 3, 0))
            elif kind == "bad tracker":
                conn.sendall(describe(-1, 0, "Tracker0") + describe(-2, 0, codecs.TRACKER_POS_QUAT))
                conn.sendall(frame(0, 0, b"\0" * 40))  # 40 bytes, must be 64: C++ drops
            elif kind == "truncated":
                conn.sendall(describe(-1, 0, "Tracker0")[:30])
                return  # and close mid-message
        time.sleep(0.2)

    return script


@pytest.mark.parametrize(
    "kind", ["wrong cookie", "garbage", "oversized", "bad tracker", "truncated"]
)
def test_client_against_a_hostile_server_counts_and_reconnects(kind):
    with RawServer(_hostile_script(kind)) as raw:
        client = VrpnClient(f"tcp://127.0.0.1:{raw.port}", ["Tracker0"])
        # It keeps coming back for more, without ever raising.
        assert wait_until(lambda: raw.connections >= 3, 10, step=lambda: client.poll(0.02), pause=0)
        counts = client.counts()
        client.close()
    expected = {
        "wrong cookie": "bad_cookies",
        "garbage": "bad_cookies",
        "oversized": "oversized",
        "bad tracker": "bad_reports",
    }.get(kind)
    if expected:
        assert counts[expected] >= 2, counts
    assert counts["ended_connections"] >= 2, counts


def test_garbage_on_the_clients_udp_channel_is_counted():
    with running_server() as server:
        t = server.register_sender("Tracker0")
        p = server.register_type(codecs.TRACKER_POS_QUAT)
        with VrpnClient(f"127.0.0.1:{server.port}", ["Tracker0"]) as client:
            assert client.wait_connected(5)
            assert wait_until(lambda: open_clients(server) == 1 and server.clients[0].udp)
            port = client._udp_in.getsockname()[1]  # the channel the client announced
            junk = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            for data in (
                b"\x01" * 7,
                struct.pack(">IiiiiI", 90000, 0, 0, 0, 0, 0),
                frame(3, 0, b"x" * 16)[:30],
            ):
                junk.sendto(data, ("127.0.0.1", port))
            junk.close()
            assert wait_until(
                lambda: client.counts()["bad_datagrams"] == 3,
                5,
                step=lambda: client.poll(0.01),
                pause=0,
            )
            server.send(t, p, codecs.encode_pose(0, (3.0, 2.0, 1.0)), reliable=False)
            got = collect(client, lambda g: any(m.type == codecs.TRACKER_POS_QUAT for m in g))
            assert [m.report.position for m in got if m.type == codecs.TRACKER_POS_QUAT] == [
                (3.0, 2.0, 1.0)
            ]
            assert client.connected and client.drops == 0
