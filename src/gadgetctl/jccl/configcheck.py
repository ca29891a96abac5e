"""Semantic checks of configurations against their definitions.

A *configuration* is what VR Juggler would load at once: one file with its includes, or,
with ``together``, every file given. Without ``together`` a file that another given file
includes is checked as part of the configuration that includes it (where its pointers
can be resolved) rather than on its own.

Each configuration's ``<definition_path>`` directories join the search path after every
other entry, resolved against the directory of the file that names them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.envvars import expand
from gadgetctl.files import real_path
from gadgetctl.jccl.configuration import ConfigElement, ConfigFile, Configuration
from gadgetctl.jccl.elementcheck import ElementChecker, at, describe
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.runtime import PATH_PROPERTIES
from gadgetctl.jccl.searchpath import SearchPathEntry, configuration_entries
from gadgetctl.jccl.typeindex import TypeIndex
from gadgetctl.jccl.units import proxy_unit_problems
from gadgetctl.jccl.wiring import Scope, check_wiring
from gadgetctl.jccl.xmlload import FileKind, XmlDocument
from gadgetctl.perf import collector_paused, retain


class Session:
    """Shared state of one run: parsed documents, read files, per-repository checkers."""

    def __init__(
        self,
        base: DefinitionRepository,
        environ: Mapping[str, str] | None = None,
        *,
        plugin_definitions: Callable[[Configuration], list[Path]] | None = None,
        plugin_names: Callable[[Configuration], set[str]] | None = None,
        unloaded_types: Callable[[Configuration], dict[str, str]] | None = None,
    ) -> None:
        self.base = base
        self.environ: Mapping[str, str] = os.environ if environ is None else environ
        self.documents: dict[Path, XmlDocument] = {}
        self.files: dict[Path, ConfigFile] = {}
        #: Definition folders of driver plug-ins usable by a configuration (their own
        #: element types); consulted only when the configuration uses a type the repository
        #: lacks.
        self.plugin_definitions = plugin_definitions
        #: Names of the driver plug-ins a configuration can load (exact spelling).
        self.plugin_names = plugin_names
        #: Element types whose driver plug-in the configuration never loads -> why (DRV030).
        self.unloaded_types = unloaded_types
        self._repos: dict[tuple[Path, ...], DefinitionRepository] = {}
        self._checkers: dict[int, ElementChecker] = {}

    def load(self, paths: Iterable[Path]) -> Configuration:
        from gadgetctl.jccl.configload import load_configuration

        return load_configuration(
            paths, environ=self.environ, documents=self.documents, files=self.files
        )

    def definition_entries(self, config: Configuration) -> list[SearchPathEntry]:
        entries: list[SearchPathEntry] = []
        for config_file in config.files:
            entries += configuration_entries(
                config_file.definition_dirs, config_file.path.parent, self.environ
            )
        return entries

    def repository(
        self, config: Configuration
    ) -> tuple[DefinitionRepository, list[SearchPathEntry]]:
        """The base repository extended by the configuration's definition_path entries and,
        when it needs them, the definitions its driver plug-ins carry."""
        entries = self.definition_entries(config)
        repo = self._extended(entries)
        if self.plugin_definitions is not None and _uses_unknown_type(config, repo):
            known = {e.path.resolve() for e in repo.entries}
            extra = [
                SearchPathEntry(raw=str(d), path=d, origin="driver plug-in")
                for d in self.plugin_definitions(config)
                if d.resolve() not in known
            ]
            if extra:
                repo = self._extended(entries + extra)
        return repo, entries

    def _extended(self, entries: list[SearchPathEntry]) -> DefinitionRepository:
        if not entries:
            return self.base
        key = tuple(e.path for e in entries)
        repo = self._repos.get(key)
        if repo is None:
            repo = self._repos[key] = self.base.extended(entries)
        return repo

    def checker(self, repo: DefinitionRepository) -> ElementChecker:
        checker = self._checkers.get(id(repo))
        if checker is None:
            shown = (
                "; ".join(
                    "bundled definitions" if e.origin == "bundled" else str(e.path)
                    for e in repo.entries
                )
                or "empty"
            )
            checker = self._checkers[id(repo)] = ElementChecker(TypeIndex(repo), shown)
        return checker


def check_configuration(config: Configuration, session: Session, scope: Scope) -> list[Diagnostic]:
    """Every configuration-level finding of one loaded configuration."""
    found = list(config.diagnostics)
    repo, entries = session.repository(config)
    found += _definition_path_findings(entries)
    checker = session.checker(repo)
    notes: list[tuple[Diagnostic, str]] = []
    for element in config.loaded:
        report = checker.check(element)  # (kept as element.report, which wiring reads)
        found += report.diagnostics
        if report.notes:
            notes += report.notes
        if element.type in _PATH_TYPES:
            found += _path_variables(element, session.environ)
    if notes:
        found += _suggestions(notes, config, session)
    unloaded = session.unloaded_types(config) if session.unloaded_types is not None else {}
    found += check_wiring(config, checker.index, scope, unloaded)
    found += proxy_unit_problems(config.elements, repo)
    return found


def _suggestions(
    notes: list[tuple[Diagnostic, str]], config: Configuration, session: Session
) -> list[Diagnostic]:
    """The notes whose value no element and no loadable plug-in has as its exact name."""
    names = {e.name for e in config.all_elements()}
    if session.plugin_names is not None:
        names |= session.plugin_names(config)
    return [diagnostic for diagnostic, value in notes if value not in names]


def _uses_unknown_type(config: Configuration, repo: DefinitionRepository) -> bool:
    elements = config.all_elements() if config.may_embed() else config.elements
    return any(type_name not in repo for type_name in {e.type for e in elements})


def _definition_path_findings(entries: list[SearchPathEntry]) -> list[Diagnostic]:
    found = []
    for entry in entries:
        location = entry.location
        if location is None:
            continue
        for name in entry.undefined:
            found.append(
                at(
                    "CFG003",
                    f"definition directory {entry.raw!r} uses ${{{name}}}, which is not set; "
                    "the entry is skipped",
                    location,
                )
            )
        if not entry.skipped and not entry.exists:
            found.append(
                at(
                    "DEF023",
                    f"definition directory {entry.path} does not exist",
                    location,
                    hint="Relative directories are resolved against the configuration "
                    "file's directory (VR Juggler uses the working directory).",
                )
            )
    return found


_PATH_TYPES = frozenset(type_name for type_name, _ in PATH_PROPERTIES)


def _path_variables(element: ConfigElement, environ: Mapping[str, str]) -> list[Diagnostic]:
    if element.type not in _PATH_TYPES:
        return []
    found = []
    for prop, values in element.property_items():
        if (element.type, prop) not in PATH_PROPERTIES:
            continue
        for value in values:
            for name in expand(value.stripped, environ).undefined:
                found.append(
                    at(
                        "CFG003",
                        f"{describe(element)}: {prop} {value.stripped!r} uses "
                        f"${{{name}}}, which is not set",
                        value.location,
                    )
                )
    return found


def _is_configuration(doc: XmlDocument) -> bool:
    if doc.root is None or doc.kind is not FileKind.CONFIGURATION:
        return False
    tag = doc.root.tag
    return isinstance(tag, str) and tag.rpartition("}")[2] == "configuration"


def check_documents(
    documents: Iterable[XmlDocument],
    base: DefinitionRepository,
    *,
    together: bool = False,
    environ: Mapping[str, str] | None = None,
    plugin_definitions: Callable[[Configuration], list[Path]] | None = None,
    plugin_names: Callable[[Configuration], set[str]] | None = None,
    unloaded_types: Callable[[Configuration], dict[str, str]] | None = None,
    real_paths: Mapping[str, str] | None = None,
) -> list[Diagnostic]:
    """Configuration-level findings for the configuration documents among ``documents``
    (``real_paths``: their real paths by their paths, where the caller knows them)."""
    session = Session(
        base,
        os.environ if environ is None else environ,
        plugin_definitions=plugin_definitions,
        plugin_names=plugin_names,
        unloaded_types=unloaded_types,
    )
    known = real_paths or {}

    def resolved(doc: XmlDocument) -> Path:
        real = known.get(doc.path)
        return Path(real) if real is not None else real_path(doc.path)

    given: list[Path] = []
    for doc in documents:
        if _is_configuration(doc):
            path = resolved(doc)
            session.documents[path] = doc
            given.append(path)
        elif doc.root is None and doc.kind is FileKind.CONFIGURATION:
            # Reported with the file itself; an include of it must not report it again.
            session.documents[resolved(doc)] = doc
    if not given:
        return []
    retain(session)  # (the loaded configurations: kept to the end when nothing is freed then)
    if together:
        config = session.load(given)
        names = ", ".join(Path(p).name for p in given)
        return _unique(check_configuration(config, session, Scope(True, names)))
    configs = {path: session.load([path]) for path in given}
    retain(configs)
    found: list[Diagnostic] = []
    reported: set[tuple] = set()
    for path in _roots(configs):
        mine = _unique(check_configuration(configs[path], session, Scope(False, path.name)))
        # A file included by several configurations: one finding per place and code (the
        # first configuration's wording), not one per configuration.
        found += [d for d in mine if (d.code, d.path, d.line, d.column) not in reported]
        reported.update((d.code, d.path, d.line, d.column) for d in mine)
    return _unique(found)


def _roots(configs: dict[Path, Configuration]) -> list[Path]:
    """Given files not included (directly or not) by another given file that they do not include."""
    reach = {path: {f.path for f in config.files} for path, config in configs.items()}
    included_by: dict[Path, list[Path]] = {}
    for path, files in reach.items():
        for included in files:
            if included != path and included in configs:
                included_by.setdefault(included, []).append(path)
    return [
        path
        for path in configs
        if not any(other not in reach[path] for other in included_by.get(path, ()))
    ]


def _unique(diagnostics: list[Diagnostic]) -> list[Diagnostic]:
    seen: set[Diagnostic] = set()
    result = []
    for d in diagnostics:
        if d not in seen:
            seen.add(d)
            result.append(d)
    return result


class OpenedConfiguration:
    """A configuration, the index of the types it is judged by, and its session."""

    __slots__ = ("configuration", "index", "session")

    def __init__(self, configuration: Configuration, index: TypeIndex, session: Session) -> None:
        self.configuration = configuration
        self.index = index
        self.session = session


def open_configuration(
    paths: Iterable[Path],
    *,
    definition_dirs: Iterable[Path] = (),
    bundled: bool = True,
    environ: Mapping[str, str] | None = None,
    plugin_definitions: Callable[[Configuration], list[Path]] | None = None,
) -> OpenedConfiguration:
    """Load files as one configuration (includes followed) with the repository they are
    judged by. A file that is missing or not well-formed raises :class:`GadgetctlError`."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.files import require_file
    from gadgetctl.jccl.configload import require_loadable
    from gadgetctl.jccl.repository import default_repository

    paths = list(paths)
    for path in paths:
        require_file(path)
    for directory in definition_dirs:
        if not directory.is_dir():
            raise GadgetctlError(f"--definitions {directory}: no such directory")
    with collector_paused():  # bulk work whose objects all live on (see gadgetctl.perf)
        session = Session(
            default_repository(definition_dirs, bundled=bundled),
            os.environ if environ is None else environ,
            plugin_definitions=plugin_definitions,
        )
        config = session.load(paths)
        require_loadable(config)
        repo, _ = session.repository(config)
        return OpenedConfiguration(config, session.checker(repo).index, session)
