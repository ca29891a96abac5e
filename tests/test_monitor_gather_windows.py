"""A monitor session notes the devices whose frames are windows of their frame group's shared
arrays from the arrays (DeviceTrack.update_window): the same samples, statistics, units and
gathered frames as noting each device from its store (DeviceTrack.update), frame by frame,
without making the store's frame until it is read (a proxy reading the newest sample does
not make it either)."""

from __future__ import annotations

import time

import pytest

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager
from gadgetctl.monitor import tracks as tracks_module
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.monitor.tracks import DeviceTrack

from jccl_samples import jconf

pytestmark = pytest.mark.timeout(60)

BODIES = {
    # alike, with events: most frames are windows, an event's frame is the device's own
    "fast": "<rate>1000</rate><position_path>circle</position_path><event_period>0.02</event_period>",
    # alike, slow: most frames bring nothing new (empty frames; the analog histories hold
    # the newest value through them)
    "slow": "<rate>40</rate><position_path>spin</position_path><button_period>0.1</button_period>"
    "<analog_waveform>sine</analog_waveform><event_period>0</event_period>",
    # values of its own (noise): its blocks are computed alone
    "noise": "<rate>500</rate><seed>{seed}</seed><analog_waveform>noise</analog_waveform>"
    "<min>-1</min><max>1</max><event_period>0</event_period>",
}


@pytest.fixture
def session(tmp_path):
    body = "".join(
        f'<waveform_device name="{name}{copy}" version="1">{text.format(seed=copy)}'
        "</waveform_device>\n"
        for name, text in BODIES.items()
        for copy in range(3)
    )
    body += (
        '<position_proxy name="Head" version="1"><device>fast1</device><unit>0</unit>'
        "</position_proxy>\n"
    )
    path = tmp_path / "w.jconf"
    path.write_text(jconf(body))
    manager, configuration = InputManager.from_files([path])
    session = MonitorSession(manager, configuration, selectors=["fast0", "slow*", "noise*", "Head"])
    session.start()
    yield session
    manager.shutdown()


def noted(track: DeviceTrack) -> dict[str, object]:
    """What a track noted, but for the instants of its frame ends (read from the clock)."""
    stats = track.stats
    return {
        "count": track.count,
        "frames": {
            kind: (samples.count, samples.timestamps()) for kind, samples in track.frames.items()
        },
        "units": dict(track.units),
        "history": [list(h) for h in track.analog_history],
        "presses": None if track.presses is None else track.presses.tolist(),
        "changed": None if track.changed is None else track.changed.tolist(),
        "stats": (
            stats.count,
            stats.first_timestamp,
            stats.newest_timestamp,
            stats.frames,
            stats.samples_per_frame,
            stats.dropped,
            stats.faults,
            stats.recent_timestamps().tobytes(),
            list(stats._frame_ends)[1::2],  # the counts at the frame ends
        ),
    }


def test_tracks_noted_from_shared_windows_are_those_noted_from_the_stores(session):
    windowed, own = [], []
    real, real_update = DeviceTrack.update_window, DeviceTrack.update

    def counted(track, *args):
        windowed.append(track.name)
        return real(track, *args)

    def counted_update(track):
        if session.gatherer.tracks.get(track.name) is track:
            own.append(track.name)
        return real_update(track)

    DeviceTrack.update_window, DeviceTrack.update = counted, counted_update
    try:
        shadows: dict[str, DeviceTrack] = {}
        gathered_shown = unmade = 0
        had: dict[str, int] = {}  # frames with samples, by device
        analog_frames: dict[str, int] = {}  # frames since its first analog sample, by device
        for _ in range(60):
            time.sleep(0.004)
            session.step()
            watched = [name for name in session.watched if session.manager.device(name)]
            assert set(watched) == {"fast0", "fast1"} | {
                f"{name}{copy}" for name in ("slow", "noise") for copy in range(3)
            }
            for name in watched:  # a frame noted from the windows is made only when read
                track = session.gatherer.tracks[name]  # (but to count button presses: "slow")
                if track._frames is tracks_module._FROM_STORE and not name.startswith("slow"):
                    store = track.device.store
                    assert store.shared[0].serial != store._synced, name
                    unmade += 1
            for name in watched:
                track = session.gatherer.tracks[name]
                shadow = shadows.get(name)
                if shadow is None:
                    shadow = shadows[name] = DeviceTrack(name, track.device, session.history)
                shadow.update()  # the same frame, noted from the store
                assert noted(track) == noted(shadow), name
            for name in ("slow0", "slow2"):  # analog histories: one value a frame, the newest
                newest = session.manager.device(name).store.latest(DeviceKind.ANALOG)
                if newest is not None:
                    analog_frames[name] = analog_frames.get(name, 0) + 1
                    device = session.manager.device(name)
                    history = session.gatherer.tracks[name].analog_history[0]
                    assert history[-1] == device.normalize(float(newest.values[0])), name
                    assert len(history) == analog_frames[name], name
            expected = [name for name in watched if shadows[name].frames]
            for name in expected:
                had[name] = had.get(name, 0) + 1
            assert list(session.gathered) == expected
            for name in expected:
                assert session.gathered[name] is shadows[name].frames
            gathered_shown += len(expected)
    finally:
        DeviceTrack.update_window, DeviceTrack.update = real, real_update
    assert gathered_shown > 100 and unmade > 100
    # most frames were noted from the windows; a frame holding an event (every 20 samples of
    # the fast devices) or a block computed alone (the noisy ones) from the store
    for name in ("fast1", "noise0"):
        assert windowed.count(name) > 30, name
    # a slow device is visited only in the frames it had samples in (the others it catches
    # up with when read: the comparison above)
    assert 5 < windowed.count("slow2") <= had["slow2"]
    assert had["slow2"] < 40
    assert own.count("fast1") >= 2 and own.count("noise0") >= 1


def test_a_fault_counted_between_window_notes_shows_when_the_track_is_read(session):
    for _ in range(5):
        time.sleep(0.004)
        session.step()
    device = session.manager.device("slow1")
    track = session.gatherer.tracks["slow1"]
    faults = track.stats.faults
    device.faults += 1  # (counted away from a frame of its own, e.g. by its sampling side)
    for _ in range(200):  # until a frame notes it from the windows (40 Hz: within ~25 ms)
        time.sleep(0.002)
        session.step()
        if (
            track._noted == session.gatherer.clock.ticks
            and track._frames is tracks_module._FROM_STORE
        ):
            break
    else:
        raise AssertionError("slow1 was never noted from the windows")
    assert track.stats.faults == faults + 1
    assert session.final_stats()["slow1"]["faults"] == faults + 1
