"""Headless Chromium for the tests of `gadgetctl view`: Debian's chromium and chromedriver
(installed by .ci/run), driven by selenium; nothing is downloaded at run time."""

from __future__ import annotations

import contextlib
import io
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
WINDOW = (1200, 800)
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-default-apps",
    "--disable-extensions",
    "--mute-audio",
)


@contextlib.contextmanager
def chromium() -> Iterator[object]:
    """A headless Chromium with a fresh profile, quit (and its profile removed) afterwards."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    assert CHROMIUM.exists() and CHROMEDRIVER.exists(), (
        "the view tests need Debian's chromium and chromium-driver (apt-get install chromium "
        "chromium-driver; .ci/run installs them)"
    )
    profile = tempfile.mkdtemp(prefix="gadgetctl-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in (*FLAGS, f"--user-data-dir={profile}", f"--window-size={WINDOW[0]},{WINDOW[1]}"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
    try:
        driver.set_page_load_timeout(30)
        driver.set_script_timeout(30)
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def page_scene(driver) -> dict | None:
    """The scene state the page holds (``window.gadgetctlScene``), or None before the first."""
    text = driver.execute_script(
        "return window.gadgetctlScene ? JSON.stringify(window.gadgetctlScene) : null"
    )
    return None if text is None else json.loads(text)


def wait_for_scene(
    driver, check: Callable[[dict], bool] = lambda s: True, *, deadline: float = 60.0
) -> dict:
    """Poll the page's scene state until ``check`` holds for it (AssertionError at the
    deadline, with the last state seen)."""
    end = time.monotonic() + deadline
    last = None
    while time.monotonic() < end:
        last = page_scene(driver)
        if last is not None and check(last):
            return last
        time.sleep(0.1)
    raise AssertionError(f"the page's scene never satisfied the check; last: {str(last)[:400]}")


def painted(driver, frames: int = 3) -> None:
    """Return once the page has drawn ``frames`` more animation frames."""
    driver.execute_async_script(
        "var done = arguments[arguments.length - 1], left = arguments[0];"
        "function next() { if (--left <= 0) { done(true); } else { requestAnimationFrame(next); } }"
        "requestAnimationFrame(next);",
        frames,
    )


def screenshot(driver):
    """The page as an RGB numpy array (and the PNG), without viser's notifications (the
    software-WebGL notice of a headless browser)."""
    import numpy as np
    from PIL import Image

    driver.execute_script(
        "document.querySelectorAll('.mantine-Notification-root, .mantine-Notifications-root')"
        ".forEach(function (e) { e.remove(); });"
    )
    png = driver.get_screenshot_as_png()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int), png


@contextlib.contextmanager
def view_process(
    *arguments: str, cwd: Path | None = None
) -> Iterator[tuple[subprocess.Popen, str]]:
    """`gadgetctl view ARGS --port 0` in its own process; yields it and the page's address
    (read from its first line), and stops it (SIGTERM, then SIGKILL) afterwards."""
    process = subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", "view", *arguments, "--port", "0", "--no-check"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
    )
    try:
        line = process.stdout.readline()
        match = re.search(r"http://127\.0\.0\.1:\d+/", line)
        assert match, (
            f"no address printed: {line!r} {process.stderr.read() if process.poll() is not None else ''}"
        )
        yield process, match.group(0)
    finally:
        process.terminate()
        try:
            process.wait(15)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(5)
        process.stdout.close()
        process.stderr.close()
