"""The input-manager side of the Ether I/O 24 driver: an ``elexol_ether24`` element becomes
a device with 24 digital units, line ``8p + b`` = pin b of port p (A, B, C), 0 or 1, after
the port's ``invert`` setting. The embedded ``port_a``/``port_b``/``port_c`` elements set the
pins (start level, direction, pull-up, threshold, Schmitt trigger), written when sampling
starts, in upstream's order.

``config_method`` Static IP talks to ``ip_address``, which may end in ``:port`` to reach a
board (or its emulator) on another port than 2424. Match MAC Address (the definition's
default) finds the board whose ``mac_address`` answers ``IO24``, sent by default to the
broadcast address 255.255.255.255 on port 2424, each time sampling starts (so a board that
changed its address is found again after a loss). The environment variable
``GADGETCTL_ETHER24_DISCOVERY`` (``host[:port]``) sends it elsewhere: a subnet's broadcast
address on a machine with several interfaces (255.255.255.255 leaves by one only), or a
board's own address. A board that does not answer within a second faults the device, which
the input manager restarts. No reply for :attr:`Ether24Device.peer_timeout` seconds raises from ``sample()``, so the
input manager marks the device faulted and restarts it.
"""

from __future__ import annotations

import os

from gadgetctl.input import DeviceConfigError, Digital
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.udp import DatagramLedger

from .standalone import (
    BOARD_PORT,
    BROADCAST,
    PORTS,
    DiscoveryCounts,
    Ether24Board,
    Ether24Disconnected,
    PortSettings,
    find_board,
    format_mac,
    lines,
    parse_address,
    parse_mac,
)

DISCOVERY_VARIABLE = "GADGETCTL_ETHER24_DISCOVERY"

_PIN_PROPERTIES = {
    "initial_value": "initial_value",
    "direction": "direction",
    "pullup": "pullup",
    "threshold": "threshold",
    "schmitt_trigger": "schmitt_trigger",
    "invert": "invert",
}


def _port_settings(access: ElementAccess, prop: str) -> PortSettings:
    child = access.child(prop)
    if child is None:  # the definition's defaults
        return PortSettings()
    sub = ElementAccess(child, access.repo)
    packed = {}
    try:
        for field, name in _PIN_PROPERTIES.items():
            packed[field] = sum((sub.integer(f"{name}{pin}") & 1) << pin for pin in range(8))
    except ValueError as err:
        raise DeviceConfigError(f"{prop}: {err}") from None
    return PortSettings(**packed)


class Ether24Device(Digital):
    """An Elexol Ether I/O 24 board (element type ``elexol_ether24``)."""

    ELEMENT_TYPE = "elexol_ether24"
    #: Seconds between two reads of the three ports (upstream read without pause).
    sample_interval = 0.005
    reply_timeout = 0.1
    probe_timeout = 0.25

    def __init__(self) -> None:
        super().__init__()
        self.host = ""
        self.board_port = BOARD_PORT
        self.peer_timeout = 1.0
        self.ports = [PortSettings()] * PORTS
        self._board: Ether24Board | None = None
        self._started = False
        self.mac: bytes | None = None  # set for config_method find_mac
        self.discovery_target = (BROADCAST, BOARD_PORT)
        self.discovery_time = 1.0
        self.discovery = DiscoveryCounts()

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        method = access.string("config_method")
        if method == "find_mac":
            try:
                self.mac = parse_mac(access.string("mac_address"))
            except ValueError as err:
                raise DeviceConfigError(f"mac_address: {err}") from None
            target = os.environ.get(DISCOVERY_VARIABLE, "").strip()
            if target:
                try:
                    self.discovery_target = parse_address(target)
                except ValueError as err:
                    raise DeviceConfigError(f"{DISCOVERY_VARIABLE}: {err}") from None
        elif method == "static_ip":
            try:
                self.host, self.board_port = parse_address(access.string("ip_address"))
            except ValueError as err:
                raise DeviceConfigError(f"ip_address: {err}") from None
        else:
            raise DeviceConfigError(f"config_method {method!r} is neither static_ip nor find_mac")
        self.ports = [_port_settings(access, p) for p in ("port_a", "port_b", "port_c")]

    def start_sampling(self) -> None:
        if self.mac is not None:
            self._discover()
        if self._board is None:
            self._board = Ether24Board(self.host, self.board_port)
        board = self._board
        board.reply_timeout = self.probe_timeout if self._started else self.reply_timeout
        board.peer_timeout = self.peer_timeout
        board.open()
        try:
            board.configure(self.ports)
            if self._started:  # after a loss: succeed only when the board answers again
                values = board.read_ports()
                if values is None:
                    raise Ether24Disconnected(
                        f"the board at {self.host}:{self.board_port} is still silent"
                    )
                self._add(values)
        except BaseException:
            board.close()
            raise
        finally:
            board.reply_timeout = self.reply_timeout
        self._started = True

    def sample(self) -> None:
        board = self._board
        if board is None or not board.is_open:
            raise Ether24Disconnected("the connection to the board is closed")
        values = board.read_ports()
        if values is not None:
            self._add(values)

    def stop_sampling(self) -> None:
        if self._board is not None:
            self._board.close()

    def _discover(self) -> None:
        """Find the board with :attr:`mac`; a new address replaces the board's connection."""
        assert self.mac is not None
        found = find_board(
            self.mac, self.discovery_target, listen=self.discovery_time, counts=self.discovery
        )
        if found is None:
            host, port = self.discovery_target
            raise Ether24Disconnected(
                f"no Ether I/O 24 with MAC {format_mac(self.mac)} answered IO24 sent to "
                f"{host}:{port} within {self.discovery_time:g} s"
            )
        if (found.host, found.port) != (self.host, self.board_port):
            if self._board is not None:
                self._board.close()
                self._board = None
            self.host, self.board_port = found.host, found.port

    def _add(self, values: list[int]) -> None:
        self.add_digital_sample(lines(values, [p.invert for p in self.ports]))

    def datagram_ledger(self) -> DatagramLedger | None:
        """The board connection's account of its datagrams: replies, bad ones, kernel drops."""
        return self._board.ledger if self._board is not None else None

    @property
    def counters(self) -> dict[str, int]:
        b = self._board
        found = (
            {
                "discovery_replies": self.discovery.replies,
                "bad_discovery_replies": self.discovery.bad_replies,
            }
            if self.mac is not None
            else {}
        )
        if b is None:
            return found
        return {
            "requests": b.requests,
            "replies": b.replies,
            "bad_replies": b.bad_replies,
            "timeouts": b.timeouts,
            **found,
        }
