"""The embedded input manager.

Configured from the elements of one or more configurations, it works like Gadgeteer's:

* ``input_manager`` elements name driver plug-ins (``driver``), where to find them
  (``driver_path``) and directories whose every plug-in is loaded (``driver_scan_path``);
* every element whose type a registered device class handles becomes a device that is
  configured and started; proxies and aliases come next (a proxy of a missing device is
  stupefied, an alias waits for its proxy);
* what cannot be configured stays pending with a reason (:mod:`gadgetctl.input.pending`);
  pending elements are retried whenever the configuration changes;
* :meth:`InputManager.update` is one frame: reconfiguration, then every device's
  ``update_data`` and every proxy's update;
* elements can be added and removed while running; removing a device stupefies its
  proxies, and elements that pointed at a removed element go back to pending until it
  returns.

Elements that are not about input (displays, users...) are ignored, not pending.
"""

from __future__ import annotations

import contextlib
import gc
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.input.clock import now
from gadgetctl.input.dependencies import pointer_targets
from gadgetctl.input.device import DeviceState, Input, SamplingMode
from gadgetctl.input.errors import DeviceConfigError, ElementVersionError, describe
from gadgetctl.input.events import EventSource
from gadgetctl.input.kinds import ALIAS, INPUT_DEVICE, INPUT_MANAGER, PROXY_BASE, UNSUPPORTED_TYPES
from gadgetctl.input.pending import CHEAP_TO_RETRY, PendingEntry, PendingKind
from gadgetctl.input.plugins.discovery import (
    DriverDirectory,
    DriverSearch,
    PluginSource,
    directory_entry,
)
from gadgetctl.input.plugins.loader import PluginLoader, PluginLoadResult
from gadgetctl.input.proxies import PROXY_CLASSES, Proxy
from gadgetctl.input.registry import DeviceRegistry, Registration
from gadgetctl.input.samples import DEFAULT_CAP
from gadgetctl.input.sampling import (
    FrameRunner,
    RestartPolicy,
    Runner,
    ScheduledRunner,
    SharedScheduler,
    ThreadRunner,
)
from gadgetctl.input.status import ACTIVE, PENDING, UNKNOWN_TYPE, ElementKind, ElementStatus
from gadgetctl.input.unloaded import no_driver_reason, provider_hint
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.activation import (
    DIFFERENCES,
    Node,
    RunTime,
    never_handled,
    settle,
    too_old,
    waits_for_pointers,
)
from gadgetctl.jccl.configuration import ConfigElement, Configuration
from gadgetctl.jccl.definitions import Location
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.units import proxy_unit_problem

if TYPE_CHECKING:
    from gadgetctl.jccl.xmlload import XmlDocument

NOT_PROCESSED = "not processed yet"
INPUT_WINDOW = "input_window"


@dataclass
class ManagerOptions:
    start_devices: bool = True  # False: configure only (what `config pending` does by default)
    sample_cap: int = DEFAULT_CAP  # samples kept per device, kind and frame
    restart: RestartPolicy = field(default_factory=RestartPolicy)
    stop_timeout: float = 2.0  # seconds to wait for a sampling thread to end
    driver_dirs: list[Path] = field(default_factory=list)  # --driver-path
    bundled_drivers: bool = True
    entry_points: bool = True
    autoload_drivers: bool = False  # load a discoverable plug-in for a type no input_manager loads
    environ: Mapping[str, str] | None = None
    retry_interval: float | None = 5.0  # seconds between retries of failed configurations/starts
    freeze_gc: bool = True  # run(): keep what exists out of full collections while frames run


@dataclass(slots=True)
class _DeviceEntry:
    element: ConfigElement
    device: Input
    runner: Runner | None


class _Context:
    """The :class:`~gadgetctl.input.device.DeviceContext` the manager gives its devices."""

    def __init__(self, manager: InputManager) -> None:
        self._manager = manager

    @property
    def frame(self) -> int:
        return self._manager.frame

    @property
    def events(self) -> EventSource:
        return self._manager.events

    def proxy(self, name: str) -> Proxy | None:
        proxy = self._manager.proxy(name)
        if proxy is not None:
            proxy.update_for_frame(self._manager.frame)
        return proxy


