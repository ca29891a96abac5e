"""The library side of the monitor: MonitorSession (selection, per-frame gathering, press
counting, statuses, records), the fast sample encoder and the replay driver, in-process."""

from __future__ import annotations

import io
import json
import math
import time
from pathlib import Path

import numpy as np
import pytest

from gadgetctl.input.clock import now
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager, ManagerOptions
from gadgetctl.jccl.configuration import Configuration
from gadgetctl.jccl.definitions import Location
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor import replaydevice
from gadgetctl.monitor.gather import frame_timestamps
from gadgetctl.monitor.recording import Recorder, read_recording
from gadgetctl.monitor.records import (
    HeaderRecord,
    SampleRecord,
    StatusRecord,
    decode_line,
    encode_record,
    encode_rows,
    encode_samples,
)
from gadgetctl.monitor.session import MonitorSession, SelectionError

from conftest import REPO

WAVEFORM = REPO / "examples" / "waveform.jconf"
HERE = Location("test")

pytestmark = pytest.mark.timeout(60)


# --------------------------------------------------------------------------- encoding


def test_encode_rows_writes_what_encode_samples_writes():
    matrix = [
        [1.0, 0.0, 0.0, 0.5],
        [0.0, 1.0, 0.0, 1.5],
        [0.0, 0.0, 1.0, -0.25],
        [0.0, 0.0, 0.0, 1.0],
    ]
    cases = [
        ("Stick", "analog", [1.5, 2.5], [[0.25, 1.0], [math.nan, 0.0]], [[-0.5, 1.0], [7, 0.0]]),
        ("Buttons", "digital", [3.0], [[0, 1, 1]], None),
        ("Head", "position", [4.0, 4.01], [[matrix], [matrix]], None),
        ("Voice", "string", [5.0], [['next "slide"']], None),
    ]
    for device, kind, stamps, rows, raws in cases:
        records = [
            SampleRecord(device, kind, unit, t, value, raws[i][unit] if raws else value)
            for i, (t, row) in enumerate(zip(stamps, rows, strict=True))
            for unit, value in enumerate(row)
        ]
        assert encode_rows(device, kind, stamps, rows, raws) == encode_samples(records)
        back = [
            decode_line(line) for line in encode_rows(device, kind, stamps, rows, raws).splitlines()
        ]
        assert [(r.unit, r.timestamp) for r in back] == [(r.unit, r.timestamp) for r in records]


def test_encode_rows_refuses_non_finite_timestamps():
    with pytest.raises(ValueError, match="timestamp"):
        encode_rows("A", "analog", [math.inf], [[0.0]])


def test_status_records_round_trip():
    record = StatusRecord(12.5, "Wand", "device", "linux_joydev", "faulted", "OSError: gone")
    line = encode_record(record)
    assert json.loads(line)["type"] == "status"
    assert decode_line(line) == record


def test_frame_timestamps_merges_kinds_sampled_at_different_instants():
    from gadgetctl.input.samples import FrameSamples, Sample, SampleBatch

    together = {
        DeviceKind.ANALOG: FrameSamples([SampleBatch(np.array([1.0, 2.0]), np.zeros((2, 1)))]),
        DeviceKind.DIGITAL: FrameSamples([SampleBatch(np.array([1.0, 2.0]), np.zeros((2, 1)))]),
    }
    assert frame_timestamps(together).tolist() == [1.0, 2.0]
    apart = {
        DeviceKind.ANALOG: FrameSamples([Sample(1.0, (0.0,)), Sample(3.0, (0.0,))]),
        DeviceKind.DIGITAL: FrameSamples([Sample(2.0, (1,))]),
    }
    assert frame_timestamps(apart).tolist() == [1.0, 2.0, 3.0]


# --------------------------------------------------------------------------- sessions


@pytest.fixture
def waveform():
    manager, configuration = InputManager.from_files([WAVEFORM])
    yield manager, configuration
    manager.shutdown()


def test_selection_by_name_and_glob_in_configuration_order(waveform):
    manager, configuration = waveform
    session = MonitorSession(
        manager, configuration, selectors=["VJ*", "waveform noise", "Wand Proxy"]
    )
    names = session.start()
    assert names == [
        "Waveform Noise",
        "Wand Proxy",
        "VJAnalog0",
        "VJAnalog1",
        "VJButton0",
        "VJButton1",
        "VJWand",
        "VJHead",
        "VJNoise",
    ]
    with pytest.raises(SelectionError, match="'Ghost\\*'"):
        MonitorSession(manager, None, selectors=["Ghost*"]).start()


