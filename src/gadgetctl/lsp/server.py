"""The language server on pygls: the protocol's side of :mod:`gadgetctl.lsp`.

Documents are checked in one worker thread, ``DEBOUNCE`` seconds after the last edit of
each (a burst of keystrokes is one check); a change re-checks the document and the open
configurations that loaded it, nothing else. Requests (completion, hover, navigation,
code actions) are answered on the protocol's thread from the cached model. A handler that
fails answers nothing (logged to the client), and the next request is served as usual.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from lsprotocol import types
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path

from gadgetctl.lsp.analysis import JCCL_SUFFIXES, Engine, EngineOptions
from gadgetctl.lsp.findings import SEVERITIES, findings
from gadgetctl.lsp.framing import BoundedStdinReader, BoundedStreamReader, FramingError
from gadgetctl.lsp.text import LineIndex
from gadgetctl.lsp.uris import is_jccl as _jccl
from gadgetctl.lsp.uris import path_of as _path

DEBOUNCE = 0.03  # seconds of quiet after an edit before the document is checked
NAME = "gadgetctl"
log = logging.getLogger("gadgetctl.lsp")


class JcclServer(LanguageServer):
    def __init__(self, options: EngineOptions | None = None) -> None:
        from gadgetctl import __version__

        super().__init__(NAME, __version__)
        self.engine = Engine(options)
        self.uris: dict[Path, str] = {}  # open documents' URIs as the client spells them
        self.findings: dict[Path, list] = {}  # the last findings published for each document
        self._pending: dict[Path, asyncio.TimerHandle] = {}
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="gadgetctl-check")

    # -- positions ----------------------------------------------------------------------

    @property
    def utf16(self) -> bool:
        return self.workspace.position_encoding != types.PositionEncodingKind.Utf32

    def lines(self, text: str) -> LineIndex:
        return LineIndex(text, utf16=self.utf16)

    def range_of(self, index: LineIndex, start: int, end: int) -> types.Range:
        a, b = index.position(start), index.position(end)
        return types.Range(types.Position(*a), types.Position(*b))

    def uri_of(self, path: Path) -> str:
        return self.uris.get(path) or from_fs_path(str(path)) or path.as_uri()

    # -- checking -----------------------------------------------------------------------

    def schedule(self, paths: list[Path], delay: float = DEBOUNCE) -> None:
        loop = asyncio.get_running_loop()
        for path in paths:
            handle = self._pending.pop(path, None)
            if handle is not None:
                handle.cancel()
            self._pending[path] = loop.call_later(
                delay, lambda p=path: asyncio.ensure_future(self.check(p))
            )

    async def check(self, path: Path) -> None:
        self._pending.pop(path, None)
        if path not in self.engine.texts:
            return
        loop = asyncio.get_running_loop()
        generation = self.engine.generation
        try:
            diagnostics = await loop.run_in_executor(self._worker, self.engine.diagnose, path)
        except Exception as err:  # never the server's end: say it, publish nothing new
            log.exception("checking %s failed", path)
            self.window_log_message(
                types.LogMessageParams(types.MessageType.Error, f"checking {path} failed: {err!r}")
            )
            return
        text = self.engine.texts.get(path)
        if text is None or path in self._pending:
            return  # closed, or changed again: a newer check comes
        self.findings[path] = diagnostics
        self.publish(path, text, diagnostics)
        if path.suffix == ".jconf":  # ready for completion, and what it loads (for refreshes)
            try:
                model = await loop.run_in_executor(self._worker, self.engine.model, path)
            except Exception:
                log.exception("reading the configuration of %s failed", path)
                return
            # A file it includes changed while it was checked, before this check knew it
            # includes that file (so the change did not ask for this check): check again.
            others = set(model.files()) - {path}
            if path not in self._pending and self.engine.changed_since(generation, others):
                self.schedule([path])

    def publish(self, path: Path, text: str, diagnostics) -> None:
        index = self.lines(text)
        uri = self.uri_of(path)
        shown = []
        for finding in findings(diagnostics, index):
            d = finding.diagnostic
            where = types.Location(uri, self.range_of(index, finding.start, finding.end))
            related = []
            if d.hint:
                related.append(types.DiagnosticRelatedInformation(where, f"hint: {d.hint}"))
            related.append(types.DiagnosticRelatedInformation(where, finding.described))
            shown.append(
                types.Diagnostic(
                    range=where.range,
                    message=d.message,
                    severity=types.DiagnosticSeverity(SEVERITIES[d.severity]),
                    code=d.code,
                    source=NAME,
                    related_information=related,
                    data={"hint": d.hint, "explain": finding.explain},
                )
            )
        self.text_document_publish_diagnostics(
            types.PublishDiagnosticsParams(uri=uri, diagnostics=shown)
        )


def create_server(options: EngineOptions | None = None) -> JcclServer:
    server = JcclServer(options)

    @server.feature(types.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: JcclServer, params: types.DidOpenTextDocumentParams) -> None:
        path = _path(params.text_document.uri)
        if not _jccl(path):
            return
        ls.uris[path] = params.text_document.uri
        changed = ls.engine.set_text(path, params.text_document.text)
        if changed is None:
            ls.window_log_message(
                types.LogMessageParams(
                    types.MessageType.Warning, f"too many open documents; {path} is not checked"
                )
            )
            return
        ls.schedule(ls.engine.affected(path, changed), delay=0)

    @server.feature(types.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: JcclServer, params: types.DidChangeTextDocumentParams) -> None:
        path = _path(params.text_document.uri)
        if not _jccl(path) or path not in ls.engine.texts:
            return
        document = ls.workspace.get_text_document(params.text_document.uri)
        changed = ls.engine.set_text(path, document.source)
        ls.schedule(ls.engine.affected(path, bool(changed)))

    @server.feature(types.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: JcclServer, params: types.DidSaveTextDocumentParams) -> None:
        path = _path(params.text_document.uri)
        if not _jccl(path):
            return
        ls.engine.saved(path)
        ls.schedule(ls.engine.affected(path))

    @server.feature(types.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: JcclServer, params: types.DidCloseTextDocumentParams) -> None:
        path = _path(params.text_document.uri)
        if not _jccl(path):
            return
        others = [p for p in ls.engine.affected(path) if p != path]
        changed = ls.engine.close(path)
        handle = ls._pending.pop(path, None)
        if handle is not None:
            handle.cancel()
        ls.text_document_publish_diagnostics(
            types.PublishDiagnosticsParams(uri=params.text_document.uri, diagnostics=[])
        )
        ls.uris.pop(path, None)
        ls.findings.pop(path, None)
        if changed:
            ls.schedule(others)  # who included it now reads the file on disk

    @server.feature(types.INITIALIZED)
    def initialized(ls: JcclServer, params: types.InitializedParams) -> None:
        """Ask a client that can to say when .jconf and .jdef files change on disk (an
        include changed by another program, a checkout)."""
        workspace = ls.client_capabilities.workspace
        watched = workspace.did_change_watched_files if workspace else None
        if watched is None or not watched.dynamic_registration:
            return
        watchers = [types.FileSystemWatcher(glob_pattern=f"**/*{s}") for s in JCCL_SUFFIXES]
        ls.client_register_capability(
            types.RegistrationParams(
                [
                    types.Registration(
                        id="gadgetctl-jccl-files",
                        method=types.WORKSPACE_DID_CHANGE_WATCHED_FILES,
                        register_options=types.DidChangeWatchedFilesRegistrationOptions(watchers),
                    )
                ]
            )
        )

    @server.feature(types.WORKSPACE_DID_CHANGE_WATCHED_FILES)
    def files_changed(ls: JcclServer, params: types.DidChangeWatchedFilesParams) -> None:
        """A file changed on disk: the open documents that read it are checked again (an
        open one is read from its buffer, which the editor reports itself)."""
        affected: set[Path] = set()
        for change in params.changes:
            path = _path(change.uri)
            if not _jccl(path) or path in ls.engine.texts:
                continue
            ls.engine.saved(path)
            affected.update(ls.engine.affected(path))
        ls.schedule(sorted(affected))

    from gadgetctl.lsp import handlers

    handlers.register(server)
    return server


def serve(*, tcp_port: int | None = None, options: EngineOptions | None = None) -> None:
    """Run the server on standard input/output, or for one client of ``tcp_port``; a client
    whose messages break the framing limits (:mod:`gadgetctl.lsp.framing`) ends the session
    with :class:`~gadgetctl.lsp.framing.FramingError`."""
    server = create_server(options)
    with logged_in_one_line():
        if tcp_port is None:
            serve_stdio(server)
        else:
            serve_tcp(server, tcp_port)


def serve_stdio(server: JcclServer) -> None:
    """pygls's ``start_io``, reading through :class:`BoundedStdinReader`."""
    import sys
    from threading import Event

    from pygls.io_ import StdoutWriter, run_async

    server._stop_event = Event()
    server.protocol.set_writer(StdoutWriter(sys.stdout.buffer))
    reader = BoundedStdinReader(sys.stdin.buffer, server.thread_pool)
    try:
        asyncio.run(
            run_async(
                stop_event=server._stop_event,
                reader=reader,
                protocol=server.protocol,
                logger=log,
                error_handler=server.report_server_error,
            )
        )
    except BrokenPipeError:
        log.error("the client has gone (its end of standard output is closed)")
    except KeyboardInterrupt:
        pass
    finally:
        server.shutdown()


