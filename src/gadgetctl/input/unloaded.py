"""Element types a configuration uses whose driver it never loads.

The input manager loads the plug-ins its ``input_manager`` elements name and leaves an
element no loaded driver handles pending (DRV030, "no loaded driver handles TYPE"), as VR
Juggler does. ``gadgetctl validate`` predicts the same from :func:`unloaded_types`, which
reads the plug-ins' metadata without importing any of them; both say it with the words of
:func:`no_driver_reason`, so the two never disagree about such an element.
"""

from __future__ import annotations

from collections.abc import Iterable

from gadgetctl.input.kinds import INPUT_MANAGER
from gadgetctl.input.plugins.discovery import DriverSearch, PluginInfo
from gadgetctl.jccl.configuration import Configuration

#: The element types of gadgetctl.input.builtin.BUILTIN_DEVICES, which need no plug-in (a
#: constant, so that validate does not import the simulated devices; a test compares them).
BUILTIN_TYPES = frozenset(
    {
        "keyboard_mouse_device",
        "input_window",
        "simulated_analog_device",
        "simulated_digital_device",
        "simulated_positional_device",
        "simulated_relative_position",
        "simulated_setable_position",
        "simulated_digital_glove",
        "simulated_glove_gesture",
        "waveform_device",
    }
)


def no_driver_reason(element_type: str) -> str:
    """Why an element of ``element_type`` stays pending when no loaded driver handles it."""
    return f"no loaded driver handles {element_type}"


def provider_hint(element_type: str, info: PluginInfo) -> str:
    """How to load the plug-in ``info``, which provides ``element_type``."""
    return (
        f"plug-in {info.name} ({info.source}) provides {element_type}: "
        f"add <driver>{info.name}</driver> to an input_manager element"
    )


def loaded_types(configuration: Configuration, search: DriverSearch) -> set[str] | None:
    """The element types the plug-ins named by the configuration's input_manager elements
    provide (from their metadata); None when an input_manager scans a directory
    (driver_scan_path loads every plug-in found there, which only the run time knows)."""
    loaded: set[str] = set()
    for element in configuration.elements:
        if element.type != INPUT_MANAGER:
            continue
        if any(value.stripped for value in element.values("driver_scan_path")):
            return None
        for value in element.values("driver"):
            info = search.find(value.stripped) if value.stripped else None
            if info is not None:
                loaded.update(info.metadata.element_types)
    return loaded


def unloaded_types(
    configuration: Configuration, search: DriverSearch, types: Iterable[str] | None = None
) -> dict[str, str]:
    """Element type -> the reason and hint, for each type of the configuration's elements
    (or ``types``) that a discoverable plug-in provides but none of the plug-ins its
    input_manager elements load does (and no built-in device handles)."""
    loaded = loaded_types(configuration, search)
    if loaded is None:
        return {}
    wanted = {e.type for e in configuration.elements} if types is None else set(types)
    found = {}
    for element_type in sorted(wanted - loaded - BUILTIN_TYPES - {INPUT_MANAGER}):
        providers = search.providers(element_type)
        if providers:
            hints = "; ".join(provider_hint(element_type, info) for info in providers)
            found[element_type] = f"{no_driver_reason(element_type)} ({hints})"
    return found
