"""Checks across the elements of one configuration: pointers, duplicate names, and which
elements VR Juggler would leave pending.

The pending simulation follows the ConfigManager (reference section 4) with the rules
gadgetctl's input manager uses too (:mod:`gadgetctl.jccl.activation`): an element becomes
active once every non-empty pointer of it and of its embedded elements names an active
top-level element; stupefiable proxies and cluster nodes skip that test; some handlers
refuse old versions, and gesture proxies are never handled. Where gadgetctl deliberately
runs what VR Juggler leaves pending, the message says so.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.jccl.activation import DIFFERENCES, Node, RunTime, never_handled, settle, too_old
from gadgetctl.jccl.chains import fold_chains, leaders
from gadgetctl.jccl.configuration import ConfigElement, Configuration
from gadgetctl.jccl.definitions import PropertyDefinition
from gadgetctl.jccl.elementcheck import PointerValue, at, describe
from gadgetctl.jccl.runtime import missing_target_effect
from gadgetctl.jccl.typeindex import TypeIndex
from gadgetctl.perf import retain
from gadgetctl.suggest import CloseNames, shared_close_names
from gadgetctl.wording import with_article

UNHANDLED = "unhandled"
_UNJUDGED = object()  # a kind whose blocking is not worked out yet (None: it blocks nothing)
_NOT_BLOCKED = ("",)
_STAYS = "which stays pending itself"
_node = partial(
    tuple.__new__, Node
)  # Node(...) without its Python-level __new__ (50,000 per check)
#: A pending element, why it is pending where (the run time wording) and its unmet pointers.
_Reason = tuple[PointerValue, "ConfigElement | None", str]
#: (a single unmet pointer is kept as its tuple, several in a list: see _reasons)
_Waiting = tuple[ConfigElement, str, "_Reason | list[_Reason] | PointerValue"]
#: Said of an element VR Juggler leaves pending where gadgetctl deliberately runs it.
GADGETCTL_RUNS_IT = "gadgetctl runs it"


@dataclass(frozen=True, slots=True)
class Scope:
    """How complete the configuration is, for wording and severity of missing targets."""

    complete: bool
    root: str  # the file (or files) the configuration was loaded from, for messages

    def nowhere(self) -> str:
        if self.complete:
            return "no element of the configuration has that name"
        return (
            f"no element in {self.root} or its includes has that name; it may come from another "
            "file loaded with it (check them together with --together)"
        )


class Wiring:
    def __init__(
        self,
        config: Configuration,
        index: TypeIndex,
        scope: Scope,
        unloaded: Mapping[str, str] | None = None,
    ) -> None:
        # (each element's findings are in ``element.report``, where the checker left them)
        self.config = config
        self.unloaded = unloaded or {}
        self.index = index
        self.scope = scope
        self.effective = config.elements
        self.by_name = {e.name: e for e in self.effective}
        self.embedded = embedded_by_name(self.effective) if config.may_embed() else {}
        self._severities: dict[Severity, set[int]] | None = None
        self._suggesters: dict[bool, CloseNames] = {}
        self._taken: dict[tuple[int, str], bool] = {}  # (property, target type) -> allowed
        self._kind_blocked: dict[tuple[str, int | None], tuple[str, Severity] | None] = {}
        #: Why each element that can never become active cannot (see :meth:`_blocked`);
        #: None until :meth:`_walk` has run.
        self.blocked: dict[int, tuple[str, Severity]] | None = None

    def check(self) -> list[Diagnostic]:
        found = self.duplicates()
        wrong: list[PointerValue] = []  # pointers at a type not allowed
        self._walk(found, wrong)
        # the "did you mean" indexes serve only the pointer checks of the walk: given back
        # before the rest (about 100 bytes an element of 200,000)
        self._suggesters.clear()
        found.extend(self._wrong_types(wrong))
        del wrong
        found.extend(self.pending())
        return found

    def _walk(self, found: list[Diagnostic], wrong: list[PointerValue]) -> None:
        """Every pointer of every loaded element checked (CFG031 into ``found``, pointers at
        a type their property does not take into ``wrong``), and why the effective elements
        that can never become active cannot (filling :attr:`blocked`; :meth:`_nodes` then
        gives them as the activation rules see them). When every name occurs once the
        loaded elements are the effective ones, and both are done in one pass."""
        loaded = self.config.loaded
        unique = len(self.by_name) == len(loaded)
        if not unique:
            self._pointers(loaded, found, wrong)
        by_name, kind_blocked = self.by_name, self._kind_blocked
        blocked = self.blocked = {}
        # the kind of the element before, and the property and target type of the pointer
        # before, with their answers: a large configuration repeats them element after element
        last_kind: tuple[str, int | None] | None = None
        blocker = None
        last_takes: tuple[PropertyDefinition, str, bool] | None = None
        for element in self.effective:
            key = id(element)
            type_name, version = element.type, element.version
            if last_kind is None or last_kind[0] != type_name or last_kind[1] != version:
                last_kind = (type_name, version)
                blocker = kind_blocked.get(last_kind, _UNJUDGED)
                if blocker is _UNJUDGED:
                    blocker = self._blocked(element)
            if blocker is not None:
                blocked[key] = blocker
            pointers = element.report.pointers
            if not pointers:
                continue
            if unique:
                for pointer in pointers:
                    target = by_name.get(pointer[3])  # (.target)
                    if target is None:
                        missing = self.pointer(pointer, element)
                        if missing is not None:
                            found.append(missing)
                        continue
                    prop = pointer[1]
                    if (
                        last_takes is None
                        or last_takes[0] is not prop
                        or last_takes[1] != target.type
                    ):
                        last_takes = (prop, target.type, self._takes(prop, target.type))
                    if not last_takes[2]:
                        wrong.append(pointer)

    def _nodes(self) -> Iterator[Node]:
        """The effective elements as the activation rules see them, made as they are used
        (a list of them would hold one more tuple per element; :meth:`_walk` first)."""
        blocked = self.blocked
        for element in self.effective:
            refused = None
            if blocked:
                blocker = blocked.get(id(element))
                if blocker is not None and (
                    blocker[0] == UNHANDLED or element.type in self.unloaded
                ):
                    refused = blocker[0]  # (no rule of activation knows of it: refused here)
            pointers = element.report.pointers
            if not pointers:
                targets: tuple[str, ...] | str = ()
            elif len(pointers) == 1:
                targets = pointers[0][3]  # (one target as its name alone: no 1-tuple)
            else:
                targets = tuple([p.target for p in pointers])
            yield _node((element.name, element.type, element.version, targets, refused))

    def _pointers(
        self,
        elements: list[ConfigElement],
        found: list[Diagnostic],
        wrong: list[PointerValue],
    ) -> None:
        """The pointer checks of :meth:`_walk` alone, for ``elements``."""
        by_name = self.by_name
        for element in elements:
            for pointer in element.report.pointers:
                target = by_name.get(pointer.target)
                if target is None:
                    missing = self.pointer(pointer, element)
                    if missing is not None:
                        found.append(missing)
                elif not self._takes(pointer.prop, target.type):
                    wrong.append(pointer)

    # -- names -----------------------------------------------------------------------

    def duplicates(self) -> list[Diagnostic]:
        """Elements whose name an earlier element already has. VR Juggler keeps the later
        one, which is JCCL's documented way to override: a file supersedes the files it
        includes and a later file given supersedes earlier ones (info, CFG042), as does a
        byte-identical copy. Within one file, or between files that neither include each
        other nor are ordered as given files, it may be an accident (CFG040, warning)."""
        if len(self.by_name) == len(self.config.loaded):
            return []  # every name once: nothing to compare (the usual case)
        return self._duplicates()

    def _duplicates(self) -> list[Diagnostic]:
        """The findings of :meth:`duplicates` when some name is used twice."""
        found = []
        first: dict[str, ConfigElement] = {}
        relation = _FileRelation(self.config)
        for element in self.config.loaded:
            if not element.name.strip():
                continue
            earlier = first.setdefault(element.name, element)
            if earlier is element:
                continue
            first[element.name] = element  # the next duplicate is compared with the one kept
            if earlier.file == element.file:
                found.append(
                    at(
                        "CFG040",
                        f"element name {element.name!r} ({element.type}) is used before in this "
                        f"file, by the {earlier.type} at {earlier.location}; VR Juggler keeps only the later "
                        "one, at the earlier one's place",
                        element.location,
                        hint="Rename or remove one of them.",
                    )
                )
                continue
            why = relation.override(earlier, element)
            # The same words in every mode: an identical copy repeats, whatever the order.
            if _same_text(earlier, element):
                why = "an identical copy" + ("" if why is None else f"; {why}")
            if why is not None:
                verb = "repeats" if why.startswith("an identical copy") else "overrides"
                found.append(
                    at(
                        "CFG042",
                        f"{element.type} {element.name!r} {verb} the {earlier.type} of that name "
                        f"from {earlier.location} ({why})",
                        element.location,
                    )
                )
                continue
            found.append(
                at(
                    "CFG040",
                    f"element name {element.name!r} ({element.type}) is used before, by the "
                    f"{earlier.type} at {earlier.location}; VR Juggler keeps only the later one, at the "
                    "earlier one's place, although neither file includes the other",
                    element.location,
                    hint="If this element is meant to override the other, include the other's file from "
                    "this one (or give the files in that order with --together); otherwise rename one.",
                )
            )
        return found

    # -- pointers --------------------------------------------------------------------

    def pointer(self, pointer: PointerValue, root: ConfigElement) -> Diagnostic | None:
        """CFG031 when the pointer names no top-level element (nor an embedded one)."""
        if pointer.target in self.by_name or pointer.target in self.embedded:
            return None  # an embedded target never satisfies a dependency: see pending()
        who = f"{describe(pointer.element)}: {pointer.prop.name} {pointer.target!r}"
        close = self._close_names("/" in pointer.target)(pointer.target, n=3, cutoff=0.7)
        effect = missing_target_effect(root.type, root.name, pointer.element is not root)
        if root.type in DIFFERENCES and pointer.element is root:
            effect += f" ({GADGETCTL_RUNS_IT})"
        return at(
            "CFG031",
            f"{who}: {self.scope.nowhere()}; {effect}",
            pointer.value.location,
            severity=Severity.ERROR if self.scope.complete else None,
            hint=f"Did you mean {', '.join(repr(c) for c in close)}?" if close else None,
        )

    def _takes(self, prop: PropertyDefinition, type_name: str) -> bool:
        """Whether the pointer property may name an element of this type (unknown types are
        not judged); the same for every pointer of a property at a type, so asked once."""
        key = (id(prop), type_name)
        takes = self._taken.get(key)
        if takes is None:
            allowed = prop.allowed_types
            index = self.index
            takes = not (
                allowed
                and all(index.known(t) for t in allowed)
                and index.known(type_name)
                and not index.is_any(type_name, allowed)
            )
            self._taken[key] = takes
        return takes

    def _wrong_types(self, wrong: list[PointerValue]) -> list[Diagnostic]:
        """CFG032 for each pointer at an element of a type the property does not take; a
        chain of elements of one type each naming the one before through the same property
        (aliases naming aliases) is one finding at its head, with a count."""
        # (keyed by the elements themselves, which hash by identity: no int object per key)
        position: dict[ConfigElement, int] = {}  # the place of its (last) wrong pointer
        several: set[ConfigElement] = set()  # elements with more than one
        by_name = self.by_name
        for i, pointer in enumerate(wrong):
            element = pointer[0]
            if element in position:
                several.add(element)
            position[element] = i
        leader = leaders(len(wrong))
        for i, pointer in enumerate(wrong):
            target = by_name[pointer[3]]
            ahead = position.get(target)
            if ahead is None:
                continue
            element, prop = pointer[0], pointer[1]
            if (
                target.type == element.type
                and (not several or (element not in several and target not in several))
                and wrong[ahead][1].name == prop.name
            ):
                leader[i] = ahead
        del position
        heads = fold_chains(len(wrong), leader)
        found = []
        for position, followers in heads.items():
            pointer = wrong[position]
            target = by_name[pointer.target]
            prop = pointer.prop
            message = (
                f"{describe(pointer.element)}: {prop.name} {pointer.target!r} is {with_article(target.type)} "
                f"(at {target.location}); {prop.name} takes {' or '.join(prop.allowed_types)}"
            )
            if followers:
                last = wrong[followers[-1]].element
                message += (
                    f"; {len(followers)} more {pointer.element.type} elements chained behind it "
                    f"make the same mistake, each naming one before it (the last is "
                    f"{describe(last)} at {last.location})"
                )
            found.append(at("CFG032", message, pointer.value.location))
        return found

    def _close_names(self, embedded: bool) -> CloseNames:
        """The indexed "did you mean" search over top-level (or embedded) element names,
        made once per configuration rather than a scan of every name per pointer."""
        found = self._suggesters.get(embedded)
        if found is None:
            names = self.embedded if embedded else self.by_name
            # (case ignored, as close_names does)
            found = self._suggesters[embedded] = shared_close_names(names)
        return found

    # -- pending ---------------------------------------------------------------------

    def _blocked(self, element: ConfigElement) -> tuple[str, Severity] | None:
        """Why the element can never become active whatever the others do, and how bad that
        is; None when it can. The same for every element of a type and version (the view it
        is judged by depends on nothing else), so worked out once per type and version."""
        kind = (element.type, element.version)
        try:
            return self._kind_blocked[kind]
        except KeyError:
            pass
        view = element.report.view
        found: tuple[str, Severity] | None
        if view is None or view.definition.abstract:
            found = UNHANDLED, Severity.ERROR  # reported as CFG010 / CFG011
        elif element.type in self.unloaded:  # both run times: its driver is never loaded
            found = self.unloaded[element.type], Severity.ERROR
        else:
            old = too_old(element.type, element.version, self.index.versions(element.type))
            if old is not None:
                found = old.replace("the run time", "VR Juggler", 1), Severity.ERROR
            else:
                reason = never_handled(element.type, RunTime.VRJUGGLER)
                found = (reason, Severity.WARNING) if reason else None
        self._kind_blocked[kind] = found
        return found

    def pending(self) -> list[Diagnostic]:
        """CFG041 for the effective elements VR Juggler would leave pending (after
        :meth:`_walk`, which it runs when it has not run yet)."""
        if self.blocked is None:
            self._walk([], [])
        versions = self.index.versions
        active: set[str] = set()
        fate = settle(self._nodes(), RunTime.VRJUGGLER, versions, active=active)
        # The run times' rules differ only for the types of DIFFERENCES: without any, their
        # fates are the same (and no element pending in VR Juggler is active in gadgetctl).
        differ = not DIFFERENCES.keys().isdisjoint(kind[0] for kind in self._kind_blocked)
        ours = settle(self._nodes(), RunTime.GADGETCTL, versions) if differ else fate
        found = []
        waiting = _WaitingList()
        # each element's place in waiting is kept on its report while this runs (-1: none
        # yet), where a dict of them would take 70 bytes an element
        for element in self.effective:
            element.report.place = -1
        leader = leaders(len(self.effective))  # place in waiting -> the place it follows
        later: list[int] = []  # places whose leader is found after the walk
        blocked, by_name, embedded = self.blocked, self.by_name, self.embedded
        for element in self.effective:
            name = element.name
            if name in active:
                continue
            where = (
                f" in VR Juggler ({GADGETCTL_RUNS_IT})"
                if differ and ours.get(name, "") is None
                else ""
            )
            if blocked:
                blocker = blocked.get(id(element))
                if blocker is not None:
                    if blocker[0] != UNHANDLED:
                        found.append(
                            at(
                                "CFG041",
                                f"{describe(element)} would stay pending{where}: {blocker[0]}",
                                element.location,
                                severity=blocker[1],
                            )
                        )
                    continue
            # the unmet pointers that name an element: (pointer, target, why never met)
            reasons = []
            for pointer in element.report.pointers:
                target_name = pointer[3]  # (.target)
                if target_name in active:
                    continue
                target = by_name.get(target_name)
                if target is not None:
                    why = self._never_met(target) if blocked and id(target) in blocked else _STAYS
                    reasons.append((pointer, target, why))
                elif target_name in embedded:
                    reasons.append(
                        (
                            pointer,
                            None,
                            f"{pointer.prop.name} names the embedded element {target_name!r}, "
                            "and VR Juggler only looks for top-level elements",
                        )
                    )
            if not reasons:  # (only missing targets: reported as CFG031)
                continue
            here = element.report.place = len(waiting)
            if len(reasons) > 1:
                cause: object = reasons
            elif reasons[0][2] is _STAYS and reasons[0][1] is not None:
                cause = reasons[0][0]  # (its pointer: see _reasons)
            else:
                cause = reasons[0]
            waiting.append(element, where, cause)
            if len(reasons) == 1 and reasons[0][1] is not None:
                # follows the one it waits for if that one waits already (most chains run
                # backwards); the others are settled once every place is known
                target = reasons[0][1]
                ahead = target.report.place if target.report is not None else -1
                if ahead < 0:
                    later.append(here)
                else:
                    # (_follows, written out: once per element)
                    if (
                        waiting.elements[ahead].type == element.type
                        and waiting.wheres[ahead] == where
                    ):
                        leader[here] = ahead
        for here in later:
            target = self._reasons(waiting[here])[0][1]
            ahead = target.report.place if target.report is not None else -1
            if ahead >= 0 and _follows(waiting[here], waiting[ahead]):
                leader[here] = ahead
        found.extend(self._waiting(waiting, leader, active))
        return found

    def _reasons(self, waiting: _Waiting) -> list[_Reason]:
        """The unmet pointers of a waiting element: (pointer, target, why never met). One is
        kept without a list around it, and as its pointer alone when its target is the
        top-level element of that name, which stays pending itself (a chain of 200,000
        aliases: 200,000 tuples fewer)."""
        reasons = waiting[2]
        if isinstance(reasons, list):
            return reasons
        if isinstance(reasons, PointerValue):
            return [(reasons, self.by_name[reasons.target], _STAYS)]
        return [reasons]

    def _never_met(self, target: ConfigElement) -> str:
        """Why a pointer at ``target``, a pending top-level element, is never met."""
        if self.blocked.get(id(target), _NOT_BLOCKED)[0] != UNHANDLED:
            return _STAYS
        if self.index.known(target.type):
            return "whose type VR Juggler does not handle"
        return "which VR Juggler drops because its type has no definition"

    def _waiting(
        self, waiting: _WaitingList, leader: Sequence[int], active: set[str]
    ) -> list[Diagnostic]:
        """CFG041 for elements pending because what they point at stays pending. A chain of
        elements of one type each waiting only for the one before (aliases naming aliases,
        ``leader``: see :func:`_follows`) is one finding at its head, with a count: the
        cause is the same for all of them."""
        heads = fold_chains(len(waiting), leader[: len(waiting)])
        self._severities = self._root_severities(active, [waiting[h][0] for h in heads])
        found = []
        for head, followers in heads.items():
            element, where, _ = waiting[head]
            reasons = self._reasons(waiting[head])
            pointer, target, why = reasons[0]
            text = (
                f"it waits for {target.type} {pointer.target!r}, {why}"
                if target is not None
                else why
            )
            more = f" (and {len(reasons) - 1} more)" if len(reasons) > 1 else ""
            message = f"{describe(element)} would stay pending{where}: {text}{more}"
            if followers:
                last = waiting[followers[-1]][0]
                message += (
                    f"; so would {len(followers)} more {element.type} elements chained behind it, "
                    f"each waiting only for one before it (the last is {describe(last)} at "
                    f"{last.location})"
                )
            found.append(
                at(
                    "CFG041",
                    message,
                    pointer.value.location,
                    severity=self._root_severity(element, active),
                )
            )
        return found

    def _root_severity(self, element: ConfigElement, active: set[str]) -> Severity:
        """The worst of the causes at the ends of the chains of unmet pointers from ``element``:
        a missing target (an error only when the configuration is complete), an element that
        can never be active, an embedded target; a pure waiting cycle is an error."""
        severities = self._severities
        if severities is None:  # not worked out for every head at once by _waiting
            severities = self._root_severities(active, [element])
        key = id(element)
        if key in severities.get(Severity.ERROR, ()):
            return Severity.ERROR
        return Severity.WARNING if key in severities.get(Severity.WARNING, ()) else Severity.ERROR

    def _root_severities(
        self, active: set[str], starts: list[ConfigElement]
    ) -> dict[Severity, set[int]]:
        """The pending elements each severity of cause reaches, for :meth:`_root_severity`
        of ``starts`` and of every pending element they wait for, directly or not (only
        those decide the answers), in time linear in their unmet pointers: each cause is
        spread backwards along the unmet pointers to everything that waits for it (walking
        each element's chain again made 8,000 chained aliases cost 8,000 x 8,000 steps)."""
        missing = Severity.ERROR if self.scope.complete else Severity.WARNING
        waiters: dict[int, list[int]] = defaultdict(list)  # element -> elements pointing at it
        reaches: dict[Severity, list[int]] = {Severity.ERROR: [], Severity.WARNING: []}
        for current in self._waited_on(active, starts):
            key = id(current)
            blocker = self.blocked.get(key)
            if blocker is not None:
                reaches.setdefault(blocker[1], []).append(key)
                continue
            for pointer in current.report.pointers:
                if pointer.target in active:
                    continue
                target = self.by_name.get(pointer.target)
                if target is not None:
                    waiters[id(target)].append(key)
                else:
                    reaches[Severity.ERROR if pointer.target in self.embedded else missing].append(
                        key
                    )
        caused: dict[Severity, set[int]] = {}
        for severity, seeds in reaches.items():
            seen = caused[severity] = set(seeds)
            stack = list(seeds)
            while stack:
                for waiter in waiters.get(stack.pop(), ()):
                    if waiter not in seen:
                        seen.add(waiter)
                        stack.append(waiter)
        return caused

    def _waited_on(self, active: set[str], starts: list[ConfigElement]) -> list[ConfigElement]:
        """``starts`` and the pending elements they wait for, directly or through others
        (each once): an element's unmet pointers at pending, unblocked top-level elements."""
        seen: set[int] = set()
        order: list[ConfigElement] = []
        stack = [e for e in starts if e.name not in active]
        while stack:
            current = stack.pop()
            key = id(current)
            if key in seen:
                continue
            seen.add(key)
            order.append(current)
            if key in self.blocked:
                continue
            for pointer in current.report.pointers:
                if pointer.target not in active:
                    target = self.by_name.get(pointer.target)
                    if target is not None and id(target) not in seen:
                        stack.append(target)
        return order


class _WaitingList:
    """The pending elements of :meth:`Wiring.pending` in three lists (element, where it
    stays pending, its unmet pointers) rather than a tuple each: ``waiting[i]`` makes that
    tuple when asked for."""

    __slots__ = ("causes", "elements", "wheres")

    def __init__(self) -> None:
        self.elements: list[ConfigElement] = []
        self.wheres: list[str] = []
        self.causes: list[object] = []

    def append(self, element: ConfigElement, where: str, cause: object) -> None:
        self.elements.append(element)
        self.wheres.append(where)
        self.causes.append(cause)

    def __len__(self) -> int:
        return len(self.elements)

    def __getitem__(self, place: int) -> _Waiting:
        return (self.elements[place], self.wheres[place], self.causes[place])  # type: ignore[return-value]


def _follows(waiting: _Waiting, ahead: _Waiting) -> bool:
    """Whether a pending element, waiting only for ``ahead``'s element, continues its chain:
    of the same type, pending in the same run times."""
    return waiting[0].type == ahead[0].type and waiting[1] == ahead[1]


class _FileRelation:
    """Whether the file of a later element supersedes the file of an earlier one."""

    def __init__(self, config: Configuration) -> None:
        self.config = config
        self.file_of = {id(e): f.path for f in config.files for e in f.elements}
        self._reach: dict[Path, set[Path]] = {}
        self._root_index: dict[Path, int] | None = None

    def reach(self, path: Path) -> set[Path]:
        found = self._reach.get(path)
        if found is None:
            found = self._reach[path] = self.config.reachable(path)
        return found

    def root_index(self, path: Path) -> int | None:
        """The position of the first given file that reaches ``path``."""
        if self._root_index is None:
            self._root_index = {}
            for index, root in enumerate(self.config.roots):
                for reached in self.reach(root):
                    self._root_index.setdefault(reached, index)
        return self._root_index.get(path)

    def override(self, earlier: ConfigElement, later: ConfigElement) -> str | None:
        old, new = self.file_of.get(id(earlier)), self.file_of.get(id(later))
        if old is None or new is None:
            return None
        if old in self.reach(new):
            return f"{new.name} includes {old.name}"
        first, second = self.root_index(old), self.root_index(new)
        if first is not None and second is not None and first < second:
            return f"{new.name} is given after {old.name}"
        # Include order is load order (VR Juggler's): a file that includes both, the later
        # one's branch after the earlier one's, makes the later an override like a later file.
        includer = self.common_includer(old, new)
        if includer is not None:
            return f"{includer.name} includes {new.name} after {old.name}"
        return None

    def common_includer(self, old: Path, new: Path) -> Path | None:
        """The nearest file that reaches both ``old`` and ``new`` through different includes,
        ``old``'s include coming first."""
        best: tuple[int, Path] | None = None
        for including, targets in self.config.includes.items():
            branches = [i for i, t in enumerate(targets) if old in self.reach(t)]
            later = [i for i, t in enumerate(targets) if new in self.reach(t)]
            if branches and later and min(branches) < min(later):
                size = len(self.reach(including))
                if best is None or size < best[0]:
                    best = (size, including)
        return None if best is None else best[1]


def _same_text(one: ConfigElement, other: ConfigElement) -> bool:
    """Whether two elements are the same copy: type, name, version and every value as
    written (text exactly, embedded elements alike), property by property in order.
    (Comments and layout between the values do not count: VR Juggler never sees them.)"""
    if (
        one.type != other.type
        or one.name != other.name
        or one.version_text != other.version_text
        or [n for n, _ in one.property_items()] != [n for n, _ in other.property_items()]
    ):
        return False
    for name, values in one.property_items():
        others = other.values(name)
        if len(values) != len(others):
            return False
        for mine, theirs in zip(values, others, strict=True):
            if mine.text != theirs.text or (mine.element is None) != (theirs.element is None):
                return False
            if mine.element is not None and not _same_text(mine.element, theirs.element):
                return False
    return True


def check_wiring(
    config: Configuration,
    index: TypeIndex,
    scope: Scope,
    unloaded: Mapping[str, str] | None = None,
) -> list[Diagnostic]:
    """Pointers, duplicates and pending elements of ``config``, whose reports the checker of
    ``index`` has just made (``element.report``); ``unloaded``: element types whose driver the
    configuration never loads, with why (gadgetctl.input.unloaded)."""
    wiring = Wiring(config, index, scope, unloaded)
    retain(wiring)
    return wiring.check()


def embedded_by_name(elements: list[ConfigElement]) -> dict[str, ConfigElement]:
    """Every embedded element of ``elements``, at any depth, by its full name (looking into
    the values of each element directly: most have no embedded element, and a generator
    per element cost a tenth of the pointer checks of 50,000 aliases)."""
    found: dict[str, ConfigElement] = {}
    for element in elements:
        for values in element.property_values():
            for value in values:
                if value.element is not None:
                    child = value.element
                    found[child.full_name] = child
                    for deeper in child.embedded():
                        found[deeper.full_name] = deeper
    return found
