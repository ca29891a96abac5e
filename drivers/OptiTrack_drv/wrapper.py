"""The input-manager side of the OptiTrack driver: an ``optitrack`` element becomes a device
whose position units are its embedded ``rigid_body`` elements (``body_index`` = NatNet
rigid-body id, or a skeleton bone's id), then its ``marker`` elements (``marker_index``: 1000
+ k is marker k of marker set 0, as Gadgeteer reads it; smaller values NatNet marker ids), in
configuration order. Matrices are in metres; rigid bodies carry the rotation of their
quaternion, markers the identity rotation.

Where it listens (Motive's defaults unless the element says otherwise): ``port`` (the data
port; an element that does not set it gets Motive's 1511, the definition's default 1001 is
VR Juggler's, for NatNet 2.0 and older servers), ``multicast_group`` (239.255.42.99; empty:
none), ``command_port`` (1510), ``connection_type`` (multicast or unicast),
``server_address`` (unicast: the server, 127.0.0.1 by default; multicast: where requests go,
by default the frames' sender) and ``natnet_version`` (empty: the one the server names).
These are gadgetctl's additions to the definition; VR Juggler's element has only ``port``.

Every NatNet frame becomes one sample (upstream polled at 100 Hz and kept the newest frame
only). Datagrams that arrive but do not decode show the device ``undecodable`` with the first
error (its datagram ledger), never ``running``. Silence longer than
:attr:`OptiTrackDevice.peer_timeout` raises from ``sample()``, so the input manager marks the
device faulted and restarts it; a restart succeeds only once frames arrive and decode again.
"""

from __future__ import annotations

import socket
from collections.abc import Sequence

import numpy as np

from gadgetctl.input import DeviceConfigError, Position
from gadgetctl.input.receiving import ReceiverSampling
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.configuration import ConfigElement

from .natnet import Version, parse_version
from .standalone import (
    COMMAND_PORT,
    DATA_PORT,
    DEFAULT_LIMITS,
    MULTICAST_GROUP,
    NatNetDisconnected,
    NatNetFrame,
    NatNetReceiver,
    NatNetUndecodable,
    NatNetUnits,
)


class OptiTrackDevice(ReceiverSampling[NatNetReceiver], Position):
    """A NaturalPoint OptiTrack NatNet server (element type ``optitrack``)."""

    ELEMENT_TYPE = "optitrack"
    DISCONNECTED = NatNetDisconnected

    #: The interface the multicast group is joined on ("0.0.0.0": every interface).
    multicast_interface = "0.0.0.0"
    limits = DEFAULT_LIMITS

    def __init__(self) -> None:
        super().__init__()
        self.port = DATA_PORT
        self.multicast_group: str | None = MULTICAST_GROUP
        self.command_port = COMMAND_PORT
        self.unicast = False
        self.server_address = ""
        self.natnet_version: Version | None = None
        self.peer_timeout = 2.0
        self.body_ids: list[int] = []
        self.marker_ids: list[int] = []
        self._units = NatNetUnits([], [])

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, position filters
        # VR Juggler's default port (1001) is for NatNet 2.0 and older servers: an element
        # that does not set it listens where Motive sends (1511).
        self.port = access.integer("port") if access.count("port") else DATA_PORT
        if not 0 <= self.port <= 65535:
            raise DeviceConfigError(f"port {self.port} is not a UDP port (0 to 65535)")
        self.command_port = access.integer("command_port")
        if not 1 <= self.command_port <= 65535:
            raise DeviceConfigError(
                f"command_port {self.command_port} is not a UDP port (1 to 65535)"
            )
        self.multicast_group = access.string("multicast_group") or None
        if self.multicast_group is not None and not _is_multicast(self.multicast_group):
            raise DeviceConfigError(
                f"multicast_group {self.multicast_group!r} is not an IPv4 multicast address "
                "(224.0.0.0 to 239.255.255.255)"
            )
        mode = access.string("connection_type").lower()
        if mode not in ("multicast", "unicast"):
            raise DeviceConfigError(f"connection_type {mode!r} is neither Multicast nor Unicast")
        self.unicast = mode == "unicast"
        self.server_address = access.string("server_address")
        text = access.string("natnet_version")
        try:
            self.natnet_version = parse_version(text) if text else None
        except ValueError as err:
            raise DeviceConfigError(f"natnet_version: {err}") from None
        self.body_ids = [
            _child_integer(access, c, "body_index") for c in access.children("rigid_body")
        ]
        self.marker_ids = [
            _child_integer(access, c, "marker_index") for c in access.children("marker")
        ]
        self._units = NatNetUnits(self.body_ids, self.marker_ids)

    # -- sampling ---------------------------------------------------------------------------

    def _new_receiver(self) -> NatNetReceiver:
        return NatNetReceiver(
            self.port,
            group=None if self.unicast else self.multicast_group,
            interface=self.multicast_interface,
            unicast=self.unicast,
            server=self.server_address or None,
            command_port=self.command_port,
            version=self.natnet_version,
            receive_timeout=self.receive_timeout,
            peer_timeout=self.peer_timeout,
            limits=self.limits,
        )

    def _silence(self, driver: NatNetReceiver) -> Exception:
        """Undecodable when datagrams came but did not decode, else disconnected."""
        undecodable = driver.undecodable_reason()
        if undecodable is not None:
            return NatNetUndecodable(undecodable)
        return NatNetDisconnected(f"still no NatNet frames on UDP port {driver.port}")

    def _add(self, frames: Sequence[NatNetFrame]) -> None:
        if not self._units.matrices.shape[0]:
            return  # no units configured: nothing to report
        matrices = np.stack([self._units.update(f).copy() for f in frames])
        self.add_position_samples(np.full(len(frames), self.now()), matrices)

    # -- diagnostics ------------------------------------------------------------------------

    @property
    def counters(self) -> dict[str, int]:
        """What the receiver counted since the device was made, reconnections included."""
        r = self._receiver
        if r is None:
            return {}
        return {
            "datagrams": r.datagrams,
            "frames": r.frames,
            "bad_datagrams": r.bad_datagrams,
            "bad_records": r.bad_records,
            "other_messages": r.other_messages,
            "missed_frames": r.missed_frames,
            "frame_jumps": r.frame_jumps,
            "undecoded_frames": r.undecoded_frames,
            "untracked_bodies": r.untracked_bodies,
            "server_infos": r.server_infos,
            "requests_sent": r.requests_sent,
            "join_failures": r.join_failures,
            "kernel_dropped": r.kernel_dropped,
        }


def _is_multicast(address: str) -> bool:
    try:
        first = socket.inet_aton(address)[0]
    except OSError:
        return False
    return address.count(".") == 3 and 224 <= first <= 239


def _child_integer(access: ElementAccess, child: ConfigElement, prop: str) -> int:
    """An integer property of an embedded element (its definition's default when unset)."""
    try:
        return ElementAccess(child, access.repo).integer(prop)
    except ValueError as err:
        raise DeviceConfigError(f"{child.type} {child.full_name!r}: {prop}: {err}") from None
