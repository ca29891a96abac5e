"""`gadgetctl defs`: the definition repository, its search path and inheritance."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit

defs_app = typer.Typer(
    help="Inspect the definition repository: list, show, tree and search path.",
    no_args_is_help=True,
)

FORMAT_OPTION = typer.Option(DataFormat.text, "--format", "-f", help="Output format.")


def register(app: typer.Typer) -> None:
    app.add_typer(defs_app, name="defs")


def _repository(definitions: list[Path], bundled: bool):
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.input.definitions import repository_for

    for directory in definitions:
        if not directory.is_dir():
            raise GadgetctlError(f"--definitions {directory}: no such directory")
    # the definitions driver plug-ins carry too (installed entry points, GADGETCTL_DRIVER_PATH),
    # last, as `validate` and `config show` use them
    return repository_for(definitions=definitions, bundled=bundled)


def unknown_definition(repo, type_name: str, what: str = "definition"):
    """The usage error for a definition name the search path does not have."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.suggest import with_suggestion

    return GadgetctlError(
        with_suggestion(
            f"no {what} named {type_name!r} on the search path", type_name, repo.names(), quote=str
        )
    )


def _table(headers: list[str], rows: list[list[str]]) -> str:
    widths = [
        max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(headers)
    ]
    line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()  # noqa: E731
    return "\n".join([line(headers), line(["-" * w for w in widths]), *(line(r) for r in rows)])


