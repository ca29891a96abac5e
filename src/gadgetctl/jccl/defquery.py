"""Read-only views of the definition repository for `gadgetctl defs` (plain data, no output)."""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.jccl.definitions import DefinitionVersion
from gadgetctl.jccl.repository import DefinitionRepository, EffectiveProperty


def definition_summary(repo: DefinitionRepository, name: str) -> dict[str, object]:
    newest = repo.get(name)
    assert newest is not None
    origin = repo.origin(name)
    return {
        "name": name,
        "version": newest.version,
        "versions": repo.versions(name),
        "label": newest.label,
        "abstract": newest.abstract,
        "parents": list(newest.parents),
        "categories": list(newest.categories),
        "source": newest.location.path if newest.location else None,
        "origin": origin.origin if origin else None,
    }


def list_definitions(
    repo: DefinitionRepository, *, category: str | None = None, base: str | None = None
) -> list[dict[str, object]]:
    rows = []
    for newest in repo.all_newest():
        if category and not any(
            c == category or c.startswith(category.rstrip("/") + "/") for c in newest.categories
        ):
            continue
        if base and not repo.is_a(newest.name, base):
            continue
        rows.append(definition_summary(repo, newest.name))
    return rows


def property_record(prop: EffectiveProperty) -> dict[str, object]:
    d = prop.definition
    record: dict[str, object] = {
        "name": d.name,
        "valuetype": d.valuetype.value,
        "variable": d.variable,
        "count": d.count,
        "values": [{"label": v.label, "default": v.default} for v in d.values],
        "allowed_types": list(d.allowed_types),
        "help": d.help,
        "defined_by": prop.defined_by,
        "inherited": prop.defined_by != prop.defined_in.name,
    }
    if d.enumeration is not None:
        record["enumeration"] = {
            "editable": d.enumeration.editable,
            "choices": [{"label": c.label, "value": c.value} for c in d.enumeration.choices],
        }
    return record


def show_definition(repo: DefinitionRepository, version: DefinitionVersion) -> dict[str, object]:
    summary = definition_summary(repo, version.name)
    summary.update(
        {
            "version": version.version,
            "label": version.label,
            "abstract": version.abstract,
            "help": version.help,
            "parents": list(version.parents),
            "ancestors": list(repo.ancestors(version.name, version.version)),
            "missing_parents": repo.missing_parents(version.name, version.version),
            "has_upgrade_transform": version.upgrade_transform is not None,
            "properties": [
                property_record(p) for p in repo.effective_properties(version.name, version.version)
            ],
        }
    )
    return summary


@dataclass
class TreeNode:
    name: str
    children: list[TreeNode]
    missing: bool = False
    repeated: bool = False

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "missing": self.missing,
            "repeated": self.repeated,
            "children": [c.to_dict() for c in self.children],
        }


def inheritance_tree(repo: DefinitionRepository, root: str | None = None) -> list[TreeNode]:
    """Children-of tree: roots are types without (known) parents, or ``root`` itself.

    A type with several parents appears under each; a subtree already shown is marked
    ``repeated`` instead of being drawn again; cycles cannot loop.
    """
    children: dict[str, list[str]] = {}
    for newest in repo.all_newest():
        for parent in newest.parents or ("",):
            children.setdefault(parent if parent in repo else "", []).append(newest.name)
    shown: set[str] = set()

    def build(name: str, path: frozenset[str]) -> TreeNode:
        node = TreeNode(name, [], missing=name not in repo)
        if name in shown or name in path:
            node.repeated = True
            return node
        shown.add(name)
        for child in sorted(children.get(name, [])):
            node.children.append(build(child, path | {name}))
        return node

    if root is not None:
        return [build(root, frozenset())]
    return [build(name, frozenset()) for name in sorted(children.get("", []))]
