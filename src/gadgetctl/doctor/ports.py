"""Checking one connection: a device file or serial port, a local UDP port, a TCP server.

Nothing here writes to a device or sends a byte: paths are only examined with ``stat``,
UDP ports are bound and closed at once, and a TCP server is connected to (and the
connection closed) only when a probe was asked for.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import socket
import stat

from gadgetctl.doctor.model import PortCheck, SerialPort, Status
from gadgetctl.doctor.permissions import Identity, access_hint, may_access, verb
from gadgetctl.doctor.stale import PTS_DIR, staleness
from gadgetctl.emulation.beacon import is_held

LOOPBACK = "127.0.0.1"
JOYSTICK_GLOB = "/dev/input/js*"


def list_serial_ports() -> list[SerialPort] | None:
    """Serial ports pyserial finds (None when pyserial cannot be imported)."""
    try:
        from serial.tools import list_ports
    except ImportError:
        return None
    return [
        SerialPort(p.device, p.description or "", p.hwid or "")
        for p in sorted(list_ports.comports())
    ]


def list_joysticks(
    pattern: str = JOYSTICK_GLOB, identity: Identity | None = None
) -> list[PortCheck]:
    """Every joystick device file matching ``pattern``, checked for reading."""
    return [check_path(path, "file", identity=identity) for path in sorted(glob.glob(pattern))]


def _problem(
    kind: str,
    target: str,
    code: str,
    detail: str,
    hint: str | None = None,
    status: Status = Status.PROBLEM,
) -> PortCheck:
    return PortCheck(kind, target, status, detail, code, hint)


def check_path(path: str, kind: str, *, identity: Identity | None = None) -> PortCheck:
    """A device file (``kind`` "file": read) or serial port ("serial": read and write).
    Symlinks are followed; ``identity`` None means the current user."""
    if not path:
        return _problem(kind, path, "DRV106", "the path is empty")
    need = os.R_OK | os.W_OK if kind == "serial" else os.R_OK
    link = f" (a symlink to {os.path.realpath(path)})" if os.path.islink(path) else ""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        if link:
            target = os.readlink(path)
            hint = (
                "a stale link left by an emulator that was killed: remove it and start the "
                "emulator again"
                if target.startswith(PTS_DIR)
                else None
            )
            return _problem(
                kind, path, "DRV100", f"is a symlink to {target}, which does not exist", hint
            )
        return _problem(kind, path, "DRV100", "does not exist")
    except PermissionError:
        return _problem(
            kind, path, "DRV101", "cannot be looked at: a directory on the way is not searchable"
        )
    except OSError as err:
        return _problem(kind, path, "DRV100", f"cannot be examined: {err.strerror or err}")
    mode = st.st_mode
    if stat.S_ISCHR(mode):
        what = "a character device"
    elif stat.S_ISFIFO(mode):
        what = "a FIFO (an emulator or another program writes it)"
    elif stat.S_ISREG(mode) and kind == "file":
        what = "a regular file"
    else:
        what = (
            "a directory"
            if stat.S_ISDIR(mode)
            else "a regular file"
            if stat.S_ISREG(mode)
            else "not a device"
        )
        return _problem(
            kind,
            path,
            "DRV102",
            f"is {what}{link}, not a device",
            "name the device node itself (for example /dev/ttyUSB0 or /dev/input/js0)",
        )
    who = identity or Identity.current()
    if not may_access(path, st, need, identity):
        return _problem(
            kind,
            path,
            "DRV101",
            f"is {what}{link} that you may not {verb(need)}",
            access_hint(st, who, need),
        )
    if stat.S_ISREG(mode):
        return _problem(
            kind,
            path,
            "DRV102",
            f"is a regular file{link}, not a device: it is read once to its end",
            "name the device node, or a FIFO an emulator writes",
            Status.WARNING,
        )
    stale = staleness(path)
    if stale is not None:
        return _problem(
            kind,
            path,
            "DRV108",
            stale.detail,
            stale.hint,
            Status.PROBLEM if stale.severe else Status.WARNING,
        )
    able = "readable and writable" if need & os.W_OK else "readable"
    held = (
        ", held by a live emulator"
        if (stat.S_ISFIFO(mode) or os.path.realpath(path).startswith(PTS_DIR)) and is_held(path)
        else ""
    )
    return PortCheck(kind, path, Status.OK, f"{what}{link}, {able}{held}")


def _port_problem(kind: str, port: int) -> PortCheck | None:
    if not 1 <= port <= 65535:
        return _problem(kind, f"{port}/{kind}", "DRV106", f"port {port} is not between 1 and 65535")
    return None


def check_udp(port: int, host: str = LOOPBACK) -> PortCheck:
    """Whether a driver could bind UDP ``host:port``: bind without SO_REUSEADDR, then close."""
    target = f"{port}/udp"
    bad = _port_problem("udp", port)
    if bad is not None:
        return bad
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 0)
        sock.bind((host, port))
    except OSError as err:
        if err.errno == errno.EADDRINUSE:
            return _problem(
                "udp",
                target,
                "DRV103",
                f"UDP port {port} is taken by another program",
                f"stop the program holding it (`ss -ulpn 'sport = :{port}'` shows it) "
                "or configure another port on both sides",
            )
        if err.errno == errno.EACCES:
            return _problem(
                "udp",
                target,
                "DRV103",
                f"binding UDP port {port} needs privileges",
                "use a port above 1023",
            )
        return _problem(
            "udp", target, "DRV103", f"cannot bind UDP {host}:{port}: {err.strerror or err}"
        )
    finally:
        sock.close()
    return PortCheck(
        "udp", target, Status.OK, f"UDP port {port} is free (bound and released on {host})"
    )


def check_multicast(group: str, interface: str = "0.0.0.0") -> PortCheck:
    """Whether a socket can join multicast ``group`` (a literal address) on ``interface``.
    Only link-local groups (224.0.0.x, never reported by the kernel) are joined; others are
    left unchecked, as joining one announces the membership on the network."""
    target = f"{group} (multicast)"
    try:
        packed = socket.inet_aton(group)
    except OSError:
        return _problem("udp", target, "DRV106", f"{group!r} is not an IPv4 address")
    if not 224 <= packed[0] <= 239:
        return _problem(
            "udp",
            target,
            "DRV106",
            f"{group} is not a multicast address (224.0.0.0 to 239.255.255.255)",
        )
    if packed[:3] != bytes([224, 0, 0]):
        return PortCheck(
            "udp",
            target,
            Status.UNCHECKED,
            f"joins multicast group {group} (not tried: it would be announced)",
        )
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(
            socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, packed + socket.inet_aton(interface)
        )
    except OSError as err:
        return _problem(
            "udp",
            target,
            "DRV103",
            f"cannot join multicast group {group}: {err.strerror or err}",
            "the host needs a multicast route (an interface that is up); unicast still arrives",
        )
    finally:
        sock.close()
    return PortCheck("udp", target, Status.OK, f"multicast group {group} can be joined")


def check_tcp(host: str, port: int, *, probe: bool, timeout: float) -> PortCheck:
    """Whether ``host:port`` accepts a TCP connection; only tried when ``probe``."""
    target = f"{host}:{port}"
    if not host:
        return _problem("tcp", target, "DRV106", "the host is empty")
    bad = _port_problem("tcp", port)
    if bad is not None:
        return bad
    if not probe:
        return PortCheck(
            "tcp",
            target,
            Status.UNCHECKED,
            f"not contacted (run with --probe to connect to {target})",
        )
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except socket.gaierror as err:
        return _problem(
            "tcp", target, "DRV104", f"host {host!r} does not resolve: {err.strerror or err}"
        )
    except ConnectionRefusedError:
        return _problem(
            "tcp",
            target,
            "DRV104",
            f"connection to {target} refused: nothing listens there",
            "start the server, or fix the address and port",
        )
    except TimeoutError:
        return _problem(
            "tcp",
            target,
            "DRV104",
            f"no answer from {target} within {timeout:g} s",
            "check that the host is up and no firewall drops the connection",
        )
    except OSError as err:
        return _problem(
            "tcp", target, "DRV104", f"cannot connect to {target}: {err.strerror or err}"
        )
    with contextlib.suppress(OSError):
        sock.close()
    return PortCheck("tcp", target, Status.OK, f"{target} accepts TCP connections")


def check_serve_port(host: str, port: int) -> PortCheck:
    """Whether `gadgetctl serve` could bind TCP and UDP ``host:port`` (as it does: TCP with
    SO_REUSEADDR); a taken port names the process holding it when this user can see it."""
    from gadgetctl.doctor.owners import describe_owners

    target = f"{host}:{port}"
    if not 1 <= port <= 65535:
        return _problem("serve", target, "DRV106", f"port {port} is not between 1 and 65535")
    for protocol, kind in (("tcp", socket.SOCK_STREAM), ("udp", socket.SOCK_DGRAM)):
        sock = socket.socket(socket.AF_INET, kind)
        try:
            if protocol == "tcp":
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, port))
        except OSError as err:
            if err.errno == errno.EADDRINUSE:
                return _problem(
                    "serve",
                    target,
                    "DRV120",
                    f"{protocol.upper()} port {port} is taken {describe_owners(protocol, port)}",
                    "stop that program, or serve on another port (--port) and name it in "
                    "the clients (NAME@host:PORT)",
                )
            if err.errno == errno.EACCES:
                return _problem(
                    "serve",
                    target,
                    "DRV120",
                    f"binding port {port} needs privileges",
                    "use a port above 1023 (VRPN's default is 3883)",
                )
            return _problem(
                "serve",
                target,
                "DRV120",
                f"cannot bind {protocol.upper()} {target}: {err.strerror or err}",
                "--bind takes an address of this machine (127.0.0.1, 0.0.0.0 or one of its NICs)",
            )
        finally:
            sock.close()
    return PortCheck(
        "serve",
        target,
        Status.OK,
        f"TCP and UDP port {port} are free on {host} for gadgetctl serve",
    )
