"""Loading a plug-in: version check, import, ``register(registry)``, checks.

Loading a plug-in:

1. refuses a plug-in whose ``GADGETCTL_API_VERSION`` is not this gadgetctl's (read from
   the source; imported only when it is not a literal), naming both versions;
2. adds the plug-in's own ``.jdef`` files to the definition repository;
3. imports it under a private module name (``spec_from_file_location``; packages get
   their folder as search location, so relative imports inside work, and two plug-ins
   with the same module names never meet in ``sys.modules``);
4. calls ``register(registry)``; registrations are held back until
5. each registered element type has a definition and the class's device types agree with
   the definition's ancestors; only then are they added to the device registry.

Every failure is a :class:`PluginLoadResult` with DRV diagnostics; nothing raises, so
other plug-ins still load.
"""

from __future__ import annotations

import importlib
import importlib.util
import re
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.input.errors import PluginError, RegistrationError, describe
from gadgetctl.input.plugins import PLUGIN_API_VERSION
from gadgetctl.input.plugins.discovery import DriverSearch, PluginInfo
from gadgetctl.input.plugins.metadata import API_VERSION, REGISTER
from gadgetctl.input.plugins.trust import writable_by_others, writable_places_accepted
from gadgetctl.input.registry import (
    DeviceRegistry,
    Registration,
    kind_disagreements,
    registration_for,
)
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.searchpath import SearchPathEntry

_MODULE_PREFIX = "_gadgetctl_plugin_"
_UNSAFE = re.compile(r"\W")


@dataclass
class PluginLoadResult:
    name: str
    info: PluginInfo | None
    registrations: list[Registration] = field(default_factory=list)
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not any(d.severity is Severity.ERROR for d in self.diagnostics)

    reason: str | None = None  # why it failed, without the plug-in's name

    @property
    def error(self) -> str | None:
        """The first error diagnostic's message."""
        for d in self.diagnostics:
            if d.severity is Severity.ERROR:
                return d.message
        return None

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "ok": self.ok,
            "path": None if self.info is None else str(self.info.path),
            "source": None if self.info is None else self.info.source.value,
            "registered": [
                {
                    "element_type": r.element_type,
                    "class": r.class_name,
                    "device_types": [k.value for k in r.kinds],
                }
                for r in self.registrations
            ],
            "error": self.reason if self.reason is not None else self.error,
            "diagnostics": [d.to_dict() for d in self.diagnostics],
        }


class PluginRegistrar:
    """What a plug-in's ``register(registry)`` receives: it collects device classes."""

    def __init__(self, plugin: str) -> None:
        self.plugin = plugin
        self.staged: list[Registration] = []

    def register_device(self, device_class: type, element_type: str | None = None) -> None:
        """Register ``device_class`` for ``element_type`` (default: its ``ELEMENT_TYPE``)."""
        self.staged.append(registration_for(device_class, element_type, self.plugin))


def module_name(info: PluginInfo) -> str:
    """The private ``sys.modules`` name a plug-in loaded from a path gets."""
    import hashlib  # (here: OpenSSL's library is 3.6 MB more of every run that loads none)

    digest = hashlib.sha1(str(info.path.resolve()).encode()).hexdigest()[:10]
    safe = _UNSAFE.sub("_", info.name)
    return f"{_MODULE_PREFIX}{safe}_{digest}"


