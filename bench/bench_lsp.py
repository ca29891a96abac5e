"""Issue 29 benchmark: the language server keeps up with typing.

A real LSP client (pygls) starts `gadgetctl lsp` over standard input/output and measures:

* diagnostics for a 300-element configuration, from the edit (didChange sent) to the
  diagnostics published for it (the 30 ms debounce included): target 100 ms (median);
* completion of a pointer in that configuration, request to answer: target 30 ms (median);
* the whole VR Juggler corpus (every .jconf and .jdef) open in one session, each checked:
  the server's peak resident memory, target 200 MB.

Baselines of the same run: a bare lxml parse of the same text (the least any check does)
and the server's memory after start-up with nothing open; ratios are printed against them.

    python bench/bench_lsp.py [--repeat N]
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
import time
from pathlib import Path

from common import CORPUS, Report

DIAGNOSTICS_MS = 100.0
COMPLETION_MS = 30.0
MEMORY_MB = 200.0
WAIT = 60.0  # seconds any one answer may take before the benchmark gives up

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
   <elements>
"""


def configuration(elements: int = 300) -> str:
    """``elements`` elements: trackers, and position, digital and analog proxies on them."""
    parts = [HEAD]
    trackers = max(1, elements // 10)
    for t in range(trackers):
        parts.append(
            f'      <dtrack name="Tracker {t}" version="1">\n'
            f"         <receive_port>{5000 + t}</receive_port>\n"
            "      </dtrack>\n"
        )
    kinds = ("position_proxy", "digital_proxy", "analog_proxy")
    for i in range(elements - trackers):
        kind = kinds[i % 3]
        parts.append(
            f'      <{kind} name="Proxy {i}" version="1">\n'
            f"         <device>Tracker {i % trackers}</device>\n"
            f"         <unit>{i % 4}</unit>\n"
            f"      </{kind}>\n"
        )
    parts.append("   </elements>\n</configuration>\n")
    return "".join(parts)


def rss_mb(pid: int, field: str = "VmHWM") -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")


class Bench:
    def __init__(self) -> None:
        from lsprotocol import types
        from pygls.lsp.client import LanguageClient

        self.types = types
        self.client = LanguageClient("bench", "1")
        self.published: asyncio.Queue = asyncio.Queue()
        self.versions: dict[str, int] = {}

        @self.client.feature(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def on_diagnostics(params) -> None:
            self.published.put_nowait((time.perf_counter(), params))

    async def start(self) -> None:
        types = self.types
        await self.client.start_io(sys.executable, "-m", "gadgetctl", "lsp")
        await self.client.initialize_async(
            types.InitializeParams(capabilities=types.ClientCapabilities())
        )
        self.client.initialized(types.InitializedParams())

    @property
    def pid(self) -> int:
        return self.client._server.pid

    async def stop(self) -> None:
        await self.client.shutdown_async(None)
        self.client.exit(None)
        await self.client.stop()

    def open(self, path: Path, text: str) -> str:
        types = self.types
        uri = path.resolve().as_uri()
        self.versions[uri] = 1
        self.client.text_document_did_open(
            types.DidOpenTextDocumentParams(
                types.TextDocumentItem(uri=uri, language_id="xml", version=1, text=text)
            )
        )
        return uri

    def change(self, uri: str, text: str) -> None:
        types = self.types
        self.versions[uri] += 1
        self.client.text_document_did_change(
            types.DidChangeTextDocumentParams(
                text_document=types.VersionedTextDocumentIdentifier(
                    version=self.versions[uri], uri=uri
                ),
                content_changes=[types.TextDocumentContentChangeWholeDocument(text=text)],
            )
        )

    async def published_for(self, uri: str) -> float:
        """The time the next diagnostics for ``uri`` arrive."""
        while True:
            at, params = await asyncio.wait_for(self.published.get(), WAIT)
            if params.uri == uri:
                return at

    async def complete(self, uri: str, line: int, character: int) -> list:
        types = self.types
        answer = await asyncio.wait_for(
            self.client.text_document_completion_async(
                types.CompletionParams(
                    types.TextDocumentIdentifier(uri), types.Position(line, character)
                )
            ),
            WAIT,
        )
        return answer.items


def lxml_parse_ms(text: str, repeat: int) -> float:
    from lxml import etree

    data = text.encode()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        etree.fromstring(data)
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1000


async def run(repeat: int, report: Report) -> None:
    text = configuration(300)
    parse_ms = lxml_parse_ms(text, max(repeat, 7))
    bench = Bench()
    await bench.start()
    try:
        idle_mb = rss_mb(bench.pid, "VmRSS")
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "bench.jconf"
            path.write_text(text)
            uri = bench.open(path, text)
            await bench.published_for(uri)
            needle = "<unit>7</unit>"
            edits = []
            for i in range(repeat):
                edited = text.replace(needle, f"<unit>{'x' if i % 2 == 0 else 7}</unit>", 1)
                start = time.perf_counter()
                bench.change(uri, edited)
                edits.append((await bench.published_for(uri)) - start)
            bench.change(uri, text)
            await bench.published_for(uri)

            lines = text.splitlines()
            line = next(i for i, s in enumerate(lines) if "<device>Tracker 5</device>" in s)
            character = lines[line].index("Tracker 5")
            completions = []
            for _ in range(repeat):
                start = time.perf_counter()
                items = await bench.complete(uri, line, character)
                completions.append(time.perf_counter() - start)
            print("  completion times (ms):", " ".join(f"{c * 1000:.1f}" for c in completions))
            if not any(item.label == "Tracker 5" for item in items):
                sys.exit("completion did not offer the trackers")

        edit_ms = statistics.median(edits) * 1000
        completion_ms = statistics.median(completions) * 1000
        print("300-element configuration:")
        report.figure("bare lxml parse of the text (baseline)", parse_ms, "ms")
        report.figure("edit -> diagnostics published", edit_ms, "ms", target=DIAGNOSTICS_MS)
        report.ratio("  against the bare parse", edit_ms, parse_ms)
        report.figure("completion of a pointer", completion_ms, "ms", target=COMPLETION_MS)
        report.ratio("  against the bare parse", completion_ms, parse_ms)

        if "--no-corpus" in sys.argv:
            return
        files = sorted(p for p in CORPUS.rglob("*") if p.suffix in (".jconf", ".jdef"))
        waiting = {}
        start = time.perf_counter()
        for file in files:
            uri = bench.open(file, file.read_text(encoding="utf-8", errors="replace"))
            waiting[uri] = file
        while waiting:
            try:
                _, params = await asyncio.wait_for(bench.published.get(), WAIT)
            except TimeoutError:
                sys.exit(f"no diagnostics within {WAIT:g} s for {sorted(waiting.values())[:5]}")
            waiting.pop(params.uri, None)
        elapsed = time.perf_counter() - start
        peak = rss_mb(bench.pid)
        print(f"the whole corpus open ({len(files)} files):")
        report.figure("server memory after start-up (baseline)", idle_mb, "MB")
        report.figure("every file opened and checked", elapsed, "s")
        report.figure("server peak memory", peak, "MB", target=MEMORY_MB)
        report.ratio("  against start-up", peak, idle_mb)
    finally:
        await bench.stop()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--no-corpus", action="store_true")
    args = parser.parse_args()
    report = Report()
    asyncio.run(run(args.repeat, report))
    report.exit()


if __name__ == "__main__":
    main()