def test_every_frame_gathers_every_sample_and_the_view_reads_the_newest(waveform):
    manager, configuration = waveform
    session = MonitorSession(
        manager, configuration, selectors=["Waveform Noise", "VJNoise", "Trigger Proxy"]
    )
    session.start()
    frames = list(session.frames(frames=30))  # a count, not a duration: load cannot change it
    assert len(frames) == 30
    stats = session.final_stats()["Waveform Noise"]
    assert stats["mean_rate"] == pytest.approx(1000.0, rel=0.01)
    assert stats["dropped"] == 0 and stats["units"] == {"analog": 2}
    snapshot = session.snapshot()
    noise, trigger, alias = snapshot.elements
    assert (noise.element, noise.state, noise.type) == ("device", "running", "waveform_device")
    assert [u.kind for u in noise.values] == ["analog", "analog"]
    # one point per frame with data (about 16 samples each), not one per sample; a loaded
    # machine may run frames before the device's first samples
    assert 0 < len(noise.values[0].history) <= len(frames)
    assert 0.0 <= noise.values[0].value <= 1.0 and noise.values[0].raw is not None
    assert (alias.element, alias.target, alias.device) == ("alias", "Noise Proxy", "Waveform Noise")
    assert alias.values[0].value == pytest.approx(noise.values[0].value)
    assert trigger.element == "proxy" and trigger.values[0].value in (0, 1, 2, 3)
    assert trigger.stats is not None  # the statistics of Waveform Sticks, watched for the proxy


def _controlled(kinds=("digital",), name="Test Device") -> tuple[InputManager, MonitorSession]:
    """A session over one replay device the test feeds by hand, with a digital proxy."""
    manager = InputManager(default_repository(), ManagerOptions(retry_interval=None))
    replaydevice.install(manager)
    device = replaydevice.RecordedDevice(name, name, "test_device", list(kinds))
    elements = [
        replaydevice.replay_element(device, HERE),
        replaydevice._element("digital_proxy", "Button", HERE, {"device": [name], "unit": [1]}),
        replaydevice._element("digital_proxy", "Nowhere", HERE, {"device": ["Ghost"], "unit": [0]}),
    ]
    session = MonitorSession(manager, Configuration(loaded=elements))
    session.start()
    return manager, session


def test_presses_between_frames_are_counted_and_toggles_marked():
    manager, session = _controlled()
    try:
        device = manager.device("Test Device")
        assert device.kinds() == (DeviceKind.DIGITAL,) and device.element_type == "test_device"
        session.step()
        t = now()
        for i, state in enumerate([(0, 0), (0, 1), (0, 0), (0, 1), (1, 1)]):
            device.feed(DeviceKind.DIGITAL, t + i * 0.001, state)
        session.step()
        view = session.element_view("Test Device")
        assert [(u.value, u.presses, u.changed) for u in view.values] == [
            (1, 1, True),
            (1, 2, True),
        ]
        button = session.element_view("Button")
        assert button.values[0].presses == 2 and button.values[0].value == 2  # toggle on
        session.step()
        view = session.element_view("Test Device")
        assert [u.changed for u in view.values] == [False, False]
        assert session.element_view("Button").values[0].value == 1  # on
        session.reset_stats()
        assert [u.presses for u in session.element_view("Test Device").values] == [0, 0]
        nowhere = session.element_view("Nowhere")
        assert nowhere.state == "stupefied" and "Ghost" in nowhere.reason
    finally:
        manager.shutdown()