def import_plugin(info: PluginInfo) -> ModuleType:
    """Import the plug-in's code; raises whatever the plug-in raises."""
    if info.module is not None:
        return importlib.import_module(info.module)
    name = module_name(info)
    if name in sys.modules:
        return sys.modules[name]
    if info.package:
        spec = importlib.util.spec_from_file_location(
            name, info.path / "__init__.py", submodule_search_locations=[str(info.path)]
        )
    else:
        spec = importlib.util.spec_from_file_location(name, info.path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot import {info.path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        for loaded in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
            del sys.modules[loaded]
        raise
    return module


def _where(error: BaseException, info: PluginInfo) -> tuple[str, int | None]:
    """The plug-in file and line an exception was raised from (the innermost inside it)."""
    root = info.path.resolve()
    path, line = str(info.source_file), None
    for frame in traceback.extract_tb(error.__traceback__):
        try:
            inside = Path(frame.filename).resolve().is_relative_to(root)
        except (OSError, ValueError):
            inside = False
        if inside:
            path, line = frame.filename, frame.lineno
    if isinstance(error, SyntaxError) and error.filename:
        path, line = error.filename, error.lineno
    return path, line


class PluginLoader:
    """Loads plug-ins into a device registry, checking them against a repository."""

    def __init__(self, registry: DeviceRegistry, repo: DefinitionRepository) -> None:
        self.registry = registry
        self.repo = repo
        self.results: dict[Path, PluginLoadResult] = {}

    def load_name(self, name: str, search: DriverSearch) -> PluginLoadResult:
        info = search.find(name)
        if info is None:
            from gadgetctl.suggest import did_you_mean

            close = did_you_mean(name, [p.name for p in search.plugins()])
            return PluginLoadResult(
                name,
                None,
                reason="not found",
                diagnostics=[
                    Diagnostic.make(
                        "DRV001",
                        f"driver plug-in {name!r} not found (looked in {search.describe_places()})",
                        hint=close[0].upper() + close[1:]
                        if close
                        else "write the plug-in's module or package name, without platform extension or _d suffix",
                    )
                ],
            )
        return self.load(info)

    def load(self, info: PluginInfo) -> PluginLoadResult:
        """Load ``info`` once; loading it again returns the first result."""
        key = info.path.resolve() if info.module is None else Path(f"<entry point {info.module}>")
        if key not in self.results:
            result = PluginLoadResult(info.name, info)
            try:
                self._load(info, result)
            except PluginError as err:
                path, line = (
                    (str(info.source_file), None)
                    if err.__cause__ is None
                    else _where(err.__cause__, info)
                )
                result.reason = str(err)
                result.diagnostics.append(
                    Diagnostic.make(err.code, f"{info.name}: {err}", path, line)
                )
            self.results[key] = result
        return self.results[key]

    # -- steps ----------------------------------------------------------------------------

    def _load(self, info: PluginInfo, result: PluginLoadResult) -> None:
        meta = info.metadata
        if meta.api_version is not None:
            self._check_version(meta.api_version)
        self._add_definitions(info)
        open_place = writable_by_others(info)
        if open_place is not None and not writable_places_accepted():
            raise PluginError(
                "DRV011",
                f"not imported: {open_place} can be written by other users "
                "(give --trust-driver-path to accept it)",
            )
        try:
            module = import_plugin(info)
        except (Exception, SystemExit) as err:
            raise PluginError("DRV003", f"import failed: {describe(err)}") from err
        if meta.api_version is None:
            version = getattr(module, API_VERSION, None)
            if not isinstance(version, int):
                raise PluginError(
                    "DRV007", f"declares no {API_VERSION} (the plug-in API it was written for)"
                )
            self._check_version(version)
        register = getattr(module, REGISTER, None)
        if not callable(register):
            raise PluginError("DRV004", f"has no {REGISTER}(registry) function")
        registrar = PluginRegistrar(info.name)
        try:
            register(registrar)
        except RegistrationError as err:
            raise PluginError("DRV004", f"{REGISTER}() failed: {err}") from err
        except (Exception, SystemExit) as err:
            raise PluginError("DRV004", f"{REGISTER}() failed: {describe(err)}") from err
        if not registrar.staged:
            raise PluginError("DRV004", f"{REGISTER}() registered no device class")
        self._check(info, registrar.staged, result)
        if not result.ok:
            result.reason = (result.error or "").removeprefix(f"{info.name}: ")
        else:
            for registration in registrar.staged:
                existing = self.registry.get(registration.element_type)
                if existing is not None and existing.device_class is not registration.device_class:
                    result.diagnostics.append(
                        Diagnostic.make(
                            "DRV009",
                            f"{info.name}: {registration.element_type} is already handled by "
                            f"{existing.class_name} ({existing.plugin}); that one stays",
                            str(info.source_file),
                        )
                    )
                    continue
                result.registrations.append(self.registry.add(registration))

    @staticmethod
    def _check_version(version: int) -> None:
        if version != PLUGIN_API_VERSION:
            raise PluginError(
                "DRV002",
                f"written for plug-in API version {version}, but this gadgetctl "
                f"provides version {PLUGIN_API_VERSION}",
            )

    def _add_definitions(self, info: PluginInfo) -> None:
        directory = info.definition_dir
        if directory is not None and all(e.path != directory for e in self.repo.entries):
            self.repo.load_entry(
                SearchPathEntry(raw=str(directory), path=directory, origin=f"driver {info.name}")
            )

    def _check(
        self, info: PluginInfo, staged: list[Registration], result: PluginLoadResult
    ) -> None:
        path = str(info.source_file)
        declared = info.metadata.element_types
        for registration in staged:
            token, kinds = registration.element_type, registration.kinds
            where = f"{info.name}: {registration.device_class.__name__} for {token}"
            if token not in self.repo:
                result.diagnostics.append(
                    Diagnostic.make(
                        "DRV005",
                        f"{where}: no definition of {token} on the definition search path",
                        path,
                        hint="ship a .jdef for it in the plug-in's folder, or fix ELEMENT_TYPE",
                    )
                )
                continue
            for problem in kind_disagreements(token, kinds, self.repo):
                result.diagnostics.append(Diagnostic.make("DRV006", f"{where}: {problem}", path))
            if declared and token not in declared:
                result.diagnostics.append(
                    Diagnostic.make(
                        "DRV008", f"{where}: ELEMENT_TYPES does not declare {token}", path
                    )
                )
            elif declared and set(declared[token]) != set(kinds):
                result.diagnostics.append(
                    Diagnostic.make(
                        "DRV008",
                        f"{where}: ELEMENT_TYPES declares {', '.join(declared[token]) or 'no device types'} "
                        f"but the class provides {', '.join(kinds) or 'none'}",
                        path,
                    )
                )
        registered = {r.element_type for r in staged}
        for token in declared:
            if token not in registered:
                result.diagnostics.append(
                    Diagnostic.make(
                        "DRV008",
                        f"{info.name}: ELEMENT_TYPES declares {token} but register() does not register it",
                        path,
                    )
                )
