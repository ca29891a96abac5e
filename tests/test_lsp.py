"""`gadgetctl lsp` end to end: a real LSP client (pytest-lsp) talks to the server over
standard input/output. Corpus files are opened where they are (read only); files to edit
are written into tmp_path."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import pytest_lsp
from lsp_samples import DEVICES, HEAD, PROXIES, TRACKERS, configuration
from lsprotocol import types
from pytest_lsp import ClientServerConfig, LanguageClient

from gadgetctl.lsp.text import LineIndex
from gadgetctl.validate import validate_paths

from conftest import CORPUS_CONFIGS

pytestmark = [pytest.mark.asyncio(loop_scope="module"), pytest.mark.timeout(60)]

DTRACK = CORPUS_CONFIGS / "example.dtrack.jconf"
TIMEOUT = 20.0  # seconds a test waits for a notification


@pytest_lsp.fixture(
    config=ClientServerConfig(server_command=[sys.executable, "-m", "gadgetctl", "lsp"]),
    scope="module",
)
async def client(lsp_client: LanguageClient):
    await lsp_client.initialize_session(
        types.InitializeParams(capabilities=types.ClientCapabilities())
    )
    yield
    await lsp_client.shutdown_session()


def _uri(path: Path) -> str:
    return path.resolve().as_uri()


_versions: dict[str, int] = {}


def _open(client: LanguageClient, path: Path, text: str | None = None) -> str:
    uri = _uri(path)
    _versions[uri] = 1
    client.text_document_did_open(
        types.DidOpenTextDocumentParams(
            types.TextDocumentItem(
                uri=uri,
                language_id="xml",
                version=1,
                text=path.read_text() if text is None else text,
            )
        )
    )
    return uri


def _change(client: LanguageClient, uri: str, text: str) -> None:
    _versions[uri] += 1
    client.text_document_did_change(
        types.DidChangeTextDocumentParams(
            types.VersionedTextDocumentIdentifier(version=_versions[uri], uri=uri),
            [types.TextDocumentContentChangeWholeDocument(text=text)],
        )
    )


async def _checked(client: LanguageClient, path: Path, text: str = DEVICES) -> str:
    """Write ``text`` to ``path``, open it and wait for its first diagnostics: its URI."""
    path.write_text(text)
    uri = _open(client, path)
    await _diagnostics(client, uri)
    return uri


async def _diagnostics(client: LanguageClient, uri: str, until=lambda found: True):
    """The diagnostics published for ``uri`` once ``until`` holds for them."""
    import asyncio

    async def wait():
        while True:
            await client.wait_for_notification(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
            found = client.diagnostics.get(uri)
            if found is not None and until(found):
                return found

    found = client.diagnostics.get(uri)
    if found is not None and until(found):
        return found
    return await asyncio.wait_for(wait(), TIMEOUT)


def _position(text: str, needle: str, after: int = 0) -> types.Position:
    offset = text.index(needle) + after
    return types.Position(*LineIndex(text).position(offset))


def _apply(text: str, edits: list[types.TextEdit]) -> str:
    index = LineIndex(text)
    spans = sorted(
        (
            index.offset(e.range.start.line, e.range.start.character),
            index.offset(e.range.end.line, e.range.end.character),
            e.new_text,
        )
        for e in edits
    )
    for start, end, new in reversed(spans):
        text = text[:start] + new + text[end:]
    return text


async def test_opening_the_dtrack_example_publishes_what_validate_finds(client):
    uri = _open(client, DTRACK)
    published = await _diagnostics(client, uri)
    expected = [
        d
        for d in validate_paths([DTRACK]).diagnostics
        if Path(d.path).resolve() == DTRACK.resolve()
    ]
    assert expected, "the example has findings to compare"
    assert sorted((d.code, d.range.start.line + 1, d.message) for d in published) == sorted(
        (d.code, d.line, d.message) for d in expected
    )
    command_port = next(d for d in published if d.code == "CFG025")
    assert command_port.severity is types.DiagnosticSeverity.Error
    related = [r.message for r in command_port.related_information]
    assert any("gadgetctl explain CFG025" in m for m in related)
    assert any(m.startswith("hint: Remove the tag") for m in related)


async def test_a_misspelled_property_is_found_and_its_quick_fix_repairs_it(client, tmp_path):
    # Typed as an editor sends it: ranged edits, after characters that take two UTF-16
    # units on the same line (positions count UTF-16 units).
    text = DEVICES.replace("<receive_port>", "<!-- Ü𝄞 --><receive_port>")
    uri = await _checked(client, tmp_path / "typo.jconf", text)
    typo = text.replace("receive_port", "recieve_port", 2)
    index = LineIndex(text)
    _versions[uri] += 1
    client.text_document_did_change(
        types.DidChangeTextDocumentParams(
            text_document=types.VersionedTextDocumentIdentifier(version=_versions[uri], uri=uri),
            content_changes=[
                types.TextDocumentContentChangePartial(
                    range=types.Range(
                        types.Position(*index.position(at)), types.Position(*index.position(at + 7))
                    ),
                    text="recieve",
                )
                for at in (text.index("receive_port"), text.index("/receive_port") + 1)
            ],
        )
    )
    published = await _diagnostics(client, uri, lambda f: any(d.code == "CFG020" for d in f))
    finding = next(d for d in published if d.code == "CFG020")
    assert "recieve_port" in finding.message
    assert finding.range.start == _position(typo, "<recieve_port>")
    actions = await client.text_document_code_action_async(
        types.CodeActionParams(
            types.TextDocumentIdentifier(uri),
            finding.range,
            types.CodeActionContext([finding]),
        )
    )
    fix = next(a for a in actions if a.is_preferred)
    assert fix.title == "Did you mean receive_port?"
    repaired = _apply(typo, fix.edit.changes[uri])
    assert repaired == text
    _change(client, uri, repaired)
    await _diagnostics(client, uri, lambda f: not any(d.code == "CFG020" for d in f))


async def test_completion_in_a_position_proxy_device_lists_only_positional_devices(
    client, tmp_path
):
    uri = await _checked(client, tmp_path / "devices.jconf")
    answer = await client.text_document_completion_async(
        types.CompletionParams(
            types.TextDocumentIdentifier(uri),
            _position(DEVICES, "<device>Tracker", len("<device>")),
        )
    )
    labels = {item.label for item in answer.items}
    assert labels == {"Tracker"}  # not the analog Sliders, nor the keyboard


async def test_hover_on_device_units_shows_the_labels_and_the_value_read(client, tmp_path):
    uri = await _checked(client, tmp_path / "units.jconf")
    answer = await client.text_document_hover_async(
        types.HoverParams(types.TextDocumentIdentifier(uri), _position(DEVICES, "device_units", 3))
    )
    shown = answer.contents.value
    assert "Meters = 1.0" in shown and "Feet = 0.3048" in shown
    assert "VR Juggler reads: '0.3048' (Feet)" in shown


async def test_renaming_an_element_updates_pointers_in_an_included_file(client, tmp_path):
    main = tmp_path / "main.jconf"
    proxies = tmp_path / "proxies.jconf"
    main_text = configuration(TRACKERS, before="   <include>proxies.jconf</include>\n")
    proxies_text = configuration(PROXIES)
    main.write_text(main_text)
    proxies.write_text(proxies_text)
    uri = _open(client, main)
    await _diagnostics(client, uri)
    edit = await client.text_document_rename_async(
        types.RenameParams(
            types.TextDocumentIdentifier(uri), _position(main_text, 'name="Tracker"', 7), "Dtrack1"
        )
    )
    assert set(edit.changes) == {uri, _uri(proxies)}
    assert 'name="Dtrack1"' in _apply(main_text, edit.changes[uri])
    assert "<device>Dtrack1</device>" in _apply(proxies_text, edit.changes[_uri(proxies)])

    # go to definition follows the include
    found = await client.text_document_definition_async(
        types.DefinitionParams(
            types.TextDocumentIdentifier(uri), _position(main_text, "proxies.jconf", 2)
        )
    )
    assert found.uri == _uri(proxies)


async def test_an_open_included_file_refreshes_who_includes_it(client, tmp_path):
    main = tmp_path / "top.jconf"
    devices = tmp_path / "devs.jconf"
    main.write_text(
        HEAD
        + """   <include>devs.jconf</include>
   <elements>
      <position_proxy name="Head" version="1">
         <device>Tracker</device>
         <unit>0</unit>
      </position_proxy>
   </elements>
