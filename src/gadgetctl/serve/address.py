"""Addresses `gadgetctl serve` binds and the ``--allow`` networks it accepts clients from."""

from __future__ import annotations

import ipaddress
import socket
from collections.abc import Iterable

from gadgetctl.errors import GadgetctlError

DEFAULT_BIND = "127.0.0.1"
DEFAULT_PORT = 3883  # VRPN's


def check_bind(address: str) -> str:
    """An IPv4 address to bind (VRPN is IPv4 only); host names are refused."""
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:
        raise GadgetctlError(
            f"--bind {address!r}: give an IPv4 address of this machine "
            f"(127.0.0.1, 0.0.0.0 for every interface, or one NIC's address)"
        ) from None
    if ip.version != 4:
        raise GadgetctlError(f"--bind {address}: VRPN speaks IPv4 only")
    return str(ip)


def check_port(port: int) -> int:
    if not 0 <= port <= 65535:
        raise GadgetctlError(f"--port {port}: a port is between 0 (chosen by the system) and 65535")
    return port


def is_loopback(address: str) -> bool:
    return ipaddress.ip_address(address).is_loopback


def parse_allow(networks: Iterable[str]) -> list[ipaddress.IPv4Network]:
    """``--allow`` values (``10.0.0.0/8``, ``192.168.1.7``) as networks."""
    result = []
    for text in networks:
        try:
            network = ipaddress.ip_network(text, strict=False)
        except ValueError:
            raise GadgetctlError(
                f"--allow {text!r}: expected an IPv4 network such as 192.168.1.0/24 or an address"
            ) from None
        if network.version != 4:
            raise GadgetctlError(f"--allow {text}: VRPN speaks IPv4 only")
        result.append(network)
    return result


def allowed(address: str, networks: list[ipaddress.IPv4Network]) -> bool:
    """Whether a client at ``address`` may connect (no networks: everyone may)."""
    if not networks:
        return True
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:
        return False
    return any(ip in network for network in networks)


def parse_serve_port(text: str) -> tuple[str, int]:
    """``[ADDR:]PORT`` of ``doctor --serve-port``."""
    host, _, port_text = text.rpartition(":")
    try:
        port = int(port_text)
    except ValueError:
        raise GadgetctlError(
            f"--serve-port {text!r}: expected PORT or ADDR:PORT, e.g. 3883"
        ) from None
    return check_bind(host or DEFAULT_BIND), port


def local_addresses() -> list[str]:
    """This machine's IPv4 addresses as far as the resolver knows (for start-up messages)."""
    try:
        return sorted(
            {info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)}
        )
    except OSError:
        return []
