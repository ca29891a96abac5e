"""Which elements a run time activates and which it leaves pending: one set of rules for
`gadgetctl validate` (its predictions for VR Juggler, CFG041/CFG031) and for gadgetctl's
own input manager (`config pending`, `monitor`).

An element becomes active once every non-empty pointer of it and of its embedded elements
names an active top-level element, unless its type skips that test; a type no handler
takes, or an element older than its handler accepts, never becomes active. The two run
times differ on purpose only where :data:`DIFFERENCES` says so; both outputs then say which
behaviour they describe.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import NamedTuple

from gadgetctl.jccl.runtime import NEVER_HANDLED, NO_DEPENDENCY_CHECK, minimum_version

_UNJUDGED = object()  # a refusal not yet worked out for a kind (None means: no refusal)

#: The fate :func:`settle` gives an element that waits for pointers that never become active.
WAITING = "waiting"


class RunTime(StrEnum):
    VRJUGGLER = "VR Juggler"
    GADGETCTL = "gadgetctl"


@dataclass(frozen=True, slots=True)
class Difference:
    """Where gadgetctl's input manager activates what VR Juggler leaves pending."""

    vrjuggler: str  # why VR Juggler leaves it pending
    gadgetctl: str  # what gadgetctl does instead


_WAITS = (
    "unlike most proxies, VR Juggler's {type} waits for its device, so it stays pending while "
    "the device is not active"
)
_BINDS = (
    "gadgetctl binds it at once and stupefies it until its device is active, like the other proxies"
)

#: The documented differences, by element type (docs/configurations.md, "Pending elements").
DIFFERENCES: dict[str, Difference] = {
    "gesture_proxy": Difference(
        NEVER_HANDLED["gesture_proxy"], "gadgetctl runs it like the other proxies"
    ),
    "command_proxy": Difference(_WAITS.format(type="command_proxy"), _BINDS),
    "string_proxy": Difference(_WAITS.format(type="string_proxy"), _BINDS),
}

#: Proxies gadgetctl binds without waiting for their device (it stupefies them instead).
GADGETCTL_UNWAITING = frozenset(DIFFERENCES) | NO_DEPENDENCY_CHECK


def waits_for_pointers(type_name: str, runtime: RunTime) -> bool:
    """Whether an element of this type stays pending until every element it points at is
    active (JCCL's default dependency check), or is configured regardless."""
    skip = GADGETCTL_UNWAITING if runtime is RunTime.GADGETCTL else NO_DEPENDENCY_CHECK
    return type_name not in skip


def never_handled(type_name: str, runtime: RunTime) -> str | None:
    """Why no handler of ``runtime`` ever takes an element of this type, or None."""
    if runtime is RunTime.GADGETCTL and type_name in DIFFERENCES:
        return None
    return NEVER_HANDLED.get(type_name)


def too_old(type_name: str, version: int | None, versions: Sequence[int]) -> str | None:
    """Why the handler refuses an element of this version (both run times), or None."""
    minimum = minimum_version(type_name, versions)
    if minimum is None or (version or 0) >= minimum:
        return None
    return (
        f"the run time refuses {type_name} elements older than version {minimum} "
        f"(this one is version {version or 0}; `gadgetctl upgrade` brings it up to date)"
    )


def refusal(
    type_name: str, version: int | None, versions: Sequence[int], runtime: RunTime
) -> str | None:
    """Why ``runtime`` never activates this element whatever the others do, or None."""
    return never_handled(type_name, runtime) or too_old(type_name, version, versions)


class Node(NamedTuple):
    """One top-level element as the rules see it: ``targets`` are the names its pointers
    (and its embedded elements' pointers) give; ``refused`` says why it can never become
    active for a reason outside the rules (no definition, abstract type, no driver...).
    (A named tuple: a configuration of 50,000 elements makes 50,000 of them per check.)"""

    name: str
    type: str
    version: int | None
    targets: tuple[str, ...] | str  # (one target may be given as its name alone)
    refused: str | None = None


def settle(
    nodes: Iterable[Node],
    runtime: RunTime,
    versions: Callable[[str], Sequence[int]],
    *,
    refused: Collection[str] = (),
    active: set[str] | None = None,
) -> dict[str, str | None]:
    """Every node's fate once nothing more can change: None when active, else why it stays
    pending (its refusal, or ``"waiting"`` for elements that wait on pointers that never
    become active). ``refused`` names more elements that never become active; ``active``,
    when given, receives the names of the active ones."""
    fate: dict[str, str | None] = {}
    # target name -> the name of the node waiting for it, or a list of the names of several
    # (one name kept without a list, and no count for a node with one target: the usual
    # case, and 200,000 aliases make 200,000 nodes)
    waiting: dict[str, str | list[str]] = {}
    unmet: dict[str, int] = {}  # nodes with several targets: how many are not active yet
    ready: list[str] = []
    refusals: dict[tuple[str, int | None], str | None] = {}  # the same for every element of a kind
    waits: dict[str, bool] = {}

    def wait(dep: str, name: str) -> None:
        found = waiting.get(dep)
        if found is None:
            waiting[dep] = name
        elif found.__class__ is str:
            waiting[dep] = [found, name]
        else:
            found.append(name)

    # one pass over the nodes, unpacked as plain tuples (50,000 aliases make 50,000 nodes)
    for name, type_name, version, targets, node_refused in nodes:
        if node_refused is not None:
            fate[name] = node_refused
            continue
        kind = (type_name, version)
        reason = refusals.get(kind, _UNJUDGED)
        if reason is _UNJUDGED:
            reason = refusals[kind] = refusal(type_name, version, versions(type_name), runtime)
        if refused and name in refused:
            reason = "refused"
        if reason is not None:
            fate[name] = reason
            continue
        waits_here = waits.get(type_name)
        if waits_here is None:
            waits_here = waits[type_name] = waits_for_pointers(type_name, runtime)
        fate[name] = WAITING
        if not waits_here or not targets:
            ready.append(name)
            continue
        if targets.__class__ is str:  # one target, given as its name
            found = waiting.get(targets)
            if found is None:  # (wait(), written out: once per element)
                waiting[targets] = name
            elif found.__class__ is str:
                waiting[targets] = [found, name]
            else:
                found.append(name)
            continue
        deps = set(targets)
        if len(deps) > 1:
            unmet[name] = len(deps)
        for dep in deps:
            wait(dep, name)
    while ready:
        name = ready.pop()
        if fate[name] is None:
            continue
        fate[name] = None
        if active is not None:
            active.add(name)
        dependents = waiting.get(name)
        if dependents is None:
            continue
        for dependent in (dependents,) if dependents.__class__ is str else dependents:
            left = unmet.get(dependent)
            if left is None:  # its one target is active
                ready.append(dependent)
                continue
            unmet[dependent] = left - 1
            if left == 1:
                ready.append(dependent)
    return fate