class InputManager:
    def __init__(
        self,
        repo: DefinitionRepository,
        options: ManagerOptions | None = None,
        *,
        registry: DeviceRegistry | None = None,
        events: EventSource | None = None,
        search: DriverSearch | None = None,
    ) -> None:
        self.repo = repo
        self.options = options or ManagerOptions()
        opts = self.options
        self.registry = registry if registry is not None else DeviceRegistry.with_builtins()
        self.events = events if events is not None else EventSource()
        self.search = (
            search
            if search is not None
            else DriverSearch.standard(
                opts.driver_dirs,
                bundled=opts.bundled_drivers,
                entry_points=opts.entry_points,
                environ=opts.environ,
            )
        )
        self.loader = PluginLoader(self.registry, repo)
        self.frame = 0
        self._context = _Context(self)
        self._scheduler = SharedScheduler()
        #: Devices configured by the running reconfiguration, started at its end.
        self._starts: list[tuple[str, Runner]] | None = None
        self._incoming: deque[tuple[bool, ConfigElement | str]] = deque()
        self._incoming_lock = threading.Lock()
        self._known: dict[str, ConfigElement] = {}  # input elements, active or pending
        self._ignored: dict[str, ConfigElement] = {}  # elements that are not about input
        self._pending: dict[str, PendingEntry] = {}
        self._devices: dict[str, _DeviceEntry] = {}
        self._device_objects: dict[str, Input] = {}
        self._proxies: dict[str, Proxy] = {}
        self._proxy_elements: dict[str, ConfigElement] = {}
        # device name -> names of proxies pointing at it: a tuple of one, a set of more (a set
        # of one is 216 bytes, 2 MB for 10,000 devices with a proxy each)
        self._proxies_of: dict[str, tuple[str] | set[str]] = {}
        self._waiters: dict[
            str, set[str]
        ] = {}  # name -> pending elements whose pointer waits for it
        # update() order (devices, or (class, devices) updated together); None: stale
        self._frame_order: (
            tuple[list[Input | tuple[type[Input], list[Input]]], list[Proxy]] | None
        ) = None
        self._aliases: dict[str, str] = {}
        self._alias_elements: dict[str, ConfigElement] = {}
        self._input_managers: dict[str, ConfigElement] = {}
        self._missing_drivers: dict[str, str] = {}  # driver name -> input_manager naming it
        self._static_diagnostics: list[Diagnostic] = []
        self._last_retry = now()
        self._shut_down = False
        self._generation = 0  # counts configuration changes, for _vrjuggler_fate()
        # per element type: what _classify answers, and the versions of its definition, kept
        # while the repository and the registry stay as they were (_type_facts)
        self._facts: dict[str, tuple[ElementKind | None, tuple[int, ...]]] = {}
        self._facts_of: tuple[object, int, object, int] | None = None
        self._fate: tuple[int, dict[str, str | None]] = (-1, {})

    @classmethod
    def from_files(
        cls,
        paths: Iterable[Path],
        *,
        definitions: Iterable[Path] = (),
        bundled: bool = True,
        options: ManagerOptions | None = None,
        parsed: Mapping[Path, XmlDocument] | None = None,
    ) -> tuple[InputManager, Configuration]:
        """Load configuration files and make a manager with the right definitions (bundled,
        ``definitions``, the files' definition_path, plug-in folders), not yet configured.
        ``parsed``: documents of these files a caller parsed already, by resolved path."""
        from gadgetctl.input.definitions import repository_for
        from gadgetctl.jccl.configload import load_configuration
        from gadgetctl.perf import collector_paused

        options = options or ManagerOptions()
        with collector_paused():  # what is loaded lives as long as the manager
            configuration = load_configuration(list(paths), environ=options.environ, parsed=parsed)
        repo = repository_for(
            configuration,
            definitions=definitions,
            bundled=bundled,
            driver_dirs=options.driver_dirs,
            environ=options.environ,
        )
        return cls(repo, options), configuration

    # -- context manager --------------------------------------------------------------------

    def __enter__(self) -> InputManager:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()

    # -- reconfiguration --------------------------------------------------------------------

    def add(self, elements: Iterable[ConfigElement]) -> None:
        """Queue elements to add (or replace, by name); applied at the next frame or
        :meth:`reconfigure`. Thread-safe."""
        with self._incoming_lock:
            self._incoming.extend((True, e) for e in elements)

    def add_configuration(self, configuration: Configuration) -> None:
        self.add(configuration.elements)

    def remove(self, elements: Iterable[ConfigElement | str]) -> None:
        """Queue elements (or names) to remove. Thread-safe."""
        with self._incoming_lock:
            self._incoming.extend(
                (False, e if isinstance(e, str) else e.full_name) for e in elements
            )

    def configure(self, configuration: Configuration | Iterable[ConfigElement]) -> int:
        """Add a whole configuration and process it now; returns elements configured."""
        elements = (
            configuration.elements if isinstance(configuration, Configuration) else configuration
        )
        self.add(elements)
        return self.reconfigure()

    def reconfigure(self, *, retry_failed: bool = False) -> int:
        """Apply queued additions and removals and retry pending elements; returns how many
        elements were configured or removed."""
        if not (self._incoming or retry_failed):
            return 0  # nothing to do (every frame asks)
        from gadgetctl.perf import collector_paused

        # the devices, proxies and stores made here live on: the cyclic collector walking
        # them again and again while 20,000 elements are configured took a third of the time
        with collector_paused():
            return self._reconfigure(retry_failed)

    def _reconfigure(self, retry_failed: bool) -> int:
        with self._incoming_lock:
            work = list(self._incoming)
            self._incoming.clear()
        processed = 0
        changed = False
        for is_add, item in work:
            if is_add:
                assert isinstance(item, ConfigElement)
                processed += self._accept(item)
            else:
                assert isinstance(item, str)
                processed += self._remove(item)
            changed = True
        if changed or retry_failed:
            self._starts = []
            try:
                processed += self._process_pending(retry_failed=retry_failed)
            finally:
                starts, self._starts = self._starts, None
                processed -= self._start_devices(starts)
            self._refresh_proxies()  # their reasons quote the final pending reasons
        return processed

    def _start_devices(self, starts: list[tuple[str, Runner]]) -> int:
        """Start the devices a reconfiguration configured, all at once after the last one
        was configured (so that none samples, and no scheduler pass runs, while the others
        are configured: with 10,000 devices that work grew with the time configuring took,
        quadratically); returns how many failed to start (pending again, as START_FAILED,
        with what pointed at them)."""
        failed = 0
        with self._scheduler.hold():
            for name, runner in starts:
                entry = self._devices.get(name)
                if entry is None or entry.runner is not runner:
                    continue  # replaced or removed meanwhile
                try:
                    runner.start()
                except Exception as err:
                    entry.device.state = DeviceState.STOPPED
                    self._devices.pop(name, None)
                    self._device_objects.pop(name, None)
                    self._frame_order = None
                    self._pending[name] = PendingEntry(
                        entry.element,
                        PendingKind.START_FAILED,
                        f"the device failed to start: {describe(err)}",
                    )
                    failed += 1
        if failed:
            self._lost_dependencies()
        return failed

    def retry_pending(self) -> int:
        """Retry every pending element, failed configurations and starts included."""
        self._last_retry = now()
        return self.reconfigure(retry_failed=True)

    def _accept(self, element: ConfigElement) -> int:
        name = element.full_name
        removed = self._remove(name) if name in self._known or name in self._ignored else 0
        if self._classify(element) is None:
            self._ignored[name] = element
            return removed
        self._known[name] = element
        self._generation += 1
        self._pending[name] = PendingEntry(element, PendingKind.WAITING, NOT_PROCESSED)
        return removed

    def _classify(self, element: ConfigElement) -> ElementKind | None:
        """What the element is to the input manager; None: not an input element. A type
        without definition counts as a device (it is reported pending)."""
        return self._type_facts(element.type)[0]

    def _type_facts(self, token: str) -> tuple[ElementKind | None, tuple[int, ...]]:
        """What :meth:`_classify` answers for an element of type ``token``, and the versions
        of its definition (none: no definition is loaded): the same for every element of the
        type (20,000 elements asked twice each), worked out again once the repository or the
        registry has changed (a driver loaded, definitions added: their generations)."""
        repo, registry = self.repo, self.registry
        state = (repo, repo.generation, registry, registry.generation)
        if state != self._facts_of:
            self._facts.clear()
            self._facts_of = state
        facts = self._facts.get(token)
        if facts is None:
            facts = self._facts[token] = (self._kind_of(token), tuple(repo.versions(token)))
        return facts

    def _kind_of(self, token: str) -> ElementKind | None:
        if token == INPUT_MANAGER:
            return ElementKind.INPUT_MANAGER
        if token == ALIAS:
            return ElementKind.ALIAS
        if token in PROXY_CLASSES or (token in self.repo and self.repo.is_a(token, PROXY_BASE)):
            return ElementKind.PROXY
        if (
            token in self.registry
            or token in UNSUPPORTED_TYPES
            or token == INPUT_WINDOW
            or (token in self.repo and self.repo.is_a(token, INPUT_DEVICE))
        ):
            return ElementKind.DEVICE
        if token not in self.repo:
            return ElementKind.DEVICE  # unknown: reported as pending, see _try
        return None

    def _process_pending(self, *, retry_failed: bool = False) -> int:
        processed = 0
        attempted_failed: set[str] = set()
        progress = True
        while progress:
            progress = False
            # input managers first (they load the drivers), the rest in their order
            entries = list(self._pending.values())
            order = [e for e in entries if e.element.type == INPUT_MANAGER]
            order += [e for e in entries if e.element.type != INPUT_MANAGER]
            for entry in order:
                name = entry.name
                if name not in self._pending:
                    continue
                if entry.kind not in CHEAP_TO_RETRY:
                    if not retry_failed or name in attempted_failed:
                        continue
                    attempted_failed.add(name)
                result = self._try(entry.element)
                if result is None:
                    del self._pending[name]
                    processed += 1 + self._configure_waiters(name)
                    progress = True
                else:
                    self._pending[name] = result
        return processed

    def _configure_waiters(self, name: str) -> int:
        """Retry at once the pending elements that waited for ``name`` (just configured),
        and theirs in turn, so one pass configures a chain written in any order (without
        it, a chain written backwards took one pass over every pending element per link)."""
        processed = 0
        ready = [name]
        while ready:
            waiting = self._waiters.pop(ready.pop(), None)
            if not waiting:
                continue  # (the usual element: nothing waited for it)
            for waiter in sorted(waiting):
                entry = self._pending.get(waiter)
                if entry is None or entry.kind not in CHEAP_TO_RETRY:
                    continue
                result = self._try(entry.element)
                if result is None:
                    del self._pending[waiter]
                    processed += 1
                    ready.append(waiter)
                else:
                    self._pending[waiter] = result
        return processed

    # -- configuring one element ------------------------------------------------------------

    def _try(self, element: ConfigElement) -> PendingEntry | None:
        token = element.type
        kind, versions = self._type_facts(token)
        if not versions:  # (no definition of the type is loaded)
            return PendingEntry(
                element,
                PendingKind.NO_DEFINITION,
                f"no definition of element type {token} is loaded",
                "add the directory of its .jdef with --definitions or a definition_path",
            )
        if token in UNSUPPORTED_TYPES:
            return PendingEntry(element, PendingKind.UNSUPPORTED, UNSUPPORTED_TYPES[token])
        # the rules validate's predictions follow too (gadgetctl.jccl.activation)
        unhandled = never_handled(token, RunTime.GADGETCTL)
        if unhandled is not None:
            return PendingEntry(element, PendingKind.UNSUPPORTED, unhandled)
        old = too_old(token, element.version, versions)
        if old is not None:
            return PendingEntry(element, PendingKind.TOO_OLD, old)
        access = ElementAccess(element, self.repo)
        if kind is ElementKind.INPUT_MANAGER:
            return self._configure_input_manager(element, access)
        if kind is ElementKind.ALIAS:
            return self._configure_alias(element, access)
        if kind is ElementKind.PROXY:
            return self._configure_proxy(element, access)
        return self._configure_device(element, access)

    def _pending_reason(self, name: str) -> str | None:
        entry = self._pending.get(name)
        return None if entry is None else entry.message

    def _active(self, name: str) -> bool:
        return (
            name in self._devices
            or name in self._proxies
            or name in self._aliases
            or name in self._input_managers
        )

    def _unmet_dependency(self, element: ConfigElement) -> PendingEntry | None:
        if not waits_for_pointers(element.type, RunTime.GADGETCTL):
            return None  # bound now, stupefied until its device is active
        for prop, target in pointer_targets(element, self.repo):
            if self._active(target):
                continue
            self._waiters.setdefault(target, set()).add(element.full_name)
            if target in self._pending:
                waiting = self._pending[target]
                return PendingEntry(
                    element,
                    PendingKind.WAITING,
                    f"{prop} points at {target!r}, which is pending: {waiting.message}",
                )
            if target in self._ignored:
                return PendingEntry(
                    element,
                    PendingKind.WAITING,
                    f"{prop} points at {target!r} ({self._ignored[target].type}), "
                    "which the input manager does not configure",
                )
            return PendingEntry(
                element,
                PendingKind.MISSING_TARGET,
                f"{prop} points at {target!r}, which is not in the configuration",
                "fix the name or add the element it should point at",
            )
        return None

    def _configure_input_manager(
        self, element: ConfigElement, access: ElementAccess
    ) -> PendingEntry | None:
        base = Path(element.file).parent
        env = self.options.environ
        directories: dict[PluginSource, list[DriverDirectory]] = {}
        for prop, source in (
            ("driver_path", PluginSource.DRIVER_PATH),
            ("driver_scan_path", PluginSource.SCAN_PATH),
        ):
            for value in element.values(prop):
                if not value.stripped:
                    continue
                directory = directory_entry(
                    value.text, source, base=base, environ=env, location=value.location
                )
                loc = value.location
                for variable in directory.undefined:
                    self._static_diagnostics.append(
                        Diagnostic.make(
                            "CFG003",
                            f"{prop} {value.stripped!r} uses ${{{variable}}}, which is not set",
                            loc.path,
                            loc.line,
                            loc.column,
                        )
                    )
                if not directory.exists:
                    self._static_diagnostics.append(
                        Diagnostic.make(
                            "DRV010",
                            f"{prop} {value.stripped!r} is not a directory ({directory.path})",
                            loc.path,
                            loc.line,
                            loc.column,
                        )
                    )
                self.search.add_directory(directory)
                directories.setdefault(source, []).append(directory)
        for index, value in enumerate(element.values("driver")):
            name = access.string("driver", index)
            if not name:
                continue
            result = self.loader.load_name(name, self.search)
            self._note_load(result, value.location)
            if result.info is None:
                self._missing_drivers[name] = element.full_name
        for directory in directories.get(PluginSource.SCAN_PATH, []):
            for info in self.search.in_directory(directory):
                self._note_load(self.loader.load(info), None)
        self._input_managers[element.full_name] = element
        return None

    def _note_load(self, result: PluginLoadResult, location: Location | None) -> None:
        for diagnostic in result.diagnostics:
            if diagnostic.path is None and location is not None:
                diagnostic = Diagnostic.make(
                    diagnostic.code,
                    diagnostic.message,
                    location.path,
                    location.line,
                    location.column,
                    hint=diagnostic.hint,
                )
            if diagnostic not in self._static_diagnostics:
                self._static_diagnostics.append(diagnostic)

    def _configure_alias(
        self, element: ConfigElement, access: ElementAccess
    ) -> PendingEntry | None:
        name = element.full_name
        target = access.string("proxy")
        if not target:
            return PendingEntry(
                element, PendingKind.BAD_ALIAS, "its proxy property is empty: it points at no proxy"
            )
        if target == name:
            return PendingEntry(element, PendingKind.BAD_ALIAS, "points at itself")
        if target in self._proxies:
            self._aliases[name] = target
            self._alias_elements[name] = element
            return None
        self._waiters.setdefault(target, set()).add(name)
        if target in self._aliases:
            return PendingEntry(
                element,
                PendingKind.BAD_ALIAS,
                f"points at alias {target!r}; an alias must point at a proxy",
                f"point it at the proxy {self._aliases[target]!r}",
            )
        if target in self._devices:
            return PendingEntry(
                element,
                PendingKind.BAD_ALIAS,
                f"points at device {target!r}; an alias must point at a proxy",
            )
        unmet = self._unmet_dependency(element)
        if unmet is not None:
            return unmet
        return PendingEntry(
            element, PendingKind.BAD_ALIAS, f"points at {target!r}, which is not a proxy"
        )

    def _configure_proxy(
        self, element: ConfigElement, access: ElementAccess
    ) -> PendingEntry | None:
        name = element.full_name
        proxy_class = PROXY_CLASSES.get(element.type)
        if proxy_class is None:
            return PendingEntry(
                element, PendingKind.NO_DRIVER, f"gadgetctl has no proxy of type {element.type}"
            )
        unmet = self._unmet_dependency(element)
        if unmet is not None:
            return unmet
        proxy = proxy_class()
        try:
            proxy.config(access)
        except Exception as err:
            return PendingEntry(element, PendingKind.CONFIG_FAILED, _error_text(err))
        problem = proxy_unit_problem(element, self._known.get(proxy.device_name), self.repo)
        if problem is not None and problem not in proxy.diagnostics:
            proxy.diagnostics.append(problem)
        devices = self._device_objects
        device_name = proxy.device_name
        # (why a device is missing is asked only when it is: refresh() reads it then alone)
        proxy.refresh(devices, None if device_name in devices else self._why_missing(device_name))
        self._proxies[name] = proxy
        self._proxy_elements[name] = element
        names = self._proxies_of.get(proxy.device_name)
        if names is None:
            self._proxies_of[proxy.device_name] = (name,)
        elif type(names) is tuple:
            self._proxies_of[proxy.device_name] = {*names, name}
        else:
            names.add(name)
        self._frame_order = None
        return None

    def _why_missing(self, device: str) -> str | None:
        reason = self._pending_reason(device)
        if reason is not None:
            return f"it is pending: {reason}"
        if device and device not in self._known:
            return "no element of that name"
        return None

    def _registration(self, element: ConfigElement) -> Registration | PendingEntry:
        token = element.type
        registration = self.registry.get(token)
        if registration is not None:
            return registration
        providers = self.search.providers(token)
        if self.options.autoload_drivers:
            for info in providers:
                self._note_load(self.loader.load(info), None)
                registration = self.registry.get(token)
                if registration is not None:
                    return registration
        for result in self.loader.results.values():
            if (
                not result.ok
                and result.info is not None
                and token in result.info.metadata.element_types
            ):
                return PendingEntry(
                    element,
                    PendingKind.DRIVER_FAILED,
                    f"driver {result.name} provides {token} but failed to load: {result.reason}",
                )
        hints = []
        missing = sorted(self._missing_drivers)
        if missing:
            hints.append(
                f"input_manager names {'driver' if len(missing) == 1 else 'drivers'} {', '.join(missing)}, "
                "which were not found"
            )
        loaded = {r.name for r in self.loader.results.values()}
        for info in providers:
            if info.name not in loaded:
                hints.append(provider_hint(token, info))
        definition = self.repo.get(token)
        detail = (
            " (an abstract base type, which cannot be a device)"
            if definition is not None and definition.abstract
            else ""
        )
        return PendingEntry(
            element,
            PendingKind.NO_DRIVER,
            f"{no_driver_reason(token)}{detail}",
            "; ".join(hints) or None,
        )

    def _configure_device(
        self, element: ConfigElement, access: ElementAccess
    ) -> PendingEntry | None:
        name = element.full_name
        registration = self._registration(element)
        if isinstance(registration, PendingEntry):
            return registration
        unmet = self._unmet_dependency(element)
        if unmet is not None:
            return unmet
        device = registration.device_class()
        device.store.cap = self.options.sample_cap
        device.context = self._context
        try:
            device.config(access)
        except ElementVersionError as err:
            return PendingEntry(
                element,
                PendingKind.TOO_OLD,
                str(err),
                "upgrade the element with `gadgetctl upgrade`",
            )
        except Exception as err:
            return PendingEntry(element, PendingKind.CONFIG_FAILED, _error_text(err))
        runner: Runner | None = None
        if self.options.start_devices:
            runner = self._runner(device)
            if self._starts is not None:  # started with the others (_start_devices)
                self._starts.append((name, runner))
            else:
                try:
                    runner.start()
                except Exception as err:
                    device.state = DeviceState.STOPPED
                    return PendingEntry(
                        element,
                        PendingKind.START_FAILED,
                        f"the device failed to start: {describe(err)}",
                    )
        self._devices[name] = _DeviceEntry(element, device, runner)
        self._device_objects[name] = device
        self._frame_order = None
        names = self._proxies_of.get(name)
        if names:
            self._refresh_proxies(names)  # only its own: O(1), not O(proxies)
        return None

    def _runner(self, device: Input) -> Runner:
        policy = self.options.restart
        if device.SAMPLING is SamplingMode.SCHEDULED and device.samples_in_thread():
            return ScheduledRunner(device, policy, self._scheduler)
        if device.samples_in_thread():
            return ThreadRunner(device, policy)
        return FrameRunner(device, policy)

    def _refresh_proxies(self, names: Iterable[str] | None = None) -> None:
        """Rebind (or stupefy) the proxies called ``names``, or every proxy."""
        proxies = self._proxies
        devices = self._device_objects
        chosen = proxies.values() if names is None else (proxies[n] for n in names if n in proxies)
        for proxy in chosen:
            bound = proxy.device
            if bound is not None and devices.get(proxy.device_name) is bound:
                continue  # bound to its device still: refresh() would leave it as it is
            proxy.refresh(devices, self._why_missing(proxy.device_name))

    # -- removal ----------------------------------------------------------------------------

    def _remove(self, name: str) -> int:
        if self._ignored.pop(name, None) is not None:
            return 0
        if self._known.pop(name, None) is None:
            return 0
        self._generation += 1
        if self._pending.pop(name, None) is not None:
            return 1
        self._teardown(name)
        self._lost_dependencies()
        self._refresh_proxies()
        return 1

    def _teardown(self, name: str) -> None:
        entry = self._devices.pop(name, None)
        if entry is not None:
            self._device_objects.pop(name, None)
            self._frame_order = None
            self._stop(entry)
        proxy = self._proxies.pop(name, None)
        if proxy is not None:
            self._proxy_elements.pop(name, None)
            names = self._proxies_of.get(proxy.device_name)
            if type(names) is tuple:
                if name in names:
                    del self._proxies_of[proxy.device_name]
            elif names is not None:
                names.discard(name)
            self._frame_order = None
        if self._aliases.pop(name, None) is not None:
            self._alias_elements.pop(name, None)
        self._input_managers.pop(name, None)

    def _stop(self, entry: _DeviceEntry) -> None:
        if entry.runner is None:
            return
        problem = entry.runner.stop(self.options.stop_timeout)
        if problem:
            loc = entry.element.location
            self._static_diagnostics.append(
                Diagnostic.make(
                    "DRV041",
                    f"{entry.device.name}: stopping it: {problem}",
                    loc.path,
                    loc.line,
                    loc.column,
                )
            )

    def _lost_dependencies(self) -> None:
        """Elements pointing at something no longer active go back to pending."""
        changed = True
        while changed:
            changed = False
            for name, element in [
                *((n, e.element) for n, e in self._devices.items()),
                *self._alias_elements.items(),
            ]:
                unmet = self._unmet_dependency(element)
                if unmet is not None:
                    self._teardown(name)
                    self._pending[name] = unmet
                    changed = True

    # -- frames -----------------------------------------------------------------------------

    def update(self) -> int:
        """One frame: reconfigure, update every device, then every proxy that looks at every
        frame (:attr:`Proxy.EVERY_FRAME`; the others read their device when read). Returns
        the frame number."""
        interval = self.options.retry_interval
        if interval is not None and self._pending and now() - self._last_retry >= interval:
            self.retry_pending()
        else:
            self.reconfigure()
        self.frame += 1
        frame = self.frame
        order = self._frame_order
        if order is None:  # sorted once per change of what is configured, not every frame
            order = self.arrangement
        for device in order[0]:
            if type(device) is tuple:  # devices updated together (Input.FRAME_GROUP)
                device[0].update_frame_group(device[1], frame)
            else:
                device.update_for_frame(frame)
        for proxy in order[1]:
            proxy.update_for_frame(frame)
        return frame

    def prepare(self) -> None:
        """Work done ahead between frames, after a frame's consumers: what frame groups
        prepare for the coming frames (:meth:`Input.prepare_frame_group`)."""
        order = self._frame_order
        if order is not None:
            for device in order[0]:
                if type(device) is tuple:
                    device[0].prepare_frame_group(device[1])

    def run(
        self,
        rate: float = 60.0,
        *,
        frames: int | None = None,
        duration: float | None = None,
        on_frame: Callable[[InputManager], bool | None] | None = None,
        stop: threading.Event | None = None,
    ) -> int:
        """Run frames at ``rate`` Hz until ``frames`` or ``duration`` (seconds of wall clock,
        however many frames that is) is reached, ``stop`` is set or ``on_frame`` returns
        False. Ctrl-C shuts everything down and is re-raised."""
        if rate <= 0:
            raise ValueError("the frame rate must be positive")
        period = 1.0 / rate
        if self.options.freeze_gc:
            self._freeze_gc(collect=True)
        began = start = now()  # start is the pacing origin: it moves when frames fall behind
        count = 0
        try:
            while not (stop is not None and stop.is_set()):
                if frames is not None and count >= frames:
                    break
                if duration is not None and now() - began >= duration:
                    break
                configured = len(self._known)
                self.update()
                if self.options.freeze_gc and len(self._known) != configured:
                    self._freeze_gc(collect=False)
                count += 1
                if on_frame is not None and on_frame(self) is False:
                    break
                self.prepare()
                delay = start + count * period - now()
                if delay > 0:
                    if stop is not None:
                        stop.wait(delay)
                    else:
                        time.sleep(delay)
                elif delay < -period:  # fell behind: do not try to catch up
                    start = now() - count * period
        except KeyboardInterrupt:
            self.shutdown()
            raise
        finally:
            if self.options.freeze_gc:
                # Frozen objects are never collected: left frozen, this manager and its
                # devices, buffers and definitions (a cycle through _context) outlived it,
                # about 0.9 MB per run() of the waveform example.
                gc.unfreeze()
        return count

    @staticmethod
    def _freeze_gc(*, collect: bool) -> None:
        """Keep the long-lived objects (definitions, configuration, devices) out of the
        garbage collector's full collections while frames run, which would otherwise stall
        frames for tens of milliseconds once the heap is large; :meth:`run` unfreezes them
        when it returns."""
        if collect:
            gc.collect()
        gc.freeze()

    def hold_sampling(self) -> contextlib.AbstractContextManager[None]:
        """While the block runs, the shared scheduler steps no device (devices sampling in
        their own threads go on): for a caller done with the samples, e.g. a monitor
        reading its final statistics before :meth:`shutdown`."""
        return self._scheduler.hold()

    def shutdown(self) -> None:
        """Stop every device (sampling threads joined with the stop timeout)."""
        if self._shut_down:
            return
        self._shut_down = True
        with self._scheduler.hold():  # no scheduler pass over the devices being stopped
            for entry in list(self._devices.values()):
                self._stop(entry)
        self._scheduler.shutdown()

    # -- lookups ----------------------------------------------------------------------------

    @property
    def arrangement(self) -> object:
        """An object that is replaced whenever the devices or proxies updated each frame
        change (a consumer that planned per device knows its plan holds while it is the same)."""
        if self._frame_order is None:
            self._frame_order = (
                _frame_groups([self._device_objects[n] for n in sorted(self._device_objects)]),
                # the proxies that must look at every frame (the others read when read)
                [p for n in sorted(self._proxies) if (p := self._proxies[n]).EVERY_FRAME],
            )
        return self._frame_order

    @property
    def devices(self) -> Mapping[str, Input]:
        return MappingProxyType(self._device_objects)

    @property
    def proxies(self) -> Mapping[str, Proxy]:
        return MappingProxyType(self._proxies)

    @property
    def aliases(self) -> Mapping[str, str]:
        return MappingProxyType(self._aliases)

    def device(self, name: str) -> Input | None:
        return self._device_objects.get(name)

    def proxy(self, name: str) -> Proxy | None:
        """The proxy ``name``, or the proxy the alias ``name`` points at (one hop; a proxy
        wins over an alias of the same name)."""
        proxy = self._proxies.get(name)
        if proxy is None and name in self._aliases:
            proxy = self._proxies.get(self._aliases[name])
        return proxy

    def lookup(self, name: str) -> Input | Proxy | None:
        """Any name: a proxy, an alias (its proxy) or a device."""
        return self.proxy(name) or self._device_objects.get(name)

    def vrjuggler_difference(self, name: str) -> str | None:
        """Why VR Juggler would leave the element ``name`` pending although gadgetctl runs
        it (a documented difference, :data:`gadgetctl.jccl.activation.DIFFERENCES`, or an
        element waiting for one), or None."""
        if not self._active(name):
            return None
        fate = self._vrjuggler_fate()
        reason = fate.get(name)
        element = self._known.get(name)
        if reason is None or element is None:
            return None
        if element.type in DIFFERENCES:
            return DIFFERENCES[element.type].vrjuggler
        for _, target in pointer_targets(element, self.repo):
            if fate.get(target) is not None and target in self._known:
                return f"it waits for {self._known[target].type} {target!r}, which VR Juggler leaves pending"
        return reason

    def _vrjuggler_fate(self) -> dict[str, str | None]:
        """What VR Juggler's run time would do with the configuration (the rules of
        gadgetctl.jccl.activation), kept until the configuration changes."""
        generation, fate = self._fate
        if generation != self._generation:
            fate = {}
            if any(e.type in DIFFERENCES for e in self._known.values()):
                elements = {**self._ignored, **self._known}
                repo = self.repo
                nodes = []
                for name, e in elements.items():
                    definition = repo.get(e.type)
                    handled = definition is not None and not definition.abstract
                    nodes.append(
                        Node(
                            name,
                            e.type,
                            e.version,
                            tuple(t for _, t in pointer_targets(e, repo)),
                            None if handled else "no handler",
                        )
                    )
                fate = settle(nodes, RunTime.VRJUGGLER, repo.versions)
            self._fate = (self._generation, fate)
        return fate

    def pending(self) -> list[PendingEntry]:
        return list(self._pending.values())

    def element(self, name: str) -> ConfigElement | None:
        """The element an active or pending input element was configured from."""
        return self._known.get(name)

    def proxy_element(self, name: str) -> ConfigElement | None:
        return self._proxy_elements.get(name)

    @property
    def plugin_results(self) -> list[PluginLoadResult]:
        return list(self.loader.results.values())

    @property
    def diagnostics(self) -> list[Diagnostic]:
        """Driver loading, input_manager elements, and the active devices' and proxies' own."""
        found = list(self._static_diagnostics)
        for device in self._device_objects.values():
            found.extend(device.diagnostics)
        for proxy in self._proxies.values():
            found.extend(proxy.diagnostics)
        return found

    def status(self, name: str) -> ElementStatus | None:
        """The status of the device, proxy, alias, input manager or pending element called
        ``name`` (looked up, not searched for in :meth:`statuses`)."""
        entry = self._devices.get(name)
        if entry is not None:
            return self._device_status(name, entry)
        proxy = self._proxies.get(name)
        if proxy is not None:
            return self._proxy_status(name, proxy)
        target = self._aliases.get(name)
        if target is not None:
            return ElementStatus(name, ALIAS, ElementKind.ALIAS, ACTIVE, target=target)
        element = self._input_managers.get(name)
        if element is not None:
            return ElementStatus(name, element.type, ElementKind.INPUT_MANAGER, ACTIVE)
        pending = self._pending.get(name)
        return None if pending is None else self._pending_status(pending)

    def statuses(self) -> list[ElementStatus]:
        result: list[ElementStatus] = []
        for name, entry in self._devices.items():
            result.append(self._device_status(name, entry))
        for name, proxy in self._proxies.items():
            result.append(self._proxy_status(name, proxy))
        for name, target in self._aliases.items():
            result.append(ElementStatus(name, ALIAS, ElementKind.ALIAS, ACTIVE, target=target))
        for name, element in self._input_managers.items():
            result.append(ElementStatus(name, element.type, ElementKind.INPUT_MANAGER, ACTIVE))
        for pending in self._pending.values():
            result.append(self._pending_status(pending))
        if self._vrjuggler_fate():
            result = [
                replace(s, note=note) if (note := self.vrjuggler_difference(s.name)) else s
                for s in result
            ]
        return result

    @staticmethod
    def _device_status(name: str, entry: _DeviceEntry) -> ElementStatus:
        device = entry.device
        state, reason = device.shown_state()
        return ElementStatus(
            name,
            entry.element.type,
            ElementKind.DEVICE,
            state.value,
            reason,
            ("DRV045" if state is DeviceState.UNDECODABLE else "DRV042") if reason else None,
            device.stats,
        )

    @staticmethod
    def _proxy_status(name: str, proxy: Proxy) -> ElementStatus:
        return ElementStatus(
            name,
            proxy.element_type,
            ElementKind.PROXY,
            proxy.state.value,
            proxy.reason if proxy.stupefied else None,
            None,
            target=proxy.device_name,
        )

    def _pending_status(self, entry: PendingEntry) -> ElementStatus:
        kind = self._classify(entry.element)
        state = UNKNOWN_TYPE if entry.kind is PendingKind.NO_DEFINITION else PENDING
        return ElementStatus(
            entry.name,
            entry.type,
            kind if isinstance(kind, ElementKind) else None,
            state,
            entry.message,
            entry.code,
        )


def _error_text(err: Exception) -> str:
    return str(err) if isinstance(err, DeviceConfigError) else describe(err)


def _frame_groups(devices: list[Input]) -> list[Input | tuple[type[Input], list[Input]]]:
    """``devices`` (in name order) as update() runs them: each alone, except the devices of a
    class with :attr:`Input.FRAME_GROUP`, together at the place of the first of them."""
    order: list[Input | tuple[type[Input], list[Input]]] = []
    groups: dict[type[Input], list[Input]] = {}
    for device in devices:
        cls = type(device)
        if not cls.FRAME_GROUP:
            order.append(device)
        elif cls in groups:
            groups[cls].append(device)
        else:
            groups[cls] = [device]
            order.append((cls, groups[cls]))
    return order
