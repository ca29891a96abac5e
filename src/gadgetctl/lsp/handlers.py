"""The request handlers: protocol objects in, feature modules' plain answers out."""

from __future__ import annotations

import logging
from collections.abc import Callable
from functools import wraps
from pathlib import Path

from lsprotocol import types

from gadgetctl.jccl.xmlload import load_file
from gadgetctl.lsp import actions as fixes
from gadgetctl.lsp import completion, hover, navigation
from gadgetctl.lsp.uris import is_jccl as _jccl
from gadgetctl.lsp.uris import path_of as _path

log = logging.getLogger("gadgetctl.lsp")


def guarded(handler: Callable) -> Callable:
    """A handler that fails answers nothing (and says so in the client's log) instead of
    ending the server."""

    @wraps(handler)
    def run(ls, params):
        try:
            return handler(ls, params)
        except Exception as err:
            log.exception("%s failed", handler.__name__)
            ls.window_log_message(
                types.LogMessageParams(
                    types.MessageType.Error, f"gadgetctl lsp: {handler.__name__} failed: {err!r}"
                )
            )
            return None

    return run


def _document(ls, uri: str, *, recent: bool = False):
    """(path, text, model) of an open JCCL document, or None. ``recent``: the newest model
    there is will do (see :meth:`Engine.recent_model`)."""
    path = _path(uri)
    if not _jccl(path) or path not in ls.engine.texts:
        return None
    text = ls.engine.texts[path]
    model = ls.engine.recent_model(path) if recent else ls.engine.good_model(path)
    return path, text, model


def _offset(ls, text: str, position: types.Position) -> int:
    return ls.lines(text).offset(position.line, position.character)


def _text_of(ls, model, path: Path) -> str | None:
    if path in ls.engine.texts:
        return ls.engine.texts[path]
    text = model.text_of(path)
    if text is None:
        doc = load_file(path)
        text = doc.text
    return text


def _location(ls, model, spot) -> types.Location | None:
    if isinstance(spot, navigation.Target):
        text = _text_of(ls, model, spot.path) or ""
        index = ls.lines(text)
        start = index.at_line_column(spot.line, spot.column)
        return types.Location(ls.uri_of(spot.path), ls.range_of(index, start, start))
    text = _text_of(ls, model, spot.path)
    if text is None:
        return None
    return types.Location(ls.uri_of(spot.path), ls.range_of(ls.lines(text), spot.start, spot.end))


def register(server) -> None:
    @server.feature(
        types.TEXT_DOCUMENT_COMPLETION,
        types.CompletionOptions(trigger_characters=["<", '"', ">"]),
    )
    @guarded
    def complete(ls, params: types.CompletionParams):
        found = _document(ls, params.text_document.uri, recent=True)
        if found is None:
            return None
        _path, text, model = found
        offset = _offset(ls, text, params.position)
        answer = completion.complete(model, text, offset)
        index = ls.lines(text)
        replace = ls.range_of(index, answer.start, offset)
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
        return types.CompletionList(is_incomplete=False, items=items)

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    @guarded
    def on_hover(ls, params: types.HoverParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        path, text, model = found
        offset = _offset(ls, text, params.position)
        shown = hover.hover(model, text, offset, ls.findings.get(path, []))
        if shown is None:
            return None
        return types.Hover(types.MarkupContent(types.MarkupKind.Markdown, shown))

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    @guarded
    def go_to(ls, params: types.DefinitionParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        _path, text, model = found
        spot = navigation.definition(model, text, _offset(ls, text, params.position))
        return _location(ls, model, spot) if spot is not None else None

    @server.feature(types.TEXT_DOCUMENT_REFERENCES)
    @guarded
    def refs(ls, params: types.ReferenceParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        _path, text, model = found
        spots = navigation.references(
            model, text, _offset(ls, text, params.position), params.context.include_declaration
        )
        return [loc for loc in (_location(ls, model, s) for s in spots) if loc is not None]

    @server.feature(types.TEXT_DOCUMENT_PREPARE_RENAME)
    @guarded
    def prepare_rename(ls, params: types.PrepareRenameParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        _path, text, model = found
        spot = navigation.rename_range(model, text, _offset(ls, text, params.position))
        if spot is None:
            return None
        return types.PrepareRenamePlaceholder(
            ls.range_of(ls.lines(text), spot[0], spot[1]), spot[2]
        )

    @server.feature(types.TEXT_DOCUMENT_RENAME)
    @guarded
    def do_rename(ls, params: types.RenameParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        _path, text, model = found
        edits = navigation.rename(model, text, _offset(ls, text, params.position), params.new_name)
        if edits is None:
            return None
        changes = {}
        for file, spots in edits.items():
            file_text = _text_of(ls, model, file) or ""
            index = ls.lines(file_text)
            changes[ls.uri_of(file)] = [
                types.TextEdit(ls.range_of(index, s.start, s.end), _escape(params.new_name))
                for s in spots
            ]
        return types.WorkspaceEdit(changes=changes)

    @server.feature(types.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    @guarded
    def outline(ls, params: types.DocumentSymbolParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        _path, text, _model = found
        index = ls.lines(text)

        def convert(symbol, kind):
            return types.DocumentSymbol(
                name=symbol.name,
                detail=symbol.detail,
                kind=kind,
                range=ls.range_of(index, symbol.start, symbol.end),
                selection_range=ls.range_of(index, symbol.select_start, symbol.select_end),
                children=[convert(c, types.SymbolKind.Object) for c in symbol.children],
            )

        return [convert(s, types.SymbolKind.Class) for s in navigation.symbols(text)]

    @server.feature(types.TEXT_DOCUMENT_FOLDING_RANGE)
    @guarded
    def folds(ls, params: types.FoldingRangeParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        return [
            types.FoldingRange(start_line=first, end_line=last)
            for first, last in navigation.folding(found[1])
        ]

    @server.feature(
        types.TEXT_DOCUMENT_CODE_ACTION,
        types.CodeActionOptions(code_action_kinds=[types.CodeActionKind.QuickFix]),
    )
    @guarded
    def code_actions(ls, params: types.CodeActionParams):
        found = _document(ls, params.text_document.uri)
        if found is None:
            return None
        path, text, model = found
        index = ls.lines(text)
        problems, by_code = [], {}
        for diagnostic in params.context.diagnostics:
            if diagnostic.source != "gadgetctl" or not isinstance(diagnostic.code, str):
                continue
            start = index.offset(diagnostic.range.start.line, diagnostic.range.start.character)
            end = index.offset(diagnostic.range.end.line, diagnostic.range.end.character)
            problems.append(fixes.Problem(diagnostic.code, start, end))
            by_code.setdefault(diagnostic.code, diagnostic)
        answer = []
        for action in fixes.actions(model, text, problems):
            changes = {}
            for file, edits in action.edits.items():
                file_index = index if file == path else ls.lines(_text_of(ls, model, file) or "")
                changes[ls.uri_of(file)] = [
                    types.TextEdit(ls.range_of(file_index, a, b), new) for a, b, new in edits
                ]
            answer.append(
                types.CodeAction(
                    title=action.title,
                    kind=types.CodeActionKind.QuickFix,
                    diagnostics=[by_code[action.code]] if action.code in by_code else None,
                    is_preferred=action.preferred or None,
                    edit=types.WorkspaceEdit(changes=changes),
                )
            )
        return answer


def _escape(name: str) -> str:
    return name.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")
