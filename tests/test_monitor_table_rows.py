"""`monitor --format table` on a terminal prints the rows its height leaves room for, and
works out only those (issue 27: 3,000 rows no terminal could show took a quarter of a run);
a pipe or a file gets every row."""

from __future__ import annotations

import io
import os

import pytest

from gadgetctl.cli.monitor_text import TABLE_CHROME, TableView
from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor.session import MonitorSession

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n<elements>\n'
)
DEVICES = 30


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def session(tmp_path):
    path = tmp_path / "many.jconf"
    path.write_text(
        HEAD
        + "".join(
            f'<waveform_device name="W{i:02d}" version="1"><rate>10</rate></waveform_device>\n'
            for i in range(DEVICES)
        )
        + "</elements>\n</configuration>\n"
    )
    manager = InputManager(
        default_repository(),
        ManagerOptions(start_devices=False, retry_interval=None, entry_points=False),
    )
    session = MonitorSession(manager, load_configuration([path]))
    session.start()
    yield session
    manager.shutdown()


def rows(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.startswith("W")]


@pytest.mark.timeout(60)
def test_a_terminal_gets_the_rows_that_fit(session, monkeypatch):
    monkeypatch.setitem(os.environ, "LINES", "16")
    monkeypatch.setitem(os.environ, "COLUMNS", "120")
    asked: list[list[str]] = []
    real = session.snapshot

    def spy(*args, names=None, **kwargs):
        asked.append(list(names) if names is not None else session.selected)
        return real(*args, names=names, **kwargs)

    monkeypatch.setattr(session, "snapshot", spy)
    out = Terminal()
    TableView(session, out).print()
    shown = 16 - TABLE_CHROME
    assert [r.split()[0] for r in rows(out.getvalue())] == [f"W{i:02d}" for i in range(shown)]
    assert f"… and {DEVICES - shown} more elements the terminal has no room for" in out.getvalue()
    assert asked == [[f"W{i:02d}" for i in range(shown)]]
    assert len(out.getvalue().splitlines()) <= 16


@pytest.mark.timeout(60)
def test_a_pipe_gets_every_row(session, monkeypatch):
    monkeypatch.setitem(os.environ, "LINES", "16")
    out = io.StringIO()
    TableView(session, out).print()
    assert len(rows(out.getvalue())) == DEVICES
    assert "more element" not in out.getvalue()


@pytest.mark.timeout(60)
def test_a_long_table_is_made_a_chunk_of_views_at_a_time_at_one_instant(session, monkeypatch):
    """Issue 27: the views of every element at once cost 10,000 devices and their proxies
    about 30 MB; a table is made from a few elements' views at a time, all at one instant,
    and is the same table."""
    from gadgetctl.cli import monitor_text

    whole = io.StringIO()
    TableView(session, whole).print()
    asked: list[tuple[float, list[str]]] = []
    real = session.snapshot

    def spy(moment=None, *, names=None, **kwargs):
        asked.append((moment, list(names)))
        return real(moment, names=names, **kwargs)

    monkeypatch.setattr(session, "snapshot", spy)
    monkeypatch.setattr(monitor_text, "TABLE_CHUNK", 7)
    out = io.StringIO()
    TableView(session, out).print()
    assert [names for _, names in asked] == [
        session.selected[i : i + 7] for i in range(0, DEVICES, 7)
    ]
    assert len({moment for moment, _ in asked}) == 1
    assert out.getvalue() == whole.getvalue()
    # written a part at a time, it is the text of one table of one snapshot of them all
    assert out.getvalue() == monitor_text.snapshot_table(real(asked[0][0])) + "\n"


def test_a_snapshot_of_some_states_has_the_views_of_those_elements(tmp_path):
    from gadgetctl.cli.monitor_text import BAD_STATES, problem_lines

    path = tmp_path / "mixed.jconf"
    path.write_text(
        HEAD + '<waveform_device name="W" version="1"><rate>10</rate>'
        "<position_path>circle</position_path></waveform_device>\n"
        '<position_proxy name="Good" version="1"><device>W</device><unit>0</unit></position_proxy>\n'
        '<position_proxy name="Lost" version="1"><device>Nowhere</device><unit>0</unit>'
        "</position_proxy>\n"
        '<position_proxy name="Empty" version="1"><device></device><unit>0</unit></position_proxy>\n'
        "</elements>\n</configuration>\n"
    )
    manager = InputManager(
        default_repository(),
        ManagerOptions(start_devices=False, retry_interval=None, entry_points=False),
    )
    session = MonitorSession(manager, load_configuration([path]))
    try:
        session.start()
        every = session.snapshot(1.0, detail=False)
        some = session.snapshot(1.0, detail=False, states=BAD_STATES)
        assert [e.name for e in some.elements] == ["Lost", "Empty"]
        assert some.elements == [e for e in every.elements if e.state in BAD_STATES]
        assert problem_lines(some) == problem_lines(every) != []
        assert session.snapshot(1.0, detail=False, states=()).elements == []
    finally:
        manager.shutdown()
