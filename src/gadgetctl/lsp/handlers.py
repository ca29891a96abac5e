"""The request handlers: protocol objects in, feature modules' plain answers out."""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from functools import wraps
from pathlib import Path

from lsprotocol import types

from gadgetctl.jccl.xmlload import load_file
from gadgetctl.lsp import actions as fixes
from gadgetctl.lsp import completion, hover, navigation
from gadgetctl.lsp.analysis import Model
from gadgetctl.lsp.text import LineIndex
from gadgetctl.lsp.uris import is_jccl, path_of

log = logging.getLogger("gadgetctl.lsp")


@dataclass
class Document:
    """An open JCCL document a request is about."""

    path: Path
    text: str
    index: LineIndex
    model: Model | None

    def offset(self, position: types.Position) -> int:
        return self.index.offset(position.line, position.character)


def on_document(model: str | None = "current") -> Callable:
    """A handler of a request about an open JCCL document, called as
    ``handler(ls, params, document)``; ``model``: "current" (the text as it is now),
    "recent" (the newest there is, see :meth:`Engine.recent_model`) or None (the text is
    enough). A request about another document answers nothing; a handler that fails
    answers nothing (and says so in the client's log) instead of ending the server."""

    def wrap(handler: Callable) -> Callable:
        @wraps(handler)
        def run(ls, params):
            try:
                path = path_of(params.text_document.uri)
                if not is_jccl(path) or path not in ls.engine.texts:
                    return None
                text = ls.engine.texts[path]
                found = None
                if model == "recent":
                    found = ls.engine.recent_model(path)
                elif model == "current":
                    found = ls.engine.good_model(path)
                return handler(ls, params, Document(path, text, ls.lines(text), found))
            except Exception as err:
                log.exception("%s failed", handler.__name__)
                ls.window_log_message(
                    types.LogMessageParams(
                        types.MessageType.Error,
                        f"gadgetctl lsp: {handler.__name__} failed: {err!r}",
                    )
                )
                return None

        return run

    return wrap


def _text_of(ls, model: Model, path: Path) -> str:
    """A file's text: the editor's, the one the model read, or the file's."""
    if path in ls.engine.texts:
        return ls.engine.texts[path]
    text = model.text_of(path)
    return text if text is not None else load_file(path).text


def _location(ls, model: Model, spot) -> types.Location:
    index = ls.lines(_text_of(ls, model, spot.path))
    if isinstance(spot, navigation.Target):
        start = end = index.at_line_column(spot.line, spot.column)
    else:
        start, end = spot.start, spot.end
    return types.Location(ls.uri_of(spot.path), ls.range_of(index, start, end))


def _workspace_edit(ls, model: Model, edits: dict[Path, list[tuple[int, int, str]]]):
    changes = {}
    for path, replacements in edits.items():
        index = ls.lines(_text_of(ls, model, path))
        changes[ls.uri_of(path)] = [
            types.TextEdit(ls.range_of(index, start, end), new) for start, end, new in replacements
        ]
    return types.WorkspaceEdit(changes=changes)


def register(server) -> None:
    @server.feature(
        types.TEXT_DOCUMENT_COMPLETION,
        types.CompletionOptions(trigger_characters=["<", '"', ">"]),
    )
    @on_document("recent")
    def complete(ls, params: types.CompletionParams, doc: Document):
        offset = doc.offset(params.position)
        answer = completion.complete(doc.model, doc.text, offset)
        replace = ls.range_of(doc.index, answer.start, offset)
        items = [
            types.CompletionItem(
                label=item.label,
                kind=types.CompletionItemKind(item.kind),
                detail=item.detail,
                documentation=item.documentation,
                sort_text=item.sort,
                text_edit=types.TextEdit(replace, item.label),
            )
            for item in answer.items
        ]
        return types.CompletionList(is_incomplete=not answer.complete, items=items)

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    @on_document()
    def on_hover(ls, params: types.HoverParams, doc: Document):
        findings = ls.findings.get(doc.path, [])
        shown = hover.hover(doc.model, doc.text, doc.offset(params.position), findings)
        if shown is None:
            return None
        return types.Hover(types.MarkupContent(types.MarkupKind.Markdown, shown))

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    @on_document()
    def go_to(ls, params: types.DefinitionParams, doc: Document):
        spot = navigation.definition(doc.model, doc.text, doc.offset(params.position))
        return _location(ls, doc.model, spot) if spot is not None else None

    @server.feature(types.TEXT_DOCUMENT_REFERENCES)
    @on_document()
    def refs(ls, params: types.ReferenceParams, doc: Document):
        offset = doc.offset(params.position)
        declaration = params.context.include_declaration
        spots = navigation.references(doc.model, doc.text, offset, declaration)
        return [_location(ls, doc.model, spot) for spot in spots]

    @server.feature(types.TEXT_DOCUMENT_PREPARE_RENAME)
    @on_document()
    def prepare_rename(ls, params: types.PrepareRenameParams, doc: Document):
        spot = navigation.rename_range(doc.model, doc.text, doc.offset(params.position))
        if spot is None:
            return None
        start, end, name = spot
        return types.PrepareRenamePlaceholder(ls.range_of(doc.index, start, end), name)

    @server.feature(types.TEXT_DOCUMENT_RENAME)
    @on_document()
    def do_rename(ls, params: types.RenameParams, doc: Document):
        offset = doc.offset(params.position)
        spots = navigation.rename(doc.model, doc.text, offset, params.new_name)
        if spots is None:
            return None
        new = _escape(params.new_name)
        edits = {path: [(s.start, s.end, new) for s in found] for path, found in spots.items()}
        return _workspace_edit(ls, doc.model, edits)

    @server.feature(types.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    @on_document(None)
    def outline(ls, params: types.DocumentSymbolParams, doc: Document):
        def convert(symbol, kind):
            return types.DocumentSymbol(
                name=symbol.name,
                detail=symbol.detail,
                kind=kind,
                range=ls.range_of(doc.index, symbol.start, symbol.end),
                selection_range=ls.range_of(doc.index, symbol.select_start, symbol.select_end),
                children=[convert(c, types.SymbolKind.Object) for c in symbol.children],
            )

        return [convert(s, types.SymbolKind.Class) for s in navigation.symbols(doc.text)]

    @server.feature(types.TEXT_DOCUMENT_FOLDING_RANGE)
    @on_document(None)
    def folds(ls, params: types.FoldingRangeParams, doc: Document):
        return [
            types.FoldingRange(start_line=first, end_line=last)
            for first, last in navigation.folding(doc.text)
        ]

    @server.feature(
        types.TEXT_DOCUMENT_CODE_ACTION,
        types.CodeActionOptions(code_action_kinds=[types.CodeActionKind.QuickFix]),
    )
    @on_document()
    def code_actions(ls, params: types.CodeActionParams, doc: Document):
        problems, by_code = [], {}
        for diagnostic in params.context.diagnostics:
            if diagnostic.source != "gadgetctl" or not isinstance(diagnostic.code, str):
                continue
            start, end = doc.offset(diagnostic.range.start), doc.offset(diagnostic.range.end)
            problems.append(fixes.Problem(diagnostic.code, start, end))
            by_code.setdefault(diagnostic.code, diagnostic)
        return [
            types.CodeAction(
                title=action.title,
                kind=types.CodeActionKind.QuickFix,
                diagnostics=[by_code[action.code]] if action.code in by_code else None,
                is_preferred=action.preferred or None,
                edit=_workspace_edit(ls, doc.model, action.edits),
            )
            for action in fixes.actions(doc.model, doc.text, problems)
        ]


def _escape(name: str) -> str:
    return name.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")
