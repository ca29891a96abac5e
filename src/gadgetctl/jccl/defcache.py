"""The bundled definitions as read, kept between processes (issue 27 goal 4).

Every `gadgetctl validate` process needs the bundled ``definitions/``; reading and parsing
their 89 files costs a fresh process about 20 ms, rebuilding them from this cache about
5 ms. The cache is one file per bundled directory in gadgetctl's own cache folder
(``$GADGETCTL_CACHE_DIR``; by default ``$XDG_CACHE_HOME/gadgetctl`` or ``~/.cache/gadgetctl``,
``%LOCALAPPDATA%\\gadgetctl`` on Windows; ``GADGETCTL_CACHE_DIR=`` set empty turns it off).

It is only ever a shortcut: a cache file is used when everything that decides what a
read gives is as it was when it was written (the directory, each ``*.jdef`` file's name,
size, times and inode, the Python, lxml and gadgetctl versions, and the source files of
the reading code); anything else (stale, corrupt, unreadable, not a regular file of this
user, writable by others) reads the files, and a fresh read replaces the cache file. It
is written to a new file that then takes the cache file's name, so a reader never sees
half a file and nothing else in the folder is touched. The file holds only data
(:mod:`marshal`: strings, numbers, tuples), never code or pickled objects.
"""

from __future__ import annotations

import marshal
import os
import stat
import sys
import zlib
from collections.abc import Mapping, Sequence
from pathlib import Path

from gadgetctl.jccl.definitions import (
    Definition,
    DefinitionVersion,
    EnumChoice,
    Enumeration,
    Location,
    PropertyDefinition,
    ValueSlot,
    ValueType,
)

#: What a definition file on the search path gave: its definition, or None and the problem.
FileOutcome = tuple[Path, Definition | None, str]

#: Changed whenever the layout of a cache file changes.
FORMAT = 1
#: The modules whose code decides what reading a directory gives (their source files'
#: sizes and times are part of the key).
READING_CODE = (
    "gadgetctl.boundedread",
    "gadgetctl.jccl.xmlload",
    "gadgetctl.jccl.defparser",
    "gadgetctl.jccl.definitions",
    "gadgetctl.jccl.repository",
    __name__,
)
CACHE_VAR = "GADGETCTL_CACHE_DIR"
_VALUETYPES = {v.value: v for v in ValueType}


def cache_dir(environ: Mapping[str, str] | None = None) -> Path | None:
    """gadgetctl's cache folder, or None when caching is off (``GADGETCTL_CACHE_DIR=``)."""
    env = os.environ if environ is None else environ
    chosen = env.get(CACHE_VAR)
    if chosen is not None:
        return Path(chosen) if chosen else None
    if os.name == "nt":
        base = env.get("LOCALAPPDATA")
        return Path(base) / "gadgetctl" if base else None
    base = env.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(base):  # (the XDG rule: a relative value is ignored)
        base = os.path.join(env.get("HOME") or os.path.expanduser("~"), ".cache")
        if not os.path.isabs(base):  # no home to speak of
            return None
    return Path(base) / "gadgetctl"


def cache_file(directory: Path, folder: Path) -> Path:
    """The cache file of ``directory``'s definitions in ``folder`` (one per directory, so
    that two installations do not take turns rewriting one file)."""
    return folder / f"definitions-{zlib.crc32(os.fsencode(directory)):08x}.marshal"


def key(directory: Path, files: Sequence[tuple[Path, os.stat_result]]) -> tuple:
    """Everything that decides what reading ``files`` of ``directory`` gives."""
    from importlib import import_module

    from lxml import etree

    from gadgetctl import __version__

    code = []
    for name in READING_CODE:
        source = import_module(name).__file__ or ""
        try:
            status = os.stat(source)
        except OSError:
            code.append((name, None))
        else:
            code.append((name, source, status.st_size, status.st_mtime_ns))
    return (
        FORMAT,
        sys.version,
        __version__,
        etree.LXML_VERSION,
        etree.LIBXML_VERSION,
        tuple(code),
        str(directory),
        tuple(
            (p.name, s.st_size, s.st_mtime_ns, s.st_ctime_ns, s.st_ino, s.st_dev) for p, s in files
        ),
    )


def load(
    directory: Path,
    files: Sequence[tuple[Path, os.stat_result]],
    environ: Mapping[str, str] | None = None,
) -> list[FileOutcome] | None:
    """What reading ``files`` (``directory``'s ``*.jdef`` files and their status, in name
    order) gave when the cache file was written, or None when there is no usable one."""
    folder = cache_dir(environ)
    if folder is None:
        return None
    try:
        data = _read_own_file(cache_file(directory, folder))
        if data is None:
            return None
        stored_key, outcomes = marshal.loads(data)
        if stored_key != key(directory, files):
            return None
        return _rebuild(directory, outcomes)
    except Exception:  # (a cache that cannot be read is no cache: the files are read)
        return None


