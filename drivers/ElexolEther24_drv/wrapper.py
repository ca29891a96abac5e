"""The input-manager side of the Ether I/O 24 driver: an ``elexol_ether24`` element becomes
a device with 24 digital units, line ``8p + b`` = pin b of port p (A, B, C), 0 or 1, after
the port's ``invert`` setting. The embedded ``port_a``/``port_b``/``port_c`` elements set the
pins (start level, direction, pull-up, threshold, Schmitt trigger), written when sampling
starts, in upstream's order.

Only ``config_method`` Static IP is supported: Match MAC Address discovers the board by
broadcasting, which gadgetctl does not do; such an element stays pending with that reason.
``ip_address`` may end in ``:port`` to reach a board (or its emulator) on another port than
2424. No reply for :attr:`Ether24Device.peer_timeout` seconds raises from ``sample()``, so the
input manager marks the device faulted and restarts it.
"""

from __future__ import annotations

from gadgetctl.input import DeviceConfigError, Digital
from gadgetctl.jccl.access import ElementAccess

from .standalone import (
    BOARD_PORT,
    PORTS,
    Ether24Board,
    Ether24Disconnected,
    PortSettings,
    lines,
    parse_address,
)

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

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        method = access.string("config_method")
        if method != "static_ip":
            raise DeviceConfigError(
                f"config_method {method!r} finds the board by broadcasting, which gadgetctl "
                "does not do: set config_method static_ip and ip_address"
            )
        try:
            self.host, self.board_port = parse_address(access.string("ip_address"))
        except ValueError as err:
            raise DeviceConfigError(f"ip_address: {err}") from None
        self.ports = [_port_settings(access, p) for p in ("port_a", "port_b", "port_c")]

    def start_sampling(self) -> None:
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

    def _add(self, values: list[int]) -> None:
        self.add_digital_sample(lines(values, [p.invert for p in self.ports]))

    @property
    def counters(self) -> dict[str, int]:
        b = self._board
        if b is None:
            return {}
        return {
            "requests": b.requests,
            "replies": b.replies,
            "bad_replies": b.bad_replies,
            "timeouts": b.timeouts,
        }