def serve_tcp(server: JcclServer, port: int) -> None:
    """Serve one client on 127.0.0.1:``port`` (0: a port the OS picks), saying on standard
    error which port; the server ends when that client's session does (as pygls's own
    ``start_tcp``, which cannot say an OS-picked port)."""
    import socket
    import sys
    from threading import Event

    from pygls.io_ import run_async

    listener = socket.create_server(("127.0.0.1", port))
    shown = listener.getsockname()[1]
    print(f"gadgetctl lsp: listening on 127.0.0.1:{shown}", file=sys.stderr, flush=True)
    server._stop_event = stop = Event()
    broken: list[FramingError] = []

    async def connection(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        server.protocol.set_writer(writer)
        try:
            await run_async(
                stop_event=stop,
                reader=BoundedStreamReader(reader),
                protocol=server.protocol,
                logger=log,
                error_handler=server.report_server_error,
            )
        except FramingError as error:
            broken.append(error)
        finally:
            server.shutdown()

    async def listen() -> None:
        server._server = await asyncio.start_server(connection, sock=listener)
        async with server._server:
            await server._server.serve_forever()

    try:
        asyncio.run(listen())
    except asyncio.CancelledError:
        pass
    if broken:
        raise broken[0]


class _OneLine(logging.Formatter):
    """``gadgetctl lsp: LEVEL: message (Error: what)``: what the server logs (pygls's
    messages it could not handle, a handler that failed) without a traceback, unless
    ``GADGETCTL_DEBUG`` is set."""

    def format(self, record: logging.LogRecord) -> str:
        import os

        text = f"gadgetctl lsp: {record.levelname.lower()}: {record.getMessage()}"
        if record.exc_info and record.exc_info[1] is not None:
            if os.environ.get("GADGETCTL_DEBUG"):
                return f"{text}\n{self.formatException(record.exc_info)}"
            error = record.exc_info[1]
            text += f" ({type(error).__name__}: {error})"
        return " ".join(text.split())


@contextmanager
def logged_in_one_line() -> Iterator[None]:
    """Warnings and errors of the server's loggers on standard error, one line each."""
    import sys

    handler = logging.StreamHandler(sys.stderr)
    handler.setLevel(logging.WARNING)
    handler.setFormatter(_OneLine())
    root = logging.getLogger()
    root.addHandler(handler)
    try:
        yield
    finally:
        root.removeHandler(handler)
