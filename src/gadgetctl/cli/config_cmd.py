"""`gadgetctl config show` and `gadgetctl config graph`."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path

import typer

from gadgetctl.cli.options import (
    BUNDLED_OPTION,
    COLOR_OPTION,
    DEFINITIONS_OPTION,
    ColorMode,
    DataFormat,
    emit,
    use_color,
)

FILES_ARGUMENT = typer.Argument(
    ...,
    metavar="FILES...",
    help="Configuration files, loaded together as one configuration (their includes too).",
    show_default=False,
)


class GraphFormat(StrEnum):
    text = "text"
    dot = "dot"
    mermaid = "mermaid"
    json = "json"


def register(app: typer.Typer) -> None:
    group = typer.Typer(
        name="config",
        help="Inspect configurations (.jconf): resolved values and wiring.",
        no_args_is_help=True,
    )
    group.command(name="show")(show)
    group.command(name="graph")(graph)
    try:  # `config pending` lives with the input manager's command-line code
        from gadgetctl.cli.pending_cmd import pending
    except ModuleNotFoundError as err:
        if err.name != "gadgetctl.cli.pending_cmd":
            raise
    else:
        group.command(name="pending")(pending)
    app.add_typer(group, name="config")


def show(
    files: list[Path] = FILES_ARGUMENT,
    element: list[str] = typer.Option(
        [],
        "--element",
        "-e",
        metavar="NAME",
        help="Show only this element (name or full name). Repeatable.",
    ),
    fmt: DataFormat = typer.Option(DataFormat.text, "--format", "-f", help="Output format."),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    color: ColorMode = COLOR_OPTION,
) -> None:
    """Show the resolved configuration: every element with every effective property, its value,
    and whether it was written or comes from a default."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.jccl.configcheck import open_configuration
    from gadgetctl.jccl.resolve import resolve_configuration
    from gadgetctl.suggest import with_suggestion
    from gadgetctl.validate import plugin_definition_finder

    opened = open_configuration(
        files,
        definition_dirs=definitions,
        bundled=bundled,
        plugin_definitions=plugin_definition_finder(),
    )
    if element:
        everything = opened.configuration.all_elements()
        known = {e.name for e in everything} | {e.full_name for e in everything}
        missing = [name for name in element if name not in known]
        if missing:
            raise GadgetctlError(
                "; ".join(
                    with_suggestion(f"no element named {name!r} in the configuration", name, known)
                    for name in missing
                )
            )
    elements = resolve_configuration(opened.configuration, opened.index, element or None)
    if fmt is DataFormat.json:
        emit(json.dumps([e.to_dict() for e in elements], indent=2))
        return
    from gadgetctl.cli.configtext import render_elements

    emit(render_elements(elements, color=use_color(color)))


def graph(
    files: list[Path] = FILES_ARGUMENT,
    fmt: GraphFormat = typer.Option(
        GraphFormat.text, "--format", "-f", help="text (a tree), dot (Graphviz), mermaid, or json."
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
) -> None:
    """Show the wiring: aliases to proxies to devices to the driver plug-ins the input manager
    loads, with the other pointers and the embedded elements.

    For a picture: gadgetctl config graph -f dot FILE | dot -Tsvg > wiring.svg
    """
    from gadgetctl.input.plugins.catalog import built_in_types, plugin_for_type
    from gadgetctl.jccl.configcheck import open_configuration
    from gadgetctl.jccl.graph import RENDERERS, build_graph
    from gadgetctl.validate import plugin_definition_finder

    opened = open_configuration(
        files,
        definition_dirs=definitions,
        bundled=bundled,
        plugin_definitions=plugin_definition_finder(),
    )
    wiring = build_graph(
        opened.configuration, opened.index, built_in=built_in_types(), plugins=plugin_for_type()
    )
    if fmt is GraphFormat.json:
        emit(json.dumps(wiring.to_dict(), indent=2))
    else:
        emit(RENDERERS[fmt.value](wiring))
