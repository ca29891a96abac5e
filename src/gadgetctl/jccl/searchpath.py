"""The definition search path: where .jdef files are looked for, in order.

1. the bundled ``definitions/`` (unless left out with ``--no-bundled``);
2. ``${VJ_BASE_DIR}/share/vrjuggler/data/definitions`` when ``VJ_BASE_DIR`` is set;
3. each entry of ``JCCL_DEFINITION_PATH`` (``os.pathsep``-separated);
4. ``--definitions DIR`` options;
5. ``<definition_path><dir>`` entries of configurations, resolved against the directory of
   the configuration file. (VR Juggler resolves them against the process working directory,
   which makes a configuration mean different things depending on where it is started.)

Earlier entries win when two provide the same definition name and version.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.envvars import expand
from gadgetctl.files import is_dir
from gadgetctl.jccl.definitions import Location
from gadgetctl.resources import definitions_dir

VJ_DEFINITIONS = Path("share") / "vrjuggler" / "data" / "definitions"


@dataclass
class SearchPathEntry:
    """A directory of the definition search path, where it came from, and what it gave."""

    raw: str
    path: Path
    origin: str
    undefined: tuple[str, ...] = ()
    location: Location | None = None
    contributed: int = 0
    files: int = 0

    @property
    def exists(self) -> bool:
        return is_dir(self.path)

    @property
    def skipped(self) -> bool:
        """An entry naming a variable that is not set is not searched at all (its
        expansion with the variable left empty would be some other directory)."""
        return bool(self.undefined)

    @property
    def source(self) -> str | None:
        """Where the entry was written, for a finding about it: its file position, the
        environment variable or the option."""
        if self.location is not None:
            return self.location.path
        if self.origin in ("JCCL_DEFINITION_PATH", "VJ_BASE_DIR"):
            return f"${self.origin}"
        return self.origin if self.origin.startswith("--") else None

    def to_dict(self) -> dict[str, object]:
        return {
            "path": str(self.path),
            "as_written": self.raw,
            "origin": self.origin,
            "exists": self.exists,
            "files": self.files,
            "definitions": self.contributed,
            "undefined_variables": list(self.undefined),
            "skipped": self.skipped,
            "location": str(self.location) if self.location else None,
        }


def make_entry(
    raw: str,
    origin: str,
    *,
    base: Path | None = None,
    environ: Mapping[str, str] | None = None,
    location: Location | None = None,
) -> SearchPathEntry:
    expansion = expand(raw, environ)
    path = Path(expansion.text).expanduser()
    if not path.is_absolute() and base is not None:
        path = base / path
    return SearchPathEntry(
        raw=raw, path=path, origin=origin, undefined=expansion.undefined, location=location
    )


@dataclass
class SearchPathOptions:
    """What the definition search path is made of."""

    bundled: bool = True
    extra_dirs: list[Path] = field(default_factory=list)
    environ: Mapping[str, str] | None = None


def build_search_path(options: SearchPathOptions | None = None) -> list[SearchPathEntry]:
    options = options or SearchPathOptions()
    env = os.environ if options.environ is None else options.environ
    entries: list[SearchPathEntry] = []
    if options.bundled:
        entries.append(
            SearchPathEntry(raw=str(definitions_dir()), path=definitions_dir(), origin="bundled")
        )
    if env.get("VJ_BASE_DIR"):
        entries.append(
            make_entry(str(Path("${VJ_BASE_DIR}") / VJ_DEFINITIONS), "VJ_BASE_DIR", environ=env)
        )
    for raw in (env.get("JCCL_DEFINITION_PATH") or "").split(os.pathsep):
        if raw.strip():
            entries.append(make_entry(raw, "JCCL_DEFINITION_PATH", environ=env))
    for directory in options.extra_dirs:
        entries.append(make_entry(str(directory), "--definitions", environ=env))
    return entries


def configuration_entries(
    dirs: Iterable[tuple[str, Location]], config_dir: Path, environ: Mapping[str, str] | None = None
) -> list[SearchPathEntry]:
    """Entries for ``<definition_path><dir>`` values of one configuration file."""
    return [
        make_entry(
            raw.strip(),
            f"definition_path in {location.path}",
            base=config_dir,
            environ=environ,
            location=location,
        )
        for raw, location in dirs
    ]