def test_status_changes_and_samples_go_to_the_sinks():
    manager, session = _controlled(kinds=("digital", "analog"))
    stream = io.BytesIO()
    session.add_sink(lambda info: Recorder.to_stream(stream, info, clock=now))
    try:
        device = manager.device("Test Device")
        session.step()
        device.feed(DeviceKind.ANALOG, now(), (0.25,))
        session.step()

        def broken() -> None:
            raise OSError("cable")

        device.update_data = broken  # a frame device whose update raises is faulted
        session.step()
        session.mark("after the fault")
        session.close_sinks()
    finally:
        manager.shutdown()
    recs = [json.loads(line) for line in stream.getvalue().decode().splitlines()]
    assert recs[0]["type"] == "header"
    assert recs[0]["info"]["elements"]["Test Device"]["kinds"] == ["digital", "analog"]
    samples = [r for r in recs if r["type"] == "sample"]
    assert [(r["device"], r["kind"], r["value"], r.get("raw")) for r in samples] == [
        ("Test Device", "analog", 0.25, None)
    ]
    faults = [
        (r["state"], r["reason"])
        for r in recs
        if r["type"] == "status" and r["name"] == "Test Device"
    ]
    assert faults == [("running", None), ("faulted", "OSError: cable")]
    assert [r["name"] for r in recs if r["type"] == "marker"] == ["after the fault"]
    assert [r["type"] for r in recs[-2:]] == ["stats", "end"]


def test_a_device_that_disappears_and_comes_back_resumes(waveform):
    manager, configuration = waveform
    session = MonitorSession(manager, configuration, selectors=["Waveform Noise", "Noise Proxy"])
    session.start()
    list(session.frames(duration=0.2))
    element = manager.element("Waveform Noise")
    manager.remove(["Waveform Noise"])
    session.step()
    gone = session.element_view("Waveform Noise")
    assert gone.state == "removed"
    assert session.element_view("Noise Proxy").state == "stupefied"
    manager.add([element])
    list(session.frames(duration=0.3))
    back = session.element_view("Waveform Noise")
    assert back.state == "running" and back.stats.count > 200
    assert session.element_view("Noise Proxy").state == "active"


# --------------------------------------------------------------------------- replay driver


def test_replay_plan_synthesises_devices_proxies_and_aliases(tmp_path):
    path = tmp_path / "r.ndjson"
    info = {
        "elements": {
            "Stick": {
                "element": "device",
                "type": "linux_joydev",
                "kinds": ["analog", "digital"],
                "units": {"analog": 2},
                "min": 0.0,
                "max": 255.0,
            },
            "Stick X": {"element": "proxy", "type": "analog_proxy", "device": "Stick", "unit": 1},
            "VJX": {"element": "alias", "type": "alias", "proxy": "Stick X"},
        }
    }
    with Recorder(path, info) as recorder:
        recorder.write_samples(
            [
                SampleRecord("Stick", "analog", u, 10.0 + i * 0.01, v / 255, v)
                for i, v in enumerate((0, 51, 255))
                for u in range(2)
            ]
            + [SampleRecord("Stick X", "analog", 1, 10.0, 0.0, 0)]
        )
    recording = read_recording(path)
    schedule = replaydevice.make_schedule(
        recording.records, speed=50.0, loop=False, mapping={"Stick": "Pad"}
    )
    plan = replaydevice.plan_replay(recording.header, schedule, path, None, {"Stick": "Pad"})
    assert list(plan.devices) == ["Pad"]  # the proxy's own samples are not replayed
    assert plan.devices["Pad"].units == {"analog": 2}
    types = {
        e.name: (e.type, {k: [v.text for v in vs] for k, vs in e.properties.items()})
        for e in plan.elements
    }
    assert types["Pad"] == (
        "replay_device",
        {
            "kind": ["analog", "digital"],
            "recorded_type": ["linux_joydev"],
            "min": ["0.0"],
            "max": ["255.0"],
        },
    )
    assert types["Stick X"] == ("analog_proxy", {"device": ["Pad"], "unit": ["1"]})
    assert types["VJX"] == ("alias", {"proxy": ["Stick X"]})

    manager = InputManager(default_repository(), ManagerOptions(retry_interval=None))
    try:
        replaydevice.install(manager)
        feeder = replaydevice.ReplayFeeder(
            schedule, manager.device, {"Pad": plan.devices["Pad"].units}
        )
        session = MonitorSession(manager, plan.configuration, source=feeder)
        session.start()
        assert not manager.pending()
        feeder.start()
        values = []
        for _ in session.frames(duration=5):
            values.append(manager.proxy("VJX").data)
        assert session.finished and feeder.fed == 3 and feeder.error is None
        assert values[-1] == 1.0
        assert manager.device("Pad").store.total(DeviceKind.ANALOG) == 3
    finally:
        manager.shutdown()


