"""Finding driver plug-ins without importing them.

Places, in order (the first plug-in of a name wins, later ones are listed as shadowed):

1. installed packages: entry points of the group ``gadgetctl.drivers`` (the entry point's
   value names the plug-in module);
2. the bundled ``drivers/`` directory;
3. each directory of ``GADGETCTL_DRIVER_PATH`` (``os.pathsep``-separated);
4. ``--driver-path`` directories given on the command line;
5. ``driver_path`` and ``driver_scan_path`` values of ``input_manager`` elements
   (environment variables expanded, relative paths taken from the configuration file's
   directory).

In a directory, a plug-in is a package (a folder with ``__init__.py``) or a module
(``name.py``); its name is the folder or file name, which is what a ``driver`` value
names. A package's ``*.jdef`` files define the element types it adds.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path

from gadgetctl.envvars import expand
from gadgetctl.files import entry_is_dir, entry_is_file, is_dir, is_file
from gadgetctl.input.kinds import BASE_DEFINITIONS, DeviceKind
from gadgetctl.input.plugins.distscan import may_declare
from gadgetctl.input.plugins.metadata import ELEMENT_TYPES, PluginMetadata, read_metadata
from gadgetctl.jccl.definitions import Location
from gadgetctl.resources import drivers_dir

ENTRY_POINT_GROUP = "gadgetctl.drivers"
DRIVER_PATH_ENV = "GADGETCTL_DRIVER_PATH"
_SKIPPED_MODULES = {"conftest.py", "setup.py"}


class PluginSource(StrEnum):
    ENTRY_POINT = "entry point"
    BUNDLED = "bundled"
    ENVIRONMENT = DRIVER_PATH_ENV
    OPTION = "--driver-path"
    DRIVER_PATH = "driver_path"
    SCAN_PATH = "driver_scan_path"


@dataclass
class DriverDirectory:
    """A directory searched for driver plug-ins, and where it was named."""

    path: Path
    source: PluginSource
    raw: str = ""
    location: Location | None = None
    undefined: tuple[str, ...] = ()

    @property
    def exists(self) -> bool:
        return is_dir(self.path)

    def __str__(self) -> str:
        return f"{self.path} ({self.source})"


@dataclass
class PluginInfo:
    """A discovered plug-in, described from its files only."""

    name: str
    path: Path  # the package directory or the module file
    source: PluginSource
    metadata: PluginMetadata
    package: bool
    origin: str = ""  # the directory, or the entry point
    module: str | None = None  # importable module name (entry points only)
    definition_files: list[Path] = field(default_factory=list)
    shadowed_by: PluginInfo | None = None

    @property
    def source_file(self) -> Path:
        return self.path / "__init__.py" if self.package else self.path

    @property
    def definition_dir(self) -> Path | None:
        return self.path if self.package and self.definition_files else None

    def declared_types(self) -> tuple[dict[str, tuple[DeviceKind, ...]], str]:
        """Element types and device types the plug-in provides, and where that was read:
        ``ELEMENT_TYPES`` in its source, else its own .jdef files (kinds from their parents)."""
        if self.metadata.element_types:
            return dict(self.metadata.element_types), ELEMENT_TYPES
        if self.definition_files:
            return definition_types(self.definition_files), "jdef"
        return {}, ""

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "source": self.source.value,
            "origin": self.origin,
            "path": str(self.path),
            "module": self.module,
            "package": self.package,
            "definitions": [str(p) for p in self.definition_files],
            "shadowed_by": None if self.shadowed_by is None else str(self.shadowed_by.path),
            **self.metadata.to_dict(),
        }


def definition_types(files: Iterable[Path]) -> dict[str, tuple[DeviceKind, ...]]:
    """Element types defined by ``.jdef`` files, with the device kinds their direct parents imply."""
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import load_file

    kinds_of = {base: kind for kind, base in BASE_DEFINITIONS.items()}
    found: dict[str, tuple[DeviceKind, ...]] = {}
    for path in files:
        try:
            doc = load_file(path)
        except OSError:
            continue
        definition = read_definition(doc, columns=False) if doc.root is not None else None
        if definition is None or not definition.name or not definition.versions:
            continue
        parents = definition.newest.parents
        found[definition.name] = tuple(kinds_of[p] for p in parents if p in kinds_of)
    return found


def plugin_at(path: Path) -> PluginInfo | None:
    """The plug-in at ``path`` (a package folder or a module file), or None."""
    path = path.resolve()
    if is_dir(path) and (path / "__init__.py").is_file():
        return _plugin(path.name, path, True, PluginSource.OPTION, str(path.parent))
    if is_file(path) and path.suffix == ".py":
        return _plugin(path.stem, path, False, PluginSource.OPTION, str(path.parent))
    return None


def _plugin(
    name: str,
    path: Path,
    package: bool,
    source: PluginSource,
    origin: str,
    module: str | None = None,
) -> PluginInfo:
    source_file = path / "__init__.py" if package else path
    definitions = _definition_files(path) if package else []
    return PluginInfo(
        name, path, source, read_metadata(source_file), package, origin, module, definitions
    )


def _definition_files(package: Path) -> list[Path]:
    """The ``*.jdef`` files of a package folder, in name order."""
    try:
        with os.scandir(package) as entries:
            names = [e.name for e in entries if e.name.endswith(".jdef") and entry_is_file(e)]
    except OSError:
        return []
    return [package / name for name in sorted(names)]


def scan_directory(directory: DriverDirectory) -> list[PluginInfo]:
    """Every plug-in directly inside ``directory``, in name order."""
    if not directory.exists:
        return []
    found: list[PluginInfo] = []
    origin = str(directory.path)
    with os.scandir(directory.path) as listing:
        entries = sorted(listing, key=lambda e: e.name)
    for entry in entries:
        name = entry.name
        if name.startswith((".", "_")):
            continue
        if entry_is_dir(entry) and os.path.isfile(os.path.join(entry.path, "__init__.py")):
            path = directory.path / name
            found.append(_plugin(name, path, True, directory.source, origin))
        elif (
            name.endswith(".py")
            and name not in _SKIPPED_MODULES
            and not name.startswith("test_")
            and entry_is_file(entry)
        ):
            path = directory.path / name
            found.append(_plugin(name[: -len(".py")], path, False, directory.source, origin))
    return found


def find_module_file(module: str) -> tuple[Path, bool] | None:
    """Where ``module`` (dotted) lives on ``sys.path``, found without importing anything."""
    parts = module.split(".")
    for base in sys.path:
        root = Path(base or ".")
        package = root.joinpath(*parts)
        if (package / "__init__.py").is_file():
            return package, True
        candidate = root.joinpath(*parts[:-1], parts[-1] + ".py")
        if candidate.is_file():
            return candidate, False
    return None


def entry_point_plugins() -> list[PluginInfo]:
    """Plug-ins of installed distributions (entry point group ``gadgetctl.drivers``)."""
    found: list[PluginInfo] = []
    for name, value, dist in _installed_entry_points():
        module = value.partition(":")[0].strip()
        origin = f"{name} = {value}" + (f" ({dist})" if dist else "")
        located = find_module_file(module)
        if located is None:
            meta = PluginMetadata()
            meta.problems.append(f"module {module!r} of the entry point is not on sys.path")
            found.append(
                PluginInfo(
                    name, Path(module), PluginSource.ENTRY_POINT, meta, False, origin, module
                )
            )
            continue
        path, package = located
        found.append(_plugin(name, path, package, PluginSource.ENTRY_POINT, origin, module))
    return found


#: The group's entry points as last read, with the sys.path they were read from and the
#: mtime_ns of its directories (installing or removing a distribution adds or removes a
#: folder there; importlib.metadata keeps its own directory listings the same way).
_ENTRY_POINTS: list[tuple[tuple, list[tuple[str, str, str]]]] = []


def _installed_entry_points() -> list[tuple[str, str, str]]:
    """(name, value, "distribution version" or "") of each entry point of the group, in name
    order, read again only once sys.path or one of its directories changed."""
    signature = tuple(_directory_state(entry) for entry in sys.path)
    if _ENTRY_POINTS and _ENTRY_POINTS[0][0] == signature:
        return _ENTRY_POINTS[0][1]
    found = []
    if not may_declare(ENTRY_POINT_GROUP):  # the usual case: no importlib.metadata to import
        _ENTRY_POINTS[:] = [(signature, found)]
        return found
    from importlib import metadata as importlib_metadata

    for entry in sorted(
        importlib_metadata.entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name
    ):
        dist = getattr(entry, "dist", None)
        found.append((entry.name, entry.value, f"{dist.name} {dist.version}" if dist else ""))
    _ENTRY_POINTS[:] = [(signature, found)]
    return found


def _directory_state(entry: str) -> tuple[str, int | None]:
    """A sys.path entry as an absolute path ("" is the working directory) and its mtime_ns."""
    try:
        return os.path.abspath(entry or "."), os.stat(entry or ".").st_mtime_ns
    except OSError:
        return entry, None


def directory_entry(
    raw: str,
    source: PluginSource,
    *,
    base: Path | None = None,
    environ: Mapping[str, str] | None = None,
    location: Location | None = None,
) -> DriverDirectory:
    expansion = expand(raw.strip(), environ)
    path = Path(expansion.text).expanduser()
    if not path.is_absolute() and base is not None:
        path = base / path
    return DriverDirectory(path, source, raw, location, expansion.undefined)


def standard_directories(
    extra: Iterable[Path] = (), *, bundled: bool = True, environ: Mapping[str, str] | None = None
) -> list[DriverDirectory]:
    """Bundled drivers, GADGETCTL_DRIVER_PATH, then ``extra`` (``--driver-path``)."""
    env = os.environ if environ is None else environ
    dirs: list[DriverDirectory] = []
    if bundled:
        dirs.append(DriverDirectory(drivers_dir(), PluginSource.BUNDLED, str(drivers_dir())))
    for raw in (env.get(DRIVER_PATH_ENV) or "").split(os.pathsep):
        if raw.strip():
            dirs.append(directory_entry(raw, PluginSource.ENVIRONMENT, environ=env))
    for path in extra:
        dirs.append(directory_entry(str(path), PluginSource.OPTION, environ=env))
    return dirs


class DriverSearch:
    """The places plug-ins are looked for, and what is found there."""

    def __init__(
        self, directories: Iterable[DriverDirectory] = (), *, entry_points: bool = True
    ) -> None:
        self.directories: list[DriverDirectory] = list(directories)
        self.entry_points = entry_points
        self._plugins: list[PluginInfo] | None = None

    @classmethod
    def standard(
        cls,
        extra: Iterable[Path] = (),
        *,
        bundled: bool = True,
        entry_points: bool = True,
        environ: Mapping[str, str] | None = None,
    ) -> DriverSearch:
        return cls(
            standard_directories(extra, bundled=bundled, environ=environ), entry_points=entry_points
        )

    def add_directory(self, directory: DriverDirectory) -> None:
        if all(d.path != directory.path or d.source != directory.source for d in self.directories):
            self.directories.append(directory)
            self._plugins = None

    def plugins(self) -> list[PluginInfo]:
        """Every plug-in in every place, in search order; repeated names are shadowed."""
        if self._plugins is None:
            found = entry_point_plugins() if self.entry_points else []
            seen_paths = {p.path for p in found}
            for directory in self.directories:
                for info in scan_directory(directory):
                    if info.path not in seen_paths:
                        seen_paths.add(info.path)
                        found.append(info)
            first: dict[str, PluginInfo] = {}
            for info in found:
                if info.name in first:
                    info.shadowed_by = first[info.name]
                else:
                    first[info.name] = info
            self._plugins = found
        return self._plugins

    def find(self, name: str) -> PluginInfo | None:
        """The plug-in a ``driver`` value names (without platform extension or ``_d`` suffix)."""
        for info in self.plugins():
            if info.name == name and info.shadowed_by is None:
                return info
        # VR Juggler's input_manager definition spells some plug-ins differently from their
        # library (its "Optitrack_drv" is the OptiTrack_drv library; Windows does not care):
        # a single plug-in whose name differs only in case is the one meant.
        folded = [
            p
            for p in self.plugins()
            if p.name.casefold() == name.casefold() and p.shadowed_by is None
        ]
        return folded[0] if len(folded) == 1 else None

    def in_directory(self, directory: DriverDirectory) -> list[PluginInfo]:
        return [
            p for p in self.plugins() if p.origin == str(directory.path) and p.shadowed_by is None
        ]

    def providers(self, element_type: str) -> list[PluginInfo]:
        """Plug-ins whose metadata declares ``element_type``."""
        return [
            p
            for p in self.plugins()
            if p.shadowed_by is None and element_type in p.metadata.element_types
        ]

    def definition_dirs(self) -> list[Path]:
        """Directories of plug-ins that carry ``.jdef`` files (for the definition search path)."""
        return [
            p.definition_dir
            for p in self.plugins()
            if p.definition_dir is not None and p.shadowed_by is None
        ]

    def describe_places(self) -> str:
        places = ["installed entry points"] if self.entry_points else []
        places += [str(d) for d in self.directories]
        return ", ".join(places) if places else "nowhere (no place configured)"