@defs_app.command("list")
def list_(
    category: str = typer.Option(
        None,
        "--category",
        metavar="CATEGORY",
        help="Only definitions in this category (e.g. /Devices).",
    ),
    base: str = typer.Option(
        None,
        "--base",
        metavar="TYPE",
        help="Only definitions that are, or inherit from, this type.",
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    fmt: DataFormat = FORMAT_OPTION,
) -> None:
    """List definitions: name, newest version, abstract, parents, category and source."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.jccl.defquery import list_definitions
    from gadgetctl.suggest import with_suggestion

    repo = _repository(definitions, bundled)
    if base is not None and base not in repo:
        raise unknown_definition(repo, base, "base type")
    if category is not None:
        known = {c for d in repo.all_newest() for c in d.categories}
        prefix = category.rstrip("/") + "/"
        if not any(c == category or c.startswith(prefix) for c in known):
            raise GadgetctlError(
                with_suggestion(
                    f"no definition is in category {category!r}", category, known, quote=str
                )
            )
    rows = list_definitions(repo, category=category, base=base)
    if fmt is DataFormat.json:
        emit(json.dumps(rows, indent=2))
        return
    emit(
        _table(
            ["NAME", "VERSION", "ABSTRACT", "PARENTS", "CATEGORY", "SOURCE"],
            [
                [
                    r["name"],
                    str(r["version"]),
                    "yes" if r["abstract"] else "",
                    ", ".join(r["parents"]),
                    ", ".join(r["categories"]),
                    f"{r['source']} ({r['origin']})",
                ]
                for r in rows
            ],
        )
    )
    from gadgetctl.wording import counted

    emit(counted(len(rows), "definition"))


@defs_app.command("show")
def show(
    type_name: str = typer.Argument(..., metavar="TYPE", help="Definition name, e.g. dtrack."),
    version: int = typer.Option(
        None, "--version", metavar="N", help="A specific version (default: the newest)."
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    fmt: DataFormat = FORMAT_OPTION,
) -> None:
    """Show a definition's effective properties, own and inherited."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.jccl.defquery import show_definition

    repo = _repository(definitions, bundled)
    found = repo.get(type_name, version)
    if found is None:
        if type_name in repo:
            raise GadgetctlError(
                f"{type_name} has no version {version} (versions: "
                f"{', '.join(map(str, repo.versions(type_name)))})"
            )
        raise unknown_definition(repo, type_name)
    data = show_definition(repo, found)
    if fmt is DataFormat.json:
        emit(json.dumps(data, indent=2))
        return
    emit(_render_show(data))


def _render_show(data: dict) -> str:
    lines = [
        f"{data['name']} version {data['version']} ({data['label']})"
        + ("  [abstract]" if data["abstract"] else ""),
        f"  versions: {', '.join(map(str, data['versions']))}",
        f"  parents: {', '.join(data['parents']) or '-'}",
        f"  ancestors: {', '.join(data['ancestors']) or '-'}",
        f"  source: {data['source']} ({data['origin']})",
    ]
    if data["missing_parents"]:
        lines.append(f"  missing parents: {', '.join(data['missing_parents'])}")
    if data["help"]:
        lines.append(f"  {data['help']}")
    lines.append("")
    for prop in data["properties"]:
        count = (
            "variable"
            if prop["variable"]
            else f"{prop['count']} value{'s' if prop['count'] != 1 else ''}"
        )
        origin = f"  (inherited from {prop['defined_by']})" if prop["inherited"] else ""
        lines.append(f"  {prop['name']}: {prop['valuetype']}, {count}{origin}")
        defaults = [v["default"] for v in prop["values"]]
        if any(d is not None for d in defaults):
            lines.append(
                f"      default: {', '.join('-' if d is None else repr(d) for d in defaults)}"
            )
        if prop["allowed_types"]:
            lines.append(f"      allowed types: {', '.join(prop['allowed_types'])}")
        if "enumeration" in prop:
            enum = prop["enumeration"]
            choices = ", ".join(f"{c['label']}={c['value']}" for c in enum["choices"][:12])
            more = f", ... ({len(enum['choices'])} in all)" if len(enum["choices"]) > 12 else ""
            lines.append(
                f"      choices{' (editable)' if enum['editable'] else ''}: {choices}{more}"
            )
        if prop["help"]:
            lines.append(f"      {prop['help']}")
    return "\n".join(lines)


@defs_app.command("tree")
def tree(
    type_name: str = typer.Argument(
        None, metavar="[TYPE]", help="Show only this type and what inherits from it."
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    fmt: DataFormat = FORMAT_OPTION,
) -> None:
    """Show the inheritance tree (children under their parents)."""
    from gadgetctl.jccl.defquery import inheritance_tree

    repo = _repository(definitions, bundled)
    if type_name is not None and type_name not in repo:
        raise unknown_definition(repo, type_name)
    roots = inheritance_tree(repo, type_name)
    if fmt is DataFormat.json:
        emit(json.dumps([r.to_dict() for r in roots], indent=2))
        return
    lines: list[str] = []

    def draw(node, prefix: str, last: bool, top: bool) -> None:
        mark = "" if top else ("└── " if last else "├── ")
        note = " (shown above)" if node.repeated and node.children == [] and not top else ""
        lines.append(f"{prefix}{mark}{node.name}{note}")
        child_prefix = prefix if top else prefix + ("    " if last else "│   ")
        for i, child in enumerate(node.children):
            draw(child, child_prefix, i == len(node.children) - 1, False)

    for root in roots:
        draw(root, "", True, True)
    emit("\n".join(lines))


@defs_app.command("path")
def path(
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    fmt: DataFormat = FORMAT_OPTION,
) -> None:
    """Show the effective definition search path, in order, and what each entry contributed."""
    repo = _repository(definitions, bundled)
    rows = [e.to_dict() for e in repo.entries]
    shadowed = [
        {"name": s.name, "version": s.version, "used": str(s.winner), "ignored": str(s.loser)}
        for s in repo.shadowed
    ]
    if fmt is DataFormat.json:
        emit(json.dumps({"entries": rows, "shadowed": shadowed}, indent=2))
        return
    emit(
        _table(
            ["#", "ORIGIN", "PATH", "EXISTS", "FILES", "DEFINITIONS"],
            [
                [
                    str(i + 1),
                    r["origin"],
                    r["path"],
                    "skipped" if r["skipped"] else "yes" if r["exists"] else "no",
                    str(r["files"]),
                    str(r["definitions"]),
                ]
                for i, r in enumerate(rows)
            ],
        )
    )
    for r in rows:
        for name in r["undefined_variables"]:
            emit(
                f"warning: {r['origin']} entry {r['as_written']!r} uses ${{{name}}}, which is not "
                "set; the entry is skipped"
            )
    for s in shadowed:
        emit(
            f"shadowed: {s['name']} version {s['version']} from {s['ignored']} (using {s['used']})"
        )
