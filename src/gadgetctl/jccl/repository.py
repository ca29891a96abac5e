"""The definition repository: every version of every definition on the search path,
with inheritance resolved correctly.

Differences from VR Juggler's C++ repository, on purpose:

* every version is kept (the C++ keeps only the newest), so old elements can be checked
  against the rules they were written for and upgraded step by step;
* :meth:`DefinitionRepository.is_a` is reflexive and follows every parent (the C++
  ``isParent`` stops at the first resolvable parent);
* missing parents and inheritance cycles are recorded and reported, never a crash, and no
  recursion is used, so a thousand-level chain is fine.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl import defcache
from gadgetctl.jccl.definitions import (
    Definition,
    DefinitionVersion,
    Location,
    PropertyDefinition,
    ValueType,
)
from gadgetctl.jccl.searchpath import SearchPathEntry


@dataclass(frozen=True, slots=True)
class EffectiveProperty:
    """A property of a type, own or inherited, and the definition it comes from."""

    definition: PropertyDefinition
    defined_by: str
    defined_in: DefinitionVersion

    @property
    def name(self) -> str:
        return self.definition.name

    @property
    def inherited(self) -> bool:
        return self.defined_by != self.defined_in.name or False


@dataclass(frozen=True, slots=True)
class Shadowing:
    """A definition version ignored because an earlier entry of the search path has it."""

    name: str
    version: int
    winner: Location | None
    loser: Location | None


class DefinitionRepository:
    """Every version of every definition on a search path (see the module)."""

    def __init__(self, entries: list[SearchPathEntry] | None = None) -> None:
        self.entries: list[SearchPathEntry] = [] if entries is None else entries
        self.diagnostics: list[Diagnostic] = []
        self.shadowed: list[Shadowing] = []
        self._versions: dict[str, dict[int, DefinitionVersion]] = {}
        self._origins: dict[tuple[str, int], SearchPathEntry | None] = {}
        self._ancestor_cache: dict[str, tuple[str, ...]] = {}
        #: effective_properties and property_map by (name, version), cleared by add()
        self._effective_cache: dict[tuple[str, int | None], tuple[EffectiveProperty, ...]] = {}
        self._map_cache: dict[str, Mapping[str, PropertyDefinition]] = {}
        #: pointer_properties by name, cleared by add()
        self._pointer_cache: dict[str, tuple[str, ...]] = {}
        self._property_owners: dict[str, frozenset[str]] | None = None
        #: close_names answers by (word, cutoff), cleared by add()
        self._close_cache: dict[tuple[str, float], list[str]] = {}
        #: Counts the calls of add(): an answer kept with the generation it was worked out
        #: in holds while the generation is the same.
        self.generation = 0

    # -- building ---------------------------------------------------------------------

    @classmethod
    def from_search_path(cls, entries: Iterable[SearchPathEntry]) -> DefinitionRepository:
        repo = cls()
        for entry in entries:
            repo.load_entry(entry)
        return repo

    def load_entry(self, entry: SearchPathEntry) -> None:
        """Load every ``*.jdef`` file of a directory (not recursive), in name order. A
        directory already on the search path is ignored: it would only shadow itself."""
        if any(_same_directory(entry.path, e.path) for e in self.entries):
            return
        self.entries.append(entry)
        if entry.skipped or not entry.exists:
            return
        for path, definition, problem in _read_directory(
            entry.path, lasting=entry.origin == "bundled"
        ):
            entry.files += 1
            if definition is None:
                self.diagnostics.append(Diagnostic.make("DEF020", problem, str(path)))
                continue
            entry.contributed += self.add(definition, entry)

    def add(self, definition: Definition, entry: SearchPathEntry | None = None) -> int:
        """Add every version of ``definition``; an existing name and version wins. Returns how many were added."""
        self.generation += 1
        self._ancestor_cache.clear()
        self._effective_cache.clear()
        self._map_cache.clear()
        self._pointer_cache.clear()
        self._property_owners = None
        self._close_cache.clear()
        versions = self._versions.setdefault(definition.name, {})
        added = 0
        for number, version in sorted(definition.versions.items()):
            existing = versions.get(number)
            if existing is not None:
                self.shadowed.append(
                    Shadowing(definition.name, number, existing.location, version.location)
                )
                continue
            versions[number] = version
            self._origins[(definition.name, number)] = entry
            added += 1
        return added

    def overlay(self, definitions: Iterable[Definition]) -> DefinitionRepository:
        """A repository where ``definitions`` come first and this one's fill the rest."""
        repo = DefinitionRepository(entries=list(self.entries))
        for definition in definitions:
            if definition.name:
                repo.add(definition)
        for name, versions in self._versions.items():
            mine = repo._versions.setdefault(name, {})
            for number, version in versions.items():
                if number not in mine:
                    mine[number] = version
                    repo._origins[(name, number)] = self._origins.get((name, number))
        return repo

    def extended(self, entries: Iterable[SearchPathEntry]) -> DefinitionRepository:
        """A copy of this repository with ``entries`` appended to its search path."""
        repo = self.overlay(())
        for entry in entries:
            repo.load_entry(entry)
        return repo

    # -- queries ----------------------------------------------------------------------

    def names(self) -> list[str]:
        return sorted(self._versions)

    def close_names(self, word: str, cutoff: float = 0.6) -> list[str]:
        """The names on the search path that look like ``word`` (see
        :func:`gadgetctl.suggest.close_names`), each word compared once: a missing type is
        usually named by several definitions or elements."""
        from gadgetctl.suggest import close_names

        key = (word, cutoff)
        found = self._close_cache.get(key)
        if found is None:
            found = self._close_cache[key] = close_names(word, self.names(), cutoff=cutoff)
        return list(found)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and bool(self._versions.get(name))

    def versions(self, name: str) -> list[int]:
        return sorted(self._versions.get(name, {}))

    def get(self, name: str, version: int | None = None) -> DefinitionVersion | None:
        versions = self._versions.get(name)
        if not versions:
            return None
        if version is None:
            return versions[max(versions)]
        return versions.get(version)

    def newest(self, name: str) -> DefinitionVersion | None:
        return self.get(name)

    def origin(self, name: str, version: int | None = None) -> SearchPathEntry | None:
        found = self.get(name, version)
        return None if found is None else self._origins.get((name, found.version))

    def all_newest(self) -> Iterator[DefinitionVersion]:
        for name in self.names():
            newest = self.get(name)
            if newest is not None:
                yield newest

    # -- inheritance ------------------------------------------------------------------

    def parents_of(self, name: str, version: int | None = None) -> tuple[str, ...]:
        found = self.get(name, version)
        return found.parents if found else ()

    def ancestors(self, name: str, version: int | None = None) -> tuple[str, ...]:
        """Every ancestor, depth-first in parent order, each once, ``name`` excluded.

        Parents resolve to their newest version, as in VR Juggler. Unknown parents are
        listed (they are ancestors by declaration) but not followed.
        """
        if version is None and name in self._ancestor_cache:
            return self._ancestor_cache[name]
        order: list[str] = []
        seen = {name}
        stack = list(reversed(self.parents_of(name, version)))
        while stack:
            current = stack.pop()
            if current in seen:
                continue
            seen.add(current)
            order.append(current)
            stack.extend(reversed(self.parents_of(current)))
        result = tuple(order)
        if version is None:
            self._ancestor_cache[name] = result
        return result

    def property_owners(self, prop_name: str) -> frozenset[str]:
        """Names of the definitions whose newest version declares a property ``prop_name``
        itself (an index built once, so a lookup per property stays constant time)."""
        if self._property_owners is None:
            owners: dict[str, set[str]] = {}
            for definition in self.all_newest():
                for prop in definition.properties:
                    owners.setdefault(prop.name, set()).add(definition.name)
            self._property_owners = {k: frozenset(v) for k, v in owners.items()}
        return self._property_owners.get(prop_name, frozenset())

    def is_a(self, name: str, base: str) -> bool:
        """True when ``name`` is ``base`` or inherits from it through any parent."""
        return name == base or base in self.ancestors(name)

    def missing_parents(self, name: str, version: int | None = None) -> list[str]:
        return [p for p in self.parents_of(name, version) if p not in self]

    def effective_properties(
        self, name: str, version: int | None = None
    ) -> list[EffectiveProperty]:
        """Own properties first, then inherited ones depth-first; the first of a name wins."""
        cached = self._effective_cache.get((name, version))
        if cached is None:
            cached = self._effective_cache[(name, version)] = tuple(
                self._effective_properties(name, version)
            )
        return list(cached)

    def property_map(self, name: str) -> Mapping[str, PropertyDefinition]:
        """The newest version's effective properties by name (read only, shared: configuring
        10,000 elements of one type works it out once)."""
        cached = self._map_cache.get(name)
        if cached is None:
            cached = self._map_cache[name] = MappingProxyType(
                {p.name: p.definition for p in self.effective_properties(name)}
            )
        return cached

    def pointer_properties(self, name: str) -> tuple[str, ...]:
        """The names of the newest version's effective properties that hold pointers
        (``configelementpointer``), in :meth:`effective_properties` order (worked out once per
        type: configuring 10,000 elements of one type asks 10,000 times)."""
        cached = self._pointer_cache.get(name)
        if cached is None:
            cached = self._pointer_cache[name] = tuple(
                p.name
                for p in self.effective_properties(name)
                if p.definition.valuetype is ValueType.POINTER
            )
        return cached

    def _effective_properties(self, name: str, version: int | None) -> list[EffectiveProperty]:
        found = self.get(name, version)
        if found is None:
            return []
        result: list[EffectiveProperty] = []
        seen: set[str] = set()
        chain = [found] + [
            d for d in (self.get(a) for a in self.ancestors(name, version)) if d is not None
        ]
        for owner in chain:
            for prop in owner.properties:
                if prop.name not in seen:
                    seen.add(prop.name)
                    result.append(EffectiveProperty(prop, owner.name, found))
        return result

    def find_property(
        self, name: str, prop: str, version: int | None = None
    ) -> EffectiveProperty | None:
        for candidate in self.effective_properties(name, version):
            if candidate.name == prop:
                return candidate
        return None

    def cycles(self) -> list[tuple[str, ...]]:
        """Inheritance cycles among the newest versions (strongly connected components)."""
        index: dict[str, int] = {}
        low: dict[str, int] = {}
        on_stack: set[str] = set()
        stack: list[str] = []
        result: list[tuple[str, ...]] = []
        counter = 0
        for start in self.names():
            if start in index:
                continue
            work = [(start, iter(self.parents_of(start)))]
            index[start] = low[start] = counter
            counter += 1
            stack.append(start)
            on_stack.add(start)
            while work:
                node, children = work[-1]
                advanced = False
                for child in children:
                    if child not in self:
                        continue
                    if child not in index:
                        index[child] = low[child] = counter
                        counter += 1
                        stack.append(child)
                        on_stack.add(child)
                        work.append((child, iter(self.parents_of(child))))
                        advanced = True
                        break
                    if child in on_stack:
                        low[node] = min(low[node], index[child])
                if advanced:
                    continue
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1 or node in self.parents_of(node):
                        result.append(tuple(sorted(component)))
        return result


