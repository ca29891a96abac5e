"""The kernel's count of UDP datagrams dropped for a full receive buffer, over real loopback
sockets: every datagram sent is either received or counted as dropped."""

from __future__ import annotations

import socket
from collections.abc import Iterator

import pytest

from gadgetctl.transport.udp import DropCountingReceiver, proc_udp_drops

pytestmark = pytest.mark.timeout(30)


@pytest.fixture
def small_socket() -> Iterator[socket.socket]:
    """A loopback UDP socket with the smallest receive buffer the kernel allows."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1)
    sock.bind(("127.0.0.1", 0))
    sock.setblocking(False)
    yield sock
    sock.close()


def flood(port: int, count: int, size: int = 200) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for n in range(count):
            tx.sendto(n.to_bytes(4, "big") * (size // 4), ("127.0.0.1", port))


def drain(receiver: DropCountingReceiver) -> int:
    got = 0
    while True:
        try:
            receiver.receive(4096)
        except BlockingIOError:
            return got
        got += 1


def test_every_datagram_is_received_or_counted_as_dropped(small_socket: socket.socket) -> None:
    receiver = DropCountingReceiver()
    receiver.attach(small_socket)
    assert receiver.method == "ancillary"  # Linux
    flood(small_socket.getsockname()[1], 300)  # nobody reads meanwhile: the buffer overflows
    got = drain(receiver)
    assert 0 < got < 300
    receiver.refresh(force=True)  # the drops after the last datagram read
    assert receiver.dropped == 300 - got
    assert proc_udp_drops(small_socket) == receiver.dropped  # the kernel's other account


def test_the_count_survives_a_new_socket(small_socket: socket.socket) -> None:
    receiver = DropCountingReceiver()
    receiver.attach(small_socket)
    flood(small_socket.getsockname()[1], 100)
    first = 100 - drain(receiver)
    receiver.refresh(force=True)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as again:
        again.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1)
        again.bind(("127.0.0.1", 0))
        again.setblocking(False)
        receiver.attach(again)
        assert receiver.dropped == first > 0
        flood(again.getsockname()[1], 100)
        second = 100 - drain(receiver)
        receiver.refresh(force=True)
        assert receiver.dropped == first + second and second > 0


def test_a_datagram_read_after_drops_carries_their_count(small_socket: socket.socket) -> None:
    receiver = DropCountingReceiver(proc_interval=3600.0)  # /proc read on attach only
    receiver.attach(small_socket)
    receiver.refresh(force=True)
    port = small_socket.getsockname()[1]
    flood(port, 50)
    got = drain(receiver)
    flood(port, 1)  # queued after the drops: the kernel tells their number with it
    got += drain(receiver)
    assert receiver.dropped == 51 - got > 0


def test_proc_net_udp_is_read_where_the_ancillary_count_is_not_offered(
    small_socket: socket.socket,
) -> None:
    flood(small_socket.getsockname()[1], 200)
    dropped = proc_udp_drops(small_socket)
    assert dropped is not None and dropped > 0
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as unbound:
        assert proc_udp_drops(unbound) in (None, 0)
