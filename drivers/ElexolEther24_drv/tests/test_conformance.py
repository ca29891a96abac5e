"""Conformance: the Ether I/O 24 client against a board that answers as another implementation of
the protocol expects, not as our emulator does.

Source: the Perl module Net::Elexol::EtherIO24 0.22 (Chris Luke), its command tables: a status
query ``'a'``/``'b'``/``'c'`` is answered by ``'A'``/``'B'``/``'C'`` and the port's byte
(``cmd_map``); writes are ``'A'`` + byte (2 bytes) and ``'!A'``, ``'@A'``, ``'#A'``, ``'$A'`` +
byte (3 bytes, ``send_commands``); the identify command ``IO24`` is answered by ``IO24``, the
board's 6-byte MAC and its 2-byte firmware version. The board below is written from those tables,
on a loopback UDP socket the OS picks.
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator

import pytest
from ElexolEther24_drv.standalone import Ether24Board, PortSettings, find_board, lines

pytestmark = pytest.mark.timeout(20)

MAC = bytes.fromhex("000ABC123456")
FIRMWARE = bytes([0x01, 0x07])


class PerlTableBoard:
    """Answers queries the way Net::Elexol::EtherIO24's tables say the device does."""

    def __init__(self, ports: list[int]) -> None:
        self.ports = ports
        self.writes: list[bytes] = []
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.address = self.sock.getsockname()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                data, peer = self.sock.recvfrom(64)
            except TimeoutError:
                continue
            except OSError:
                return
            if data == b"IO24":
                self.sock.sendto(b"IO24" + MAC + FIRMWARE, peer)
            elif len(data) == 1 and data in b"abc":
                port = data[0] - ord("a")
                self.sock.sendto(bytes([ord("A") + port, self.ports[port]]), peer)
            else:
                self.writes.append(data)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.sock.close()


@pytest.fixture
def board() -> Iterator[PerlTableBoard]:
    peer = PerlTableBoard([0b1000_0001, 0x00, 0xFF])
    yield peer
    peer.close()


def test_port_queries_give_the_24_lines(board: PerlTableBoard) -> None:
    client = Ether24Board(*board.address, reply_timeout=2.0)
    client.open()
    try:
        values = client.read_ports()
    finally:
        client.close()
    assert values == [0b1000_0001, 0x00, 0xFF]
    assert client.bad_replies == 0
    got = lines(values, [0, 0, 0])
    assert got[0] == 1 and got[7] == 1 and sum(got[1:7]) == 0  # port A: lines 0 and 7
    assert sum(got[8:16]) == 0 and sum(got[16:24]) == 8


def test_writes_have_the_lengths_the_perl_table_gives(board: PerlTableBoard) -> None:
    client = Ether24Board(*board.address, reply_timeout=2.0)
    client.open()
    try:
        client.configure([PortSettings(initial_value=0x5A, direction=0x0F)] * 3)
        client.read_ports()  # the board handles datagrams in order: the writes are in
    finally:
        client.close()
    assert board.writes[:5] == [b"AZ", b"!A\x0f", b"@A\xff", b"#A\xff", b"$A\xff"]
    assert all(len(w) == (2 if w[:1] in b"ABC" else 3) for w in board.writes)
    assert len(board.writes) == 15


def test_identify_reply_names_the_board_by_its_mac(board: PerlTableBoard) -> None:
    found = find_board(MAC, board.address, listen=2.0)
    assert found is not None
    assert found.mac == MAC and found.firmware == 0x0107
