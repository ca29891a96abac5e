"""`gadgetctl validate`: run every check on a set of files and collect diagnostics.

Stages: each file is read safely and checked at the XML, format and schema level; the
definitions among the files join the definition repository (taking precedence over the
search path, so a file is judged by its own content) and get definition-level checks;
configurations are then checked against the definitions.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from gadgetctl.diagnostics import Diagnostic, sort_key
from gadgetctl.errors import GadgetctlError
from gadgetctl.files import resolved_paths
from gadgetctl.jccl.xmlload import DEFAULT_MAX_SIZE, FileKind, XmlDocument, load_file

if TYPE_CHECKING:
    from gadgetctl.jccl.repository import DefinitionRepository

LEVELS = ("xml", "schema", "definitions", "full")


@dataclass
class ValidateOptions:
    """What `gadgetctl validate` checks, how far, and against which definitions."""

    max_size: int = DEFAULT_MAX_SIZE
    level: str = "full"  # how far to go: xml, schema, definitions or full
    bundled: bool = True
    definition_dirs: list[Path] = field(default_factory=list)
    together: bool = False
    environ: Mapping[str, str] | None = None  # for ${VAR} in paths; os.environ when None
    #: The definitions of the search path (bundled, VJ_BASE_DIR, JCCL_DEFINITION_PATH,
    #: definition_dirs), when the caller already has them: the language server keeps them
    #: between checks instead of reading every .jdef again for each edit.
    repository: DefinitionRepository | None = None
    #: Driver plug-in searches by the places a configuration's input_manager elements name,
    #: kept between runs by a caller that checks again and again (the language server
    #: clears it now and then); None: each run searches afresh.
    driver_searches: dict | None = None


@dataclass
class ValidationResult:
    """The files checked, their findings, and their loaded documents."""

    files: list[str] = field(default_factory=list)
    diagnostics: list[Diagnostic] = field(default_factory=list)
    documents: list[XmlDocument] = field(default_factory=list)


def check_document(doc: XmlDocument, options: ValidateOptions) -> None:
    """XML-level and schema-level checks of one loaded document."""
    from gadgetctl.jccl.formats import check_format
    from gadgetctl.jccl.schema import check_schema
    from gadgetctl.jccl.straytext import stray_text

    if doc.root is None:
        return
    check_format(doc)
    doc.diagnostics.extend(stray_text(doc))
    if LEVELS.index(options.level) >= LEVELS.index("schema"):
        check_schema(doc)


def load_and_check(path: Path, options: ValidateOptions) -> XmlDocument:
    from gadgetctl.jccl.configload import parse_configuration

    try:
        # (a configuration's elements are read as it is parsed: see parse_configuration)
        doc = load_file(path, max_size=options.max_size, parse=parse_configuration)
    except OSError as err:
        raise GadgetctlError(f"{path}: {err.strerror or err}") from None
    check_document(doc, options)
    return doc


def search_path_diagnostics(
    repo, given: Iterable[str] = (), real_paths: Mapping[str, str] | None = None
) -> list[Diagnostic]:
    """Problems of user-given search-path entries (the bundled one is trusted). A file that
    is also ``given`` is reported with the file itself, not a second time here.
    ``real_paths``: the real paths of given files, where known."""
    found = list(repo.diagnostics)
    if found:
        known = real_paths or {}
        mine = {known.get(path) or _resolved(path) for path in given}
        found = [d for d in found if d.path is None or _resolved(d.path) not in mine]
    for entry in repo.entries:
        if entry.origin == "bundled":
            continue
        where = _where(entry.location) if entry.location else (entry.source,)
        for name in entry.undefined:
            found.append(
                Diagnostic.make(
                    "DEF022",
                    f"{entry.origin} entry {entry.raw!r} uses ${{{name}}}, which is not set; "
                    "the entry is skipped",
                    *where,
                )
            )
        if not entry.skipped and not entry.exists:
            found.append(
                Diagnostic.make(
                    "DEF023",
                    f"{entry.origin} directory {entry.path} does not exist",
                    *where,
                )
            )
    for shadow in repo.shadowed:
        if shadow.loser is not None:
            found.append(
                Diagnostic.make(
                    "DEF021",
                    f"{shadow.name} version {shadow.version} is ignored here: "
                    f"{shadow.winner} comes first on the search path",
                    shadow.loser.path,
                    shadow.loser.line,
                    shadow.loser.column,
                )
            )
    return found


def _resolved(path: str) -> str:
    from gadgetctl.files import real_path_text

    try:
        return real_path_text(path)
    except OSError:
        return path


def _where(location) -> tuple:
    return (location.path, location.line, location.column) if location else ()


def validate_paths(
    paths: Sequence[Path], options: ValidateOptions | None = None
) -> ValidationResult:
    from gadgetctl.perf import collector_paused

    with collector_paused():
        return _validate_paths(paths, options)


def _validate_paths(
    paths: Sequence[Path], options: ValidateOptions | None = None
) -> ValidationResult:
    from gadgetctl.jccl.defchecks import check_cycles, check_definition
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.repository import default_repository

    options = options or ValidateOptions()
    for directory in options.definition_dirs:
        if not directory.is_dir():
            raise GadgetctlError(f"--definitions {directory}: no such directory")
    result = ValidationResult()
    real_paths: dict[str, str] = {}  # each file's real path, by its path as shown
    for path, real in resolved_paths(paths):
        doc = load_and_check(path, options)
        real_paths[doc.path] = real
        result.files.append(doc.path)
        result.documents.append(doc)
        result.diagnostics.extend(doc.diagnostics)
    if LEVELS.index(options.level) < LEVELS.index("definitions"):
        result.diagnostics.sort(key=sort_key)
        return result

    definitions = [
        d
        for d in (
            read_definition(doc)
            for doc in result.documents
            if doc.root is not None and doc.kind is FileKind.DEFINITION
        )
        if d and d.name
    ]
    base = options.repository
    if base is None:
        base = default_repository(options.definition_dirs, bundled=options.bundled)
    repo = base.overlay(definitions)
    result.diagnostics.extend(search_path_diagnostics(base, result.files, real_paths))
    for definition in definitions:
        result.diagnostics.extend(check_definition(definition, definition.order, repo))
    result.diagnostics.extend(check_cycles(definitions, repo))
    if options.level == "full":
        result.diagnostics.extend(check_configurations(result, repo, options, real_paths))
    result.diagnostics.sort(key=sort_key)
    return result


def check_configurations(
    result: ValidationResult,
    repo,
    options: ValidateOptions,
    real_paths: Mapping[str, str] | None = None,
) -> list[Diagnostic]:
    """Configuration-level checks of the configurations among the files (see
    :mod:`gadgetctl.jccl.configcheck`): each file with its includes, or all of them as one
    configuration with ``options.together``. ``real_paths``: the files' real paths, by
    their paths as shown, where known."""
    from gadgetctl.jccl.configcheck import check_documents

    # One driver search per set of driver places for the three questions below (each
    # search scans the plug-in directories and the installed entry points).
    searches = {} if options.driver_searches is None else options.driver_searches
    return check_documents(
        result.documents,
        repo,
        together=options.together,
        environ=options.environ,
        plugin_definitions=plugin_definition_finder(options.environ, searches),
        plugin_names=plugin_name_finder(options.environ, searches),
        unloaded_types=unloaded_type_finder(options.environ, searches),
        real_paths=real_paths,
    )


def plugin_definition_finder(environ=None, searches: dict | None = None):
    """A function giving the definition folders of the driver plug-ins a configuration can
    load (bundled, installed, GADGETCTL_DRIVER_PATH, its input_manager driver paths)."""
    searches = {} if searches is None else searches

    def find(config) -> list[Path]:
        return _driver_search(config, environ, searches).definition_dirs()

    return find


def plugin_name_finder(environ=None, searches: dict | None = None):
    """A function giving the names of the driver plug-ins a configuration can load."""
    searches = {} if searches is None else searches

    def find(config) -> set[str]:
        search = _driver_search(config, environ, searches)
        return {p.name for p in search.plugins() if p.shadowed_by is None}

    return find


def unloaded_type_finder(environ=None, searches: dict | None = None):
    """A function giving, for a configuration, the element types whose driver plug-in its
    input_manager elements never load, with the reason the input manager gives (DRV030)."""
    searches = {} if searches is None else searches  # one search per set of driver places

    def find(config) -> dict[str, str]:
        from gadgetctl.input.unloaded import unloaded_types

        return unloaded_types(config, _driver_search(config, environ, searches))

    return find


def _driver_search(config, environ, searches: dict):
    """The driver search of a configuration, shared by every configuration whose
    input_manager elements name the same driver places."""
    from gadgetctl.input.definitions import DRIVER_PROPERTIES, driver_search_for
    from gadgetctl.input.kinds import INPUT_MANAGER

    places = tuple(
        (prop, value.text, str(Path(element.file).parent))
        for element in config.elements
        if element.type == INPUT_MANAGER
        for prop, _ in DRIVER_PROPERTIES
        for value in element.values(prop)
        if value.stripped
    )
    search = searches.get(places)
    if search is None:
        search = searches[places] = driver_search_for(configuration=config, environ=environ)
    return search


def summarize(diagnostics: Iterable[Diagnostic]) -> dict[str, int]:
    counts = {"error": 0, "warning": 0, "info": 0}
    for d in diagnostics:
        counts[d.severity.value] += 1
    return counts
