"""`gadgetctl view --export FILE.html`: one self-contained page that opens offline, with no
server, in headless Chromium (nothing fetched)."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

from test_view_browser import EMPTY, c4_arguments, configured_corners, differs_near, project
from test_view_replay import CONFIG, MARKERS, write_recording
from view_browser import chromium, painted, screenshot, wait_for_scene

pytestmark = pytest.mark.timeout(240)


def export(*arguments: str) -> str:
    done = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "view", *arguments, "--no-check"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    return done.stdout


def test_the_c4_scene_exports_to_a_page_that_opens_offline(tmp_path):
    page = tmp_path / "c4.html"
    said = export(*c4_arguments(), "--export", str(page), "--duration", "1")
    assert said.startswith(f"gadgetctl view: wrote {page} (")
    empty_config = tmp_path / "empty.jconf"
    empty_config.write_text(EMPTY, encoding="utf-8")
    empty_page = tmp_path / "empty.html"
    export(str(empty_config), "--export", str(empty_page), "--duration", "0.2")
    text = page.read_text(encoding="utf-8")
    assert "__VISER_EMBED_DATA__" in text and "127.0.0.1" not in text
    expected = configured_corners()
    front = np.mean(expected["FrontScreen viewport"], axis=0)
    with chromium() as driver:  # no server runs: the file alone
        driver.get(empty_page.as_uri())
        wait_for_scene(driver)
        painted(driver)
        empty, _ = screenshot(driver)
        driver.get(page.as_uri())
        scene = wait_for_scene(driver)
        surfaces = {s["name"]: s["corners"] for s in scene["surfaces"]}
        assert set(surfaces) == set(expected)
        for name, corners in expected.items():
            assert np.allclose(surfaces[name], corners), name
        assert any(p["name"] == "VJHead" and p["matrix"] for p in scene["poses"])
        # The page's scene state is a script of the file, there before viser's client has
        # drawn the embedded scene: wait for the front screen to be drawn where it belongs.
        difference, deadline = 0.0, time.monotonic() + 30.0
        while difference <= 5 and time.monotonic() < deadline:
            painted(driver)
            full, _ = screenshot(driver)
            difference = differs_near(full, empty, project(front, full.shape), 15)
        assert difference > 5
        fetched = driver.execute_script(
            "return performance.getEntriesByType('resource').map(function (e) { return e.name; })"
        )
        assert [f for f in fetched if not f.startswith(("data:", "blob:", "file:"))] == []


def test_a_recording_exports_with_its_markers(tmp_path):
    recording = write_recording(tmp_path / "session.ndjson")
    config = tmp_path / "replayed.jconf"
    config.write_text(CONFIG, encoding="utf-8")
    page = tmp_path / "session.html"
    said = export("--replay", str(recording), str(config), "--export", str(page))
    assert "91 frames" in said  # 3 s at 30 frames a second, both ends
    with chromium() as driver:
        driver.get(page.as_uri())
        scene = wait_for_scene(driver)
    assert [m["name"] for m in scene["replay"]["markers"]] == list(MARKERS)
    tracker = next(p for p in scene["poses"] if p["name"] == "TrackerProxy")
    assert tracker["matrix"][0][3] == pytest.approx(3.0)  # the last frame: the end