def test_replay_refuses_a_recording_without_device_samples(tmp_path):
    path = tmp_path / "empty.ndjson"
    Recorder(path, {}).close()
    recording = read_recording(path)
    schedule = replaydevice.make_schedule(recording.records, speed=1.0, loop=False, mapping={})
    with pytest.raises(replaydevice.ReplayError, match="no samples"):
        replaydevice.plan_replay(recording.header, schedule, path, None, {})


def test_header_record_info_survives_a_round_trip():
    header = HeaderRecord.now({"elements": {"A": {"element": "device", "units": {"analog": 2}}}})
    assert decode_line(encode_record(header)).info["elements"]["A"]["units"] == {"analog": 2}


def test_replay_definition_is_only_known_while_replaying():
    assert "replay_device" not in default_repository()
    assert (Path(replaydevice.__file__).parent / "replay_device.jdef").is_file()


def test_keyboard_events_and_keyboard_proxies_are_recorded_as_json():
    from gadgetctl.input.keys import Key

    manager, configuration = InputManager.from_files([REPO / "examples" / "all_devices.jconf"])
    session = MonitorSession(
        manager, configuration, selectors=["Sim Keyboard", "Sim Buttons", "Sim Keyboard Proxy"]
    )
    session.start()
    stream = io.BytesIO()
    session.add_sink(lambda info: Recorder.to_stream(stream, info, clock=now))
    try:
        session.step()
        manager.events.tap(Key.KEY_SPACE)
        manager.events.move(10, -5)
        session.step()
        session.close_sinks()
    finally:
        manager.shutdown()
    recs = [json.loads(line) for line in stream.getvalue().decode().splitlines()]
    keyboard = [r["value"] for r in recs if r["type"] == "sample" and r["device"] == "Sim Keyboard"]
    assert keyboard == [
        {"event": "key", "key": "KEY_SPACE", "pressed": True},
        {"event": "key", "key": "KEY_SPACE", "pressed": False},
        {"event": "move", "dx": 10.0, "dy": -5.0},
    ]
    proxy = [
        r["value"] for r in recs if r["type"] == "sample" and r["device"] == "Sim Keyboard Proxy"
    ]
    assert proxy == [[]]  # the keys held at the end of the frame
    buttons = [
        r["value"]
        for r in recs
        if r["type"] == "sample" and r["device"] == "Sim Buttons" and r["unit"] == 0
    ]
    assert buttons[-1] == 1


def test_a_frames_sample_records_go_out_in_parts_after_the_header(monkeypatch):
    """Issue 27: a frame's sample records are written in parts of about ``ENCODED_PART``
    characters as they are encoded (10,000 devices' first frame made whole was three copies
    of megabytes of text), after the header: the same records, in the same order."""
    from gadgetctl.monitor import framerecords

    monkeypatch.setattr(framerecords, "ENCODED_PART", 200)
    manager, session = _controlled(kinds=("digital", "analog"))
    writes: list[bytes] = []

    class Stream(io.BytesIO):
        def write(self, data) -> int:
            writes.append(bytes(data))
            return super().write(data)

    stream = Stream()
    session.add_sink(lambda info: Recorder.to_stream(stream, info, clock=now))
    try:
        device = manager.device("Test Device")
        session.step()  # no sample yet: the sinks wait for one (or half a second)
        assert writes == []
        t = now()
        for i in range(10):
            device.feed(DeviceKind.ANALOG, t + i * 0.001, (i / 10,))
            device.feed(DeviceKind.DIGITAL, t + i * 0.001, (0, i % 2))
        session.step()
        expected, count = session.encode_samples()
        recorder = session.recorders[0]
    finally:
        manager.shutdown()
    assert json.loads(writes[0])["type"] == "header"
    parts = [w for w in writes if b'"type":"sample"' in w]
    assert len(parts) > 1 and all(len(p) >= 200 for p in parts[:-1])
    assert b"".join(parts).decode() == expected and count == 30
    assert recorder.samples == session.samples_written == 30
    types = [json.loads(line)["type"] for line in b"".join(writes).decode().splitlines()]
    assert types[0] == "header" and set(types[1 : types.index("sample")]) == {"status"}


