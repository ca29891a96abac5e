"""VRPN device names for the elements `gadgetctl serve` shares.

A VRPN client addresses a device as ``NAME@host``: the name ends at the first ``@``, VRPN's
own configuration files split on white space, and a C++ peer refuses names longer than 95
characters. So every served element gets a name by this rule:

1. ``--name OLD=NEW`` renames come first; NEW must already be a valid name.
2. A valid element name (only ASCII letters, digits, ``_``, ``-`` and ``.``, at most 95
   characters) is kept unchanged, and such names are claimed before any derived one.
3. Every other name is derived: each run of other characters (spaces, ``@``, ``:``, ``/``,
   non-ASCII letters...) becomes one ``_``, and the result is cut to 95 characters
   (``Waveform Sticks`` -> ``Waveform_Sticks``; an empty result is ``unnamed``).
4. Derived names that collide with a name already given get ``_2``, ``_3``... (the first
   free one), the elements being taken in the order of their names (code points), so the
   outcome depends only on the set of names.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping

from gadgetctl.errors import GadgetctlError
from gadgetctl.suggest import close_names

MAX_NAME = 95
_VALID = re.compile(r"[A-Za-z0-9_.-]+")
_INVALID_RUN = re.compile(r"[^A-Za-z0-9_.-]+")


class NamingError(GadgetctlError):
    """A ``--name`` rename that cannot be applied."""


def is_valid_name(name: str) -> bool:
    return len(name) <= MAX_NAME and _VALID.fullmatch(name) is not None


def derive_name(element_name: str) -> str:
    """The VRPN name of ``element_name`` before collisions are resolved (rule 3)."""
    derived = _INVALID_RUN.sub("_", element_name)[:MAX_NAME]
    return derived or "unnamed"


def parse_renames(pairs: Iterable[str]) -> dict[str, str]:
    """``OLD=NEW`` strings as a mapping (the last ``=`` separates, as element names may hold one)."""
    renames: dict[str, str] = {}
    for pair in pairs:
        old, sep, new = pair.rpartition("=")
        if not sep or not old or not new:
            raise NamingError(
                f"--name {pair!r}: expected OLD=NEW (an element name, then its VRPN name)"
            )
        if not is_valid_name(new):
            raise NamingError(
                f"--name {pair!r}: {new!r} is not a VRPN name: use at most {MAX_NAME} ASCII "
                f"letters, digits, '_', '-' and '.' (for example {derive_name(new)!r})"
            )
        if old in renames and renames[old] != new:
            raise NamingError(f"--name: {old!r} is renamed twice ({renames[old]!r} and {new!r})")
        renames[old] = new
    return renames


def assign_names(
    element_names: Iterable[str], renames: Mapping[str, str] | None = None
) -> dict[str, str]:
    """The VRPN name of every element (element name -> VRPN name), by the module's rule."""
    names = sorted(set(element_names))
    renames = dict(renames or {})
    unknown = [old for old in renames if old not in names]
    if unknown:
        close = close_names(unknown[0], names, cutoff=0.6)
        hint = f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""
        raise NamingError(f"--name: no served element is called {unknown[0]!r}{hint}")
    taken: dict[str, str] = {}  # VRPN name -> element name
    for old, new in renames.items():
        if new in taken:
            raise NamingError(f"--name: {taken[new]!r} and {old!r} would both be served as {new!r}")
        taken[new] = old
    result = {old: new for old, new in renames.items()}
    for name in names:
        if name not in result and is_valid_name(name) and name not in taken:
            taken[name] = name
            result[name] = name
    for name in names:
        if name in result:
            continue
        base = derive_name(name)
        candidate, number = base, 1
        while candidate in taken:
            number += 1
            suffix = f"_{number}"
            candidate = base[: MAX_NAME - len(suffix)] + suffix
        taken[candidate] = name
        result[name] = candidate
    return result
