"""Building a :class:`DoctorReport`: search paths, plug-ins, configured devices, system."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.doctor.devices import CheckSettings, check_transport
from gadgetctl.doctor.model import DeviceReport, DoctorReport, PluginReport, PortCheck, Status
from gadgetctl.doctor.permissions import Identity
from gadgetctl.doctor.ports import (
    JOYSTICK_GLOB,
    check_serve_port,
    list_joysticks,
    list_serial_ports,
)
from gadgetctl.doctor.transports import transports_for
from gadgetctl.errors import GadgetctlError
from gadgetctl.input.kinds import INPUT_DEVICE, INPUT_MANAGER, UNSUPPORTED_TYPES
from gadgetctl.input.pending import PendingEntry, PendingKind
from gadgetctl.input.plugins.discovery import DriverSearch, PluginInfo
from gadgetctl.input.plugins.emulators import emulator_of
from gadgetctl.input.registry import BUILTIN, DeviceRegistry
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.configuration import ConfigElement, Configuration
from gadgetctl.jccl.repository import DefinitionRepository

_SEVERITY = {
    Status.PROBLEM: Severity.ERROR,
    Status.WARNING: Severity.WARNING,
    Status.UNCHECKED: Severity.INFO,
}


@dataclass
class DoctorOptions:
    definitions: list[Path] = field(default_factory=list)  # --definitions
    bundled: bool = True
    driver_dirs: list[Path] = field(default_factory=list)  # --driver-path
    probe: bool = False  # connect to configured TCP servers
    timeout: float = 2.0  # seconds per probe
    identity: Identity | None = None  # whose access is judged; None: the current user
    joystick_glob: str = JOYSTICK_GLOB
    environ: Mapping[str, str] | None = None
    serve_port: tuple[str, int] | None = None  # (bind address, port) to check for `gadgetctl serve`
    vrpn_names: list[str] = field(default_factory=list)  # Device@host names given as vrpn:NAME


def diagnose(configs: Sequence[Path] = (), options: DoctorOptions | None = None) -> DoctorReport:
    """Everything doctor finds; a configuration's devices when ``configs`` are given, an
    overview of the system otherwise. Raises GadgetctlError for unusable input."""
    from gadgetctl.input.definitions import driver_search_for, repository_for

    options = options or DoctorOptions()
    if not options.timeout > 0:
        raise GadgetctlError("--timeout must be a positive number of seconds")
    for directory in options.definitions:
        if not directory.is_dir():
            raise GadgetctlError(f"--definitions {directory}: no such directory")
    configuration = _load(configs, options) if configs else None
    repo = repository_for(
        configuration,
        definitions=options.definitions,
        bundled=options.bundled,
        driver_dirs=options.driver_dirs,
        environ=options.environ,
    )
    search = driver_search_for(configuration, options.driver_dirs, environ=options.environ)
    report = DoctorReport(
        [str(p) for p in configs], [e.to_dict() for e in repo.entries], search.describe_places()
    )
    report.serial_ports = list_serial_ports()
    report.joysticks = list_joysticks(options.joystick_glob, options.identity)
    if configuration is None:
        report.plugins, found = _plugins(search, repo, None)
        from gadgetctl.doctor.sdl import sdl_joysticks

        report.sdl_joysticks = sdl_joysticks()
        found += [
            _diagnostic(c, f"joystick {c.target} {c.detail}") for c in report.joysticks if c.code
        ]
    else:
        found, used = _configured(configuration, repo, search, options, report)
        report.plugins, listed = _plugins(search, repo, used)
        found += listed
    for text in options.vrpn_names:
        found += _vrpn_device(text, report, options)
    if options.serve_port is not None:
        report.serve_port = check_serve_port(*options.serve_port)
        if report.serve_port.code:
            found.append(
                _diagnostic(
                    report.serve_port,
                    f"gadgetctl serve on {report.serve_port.target}: {report.serve_port.detail}",
                )
            )
    report.diagnostics = _unique(found)
    return report


def _load(configs: Sequence[Path], options: DoctorOptions) -> Configuration:
    from gadgetctl.files import require_file
    from gadgetctl.jccl.configload import load_configuration

    for path in configs:
        require_file(path)
    configuration = load_configuration(list(configs), environ=options.environ)
    broken = [d for d in configuration.diagnostics if d.code == "XML001"]
    if broken:
        raise GadgetctlError(f"{broken[0].location}: {broken[0].message}")
    return configuration


def _plugins(
    search: DriverSearch, repo: DefinitionRepository, used: set[str] | None
) -> tuple[list[PluginReport], list[Diagnostic]]:
    """Load every discoverable plug-in into a private registry; failures of plug-ins the
    configuration does not use (``used``; None: all count) are only warnings."""
    from gadgetctl.input.plugins.loader import PluginLoader

    loader = PluginLoader(DeviceRegistry.with_builtins(), repo)
    reports, found = [], []
    for info in search.plugins():
        types = sorted(info.declared_types()[0])
        counts = used is None or info.name in used
        if info.shadowed_by is not None:
            reports.append(
                PluginReport(
                    info.name,
                    info.source.value,
                    str(info.path),
                    False,
                    "shadowed",
                    types,
                    False,
                    str(info.shadowed_by.path),
                )
            )
            continue
        result = loader.load(info)
        reports.append(
            PluginReport(
                info.name,
                info.source.value,
                str(info.path),
                result.ok,
                None if result.ok else (result.reason or result.error),
                types,
                used is not None and counts,
            )
        )
        for d in result.diagnostics:
            if not counts and d.severity is Severity.ERROR:
                d = Diagnostic.make(
                    d.code,
                    f"{d.message} (not used by the configuration)",
                    d.path,
                    d.line,
                    d.column,
                    hint=d.hint,
                    severity=Severity.WARNING,
                )
            found.append(d)
    return reports, found


def _configured(
    configuration: Configuration,
    repo: DefinitionRepository,
    search: DriverSearch,
    options: DoctorOptions,
    report: DoctorReport,
) -> tuple[list[Diagnostic], set[str]]:
    """Configure an input manager without starting devices; check each device's connections."""
    from gadgetctl.input.manager import InputManager, ManagerOptions

    manager_options = ManagerOptions(
        start_devices=False,
        driver_dirs=list(options.driver_dirs),
        retry_interval=None,
        environ=options.environ,
    )
    serial = None if report.serial_ports is None else tuple(p.device for p in report.serial_ports)
    settings = CheckSettings(
        options.probe, options.timeout, options.identity, options.joystick_glob, serial
    )
    with InputManager(repo, manager_options, search=search) as manager:
        manager.configure(configuration)
        found = list(manager.diagnostics)
        pending = {entry.name: entry for entry in manager.pending()}
        used = {r.name for r in manager.plugin_results}
        for element in configuration.elements:
            entry = pending.get(element.full_name)
            if element.type == INPUT_MANAGER:
                found += [entry.diagnostic()] if entry is not None else []
                continue
            if not _is_device(element, repo, manager.registry, entry):
                continue
            device, diagnostics, provider = _device(
                element, repo, manager.registry, search, entry, settings
            )
            report.devices.append(device)
            found += diagnostics
            used |= {provider.name} if provider is not None else set()
    return found, used


