"""What the language server knows about the open documents, with no protocol in sight.

:class:`Engine` keeps the editor's texts by real path. A check of one document is
``validate_paths([path])`` run inside :func:`unsaved_texts` over every open text, so the
findings are exactly those of ``gadgetctl validate PATH`` on what the editor shows
(includes and definitions that are open read from their buffers too). The search path's
definitions are read once and kept until a .jdef changes. Completion, hover and navigation
use a :class:`Model`: the document's configuration as the loader the checks use reads it,
with the type index of the repository it is judged by.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.errors import GadgetctlError
from gadgetctl.jccl.configuration import ConfigElement, Configuration
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.typeindex import TypeIndex
from gadgetctl.jccl.xmlload import DEFAULT_MAX_SIZE, XmlDocument, unsaved_texts

JCCL_SUFFIXES = (".jconf", ".jdef")
#: Seconds the driver plug-in searches are kept (plug-ins installed meanwhile are seen after).
DRIVER_SEARCH_LIFETIME = 30.0
#: Open documents kept at most; a client opening more is told the newest ones are not checked.
MAX_OPEN_DOCUMENTS = 4096


def real(path: str | os.PathLike[str]) -> Path:
    return Path(os.path.realpath(path))


@dataclass
class Model:
    """One document's configuration (with its includes) and the definitions it is judged by."""

    path: Path
    text: str
    configuration: Configuration | None
    index: TypeIndex
    documents: dict[Path, XmlDocument] = field(default_factory=dict)
    environ: Mapping[str, str] = field(default_factory=lambda: os.environ)

    @property
    def repo(self) -> DefinitionRepository:
        return self.index.repo

    def files(self) -> list[Path]:
        """The document and every file its configuration loaded."""
        if self.configuration is None:
            return [self.path]
        return [f.path for f in self.configuration.files] or [self.path]

    def text_of(self, path: Path) -> str | None:
        doc = self.documents.get(path)
        return doc.text if doc is not None else None


@dataclass
class EngineOptions:
    definition_dirs: list[Path] = field(default_factory=list)
    bundled: bool = True
    environ: Mapping[str, str] | None = None
    max_size: int = DEFAULT_MAX_SIZE