def store(
    directory: Path,
    files: Sequence[tuple[Path, os.stat_result]],
    outcomes: Sequence[FileOutcome],
    environ: Mapping[str, str] | None = None,
) -> None:
    """Keep ``outcomes``, what reading ``files`` of ``directory`` gave, for later processes
    (quietly nothing when there is no cache folder, it cannot be written, or an outcome is
    not one this cache can hold)."""
    folder = cache_dir(environ)
    if folder is None:
        return
    try:
        data = marshal.dumps((key(directory, files), _flattened(directory, outcomes)))
    except _Unusual:
        return
    import tempfile

    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=folder, prefix=".definitions-", suffix=".tmp")
    except OSError:
        return
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(data)
        os.replace(temporary, cache_file(directory, folder))
    except OSError:
        try:
            os.unlink(temporary)
        except OSError:
            pass


def _read_own_file(path: Path) -> bytes | None:
    """The bytes of ``path`` when it is a regular file of this user that no one else may
    write (on Windows: when it is a regular file), else None."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
    try:
        handle = os.open(path, flags)
    except OSError:
        return None
    with os.fdopen(handle, "rb") as file:
        status = os.fstat(file.fileno())
        if not stat.S_ISREG(status.st_mode):
            return None
        if os.name != "nt" and (
            status.st_uid != os.getuid() or status.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
        ):
            return None
        return file.read()


class _Unusual(Exception):
    """An outcome this cache does not hold (it is then not written)."""


def _flattened(directory: Path, outcomes: Sequence[FileOutcome]) -> tuple:
    """``outcomes`` as strings, numbers and tuples (see :func:`_rebuild`)."""
    flat = []
    for path, definition, problem in outcomes:
        if path.parent != directory:
            raise _Unusual(path)
        if definition is None:
            flat.append((path.name, None, problem))
            continue
        shown = str(path)
        versions = tuple(
            (
                v.version,
                v.name,
                v.label,
                v.abstract,
                v.help,
                v.parents,
                v.categories,
                tuple(_flat_property(p, shown) for p in v.properties),
                v.upgrade_transform,
                _line(v.location, shown),
            )
            for v in definition.versions.values()
        )
        flat.append(
            (
                path.name,
                (
                    definition.name,
                    _line(definition.location, shown),
                    definition.icon_path,
                    tuple(definition.order),
                    versions,
                ),
                problem,
            )
        )
    return tuple(flat)


def _flat_property(prop: PropertyDefinition, shown: str) -> tuple:
    enumeration = prop.enumeration
    return (
        prop.name,
        prop.valuetype.value,
        prop.variable,
        prop.help,
        tuple((slot.label, slot.default) for slot in prop.values),
        prop.allowed_types,
        None
        if enumeration is None
        else (enumeration.editable, tuple((c.label, c.value) for c in enumeration.choices)),
        _line(prop.location, shown),
    )


def _line(location: object, shown: str) -> int | None:
    """The line of a location of the file ``shown`` read without columns (the only kind a
    directory's read gives)."""
    if type(location) is not Location or location.path != shown or location.column is not None:
        raise _Unusual(location)
    return location.line


def _rebuild(directory: Path, flat: tuple) -> list[FileOutcome]:
    """The outcomes :func:`_flattened` flattened."""
    outcomes: list[FileOutcome] = []
    for file_name, definition, problem in flat:
        path = directory / file_name
        if definition is None:
            outcomes.append((path, None, problem))
            continue
        shown = str(path)
        name, line, icon_path, order, flat_versions = definition
        versions: dict[int, DefinitionVersion] = {}
        for (
            number,
            owner,
            label,
            abstract,
            help_text,
            parents,
            categories,
            props,
            upgrade,
            at,
        ) in flat_versions:
            versions[number] = DefinitionVersion(
                owner,
                number,
                label,
                abstract,
                help_text,
                parents,
                categories,
                tuple(_property(p, shown) for p in props),
                upgrade,
                Location(shown, at),
            )
        outcomes.append(
            (
                path,
                Definition(name, versions, Location(shown, line), icon_path, list(order)),
                problem,
            )
        )
    return outcomes


def _property(flat: tuple, shown: str) -> PropertyDefinition:
    name, valuetype, variable, help_text, slots, allowed, enumeration, line = flat
    return PropertyDefinition(
        name,
        _VALUETYPES[valuetype],
        variable,
        help_text,
        tuple([ValueSlot(label, default) for label, default in slots]),
        allowed,
        None
        if enumeration is None
        else Enumeration(
            enumeration[0], tuple([EnumChoice(label, value) for label, value in enumeration[1]])
        ),
        Location(shown, line),
    )
