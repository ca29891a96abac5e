"""`gadgetctl view` in a real browser: headless Chromium loads the page and the tests read
the scene the page holds (``window.gadgetctlScene``) and its pixels."""

from __future__ import annotations

import os

import numpy as np
import pytest
from lxml import etree

from gadgetctl.input.testing.configs import checkout, corpus_file
from gadgetctl.view.render import INITIAL_CAMERA

from view_browser import chromium, painted, screenshot, view_process, wait_for_scene

pytestmark = pytest.mark.timeout(240)

C4_FILES = ("C4.base.jconf", "C4.displays.closed.jconf", "C4.rfwand.jconf")
SIMULATED = checkout() / "examples/c4_simulated_tracking.jconf"
SCREENSHOT = checkout() / "docs/images/view-c4-cave.png"
CORNERS = ("lower_left_corner", "lower_right_corner", "upper_right_corner", "upper_left_corner")
EMPTY = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="empty">'
    "<elements/></configuration>\n"
)


#: The C4's MotionStar with no input_manager loading its driver: it stays pending, with the
#: reason, beside the simulated head and wand.
PENDING_MOTIONSTAR = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="mstar">'
    '<elements><motion_star name="Motion Star master" version="2"><address>mstar3</address>'
    "<server_port>6000</server_port></motion_star></elements></configuration>\n"
)


def c4_arguments(*more: str) -> list[str]:
    return [str(corpus_file(name)) for name in C4_FILES] + [str(SIMULATED), *more]


def configured_corners() -> dict[str, list[list[float]]]:
    """The surface viewports' corners as the corpus file writes them (read here with lxml,
    not by gadgetctl)."""
    tree = etree.parse(str(corpus_file("C4.displays.closed.jconf")))
    result = {}
    for viewport in tree.iter("{*}surface_viewport"):
        result[viewport.get("name")] = [
            [float(e.text) for e in viewport.findall(f"{{*}}{corner}")] for corner in CORNERS
        ]
    return result


def pose(scene: dict, name: str) -> dict:
    return next(p for p in scene["poses"] if p["name"] == name)


def project(point, shape) -> tuple[int, int]:
    """Pixel of a world point seen by the page's initial camera (a pinhole, vertical fov)."""
    height, width = shape[:2]
    eye = np.array(INITIAL_CAMERA["position"], dtype=float)
    forward = np.array(INITIAL_CAMERA["look_at"], dtype=float) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, (0.0, 1.0, 0.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = np.asarray(point, dtype=float) - eye
    x, y, z = d @ right, d @ up, d @ forward
    half = np.tan(INITIAL_CAMERA["fov"] / 2)
    ndc_x, ndc_y = x / (z * half * width / height), y / (z * half)
    return round((ndc_x + 1) / 2 * width), round((1 - ndc_y) / 2 * height)


def differs_near(a: np.ndarray, b: np.ndarray, pixel: tuple[int, int], radius: int) -> float:
    """Mean absolute difference of the two screenshots in a square around ``pixel``."""
    x, y = pixel
    window = (slice(max(0, y - radius), y + radius), slice(max(0, x - radius), x + radius))
    return float(np.abs(a[window] - b[window]).mean())


def not_blank(image: np.ndarray) -> bool:
    colours = len(np.unique(image.reshape(-1, 3), axis=0))
    return float(image.std()) > 10 and colours > 50


def test_c4_cave_with_simulated_head_and_wand_in_a_browser(tmp_path):
    expected = configured_corners()
    assert len(expected) == 4
    pending = tmp_path / "c4.mstar.pending.jconf"
    pending.write_text(PENDING_MOTIONSTAR, encoding="utf-8")
    with view_process(*c4_arguments(str(pending))) as (_, url), chromium() as driver:
        driver.get(url)
        first = wait_for_scene(
            driver, lambda s: all(pose(s, n)["matrix"] for n in ("VJHead", "VJWand"))
        )
        # four screens at the configured corners
        surfaces = {s["name"]: s for s in first["surfaces"]}
        assert set(surfaces) == set(expected)
        for name, corners in expected.items():
            assert np.allclose(surfaces[name]["corners"], corners, atol=1e-6), name
        # the head and the wand move between two reads
        second = wait_for_scene(driver, lambda s: s["frame"] >= first["frame"] + 30)
        for name in ("VJHead", "VJWand", "HeadProxy", "WandProxy"):
            before = np.array(pose(first, name)["matrix"])[:3, 3]
            after = np.array(pose(second, name)["matrix"])[:3, 3]
            assert np.linalg.norm(after - before) > 0.005, name
        user = next(u for u in second["users"] if u["name"] == "User1")
        assert user["head"] == "VJHead"
        eyes = np.array(user["right_eye"]) - np.array(user["left_eye"])
        assert np.linalg.norm(eyes) == pytest.approx(0.069, abs=1e-6)
        # a pending device shown with its reason, in the state and in the side panel
        pending = next(e for e in second["elements"] if e["name"] == "Motion Star master")
        assert pending["state"] == "pending"
        assert "motion_star" in pending["reason"]
        panel = driver.execute_script(
            "return document.getElementById('gadgetctl-problems').textContent"
        )
        assert "Motion Star master" in panel and "pending" in panel and "motion_star" in panel
        fetched = driver.execute_script(
            "return performance.getEntriesByType('resource').map(function (e) { return e.name; })"
        )
        assert [f for f in fetched if not f.startswith((url, "data:", "blob:"))] == []
        painted(driver)
        # the page timed, itself, when it first held the most poses and drew the frame after
        most = driver.execute_script("return window.gadgetctlSceneMost")
        assert most["poses"] >= sum(1 for p in second["poses"] if p["matrix"]) > 0
        assert 0 < most["at"] <= most["painted"]
        full, png = screenshot(driver)
        shown = wait_for_scene(driver)
    empty_config = tmp_path / "empty.jconf"
    empty_config.write_text(EMPTY, encoding="utf-8")
    with view_process(str(empty_config)) as (_, url), chromium() as driver:
        driver.get(url)
        wait_for_scene(driver)
        painted(driver)
        empty, _ = screenshot(driver)
    assert full.shape == empty.shape
    assert not_blank(full)
    front = np.mean(expected["FrontScreen viewport"], axis=0)
    assert differs_near(full, empty, project(front, full.shape), 15) > 5, "the front screen"
    floor = np.mean(expected["FloorScreen viewport"], axis=0)
    assert differs_near(full, empty, project(floor, full.shape), 15) > 5, "the floor screen"
    head = np.array(pose(shown, "HeadProxy")["matrix"])[:3, 3]
    assert differs_near(full, empty, project(head, full.shape), 40) > 3, "the head"
    wand = np.array(pose(shown, "WandProxy")["matrix"])[:3, 3]
    assert differs_near(full, empty, project(wand, full.shape), 40) > 3, "the wand"
    (tmp_path / "view-c4-cave.png").write_bytes(png)
    if os.environ.get("GADGETCTL_UPDATE_SCREENSHOTS"):
        SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
        SCREENSHOT.write_bytes(png)


def test_the_readme_screenshot_is_the_c4_cave_and_not_blank():
    from PIL import Image

    assert SCREENSHOT.is_file(), (
        "make it with GADGETCTL_UPDATE_SCREENSHOTS=1 pytest tests/test_view_browser.py"
    )
    assert str(SCREENSHOT.relative_to(checkout())) in (checkout() / "README.md").read_text()
    image = np.asarray(Image.open(SCREENSHOT).convert("RGB")).astype(int)
    assert not_blank(image)