class Engine:
    def __init__(self, options: EngineOptions | None = None) -> None:
        self.options = options or EngineOptions()
        self.texts: dict[Path, str] = {}
        self._base: DefinitionRepository | None = None
        self._lock = threading.RLock()
        self._models: dict[Path, tuple[tuple, Model]] = {}
        self._good: dict[Path, Model] = {}  # the last model whose document parsed
        self._generation = 0  # counts changes of the open texts (models of older ones are stale)
        #: The files each open document's configuration loaded at its last check.
        self.reaches: dict[Path, set[Path]] = {}
        self._changed: dict[Path, int] = {}  # the generation of each document's last change
        self._searches: dict = {}  # driver plug-in searches (validate's driver_searches)
        self._searches_at = time.monotonic()

    # -- documents ----------------------------------------------------------------------

    def set_text(self, path: Path, text: str) -> bool | None:
        """Open or change a document. True when what the checks read changed (a document
        opened as it is on disk changes nothing for the others), False when not, None when
        too many documents are open (it is then not kept)."""
        key = real(path)
        with self._lock:
            previous = self.texts.get(key)
            if previous is None and len(self.texts) >= MAX_OPEN_DOCUMENTS:
                return None
            self.texts[key] = text
            self._generation += 1
        changed = previous != text if previous is not None else _on_disk(key) != text
        if changed:
            with self._lock:
                self._changed[key] = self._generation
        if changed and key.suffix == ".jdef":
            with self._lock:
                self._base = None  # a definition may be on the search path
        return changed

    def close(self, path: Path) -> bool:
        """Forget a document; True when its text differed from the file (the checks of
        others then read something else from now on)."""
        key = real(path)
        with self._lock:
            text = self.texts.pop(key, None)
            self._generation += 1
            self._changed[key] = self._generation
            if len(self._changed) > 2 * MAX_OPEN_DOCUMENTS:  # (closed long ago: forgotten)
                self._changed = {p: g for p, g in self._changed.items() if p in self.texts}
            self.reaches.pop(key, None)
            self._models.pop(key, None)
            self._good.pop(key, None)
        changed = text is not None and _on_disk(key) != text
        if changed and key.suffix == ".jdef":
            with self._lock:
                self._base = None
        return changed

    def saved(self, path: Path) -> None:
        """A file was written (saved from the editor, or changed on disk by another program):
        what was read of it is stale."""
        key = real(path)
        with self._lock:
            self._searches = {}  # (a saved file may be a plug-in's: look again)
            self._generation += 1
            self._changed[key] = self._generation
            if key.suffix == ".jdef":
                self._base = None

    @property
    def generation(self) -> int:
        return self._generation

    def changed_since(self, generation: int, paths: set[Path]) -> bool:
        """Whether one of ``paths`` changed after ``generation``."""
        with self._lock:
            return any(self._changed.get(p, -1) > generation for p in paths)

    def affected(self, path: Path, changed: bool = True) -> list[Path]:
        """The open documents whose findings a change of ``path`` can change: itself and,
        when what the checks read ``changed``, every open configuration that loaded it (for
        a definition: every open document)."""
        key = real(path)
        with self._lock:
            if not changed:
                return [key] if key in self.texts else []
            if key.suffix == ".jdef":
                return list(self.texts)
            found = [key] if key in self.texts else []
            found += [p for p, reach in self.reaches.items() if key in reach and p != key]
            return found

    # -- definitions --------------------------------------------------------------------

    def base(self) -> DefinitionRepository:
        """The search path's definitions (open .jdef buffers read as the editor shows them)."""
        with self._lock:
            if self._base is None:
                from gadgetctl.jccl.repository import default_repository

                with unsaved_texts(self.texts):
                    self._base = default_repository(
                        self.options.definition_dirs, bundled=self.options.bundled
                    )
            return self._base

    # -- findings -----------------------------------------------------------------------

    def diagnose(self, path: Path) -> list[Diagnostic]:
        """``gadgetctl validate PATH``'s findings located in PATH, for the editor's texts."""
        from gadgetctl.validate import ValidateOptions, validate_paths

        key = real(path)
        with self._lock:
            texts = dict(self.texts)
        base = self.base()
        with self._lock:
            if time.monotonic() - self._searches_at > DRIVER_SEARCH_LIFETIME:
                self._searches, self._searches_at = {}, time.monotonic()
            searches = self._searches
        options = ValidateOptions(
            max_size=self.options.max_size,
            definition_dirs=list(self.options.definition_dirs),
            bundled=self.options.bundled,
            environ=self.options.environ,
            repository=base,
            driver_searches=searches,
        )
        try:
            with unsaved_texts(texts):
                result = validate_paths([key], options)
        except GadgetctlError:
            return []  # (a buffer whose file does not exist: validate has nothing to say)
        return [d for d in result.diagnostics if d.path is not None and _same(d.path, key)]

    # -- the model ----------------------------------------------------------------------

    def model(self, path: Path) -> Model:
        """The document's configuration as the checks load it, cached until a text changes."""

        key = real(path)
        with self._lock:
            texts = dict(self.texts)
            stamp = (self._generation, self._base is not None)
            cached = self._models.get(key)
            if cached is not None and cached[0] == stamp:
                return cached[1]
        from gadgetctl.perf import collector_paused

        with collector_paused():
            return self._model(key, texts, stamp)

    def _model(self, key: Path, texts: dict[Path, str], stamp: tuple) -> Model:
        from gadgetctl.jccl.configcheck import Session
        from gadgetctl.validate import plugin_definition_finder

        base = self.base()
        session = Session(
            base,
            os.environ if self.options.environ is None else self.options.environ,
            plugin_definitions=plugin_definition_finder(self.options.environ),
        )
        configuration = None
        with unsaved_texts(texts):
            if key.suffix == ".jconf":
                configuration = session.load([key])
                repo, _ = session.repository(configuration)
            else:
                repo = base
        index = session.checker(repo).index
        text = texts.get(key)
        if text is None:
            doc = session.documents.get(key)
            text = doc.text if doc is not None else ""
        model = Model(key, text, configuration, index, dict(session.documents), session.environ)
        with self._lock:
            self._models[key] = (stamp, model)
            if configuration is not None:
                self.reaches[key] = {f.path for f in configuration.files}
                doc = session.documents.get(key)
                if doc is not None and doc.root is not None:
                    self._good[key] = model
        return model

    def recent_model(self, path: Path) -> Model:
        """The newest model there is, even if the text changed since (completion reads the
        position from the current text and only the definitions and the element names from
        the model, which one edit rarely changes): no check's worth of waiting per keystroke.
        The current model when there is none, or when the last one did not parse."""
        key = real(path)
        with self._lock:
            good = self._good.get(key)
        return good if good is not None else self.good_model(key)

    def good_model(self, path: Path) -> Model:
        """The current model, or while the document does not parse (being typed), the last
        one that did (its elements and pointer targets are what completion can offer)."""
        model = self.model(path)
        doc = model.documents.get(model.path)
        if doc is not None and doc.root is None:
            return self._good.get(model.path, model)
        return model


def _on_disk(path: Path) -> str | None:
    """The file's text as a check would read it from disk (None when unreadable)."""
    from gadgetctl.boundedread import read_limited

    try:
        return read_limited(path, DEFAULT_MAX_SIZE).decode("utf-8")
    except (OSError, UnicodeDecodeError):
        return None


_REAL: dict[str, Path] = {}


def _same(shown: str, key: Path) -> bool:
    """Whether a diagnostic's path (as validate shows it: as given, or relative to the
    working directory for includes) names ``key``."""
    found = _REAL.get(shown)
    if found is None:
        found = real(shown)
        if len(_REAL) < 65536:
            _REAL[shown] = found
    return found == key


def elements_of(model: Model, path: Path) -> list[ConfigElement]:
    """Every element read from ``path`` (overridden ones too), embedded ones after their
    holder, in document order."""
    configuration = model.configuration
    if configuration is None:
        return []
    found: list[ConfigElement] = []
    for config_file in configuration.files:
        if config_file.path == path:
            for element in config_file.elements:
                found.append(element)
                found.extend(element.embedded())
    return found


def element_at_line(model: Model, line: int, type_name: str) -> ConfigElement | None:
    """The element of the model's document whose start tag (of ``type_name``) is on ``line``
    (1-based)."""
    for element in elements_of(model, model.path):
        if element.type == type_name and element.location.line == line:
            return element
    return None
