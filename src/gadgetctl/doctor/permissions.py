"""Who may read or write a device file, and which group to join when it is not you.

The current user is judged by ``os.access`` (which also knows ACLs and root); any other
:class:`Identity` by the file's mode bits, so the logic can be checked for a user other
than the one running (root, in CI, may read everything).
"""

from __future__ import annotations

import grp
import os
import pwd
import stat
from dataclasses import dataclass

_BITS = {  # need -> (owner, group, other) mode bits
    os.R_OK: (stat.S_IRUSR, stat.S_IRGRP, stat.S_IROTH),
    os.W_OK: (stat.S_IWUSR, stat.S_IWGRP, stat.S_IWOTH),
}


@dataclass(frozen=True)
class Identity:
    """A user: its uid and every group it belongs to."""

    uid: int
    gids: frozenset[int]

    @classmethod
    def current(cls) -> Identity:
        return cls(os.geteuid(), frozenset({os.getegid(), *os.getgroups()}))


def _wants(need: int) -> list[int]:
    return [flag for flag in (os.R_OK, os.W_OK) if need & flag]


def allowed(st: os.stat_result, identity: Identity, need: int) -> bool:
    """Whether ``identity`` may access a file of status ``st`` as ``need`` (R_OK|W_OK) says,
    from the mode bits (root may always)."""
    if identity.uid == 0:
        return True
    for flag in _wants(need):
        owner, group, other = _BITS[flag]
        if identity.uid == st.st_uid:
            bit = owner
        elif st.st_gid in identity.gids:
            bit = group
        else:
            bit = other
        if not st.st_mode & bit:
            return False
    return True


def may_access(path: str, st: os.stat_result, need: int, identity: Identity | None = None) -> bool:
    """``os.access`` for the current user (``identity`` None), the mode bits otherwise."""
    if identity is None:
        return os.access(path, need)
    return allowed(st, identity, need)


def group_name(gid: int) -> str:
    try:
        return grp.getgrgid(gid).gr_name
    except KeyError:
        return str(gid)


def owner_name(uid: int) -> str:
    try:
        return pwd.getpwuid(uid).pw_name
    except KeyError:
        return str(uid)


def verb(need: int) -> str:
    return " and ".join({os.R_OK: "read", os.W_OK: "write"}[f] for f in _wants(need))


def access_hint(st: os.stat_result, identity: Identity, need: int) -> str:
    """What to do so ``identity`` gets ``need`` access: the group to join when the file's
    group has it, else a udev rule."""
    group = group_name(st.st_gid)
    group_has = all(st.st_mode & _BITS[f][1] for f in _wants(need))
    if group_has and st.st_gid not in identity.gids:
        return (
            f"add yourself to group {group}: sudo usermod -aG {group} $USER "
            "(then log out and in again)"
        )
    mode = stat.filemode(st.st_mode)
    return (
        f"{mode} {owner_name(st.st_uid)}:{group} lets neither your groups nor others {verb(need)} it; "
        f'a udev rule with GROUP="{group}" MODE="0660" (and joining group {group}) grants access'
    )
