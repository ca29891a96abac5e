"""Whether a System V shared-memory segment (trackd's) exists under a key and may be read,
from the kernel's table ``/proc/sysvipc/shm`` (no segment is attached)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gadgetctl.doctor.model import PortCheck, Status
from gadgetctl.doctor.permissions import Identity

SHM_TABLE = Path("/proc/sysvipc/shm")


@dataclass(frozen=True)
class Segment:
    key: int
    shmid: int
    mode: int
    size: int
    uid: int
    gid: int
    attached: int


def segments(table: Path = SHM_TABLE) -> dict[int, Segment]:
    """Every segment with a key, by key."""
    lines = table.read_text().splitlines()
    if not lines:
        return {}
    names = lines[0].split()
    found = {}
    for line in lines[1:]:
        row = dict(zip(names, line.split(), strict=False))
        try:
            seg = Segment(
                int(row["key"]),
                int(row["shmid"]),
                int(row["perms"], 8),
                int(row["size"]),
                int(row["uid"]),
                int(row["gid"]),
                int(row["nattch"]),
            )
        except (KeyError, ValueError):
            continue
        if seg.key:
            found[seg.key] = seg
    return found


def _readable(seg: Segment, identity: Identity) -> bool:
    if identity.uid == 0:
        return True
    if identity.uid == seg.uid:
        return bool(seg.mode & 0o400)
    if seg.gid in identity.gids:
        return bool(seg.mode & 0o040)
    return bool(seg.mode & 0o004)


def check_shm(
    key: int,
    *,
    identity: Identity | None = None,
    table: Path = SHM_TABLE,
    emulator: str | None = None,
) -> PortCheck:
    """One check of the segment under ``key``: present and readable by ``identity``."""
    target = f"shm key {key}"
    if not 0 < key <= 0x7FFFFFFF:
        return PortCheck(
            "shm",
            target,
            Status.PROBLEM,
            f"{key} is not a System V key (1 to 2147483647)",
            "DRV106",
        )
    try:
        found = segments(table).get(key)
    except OSError as err:
        return PortCheck(
            "shm", target, Status.UNCHECKED, f"cannot read {table}: {err.strerror or err}", "DRV105"
        )
    if found is None:
        hint = "start trackd (or whatever publishes the segment) first"
        if emulator:
            hint += f"; to try without it: gadgetctl emulate {emulator}"
        return PortCheck(
            "shm", target, Status.PROBLEM, f"no shared-memory segment has key {key}", "DRV100", hint
        )
    who = identity or Identity.current()
    if not _readable(found, who):
        return PortCheck(
            "shm",
            target,
            Status.PROBLEM,
            f"segment {found.shmid} (mode {found.mode:03o}, owner uid {found.uid}) "
            "may not be read by you",
            "DRV101",
            "run as the segment's owner or a member of its group, or have it made readable",
        )
    return PortCheck(
        "shm",
        target,
        Status.OK,
        f"segment {found.shmid}, {found.size} bytes, readable, {found.attached} attached",
    )
