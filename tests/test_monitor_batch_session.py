"""A monitor session's final statistics and table, computed for many devices together
(FinalStats parts, MonitorSession._refresh_stats), are those computed device by device:
the same entries, the same stats record text, the same table."""

from __future__ import annotations

import io
import json
import struct

import pytest

from gadgetctl.input.manager import InputManager
from gadgetctl.monitor import session as session_module
from gadgetctl.monitor.recording import Recorder
from gadgetctl.monitor.session import MonitorSession

from jccl_samples import jconf

pytestmark = pytest.mark.timeout(60)

RATES = [1, 10, 60, 250, 1000]


@pytest.fixture
def many(tmp_path):
    body = "".join(
        f'<waveform_device name="W{i}" version="1"><rate>{RATES[i % len(RATES)]}</rate>'
        f"<seed>{i}</seed><position_path>circle</position_path></waveform_device>\n"
        f'<position_proxy name="P{i}" version="1"><device>W{i}</device><unit>0</unit>'
        "</position_proxy>\n"
        for i in range(23)
    )
    path = tmp_path / "many.jconf"
    path.write_text(jconf(body))
    manager, configuration = InputManager.from_files([path])
    yield manager, configuration
    manager.shutdown()


def _exact(entry):
    """An entry with its floats' exact bits."""
    return {k: struct.pack("<d", v) if isinstance(v, float) else v for k, v in entry.items()}


def test_final_statistics_by_parts_are_those_device_by_device(many, monkeypatch):
    monkeypatch.setattr(session_module, "FINAL_PART", 4)  # 23 devices: six parts
    manager, configuration = many
    session = MonitorSession(manager, configuration)
    session.start()
    list(session.frames(duration=0.4))
    session.gatherer.tracks["W3"].stats.add_dropped(5)
    session.gatherer.tracks["W4"].stats.add_fault(2)
    with manager.hold_sampling():
        moment = session.last_look
        view = session.final_stats_view()
        names = list(view)
        assert len(names) == 23
        one_by_one = {name: session._final_entry(name, moment) for name in names}
        assert {name: _exact(view[name]) for name in names} == {
            name: _exact(entry) for name, entry in one_by_one.items()
        }
        # read out of order, across parts and back: the same entries, each a new dict
        for name in ["W22", "W0", "W9", "W0", "W21"]:
            entry = view[name]
            assert _exact(entry) == _exact(one_by_one[name])
            assert entry is not view[name]
        assert any(entry["count"] > 100 for entry in one_by_one.values())
        assert one_by_one["W3"]["dropped"] == 5 and one_by_one["W4"]["faults"] == 2
        kinds = [kind.value for kind in manager.device("W0").kinds()]
        assert one_by_one["W0"]["kinds"] == one_by_one["W1"]["kinds"] == kinds
        assert "position" in kinds
        mine = view["W0"]
        mine["kinds"].append("mine")  # each entry's list is its own
        assert view["W0"]["kinds"] == view["W1"]["kinds"] == kinds
        stream = io.BytesIO()
        session.add_sink(lambda info: Recorder.to_stream(stream, info))
        session.open_sinks()
        session.close_sinks()
    (line,) = [
        line
        for line in stream.getvalue().decode().splitlines()
        if json.loads(line)["type"] == "stats"
    ]
    head = json.loads(line)  # (the record's own instant: when the sinks closed)
    expected = json.dumps(
        {"v": head["v"], "type": "stats", "timestamp": head["timestamp"], "devices": one_by_one},
        separators=(",", ":"),
    )
    assert line == expected


def test_the_table_of_statistics_computed_together_is_the_one_device_by_device(many, monkeypatch):
    from gadgetctl.cli.monitor_text import TableView

    manager, configuration = many
    session = MonitorSession(manager, configuration)
    session.start()
    list(session.frames(duration=0.4))
    computed = []
    original = session_module.snapshots
    monkeypatch.setattr(
        session_module,
        "snapshots",
        lambda devices, moment: computed.append(len(devices)) or original(devices, moment),
    )
    with manager.hold_sampling():
        together = io.StringIO()
        TableView(session, together).print()
        assert sum(computed) == 23  # every device's figures computed together
        for track in session.gatherer.tracks.values():  # forget them: computed again one by one
            track._snapshot = None
        monkeypatch.setattr(MonitorSession, "_refresh_stats", lambda self, names, moment: None)
        one_by_one = io.StringIO()
        TableView(session, one_by_one).print()
    assert together.getvalue() == one_by_one.getvalue()
    assert together.getvalue().count("W1") >= 1 and "Hz" in together.getvalue()


def test_health_s_dropped_is_the_device_stats_dropped(many, monkeypatch):
    """health() counts ``dropped`` as Input.stats does (the store's drops and the
    transport's), without counting the samples."""
    manager, configuration = many
    session = MonitorSession(manager, configuration, selectors=["W1"])
    session.start()
    list(session.frames(frames=2))
    device = manager.device("W1")
    assert device.health()["dropped"] == device.stats.dropped == 0
    monkeypatch.setattr(type(device), "transport_dropped", lambda self: 7)
    monkeypatch.setattr(type(device.store), "dropped", lambda self, kind=None: 4)
    assert device.health()["dropped"] == device.stats.dropped == 11
