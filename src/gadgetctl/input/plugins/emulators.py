"""Device emulators shipped by driver plug-ins (``emulator.py`` in a plug-in package).

An emulator is found from files only and loaded by file path under a private module name
whose parent package is the plug-in's folder, so ``from .standalone import X`` works; the
plug-in's ``__init__.py`` (and so its ``register()``) never runs. Its ``main(argv) -> int``
is what `gadgetctl emulate` calls.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.machinery
import importlib.util
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from gadgetctl.input.plugins.discovery import DriverSearch, PluginInfo
from gadgetctl.suggest import close_names

EMULATOR_FILE = "emulator.py"
_MODULE_PREFIX = "_gadgetctl_emulator_"
_UNSAFE = re.compile(r"\W")
_SENTENCE = re.compile(r"(.+?[.!?])(?:\s|$)")
_MARKUP = re.compile(r"(?::\w+:)?`{1,2}([^`]+)`{1,2}")
_DEVELOPER_NOTE = re.compile(
    r",? (?:independent of gadgetctl's input manager )?\([^()]*\)(?=\.$)|, independent of gadgetctl's input manager(?=\.$)"
)


class EmulatorLookupError(LookupError):
    """DRIVER names no plug-in, or a plug-in without an emulator; the message says which."""


@dataclass(frozen=True)
class Emulator:
    """A plug-in's emulator, described from its files."""

    plugin: PluginInfo
    path: Path

    @property
    def summary(self) -> str:
        """The first sentence of the emulator's docstring, whole however many lines it takes
        (read without importing it), without reST markup and without a closing note on how
        the emulator is built (", independent of gadgetctl's input manager (...)")."""
        try:
            doc = ast.get_docstring(ast.parse(self.path.read_text(encoding="utf-8")))
        except (OSError, UnicodeDecodeError, SyntaxError, ValueError):
            return ""
        if not doc:
            return ""
        paragraph = " ".join(doc.strip().split("\n\n")[0].split())
        paragraph = _MARKUP.sub(r"\1", paragraph)  # ``x`` and :mod:`x` read as x
        sentence = _SENTENCE.match(paragraph)
        text = sentence.group(1) if sentence else paragraph
        # what only a developer needs (how the emulator is built) is left to --help
        return _DEVELOPER_NOTE.sub("", text)

    def to_dict(self) -> dict[str, object]:
        return {
            "plugin": self.plugin.name,
            "element_types": sorted(self.plugin.declared_types()[0]),
            "path": str(self.path),
            "source": self.plugin.source.value,
            "summary": self.summary,
        }


def emulator_of(info: PluginInfo) -> Emulator | None:
    """The emulator ``info`` ships, or None (module plug-ins have none)."""
    path = info.path / EMULATOR_FILE
    return Emulator(info, path) if info.package and path.is_file() else None


def emulators(search: DriverSearch) -> list[Emulator]:
    """Every emulator of a discoverable (not shadowed) plug-in, in search order."""
    found = (emulator_of(p) for p in search.plugins() if p.shadowed_by is None)
    return [e for e in found if e is not None]


def _names(info: PluginInfo) -> set[str]:
    names = {info.name.lower(), info.name.lower().removesuffix("_drv")}
    return names | {t.lower() for t in info.declared_types()[0]}


def find_emulator(name: str, search: DriverSearch) -> Emulator:
    """The emulator of the plug-in ``name`` names: its plug-in name (with or without
    ``_drv``) or one of its element types, case-insensitive. Raises EmulatorLookupError
    with close names when nothing matches, or when the plug-in ships no emulator."""
    wanted = name.lower()
    plugins = [p for p in search.plugins() if p.shadowed_by is None]
    for info in plugins:
        if wanted in _names(info):
            emulator = emulator_of(info)
            if emulator is None:
                available = ", ".join(e.plugin.name for e in emulators(search)) or "none"
                raise EmulatorLookupError(
                    f"driver plug-in {info.name} ({info.path}) ships no emulator "
                    f"({EMULATOR_FILE}); plug-ins with one: {available}"
                )
            return emulator
    candidates: dict[str, str] = {}
    for info in plugins:
        for known in sorted(_names(info)):
            candidates.setdefault(known, info.name)
    close = close_names(wanted, candidates)
    suggestion = sorted({candidates[c] for c in close})
    hint = f"; did you mean {' or '.join(suggestion)}?" if suggestion else ""
    raise EmulatorLookupError(
        f"no driver plug-in named {name!r} (looked in {search.describe_places()}){hint}"
    )


def module_name(emulator: Emulator) -> str:
    """The private package name under which the emulator's folder is imported."""
    digest = hashlib.sha1(str(emulator.path.resolve()).encode()).hexdigest()[:10]
    return f"{_MODULE_PREFIX}{_UNSAFE.sub('_', emulator.plugin.name)}_{digest}"


def load_emulator(emulator: Emulator) -> ModuleType:
    """Import ``emulator.py`` by path; raises whatever it raises. The plug-in's folder is an
    empty namespace-like package here, so its ``__init__.py`` is not executed."""
    package = module_name(emulator)
    name = f"{package}.emulator"
    if name in sys.modules:
        return sys.modules[name]
    folder = str(emulator.path.parent)
    if package not in sys.modules:
        spec = importlib.machinery.ModuleSpec(package, None, is_package=True)
        spec.submodule_search_locations = [folder]
        parent = importlib.util.module_from_spec(spec)
        parent.__path__ = [folder]
        sys.modules[package] = parent
    spec = importlib.util.spec_from_file_location(name, emulator.path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot import {emulator.path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        for loaded in [m for m in sys.modules if m == package or m.startswith(package + ".")]:
            del sys.modules[loaded]
        raise
    return module