def test_the_final_statistics_made_when_read_are_those_made_at_once(waveform):
    manager, configuration = waveform
    session = MonitorSession(manager, configuration)
    session.start()
    for _ in session.frames(frames=5):
        pass
    with manager.hold_sampling():
        view = session.final_stats_view()
        at_once = {name: view[name] for name in view}  # at the view's instant, read twice
        assert dict(view.items()) == at_once == dict(view)
        assert list(view) == list(session.final_stats())  # the same devices, in order
        assert session.final_faults() == {
            name: (entry["faults"], entry["state"], entry["error"])
            for name, entry in at_once.items()
        }
        assert "Wand Proxy" not in view and len(view) == len(at_once) > 0
        with pytest.raises(KeyError):
            view["Wand Proxy"]
        stream = io.BytesIO()
        session.add_sink(lambda info: Recorder.to_stream(stream, info, clock=now))
        session.open_sinks()
        session.close_sinks(final=view)
    (stats,) = [
        r for r in map(json.loads, stream.getvalue().decode().splitlines()) if r["type"] == "stats"
    ]
    assert stats["devices"] == json.loads(json.dumps(at_once))


def test_the_figures_at_the_end_are_those_of_the_latest_frame(waveform):
    """A monitor whose frames are slower than its devices' samples (10,000 devices make about
    one frame a second) has not read what came after its latest frame. The final statistics
    and the table describe that frame's instant: read a second later, a 120 Hz tracker's
    window rate had fallen to 0 Hz and its age had grown by the second, while it sampled on."""
    from gadgetctl.cli.monitor_text import TableView

    manager, configuration = waveform
    session = MonitorSession(manager, configuration, selectors=["Waveform Tracker"])
    session.start()
    list(session.frames(duration=0.4))
    looked = session.last_look
    deadline = looked + 10.0
    while now() < looked + 1.2:  # a frame's worth of silence longer than the 1 s window
        assert now() < deadline
        time.sleep(0.05)  # the devices sample on (the scheduler stands in); no frame reads them
    with manager.hold_sampling():
        entry = session.final_stats()["Waveform Tracker"]
        table = io.StringIO()
        TableView(session, table).print()
    assert session.last_look == looked
    assert 80.0 < entry["window_rate"] < 160.0  # 120 Hz, as at the latest frame
    assert entry["age"] < 0.1
    row = next(line for line in table.getvalue().splitlines() if line.startswith("Waveform"))
    rate = float(row.split()[row.split().index("running") + 1])
    assert 80.0 < rate < 160.0


def test_devices_alike_share_one_header_entry_written_as_before(tmp_path):
    """Issue 27 goal 3: the header's entries of devices alike (type, kinds, units, limits)
    are one dict, not one each (10,000 devices' were about 6 MB held while the header was
    encoded); the header reads as entries made one by one, and a device that differs in
    anything, -0.0 for 0.0 included, has its own."""
    body = "".join(
        f'<waveform_device name="W{i}" version="1"><rate>10</rate>'
        f"<analog_waveform>sine</analog_waveform>{limit}</waveform_device>\n"
        for i, limit in enumerate(["", "", "<min>-0.0</min>", "<min>0.0</min>", ""])
    )
    path = tmp_path / "alike.jconf"
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n'
        f"<elements>\n{body}</elements>\n</configuration>\n"
    )
    manager, configuration = InputManager.from_files([path])
    try:
        session = MonitorSession(manager, configuration)
        session.start()
        for _ in session.frames(duration=0.3):
            pass
        info = session.header_info()
    finally:
        manager.shutdown()
    entries = info["elements"]
    assert entries["W0"] is entries["W1"] is entries["W4"]
    assert len({id(entries[f"W{i}"]) for i in range(5)}) == 3
    expected = {
        "element": "device",
        "type": "waveform_device",
        "kinds": [k.value for k in manager.device("W0").kinds()],
        "units": entries["W0"]["units"],
        "min": -1.0,
        "max": 1.0,
    }
    assert entries["W0"] == expected and entries["W0"]["units"]["analog"] == 1
    assert entries["W3"] == {**expected, "min": 0.0} == entries["W2"]
    assert math.copysign(1.0, entries["W2"]["min"]) == -1.0
    assert math.copysign(1.0, entries["W3"]["min"]) == 1.0
    text = encode_record(HeaderRecord.now(info))
    unshared = {**info, "elements": {n: json.loads(json.dumps(e)) for n, e in entries.items()}}
    assert '"min":-0.0' in text
    assert json.loads(text)["info"] == json.loads(encode_record(HeaderRecord.now(unshared)))["info"]
    assert text.split('"info":')[1] == encode_record(HeaderRecord.now(unshared)).split('"info":')[1]