def _same_directory(one: Path, other: Path) -> bool:
    if one == other:
        return True
    try:
        return one.resolve() == other.resolve()
    except OSError:
        return False


_FileOutcome = defcache.FileOutcome

#: The outcomes of a directory's definition files, by the directory, while its ``*.jdef``
#: files stay the same (names, sizes, modification times, inodes): a process that builds
#: repositories again and again (the language server, validating in-process) reads the
#: bundled definitions once. Definitions are not changed once read, so repositories share them.
_READ_DIRECTORIES: dict[str, tuple[tuple[tuple[str, int, int, int], ...], list[_FileOutcome]]] = {}
_READ_DIRECTORIES_KEPT = 32


def _read_directory(directory: Path, *, lasting: bool = False) -> list[_FileOutcome]:
    """Every ``*.jdef`` file of ``directory`` in name order, read (or taken from what an
    earlier read of the same unchanged files gave, in this process or, ``lasting``, in an
    earlier one: see :mod:`gadgetctl.jccl.defcache`)."""
    import stat

    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import load_file, unsaved_within

    files: list[tuple[Path, os.stat_result]] = []
    for path in sorted(directory.glob("*.jdef")):
        try:
            status = path.stat()
        except OSError:
            continue  # gone, or a dangling link: not a file
        if stat.S_ISREG(status.st_mode):
            files.append((path, status))
    signature = tuple((p.name, s.st_size, s.st_mtime_ns, s.st_ino) for p, s in files)
    key = str(directory)
    known = _READ_DIRECTORIES.get(key)
    # an editor's unsaved text of a file there (the language server) is read, never kept
    keep = not unsaved_within(directory)
    if keep and known is not None and known[0] == signature:
        return known[1]
    lasting = lasting and keep
    cached = defcache.load(directory, files) if lasting else None
    if cached is not None:
        _keep_read(key, signature, cached)
        return cached
    outcomes: list[_FileOutcome] = []
    for path, _ in files:
        try:
            doc = load_file(path)
        except OSError as err:
            outcomes.append(
                (path, None, f"definition file on the search path cannot be read: {err.strerror}")
            )
            keep = False  # tried again next time
            continue
        definition = read_definition(doc, columns=False) if doc.root is not None else None
        if definition is None or not definition.name:
            first = doc.diagnostics[0].message if doc.diagnostics else "not a definition file"
            outcomes.append(
                (path, None, f"definition file on the search path was skipped: {first}")
            )
            continue
        outcomes.append((path, definition, ""))
    if keep:
        _keep_read(key, signature, outcomes)
        if lasting:
            defcache.store(directory, files, outcomes)
    return outcomes


def _keep_read(key: str, signature: tuple, outcomes: list[_FileOutcome]) -> None:
    if len(_READ_DIRECTORIES) >= _READ_DIRECTORIES_KEPT:
        _READ_DIRECTORIES.pop(next(iter(_READ_DIRECTORIES)))
    _READ_DIRECTORIES[key] = (signature, outcomes)


def load_repository(entries: Iterable[SearchPathEntry]) -> DefinitionRepository:
    return DefinitionRepository.from_search_path(entries)


def default_repository(
    extra_dirs: Iterable[Path] = (), *, bundled: bool = True
) -> DefinitionRepository:
    from gadgetctl.jccl.searchpath import SearchPathOptions, build_search_path

    return load_repository(
        build_search_path(SearchPathOptions(bundled=bundled, extra_dirs=list(extra_dirs)))
    )
