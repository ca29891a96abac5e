"""`gadgetctl view --replay`: the timeline (play, pause, speed, seeking, markers), in
Python and in a real browser (clicking the page's own controls)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gadgetctl.monitor.session import MonitorSession
from gadgetctl.view.layout import read_layout
from gadgetctl.view.replaysource import open_view_replay
from gadgetctl.view.scene import SceneModel

from view_browser import chromium, view_process, wait_for_scene

pytestmark = pytest.mark.timeout(180)

T0 = 1000.0
STEP = 0.01
SAMPLES = 301  # x goes from 0 to 3.00 m in 3 s
MARKERS = {"middle": 1.505, "late": 2.505}
CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="replayed">
<elements>
<waveform_device name="Tracker" version="1"><rate>100</rate></waveform_device>
<position_proxy name="TrackerProxy" version="1"><device>Tracker</device><unit>0</unit></position_proxy>
</elements>
</configuration>
"""


def recorded_x(offset: float) -> float:
    """x of the newest sample at ``offset`` seconds into the recording."""
    return int((offset + 1e-9) / STEP) * STEP


def write_recording(path):
    header = {
        "v": 1,
        "type": "header",
        "format": "gadgetctl-recording",
        "created": "2026-01-01T00:00:00Z",
        "wall_time": 1.0,
        "monotonic": T0,
        "clock": "monotonic",
        "generator": "tests/test_view_replay.py",
        "info": {
            "devices": ["Tracker"],
            "elements": {
                "Tracker": {
                    "element": "device",
                    "type": "waveform_device",
                    "kinds": ["position"],
                    "units": {"position": 1},
                }
            },
        },
    }
    records = []
    for k in range(SAMPLES):
        m = [[1, 0, 0, round(k * STEP, 6)], [0, 1, 0, 1.5], [0, 0, 1, 0], [0, 0, 0, 1]]
        records.append(
            {
                "v": 1,
                "type": "sample",
                "device": "Tracker",
                "kind": "position",
                "unit": 0,
                "timestamp": T0 + k * STEP,
                "value": m,
                "raw": m,
            }
        )
    for name, offset in MARKERS.items():
        records.append({"v": 1, "type": "marker", "name": name, "timestamp": T0 + offset})
    records.sort(key=lambda r: r["timestamp"])
    path.write_text("\n".join(json.dumps(r) for r in [header, *records]) + "\n", encoding="utf-8")
    return path


@pytest.fixture
def files(tmp_path):
    config = tmp_path / "replayed.jconf"
    config.write_text(CONFIG, encoding="utf-8")
    return write_recording(tmp_path / "session.ndjson"), config


def proxy_x(manager) -> float:
    return float(manager.proxy("TrackerProxy").matrix[0, 3])


def test_seeking_shows_the_poses_recorded_then_and_playing_moves_on(files):
    recording, config = files
    opened = open_view_replay(recording, [config], definitions=[], bundled=True, driver_dirs=[])
    manager, timeline = opened.manager, opened.timeline
    try:
        session = MonitorSession(manager, opened.configuration, rate=60, source=timeline)
        session.start()
        model = SceneModel(session, read_layout(opened.configuration.elements, manager.repo))
        model.timeline = timeline
        assert timeline.duration == pytest.approx(3.0)
        assert [(n, round(t, 3)) for n, t in timeline.markers] == list(MARKERS.items())
        timeline.pause()
        for index, (name, offset) in enumerate(MARKERS.items()):
            timeline.seek_marker(index)
            timeline.advance()
            session.step()
            model.update()
            assert proxy_x(manager) == pytest.approx(recorded_x(offset), abs=1e-9), name
            state = model.snapshot()
            assert state["replay"]["position"] == pytest.approx(offset)
            pose = next(p for p in state["poses"] if p["name"] == "TrackerProxy")
            assert pose["matrix"][0][3] == pytest.approx(recorded_x(offset), abs=1e-6)
        timeline.seek(0.5)
        timeline.advance()
        session.step()
        assert proxy_x(manager) == pytest.approx(0.5)
        timeline.set_speed(4.0)
        timeline.play()
        ran = 0
        for _ in session.frames(frames=600):
            ran += 1
            timeline.advance()
            if session.markers:
                break
        assert ran < 600
        # the first marker passed while playing is the one after 0.5 s (a stalled frame on a
        # loaded machine may pass the next one in the same frame: they come in order)
        names = [m.name for m in session.markers]
        assert names[0] == "middle" and names == [n for n in MARKERS if n in names]
        assert proxy_x(manager) >= 1.5
    finally:
        manager.shutdown()


def test_a_recording_replays_in_the_page_and_a_marker_scrubs_to_its_poses(files):
    from selenium.webdriver.common.by import By

    recording, config = files
    with view_process("--replay", str(recording), str(config)) as (_, url), chromium() as driver:
        driver.get(url)
        state = wait_for_scene(driver, lambda s: s["replay"] is not None)
        assert [m["name"] for m in state["replay"]["markers"]] == list(MARKERS)
        assert [m["time"] for m in state["replay"]["markers"]] == pytest.approx(
            list(MARKERS.values())
        )
        driver.find_element(By.XPATH, "//button[normalize-space()='Pause']").click()
        wait_for_scene(driver, lambda s: not s["replay"]["playing"])
        for name, offset in MARKERS.items():
            driver.find_element(
                By.XPATH, f"//button[contains(normalize-space(), 'Go to marker: {name}')]"
            ).click()

            def shows(s, offset=offset):
                pose = next(p for p in s["poses"] if p["name"] == "TrackerProxy")
                return (
                    abs(s["replay"]["position"] - offset) < 1e-6
                    and pose["matrix"] is not None
                    and abs(pose["matrix"][0][3] - recorded_x(offset)) < 1e-6
                )

            shown = wait_for_scene(driver, shows)
            assert np.array(shown["poses"][0]["matrix"]).shape == (4, 4)
        driver.find_element(By.XPATH, "//button[normalize-space()='Play']").click()
        wait_for_scene(
            driver, lambda s: s["replay"]["playing"] or s["replay"]["position"] > MARKERS["late"]
        )
        wait_for_scene(driver, lambda s: s["replay"]["position"] > MARKERS["late"] + 0.1)


def test_a_recording_with_no_configuration_shows_its_devices_units(files):
    recording, _ = files
    opened = open_view_replay(recording, [], definitions=[], bundled=True, driver_dirs=[])
    manager, timeline = opened.manager, opened.timeline
    try:
        session = MonitorSession(manager, opened.configuration, rate=60, source=timeline)
        session.start()
        model = SceneModel(session, read_layout(opened.configuration.elements, manager.repo))
        timeline.pause()
        timeline.seek_marker(1)
        timeline.advance()
        session.step()
        model.update()
        pose = next(p for p in model.snapshot()["poses"] if p["name"] == "Tracker[0]")
        assert pose["element"] == "device"
        assert pose["matrix"][0][3] == pytest.approx(recorded_x(MARKERS["late"]), abs=1e-9)
    finally:
        manager.shutdown()
