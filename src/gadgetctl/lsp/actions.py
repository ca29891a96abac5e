"""Code actions: the fixes validate's findings name, as edits in the file's own spelling.

Each fix comes from what the check that found the problem knows: the close names it
suggests (:func:`gadgetctl.suggest.close_names` over the same candidates: the element's
properties, the enumeration's labels, the known types), the enumeration's label of another
case, the pointers a type must set, and `gadgetctl upgrade` (which rewrites only what
changes) for outdated elements and file formats.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.jccl.xmlload import declared_encoding
from gadgetctl.lsp.analysis import Model
from gadgetctl.lsp.elements import place_of, property_of, required_properties, view_of
from gadgetctl.lsp.syntax import TAG, context_at, end_tag, local, open_stack, text_range
from gadgetctl.suggest import close_names

UPGRADE_CODES = frozenset({"CFG012", "CFG021", "XML010", "XML011", "XML012"})
MAX_FIXES = 5
POINTER_CUTOFF = 0.7  # how close a name must be to a pointer naming nothing (as validate's)


@dataclass
class Action:
    title: str
    code: str  # the finding it fixes
    edits: dict[Path, list[tuple[int, int, str]]] = field(default_factory=dict)
    preferred: bool = False


@dataclass(frozen=True)
class Problem:
    """A finding as the editor sent it back: its code and range (offsets)."""

    code: str
    start: int
    end: int


def actions(model: Model, text: str, problems: list[Problem]) -> list[Action]:
    found: list[Action] = []
    upgraded: list[list[tuple[int, int, str]] | None] = []  # the file's upgrade, once
    for problem in problems:
        code = problem.code
        if code in ("CFG020", "CFG010"):
            found += _rename_tag(model, text, problem)
        elif code in ("CFG026", "CFG027", "CFG028"):
            found += _fix_value(model, text, problem)
        elif code == "CFG031":
            found += _fix_pointer(model, text, problem)
        elif code == "CFG033":
            found += _add_required(model, text, problem)
        if code in UPGRADE_CODES:
            if not upgraded:
                upgraded.append(_upgrade_hunks(model, text))
            if upgraded[0]:
                found += _upgrades(model, text, problem, upgraded[0])
    files = [a for a in found if a.title == FILE_UPGRADE]
    for extra in files[1:]:
        found.remove(extra)
    return found


def _tag_name_at(text: str, start: int) -> tuple[str, int, int] | None:
    match = re.compile(r"<([A-Za-z_][\w.:-]*)").match(text, start)
    if match is None:
        return None
    return local(match.group(1)), match.end(1) - len(local(match.group(1))), match.end(1)


def _rename_tag(model: Model, text: str, problem: Problem) -> list[Action]:
    found = _tag_name_at(text, problem.start)
    if found is None:
        return []
    name, name_start, name_end = found
    if problem.code == "CFG020":
        place = place_of(open_stack(text, problem.start))
        if place is None or place.element is None:
            return []
        view = view_of(model.index, place.element)
        if view is None:
            return []
        candidates = close_names(name, list(view.properties), cutoff=0.6)
    else:
        candidates = close_names(name, model.repo.names(), cutoff=0.6)  # (validate's hint)
    end = end_tag(text, problem.start, name)
    result = []
    for i, candidate in enumerate(candidates[:MAX_FIXES]):
        edits = [(name_start, name_end, candidate)]
        if end is not None:
            edits.append((*end, candidate))
        result.append(
            Action(
                f"Did you mean {candidate}?", problem.code, {model.path: edits}, preferred=i == 0
            )
        )
    return result


def _fix_value(model: Model, text: str, problem: Problem) -> list[Action]:
    tag = _tag_name_at(text, problem.start)
    if tag is None:
        return []
    place = place_of(open_stack(text, problem.start))
    if place is None or place.element is None:
        return []
    prop = property_of(model.index, place.element, tag[0])
    tag_end = text.find(">", problem.start)
    if prop is None or tag_end < 0 or text[tag_end - 1] == "/":
        return []
    start, end = text_range(text, tag_end + 1)
    value = text[start:end]
    replacements: list[str] = []
    if problem.code == "CFG026":
        if value.lower() in ("true", "false"):
            replacements = [value.lower()]
    elif prop.enumeration is not None:
        if problem.code == "CFG027":
            near = prop.enumeration.case_insensitive_label(value)
            replacements = [near.label] if near is not None else []
        else:
            labels = [c.label for c in prop.enumeration.choices]
            replacements = close_names(value, labels, cutoff=0.6)
    return [
        Action(f"Write {r!r}", problem.code, {model.path: [(start, end, r)]}, preferred=i == 0)
        for i, r in enumerate(replacements[:MAX_FIXES])
    ]


def _value_at(text: str, problem: Problem) -> tuple[int, int] | None:
    """The range of the text of the property tag a finding is on."""
    if _tag_name_at(text, problem.start) is None:
        return None
    tag_end = text.find(">", problem.start)
    if tag_end < 0 or text[tag_end - 1] == "/":
        return None
    return text_range(text, tag_end + 1)


def _fix_pointer(model: Model, text: str, problem: Problem) -> list[Action]:
    """A pointer naming no element: the names close to it, as validate's hint gives them
    (top-level names, or embedded elements' full names for a name with a '/')."""
    configuration = model.configuration
    where = _value_at(text, problem)
    if configuration is None or where is None:
        return []
    value = text[where[0] : where[1]]
    if "/" in value:
        names = [e.full_name for e in configuration.all_elements() if e.parent is not None]
    else:
        names = [e.name for e in configuration.elements]
    close = close_names(value, names, n=3, cutoff=POINTER_CUTOFF)
    return [
        Action(f"Did you mean {name!r}?", problem.code, {model.path: [(*where, name)]}, i == 0)
        for i, name in enumerate(close)
    ]


def _add_required(model: Model, text: str, problem: Problem) -> list[Action]:
    tag = _tag_name_at(text, problem.start)
    if tag is None:
        return []
    ctx = context_at(text, problem.start)
    place = place_of(ctx.stack)
    if place is None or (place.element is not None and place.prop is None):
        return []  # (the finding is on an empty property tag: nothing to add)
    tag_end = text.find(">", problem.start)
    if tag_end < 0 or text[tag_end - 1] == "/":
        return []
    element = open_stack(text, tag_end + 1)[-1]
    view = view_of(model.index, element)
    if view is None:
        return []
    end = end_tag(text, problem.start, tag[0])
    body = text[tag_end + 1 : end[0] - 2 if end else tag_end + 1]  # (up to its "</")
    present = {local(m.group(2)) for m in TAG.finditer(body) if not m.group(1)}
    missing = [p for p in required_properties(model.index, view) if p not in present]
    line_start = text.rfind("\n", 0, problem.start) + 1
    own = text[line_start : problem.start]
    own = own if not own.strip() else ""
    child = re.search(r"\n([ \t]*)<", body)
    indent = child.group(1) if child else own + "   "
    actions = []
    for prop in missing:
        insert = f"\n{indent}<{prop}></{prop}>"
        actions.append(
            Action(
                f"Add the required property {prop}",
                problem.code,
                {model.path: [(tag_end + 1, tag_end + 1, insert)]},
                preferred=True,
            )
        )
    return actions


FILE_UPGRADE = "Upgrade the file (gadgetctl upgrade)"


def _upgrade_hunks(model: Model, text: str) -> list[tuple[int, int, str]] | None:
    """`gadgetctl upgrade` of the text as edits, one per changed run of lines (the rest of
    the file is left alone); None when nothing changes or it cannot be upgraded."""
    from gadgetctl.jccl.upgrade import upgrade_bytes
    from gadgetctl.jccl.xmlload import unsaved_bytes

    data = unsaved_bytes(text)
    result = upgrade_bytes(model.path, data, model.repo, environ=model.environ)
    if result.failed or not result.changed or result.upgraded is None:
        return None
    try:
        return _hunks(text, result.upgraded.decode(declared_encoding(data)))
    except (UnicodeDecodeError, LookupError):
        return None


def _upgrades(
    model: Model, text: str, problem: Problem, hunks: list[tuple[int, int, str]]
) -> list[Action]:
    """The whole file's upgrade and, for an outdated element, the edits within it alone."""
    found = [Action(FILE_UPGRADE, problem.code, {model.path: hunks})]
    if problem.code == "CFG012":
        tag = _tag_name_at(text, problem.start)
        end = end_tag(text, problem.start, tag[0]) if tag else None
        stop = end[1] + 1 if end else text.find(">", problem.start) + 1
        mine = [h for h in hunks if h[0] < stop and h[1] > problem.start]
        if mine and mine != hunks:
            found.insert(0, Action("Upgrade this element", problem.code, {model.path: mine}))
    found[0].preferred = True
    return found


def _hunks(old: str, new: str) -> list[tuple[int, int, str]]:
    """The edits turning ``old`` into ``new``: one per run of changed lines."""
    from difflib import SequenceMatcher

    old_lines = old.splitlines(keepends=True)
    new_lines = new.splitlines(keepends=True)
    starts = [0]
    for line in old_lines:
        starts.append(starts[-1] + len(line))
    matcher = SequenceMatcher(None, old_lines, new_lines, autojunk=False)
    return [
        (starts[i1], starts[i2], "".join(new_lines[j1:j2]))
        for op, i1, i2, j1, j2 in matcher.get_opcodes()
        if op != "equal"
    ]
