"""Which process holds a local TCP or UDP port, read from Linux's /proc (no external tool).

``/proc/net/{tcp,udp}[6]`` list the sockets with their local address and inode; each
process's ``/proc/PID/fd`` links name the sockets it holds (``socket:[INODE]``). Processes
of other users cannot be looked into without privileges; they are then not named.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass
from pathlib import Path

PROC = Path("/proc")
TCP_LISTEN = "0A"


@dataclass(frozen=True, slots=True)
class PortOwner:
    pid: int
    command: str

    def __str__(self) -> str:
        return f"{self.command} (pid {self.pid})"


def _socket_inodes(protocol: str, port: int, proc: Path) -> set[str]:
    inodes: set[str] = set()
    for table in (protocol, protocol + "6"):
        try:
            lines = (proc / "net" / table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            if len(fields) < 10:
                continue
            local, state, inode = fields[1], fields[3], fields[9]
            try:
                local_port = int(local.rpartition(":")[2], 16)
            except ValueError:
                continue
            if local_port != port or inode == "0":
                continue
            if protocol == "tcp" and state != TCP_LISTEN:
                continue
            inodes.add(inode)
    return inodes


def _command(pid_dir: Path) -> str:
    with contextlib.suppress(OSError):
        argv = (pid_dir / "cmdline").read_bytes().split(b"\0")
        words = [a.decode(errors="replace") for a in argv if a]
        if words:
            text = " ".join(" ".join([os.path.basename(words[0]), *words[1:]]).split())
            return text if len(text) <= 200 else text[:197] + "..."
    with contextlib.suppress(OSError):
        return (pid_dir / "comm").read_text().strip()
    return "?"


def port_owners(protocol: str, port: int, *, proc: Path = PROC) -> list[PortOwner]:
    """The processes holding a ``protocol`` ("tcp": listening, or "udp") socket on local
    ``port``, as far as this user may see them."""
    inodes = _socket_inodes(protocol, port, proc)
    if not inodes:
        return []
    wanted = {f"socket:[{inode}]" for inode in inodes}
    owners: list[PortOwner] = []
    for pid_dir in proc.iterdir():
        if not pid_dir.name.isdigit():
            continue
        try:
            fds = list((pid_dir / "fd").iterdir())
        except OSError:
            continue
        for fd in fds:
            try:
                target = os.readlink(fd)
            except OSError:
                continue
            if target in wanted:
                owners.append(PortOwner(int(pid_dir.name), _command(pid_dir)))
                break
    return sorted(owners, key=lambda o: o.pid)


def describe_owners(protocol: str, port: int) -> str:
    """ "by NAME (pid N)" or "by another program" when the holder cannot be seen."""
    owners = port_owners(protocol, port)
    if not owners:
        return f"by another program (not visible to this user; `ss -lpn 'sport = :{port}'` as root names it)"
    return "by " + ", ".join(str(o) for o in owners)
