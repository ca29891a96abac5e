"""Definitions an input manager needs: the usual search path plus the folders of driver
plug-ins that carry their own ``.jdef`` files."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from gadgetctl.input.kinds import INPUT_MANAGER
from gadgetctl.input.plugins.discovery import DriverSearch, PluginSource, directory_entry
from gadgetctl.jccl.configuration import Configuration
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.searchpath import (
    SearchPathEntry,
    SearchPathOptions,
    build_search_path,
    configuration_entries,
)

DRIVER_PROPERTIES = (
    ("driver_path", PluginSource.DRIVER_PATH),
    ("driver_scan_path", PluginSource.SCAN_PATH),
)


def driver_search_for(
    configuration: Configuration | None = None,
    extra_dirs: Iterable[Path] = (),
    *,
    bundled: bool = True,
    entry_points: bool = True,
    environ: Mapping[str, str] | None = None,
) -> DriverSearch:
    """Every place plug-ins are looked for, the configuration's input_manager paths included."""
    search = DriverSearch.standard(
        extra_dirs, bundled=bundled, entry_points=entry_points, environ=environ
    )
    if configuration is not None:
        for element in configuration.elements:
            if element.type != INPUT_MANAGER:
                continue
            base = Path(element.file).parent
            for prop, source in DRIVER_PROPERTIES:
                for value in element.values(prop):
                    if value.stripped:
                        search.add_directory(
                            directory_entry(
                                value.text,
                                source,
                                base=base,
                                environ=environ,
                                location=value.location,
                            )
                        )
    return search


def driver_definition_dirs(
    extra_dirs: Iterable[Path] = (),
    configuration: Configuration | None = None,
    *,
    bundled: bool = True,
    environ: Mapping[str, str] | None = None,
) -> list[Path]:
    """Folders of discoverable plug-ins that carry ``.jdef`` files, for the definition
    search path of `validate` and the config commands (found without importing anything)."""
    return driver_search_for(
        configuration, extra_dirs, bundled=bundled, environ=environ
    ).definition_dirs()


def repository_for(
    configuration: Configuration | None = None,
    *,
    definitions: Iterable[Path] = (),
    bundled: bool = True,
    driver_dirs: Iterable[Path] = (),
    environ: Mapping[str, str] | None = None,
) -> DefinitionRepository:
    """The bundled definitions, ``definitions``, the configuration's definition_path
    directories and the definitions carried by plug-ins, in that order of precedence."""
    env = os.environ if environ is None else environ
    entries = build_search_path(
        SearchPathOptions(bundled=bundled, extra_dirs=list(definitions), environ=env)
    )
    if configuration is not None:
        for config_file in configuration.files:
            entries += configuration_entries(
                config_file.definition_dirs, config_file.path.parent, env
            )
    for directory in driver_definition_dirs(driver_dirs, configuration, environ=env):
        entries.append(SearchPathEntry(raw=str(directory), path=directory, origin="driver plug-in"))
    return DefinitionRepository.from_search_path(entries)