def _is_device(
    element: ConfigElement,
    repo: DefinitionRepository,
    registry: DeviceRegistry,
    entry: PendingEntry | None,
) -> bool:
    token = element.type
    if entry is not None and entry.kind is PendingKind.NO_DEFINITION:
        return True
    return (
        token in registry
        or token in UNSUPPORTED_TYPES
        or (token in repo and repo.is_a(token, INPUT_DEVICE))
    )


def _provider(token: str, registry: DeviceRegistry, search: DriverSearch) -> PluginInfo | None:
    registration = registry.get(token)
    if registration is not None and registration.plugin != BUILTIN:
        info = search.find(registration.plugin)
        if info is not None:
            return info
    providers = search.providers(token)
    return providers[0] if providers else None


def _device(
    element: ConfigElement,
    repo: DefinitionRepository,
    registry: DeviceRegistry,
    search: DriverSearch,
    entry: PendingEntry | None,
    settings: CheckSettings,
) -> tuple[DeviceReport, list[Diagnostic], PluginInfo | None]:
    token, name = element.type, element.full_name
    loc = element.location
    registration = registry.get(token)
    provider = _provider(token, registry, search)
    driver = (
        registration.plugin if registration is not None else (provider.name if provider else None)
    )
    device = DeviceReport(
        name,
        token,
        loc.path,
        loc.line,
        driver,
        registration is not None,
        entry.message if entry is not None else None,
    )
    found = [entry.diagnostic()] if entry is not None else []
    if driver == BUILTIN or token in UNSUPPORTED_TYPES or token not in repo:
        return device, found, provider
    transports, device.transport_source = transports_for(token, provider)
    if not transports:
        check = PortCheck(
            "",
            "",
            Status.UNCHECKED,
            "cannot check this device's connection",
            "DRV105",
            f"no driver plug-in declares TRANSPORTS for {token}, and gadgetctl knows no "
            "port property of it",
        )
        device.checks.append(check)
        found.append(
            _diagnostic(check, f"{name} ({token}): cannot check this device's connection", element)
        )
        return device, found, provider
    has_emulator = provider is not None and emulator_of(provider) is not None
    settings = replace(settings, emulator=provider.name if has_emulator else None)
    access = ElementAccess(element, repo)
    for transport in transports:
        for check in check_transport(access, transport, settings):
            device.checks.append(check)
            if check.code is not None:
                found.append(_diagnostic(check, f"{name} ({token}): {_describe(check)}", element))
    return device, found, provider


def _vrpn_device(text: str, report: DoctorReport, options: DoctorOptions) -> list[Diagnostic]:
    """A VRPN device named on the command line (``vrpn:Device@host``), checked as a vrpn
    element's *_server property is."""
    from gadgetctl.doctor.vrpn import check_vrpn_name

    check = check_vrpn_name(text, probe=options.probe, timeout=options.timeout)
    device = DeviceReport(f"vrpn:{text}", "vrpn", None, None, "VRPN_drv", True, checks=[check])
    report.devices.append(device)
    return [_diagnostic(check, f"vrpn:{text}: {check.detail}")] if check.code else []


def _describe(check: PortCheck) -> str:
    if check.kind == "vrpn" and check.target:
        return f"{check.prop} {check.target}: {check.detail}" if check.prop else check.detail
    if check.kind in ("file", "serial") and check.target:
        return f"{check.prop} {check.target} {check.detail}"
    return f"{check.prop}: {check.detail}" if check.prop else check.detail


def _diagnostic(check: PortCheck, message: str, element: ConfigElement | None = None) -> Diagnostic:
    loc = None
    if element is not None:
        loc = element.location
        values = element.values((check.prop or "").split(",")[0])
        if values:
            loc = values[0].location
    return Diagnostic.make(
        check.code or "DRV105",
        message,
        loc.path if loc else check.target or None,
        loc.line if loc else None,
        loc.column if loc else None,
        hint=check.hint,
        severity=_SEVERITY.get(check.status),
    )


def _unique(found: list[Diagnostic]) -> list[Diagnostic]:
    seen: set[tuple[str, str]] = set()
    result = []
    for d in found:
        key = (d.code, d.message.removesuffix(" (not used by the configuration)"))
        if key not in seen:
            seen.add(key)
            result.append(d)
    return result
