"""The serve feed is a consumer of the monitor session's frames (the same hook the
recording writers use): every sample of every served device becomes VRPN reports, proxies
and aliases serve what applications read."""

from __future__ import annotations

import numpy as np
import pytest
from vrpn_peers import Broadcasts

from gadgetctl.input.manager import InputManager
from gadgetctl.input.transforms import matrices_from_pos_quat
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.serve.catalog import build_catalog
from gadgetctl.serve.feed import ServeFeed

from conftest import REPO


class Collected:
    """An outlet that keeps every report (the feed's interface, without a network)."""

    def __init__(self) -> None:
        self.poses: dict[str, list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
        self.changes: dict[str, list[tuple[float, int, int]]] = {}
        self.analogs: dict[str, list[np.ndarray]] = {}
        self.texts: dict[str, list[tuple[int, str]]] = {}

    def tracker(self, sender, times, matrices):
        from gadgetctl.input.transforms import quaternions_xyzw

        self.poses.setdefault(sender, []).append(
            (times, matrices[..., :3, 3], quaternions_xyzw(matrices))
        )

    def buttons(self, sender, changes, states):
        self.changes.setdefault(sender, []).extend(changes)

    def analog(self, sender, times, values):
        self.analogs.setdefault(sender, []).append(values)

    def text(self, sender, moment, level, text):
        self.texts.setdefault(sender, []).append((level, text))


class DeviceLog:
    """A second consumer, registered after the feed: every device sample of each frame."""

    def __init__(self) -> None:
        self.samples: dict[tuple[str, str], list] = {}

    def __call__(self, session, moment):
        for name in session.watched:
            for kind, frame in session.frame_samples(name).items():
                self.samples.setdefault((name, kind.value), []).extend(frame)


@pytest.fixture
def served():
    manager, configuration = InputManager.from_files([REPO / "examples" / "waveform.jconf"])
    session = MonitorSession(manager, configuration, rate=200.0)
    session.start()
    list(session.frames(frames=3))
    catalog = build_catalog(manager, session.selected, {"Waveform Tracker": "Tracker0"})
    outlet, log = Collected(), DeviceLog()
    feed = ServeFeed(catalog, outlet, offset=1000.0)
    session.add_consumer(feed)
    session.add_consumer(log)
    try:
        yield session, outlet, log
    finally:
        manager.shutdown()


@pytest.mark.timeout(60)
def test_every_device_sample_is_served(served):
    session, outlet, log = served
    list(session.frames(duration=1.5))
    samples = log.samples[("Waveform Tracker", "position")]
    times = np.concatenate([t for t, _, _ in outlet.poses["Tracker0"]])
    positions = np.concatenate([p for _, p, _ in outlet.poses["Tracker0"]])
    quats = np.concatenate([q for _, _, q in outlet.poses["Tracker0"]])
    assert len(samples) == len(times) > 100  # 120 Hz for 1.5 s, every one
    matrices = np.asarray([s.values for s in samples])
    np.testing.assert_allclose(times, [s.timestamp + 1000.0 for s in samples])
    np.testing.assert_array_equal(positions, matrices[..., :3, 3])
    np.testing.assert_allclose(matrices_from_pos_quat(positions, quats), matrices, atol=1e-12)
    # the analog rows are the raw values, all of them
    rows = np.concatenate(outlet.analogs["Waveform_Noise"])
    np.testing.assert_array_equal(
        rows, [s.values for s in log.samples[("Waveform Noise", "analog")]]
    )


@pytest.mark.timeout(60)
def test_buttons_are_served_as_their_transitions(served):
    session, outlet, log = served
    list(session.frames(duration=2.2))
    rows = np.asarray([s.values for s in log.samples[("Waveform Sticks", "digital")]]) != 0
    stamps = [s.timestamp + 1000.0 for s in log.samples[("Waveform Sticks", "digital")]]
    expected = []
    previous = np.zeros(rows.shape[1], bool)  # before the first sample served: released
    for t, row in zip(stamps, rows, strict=True):
        for unit in np.nonzero(row != previous)[0]:
            expected.append((t, int(unit), int(row[unit])))
        previous = row
    changes = outlet.changes["Waveform_Sticks"]
    assert changes == expected
    assert (
        sum(1 for _, unit, state in changes if unit == 0 and state == 1) >= 2
    )  # 1 s period: pressed again


@pytest.mark.timeout(60)
def test_proxies_and_aliases_serve_what_applications_read(served):
    session, outlet, _ = served
    seen_analog, seen_pose = [], []
    manager = session.manager

    def application(session, moment):
        seen_analog.append(manager.proxy("VJAnalog0").data)
        seen_pose.append(np.array(manager.proxy("VJWand").data))

    session.add_consumer(application)
    list(session.frames(duration=1.0))
    served_analog = np.concatenate(outlet.analogs["VJAnalog0"])[:, 0]
    assert (
        served_analog.min() >= 0.0 and served_analog.max() <= 1.0
    )  # normalised, as applications see it
    assert set(np.round(served_analog, 12)) <= set(np.round(seen_analog, 12))
    wand = outlet.poses["VJWand"]
    assert all(p.shape == (1, 1, 3) for _, p, _ in wand)  # one sensor
    _, last_p, last_q = wand[-1]
    np.testing.assert_allclose(
        matrices_from_pos_quat(last_p, last_q)[0, 0], seen_pose[-1], atol=1e-12
    )
    assert outlet.changes["VJButton0"] == outlet.changes["Trigger_Proxy"]


@pytest.mark.timeout(60)
def test_monitor_recorders_use_the_same_consumer_hook():
    from gadgetctl.monitor.recording import Recorder

    manager, configuration = InputManager.from_files([REPO / "examples" / "waveform.jconf"])
    session = MonitorSession(manager, configuration, rate=100.0)
    session.start()
    calls = []
    session.add_consumer(lambda s, moment: calls.append(moment))
    import io

    stream = io.BytesIO()
    session.add_sink(lambda info: Recorder.to_stream(stream, info))
    try:
        list(session.frames(frames=60))
    finally:
        manager.shutdown()
    assert len(calls) == 60
    assert session._consumers[1] is MonitorSession._write_frame  # the recorders' consumer
    assert b'"type": "sample"' in stream.getvalue() or b'"type":"sample"' in stream.getvalue()


WAVE = """<waveform_device name="Wave {i}" version="1"><rate>1000</rate><seed>{i}</seed>
  <event_period>0.0</event_period><position_path>circle</position_path>
  <position_path>spin</position_path></waveform_device>"""


@pytest.mark.timeout(60)
@pytest.mark.parametrize("devices", [1, 20], ids=["few-devices", "many-devices"])
def test_a_frame_groups_shared_windows_are_served_as_its_devices_samples(tmp_path, devices):
    """As `serve` runs them (no statistics, no recording: the frame group's shared windows
    read at once, slot by slot for a few devices, with numpy for more), the messages served
    are every device's own samples, each once and in order, with their times."""
    from gadgetctl.input.kinds import DeviceKind
    from gadgetctl.serve.outlet import VrpnOutlet
    from gadgetctl.vrpn import codecs
    from gadgetctl.vrpn.wire import decode_datagram

    path = tmp_path / "waves.jconf"
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="w">\n'
        "<elements>\n" + "\n".join(WAVE.format(i=i) for i in range(devices)) + "\n"
        "</elements>\n</configuration>\n"
    )
    manager, configuration = InputManager.from_files([path])
    try:
        session = MonitorSession(manager, configuration, rate=500.0, statistics=False)
        session.start()
        catalog = build_catalog(manager, session.selected)
        server = Broadcasts()
        outlet = VrpnOutlet(server, catalog)
        feed = ServeFeed(catalog, outlet, offset=1000.0)
        session.add_consumer(feed)
        session.add_consumer(lambda session, moment: outlet.end_frame())
        outlet.audience = True
        grouped = 0
        for _ in session.frames(duration=0.6):
            grouped += bool(getattr(session.gathered, "groups", ()))
            outlet.audience = True
        assert grouped > 100  # the frames were read from the group's shared windows
        served: dict[int, list] = {}
        for message in decode_datagram(b"".join(server.sent)):
            report = codecs.decode(codecs.TRACKER_POS_QUAT, message.payload)
            served.setdefault(message.sender_id, []).append(
                (message.sec + message.usec * 1e-6, report.sensor, report.position, report.quat)
            )
        for entry in catalog:
            device = manager.device(entry.element)
            got = served[server.names[entry.vrpn_name]]
            count = len(got) // 2
            assert count > 200 and [s for _, s, _, _ in got] == [0, 1] * count
            block = device.compute(0, count)
            stamps = np.repeat(block.timestamps + 1000.0, 2)
            np.testing.assert_allclose([t for t, _, _, _ in got], stamps, atol=2e-6)
            matrices = block.data[DeviceKind.POSITION].reshape(-1, 4, 4)
            positions = np.asarray([p for _, _, p, _ in got])
            quats = np.asarray([q for _, _, _, q in got])
            np.testing.assert_array_equal(positions, matrices[:, :3, 3])
            np.testing.assert_allclose(
                matrices_from_pos_quat(positions, quats), matrices, atol=1e-12
            )
    finally:
        manager.shutdown()
