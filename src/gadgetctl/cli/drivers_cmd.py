"""`gadgetctl drivers list` and `gadgetctl drivers load`."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit

DRIVER_PATH_OPTION = typer.Option(
    [],
    "--driver-path",
    metavar="DIR",
    help="Also look for driver plug-ins in DIR (after the bundled drivers and GADGETCTL_DRIVER_PATH). Repeatable.",
)


def _trust(value: bool) -> bool:
    if value:
        from gadgetctl.input.plugins.trust import accept_writable_places

        accept_writable_places()
    return value


TRUST_OPTION = typer.Option(
    False,
    "--trust-driver-path",
    callback=_trust,
    help="Import plug-ins also from directories other users can write to (refused by default: DRV011).",
)
FORMAT_OPTION = typer.Option(DataFormat.text, "--format", "-f", help="Output format.")

drivers_app = typer.Typer(
    help="Driver plug-ins: list what can be found, load and check them.", no_args_is_help=True
)


def register(app: typer.Typer) -> None:
    app.add_typer(drivers_app, name="drivers")


@drivers_app.command("list")
def list_drivers(
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    configs: list[Path] = typer.Option(
        [],
        "--config",
        "-c",
        metavar="FILE",
        help="Also look in the driver_path and driver_scan_path of this configuration's input_manager elements. Repeatable.",
    ),
    fmt: DataFormat = FORMAT_OPTION,
) -> None:
    """List every discoverable driver plug-in, without importing any of them.

    For each: its name (what a driver value names), where it comes from, the element types
    and device types it provides (from its metadata or its own .jdef files), its plug-in API
    version and any problem with its metadata.
    """
    from gadgetctl.input.definitions import driver_search_for
    from gadgetctl.input.plugins import PLUGIN_API_VERSION

    configuration = _load_configs(configs)
    search = driver_search_for(configuration, driver_paths)
    plugins = search.plugins()
    if fmt is DataFormat.json:
        entries = []
        for info in plugins:
            types, read_from = info.declared_types()
            entries.append(
                {
                    **info.to_dict(),
                    "provides": {t: [k.value for k in kinds] for t, kinds in types.items()},
                    "provides_from": read_from or None,
                    "problems": _problems(info, PLUGIN_API_VERSION),
                }
            )
        emit(
            json.dumps(
                {
                    "api_version": PLUGIN_API_VERSION,
                    "places": search.describe_places(),
                    "plugins": entries,
                },
                indent=2,
            )
        )
        return
    if not plugins:
        emit(f"no driver plug-ins found (looked in {search.describe_places()})")
        return
    lines = []
    for info in plugins:
        api = info.metadata.api_version
        head = f"{info.name}  [{info.source}]  API {api if api is not None else '?'}  {info.path}"
        lines.append(head)
        types, read_from = info.declared_types()
        for token, kinds in types.items():
            note = " (from its .jdef)" if read_from == "jdef" else ""
            lines.append(f"    {token}: {', '.join(kinds) or 'no device types'}{note}")
        if not types:
            lines.append("    provides no declared element types")
        lines.extend(f"    ! {problem}" for problem in _problems(info, PLUGIN_API_VERSION))
    lines.append(
        f"{len(plugins)} plug-in{'s' if len(plugins) != 1 else ''}; gadgetctl provides plug-in API {PLUGIN_API_VERSION}"
    )
    emit("\n".join(lines))


@drivers_app.command("load")
def load_drivers(
    names: list[str] = typer.Argument(
        ...,
        metavar="NAME...",
        help="Plug-in names (as a driver value writes them) or paths of plug-in folders or modules.",
        show_default=False,
    ),
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    fmt: DataFormat = FORMAT_OPTION,
) -> None:
    """Import, check and register driver plug-ins, and report for each one: ok, or why not.

    Exit status: 0 when every plug-in loaded, 1 when any failed, 2 when a NAME names no
    plug-in (nothing is loaded then).
    """
    from gadgetctl.input.definitions import driver_search_for
    from gadgetctl.input.plugins.discovery import plugin_at
    from gadgetctl.input.plugins.loader import PluginLoader
    from gadgetctl.input.registry import DeviceRegistry
    from gadgetctl.jccl.repository import default_repository

    search = driver_search_for(None, driver_paths)
    chosen = [
        plugin_at(Path(name))
        if ("/" in name or name.endswith(".py")) and Path(name).exists()
        else search.find(name)
        for name in names
    ]
    unknown = [name for name, info in zip(names, chosen, strict=True) if info is None]
    if unknown:
        raise _unknown_plugins(unknown, search)
    repo = default_repository(list(definitions), bundled=bundled)
    loader = PluginLoader(DeviceRegistry.with_builtins(), repo)
    results = [loader.load(info) for info in chosen if info is not None]
    failed = [r for r in results if not r.ok]
    if fmt is DataFormat.json:
        emit(
            json.dumps(
                {
                    "loaded": len(results) - len(failed),
                    "failed": len(failed),
                    "plugins": [r.to_dict() for r in results],
                },
                indent=2,
            )
        )
    else:
        lines = []
        for result in results:
            if result.ok:
                registered = "; ".join(
                    f"{r.element_type} -> {r.device_class.__qualname__} "
                    f"({', '.join(r.kinds) or 'no device types'})"
                    for r in result.registrations
                )
                lines.append(f"{result.name}: ok: {registered or 'nothing new registered'}")
            else:
                lines.append(f"{result.name}: failed: {result.reason or result.error}")
            for d in result.diagnostics:
                lines.append(f"    {d.location}: {d.severity.value} {d.code} {d.message}")
                if d.hint:
                    lines.append(f"        hint: {d.hint}")
        lines.append(f"{len(results) - len(failed)} loaded, {len(failed)} failed")
        emit("\n".join(lines))
    raise typer.Exit(1 if failed else 0)


def _unknown_plugins(names: list[str], search):
    """The usage error for plug-in names (or paths) that name nothing."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.suggest import did_you_mean

    known = [info.name for info in search.plugins()]
    parts = []
    for name in names:
        if "/" in name or name.endswith(".py"):
            parts.append(f"{name}: no such plug-in folder or module")
            continue
        close = did_you_mean(name, known)
        parts.append(f"no driver plug-in named {name!r}" + (f" ({close})" if close else ""))
    return GadgetctlError(
        f"{'; '.join(parts)} (looked in {search.describe_places()}; "
        "gadgetctl drivers list shows them)"
    )


def _problems(info, api_version: int) -> list[str]:
    from gadgetctl.input.plugins.metadata import missing_requirements

    problems = list(info.metadata.problems)
    problems += [f"not loadable: {need}" for need in missing_requirements(info.metadata)]
    declared = info.metadata.api_version
    if declared is not None and declared != api_version:
        problems.insert(
            0,
            f"written for plug-in API {declared}; gadgetctl provides {api_version} (it will be refused)",
        )
    if info.shadowed_by is not None:
        problems.append(
            f"shadowed by {info.shadowed_by.path} ({info.shadowed_by.source}), which is found first"
        )
    return problems


def _load_configs(paths: list[Path]):
    if not paths:
        return None
    from gadgetctl.files import require_file
    from gadgetctl.jccl.configload import load_configuration

    for path in paths:
        require_file(path)
    return load_configuration(paths)