</configuration>
"""
    )
    devices.write_text(DEVICES.replace("Head", "Other"))
    main_uri = _open(client, main)
    dev_uri = _open(client, devices)
    await _diagnostics(client, main_uri, lambda f: not any(d.code == "CFG031" for d in f))
    _change(client, dev_uri, devices.read_text().replace('name="Tracker"', 'name="Gone"'))
    found = await _diagnostics(client, main_uri, lambda f: any(d.code == "CFG031" for d in f))
    assert any("Tracker" in d.message for d in found)


@pytest.mark.parametrize(
    "text",
    [
        HEAD + '   <elements>\n      <position_proxy name="P" version="1">\n         <dev',
        "<configuration><elements><a></b></elements>",
        "\x00\xff<<<>>>&&&",
        "",
    ],
)
async def test_hostile_documents_never_end_the_server(client, tmp_path, text):
    path = tmp_path / "hostile.jconf"
    path.write_text("")
    uri = _open(client, path, text)
    await _diagnostics(client, uri)
    for offset in range(0, len(text) + 1, max(1, len(text) // 7)):
        position = types.Position(*LineIndex(text).position(offset))
        ident = types.TextDocumentIdentifier(uri)
        await client.text_document_completion_async(types.CompletionParams(ident, position))
        await client.text_document_hover_async(types.HoverParams(ident, position))
        await client.text_document_definition_async(types.DefinitionParams(ident, position))
    symbols = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(types.TextDocumentIdentifier(uri))
    )
    assert symbols is not None


async def test_a_16_mb_document_is_a_finding_and_the_server_answers_next(client, tmp_path):
    path = tmp_path / "huge.jconf"
    path.write_text("")
    big = (
        HEAD
        + "<elements>"
        + "<!-- padding -->\n" * (17 * 1024 * 1024 // 17)
        + "</elements></configuration>"
    )
    uri = _open(client, path, big)
    found = await _diagnostics(client, uri)
    assert [d.code for d in found] == ["XML004"]
    other = tmp_path / "after.jconf"
    other.write_text(DEVICES)
    after = _open(client, other)
    await _diagnostics(client, after)
    answer = await client.text_document_hover_async(
        types.HoverParams(
            types.TextDocumentIdentifier(after), _position(DEVICES, "device_units", 3)
        )
    )
    assert answer is not None


async def test_an_include_changed_on_disk_refreshes_who_includes_it(client, tmp_path):
    main = tmp_path / "top.jconf"
    devices = tmp_path / "devs.jconf"
    devices.write_text(DEVICES.replace("Head", "Other"))
    text = configuration(PROXIES, before="   <include>devs.jconf</include>\n")
    main_uri = await _checked(client, main, text)
    assert not any(d.code == "CFG031" for d in client.diagnostics[main_uri])
    devices.write_text(DEVICES.replace("Head", "Other").replace('name="Tracker"', 'name="Gone"'))
    client.workspace_did_change_watched_files(
        types.DidChangeWatchedFilesParams(
            [types.FileEvent(uri=_uri(devices), type=types.FileChangeType.Changed)]
        )
    )
    found = await _diagnostics(client, main_uri, lambda f: any(d.code == "CFG031" for d in f))
    assert any("Tracker" in d.message for d in found)


registrations: list[types.RegistrationParams] = []


@pytest_lsp.fixture(
    config=ClientServerConfig(server_command=[sys.executable, "-m", "gadgetctl", "lsp"]),
    scope="module",
)
async def watching(lsp_client: LanguageClient):
    @lsp_client.feature(types.CLIENT_REGISTER_CAPABILITY)
    def on_register(params: types.RegistrationParams) -> None:
        registrations.append(params)

    capabilities = types.ClientCapabilities(
        workspace=types.WorkspaceClientCapabilities(
            did_change_watched_files=types.DidChangeWatchedFilesClientCapabilities(
                dynamic_registration=True
            )
        )
    )
    await lsp_client.initialize_session(types.InitializeParams(capabilities=capabilities))
    yield
    await lsp_client.shutdown_session()


async def test_a_client_that_can_watch_files_is_asked_to_watch_jccl_files(watching):
    import asyncio

    async def registered():
        while not registrations:
            await asyncio.sleep(0.01)

    await asyncio.wait_for(registered(), TIMEOUT)
    (registration,) = registrations[0].registrations
    assert registration.method == types.WORKSPACE_DID_CHANGE_WATCHED_FILES
    patterns = {w["globPattern"] for w in registration.register_options["watchers"]}
    assert patterns == {"**/*.jconf", "**/*.jdef"}
