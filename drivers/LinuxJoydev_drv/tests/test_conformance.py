"""Conformance: the joydev decoder against records laid out by the C compiler from the kernel's own
ABI header, not by our emulator or by our ``struct`` format.

Sources:

* ``<linux/joystick.h>`` (the system's kernel UAPI header, package linux-libc-dev): ``struct
  js_event``, the ``JS_EVENT_*`` flags and the ``JSIOCG*`` request numbers. A small C program
  compiled here with that header writes the records and prints the request numbers, so the
  layout, padding and byte order are the compiler's, not ours.
* The kernel's joydev documentation (Documentation/input/joydev/joystick-api.rst) and its
  ``joydev_generate_startup_event``: on open, one ``JS_EVENT_INIT``-flagged record per button,
  then one per axis; axis values run from -32767 to +32767.
* VR Juggler's ``Open/LinuxJoydev/LinuxJoydev.cpp`` ``updateData``: axes normalised over
  [-32767, 32767]; an axis button pair is (low, high) = (1, 0) below 0.5, (0, 1) above, (0, 0) at
  exactly 0.5.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from pathlib import Path

import pytest
from LinuxJoydev_drv.standalone import (
    JSIOCGAXES,
    JSIOCGBUTTONS,
    JSIOCGNAME,
    JSIOCGVERSION,
    JoystickEvent,
    LinuxJoydevStandalone,
)

pytestmark = pytest.mark.timeout(60)

WRITER_C = r"""
#include <linux/joystick.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

static int put(int fd, __u32 t, __s16 value, __u8 type, __u8 number) {
    struct js_event e;
    memset(&e, 0, sizeof e);
    e.time = t; e.value = value; e.type = type; e.number = number;
    return write(fd, &e, sizeof e) == (ssize_t)sizeof e ? 0 : 1;
}

int main(int argc, char **argv) {
    if (argc == 2 && strcmp(argv[1], "requests") == 0) {
        printf("%lu %lu %lu %lu %zu\n", (unsigned long)JSIOCGVERSION, (unsigned long)JSIOCGAXES,
               (unsigned long)JSIOCGBUTTONS, (unsigned long)JSIOCGNAME(128),
               sizeof(struct js_event));
        return 0;
    }
    int fd = open(argv[1], O_WRONLY);
    if (fd < 0) return 2;
    int bad = 0;
    /* the start-up burst: 4 buttons (button 2 held), then 3 axes */
    for (int b = 0; b < 4; b++) bad |= put(fd, 1000, b == 2, JS_EVENT_BUTTON | JS_EVENT_INIT, b);
    bad |= put(fd, 1000, 0, JS_EVENT_AXIS | JS_EVENT_INIT, 0);
    bad |= put(fd, 1000, -32767, JS_EVENT_AXIS | JS_EVENT_INIT, 1);
    bad |= put(fd, 1000, 32767, JS_EVENT_AXIS | JS_EVENT_INIT, 2);
    /* live changes */
    bad |= put(fd, 1010, 1, JS_EVENT_BUTTON, 0);
    bad |= put(fd, 1011, 0, JS_EVENT_BUTTON, 2);
    bad |= put(fd, 1012, 16384, JS_EVENT_AXIS, 0);
    bad |= put(fd, 1013, -20000, JS_EVENT_AXIS, 2);
    bad |= put(fd, 1014, 32767, JS_EVENT_AXIS, 1);
    close(fd);
    return bad;
}
"""


@pytest.fixture(scope="module")
def writer(tmp_path_factory: pytest.TempPathFactory) -> Path:
    compiler = shutil.which("cc") or shutil.which("gcc")
    assert compiler, "a C compiler is needed to lay out struct js_event from <linux/joystick.h>"
    folder = tmp_path_factory.mktemp("jswriter")
    (folder / "writer.c").write_text(WRITER_C)
    program = folder / "writer"
    subprocess.run(
        [compiler, "-O0", "-o", str(program), str(folder / "writer.c")], check=True, timeout=60
    )
    return program


def test_request_numbers_and_record_size_match_the_kernel_header(writer: Path) -> None:
    out = subprocess.run(
        [str(writer), "requests"], capture_output=True, text=True, check=True, timeout=30
    ).stdout.split()
    version, axes, buttons, name, size = (int(word) for word in out)
    assert (
        version,
        axes,
        buttons,
        name,
    ) == (JSIOCGVERSION, JSIOCGAXES, JSIOCGBUTTONS, JSIOCGNAME)
    assert size == 8


def test_records_written_by_c_decode_to_the_kernel_documented_state(
    writer: Path, tmp_path: Path
) -> None:
    fifo = tmp_path / "js0"
    os.mkfifo(fifo)
    driver = LinuxJoydevStandalone(fifo, axis_buttons=[0, 2], poll_timeout=0.2)
    driver.open()
    process = subprocess.Popen([str(writer), str(fifo)])
    events: list[JoystickEvent] = []
    try:
        deadline = time.monotonic() + 10
        while len(events) < 12:
            assert time.monotonic() < deadline, f"only {len(events)} of 12 records arrived"
            events.extend(driver.sample().events)
        sample = driver.state()
    finally:
        assert process.wait(timeout=10) == 0
        driver.close()
    assert sum(e.is_init for e in events) == 7
    assert [(e.number, e.is_button) for e in events[:7]] == [
        (0, True),
        (1, True),
        (2, True),
        (3, True),
        (0, False),
        (1, False),
        (2, False),
    ]
    assert [e.time_ms for e in events] == [1000] * 7 + [1010, 1011, 1012, 1013, 1014]
    assert sample.buttons == (1, 0, 0, 0)
    assert sample.axes == (16384, 32767, -20000)
    normalised = sample.normalized()
    assert normalised[0] == pytest.approx((16384 + 32767) / 65534)
    assert normalised[1] == 1.0
    assert normalised[2] == pytest.approx((-20000 + 32767) / 65534)
    # axis 0 above the middle: (low, high) = (0, 1); axis 2 below: (1, 0)
    assert sample.virtual_buttons == (0, 1, 1, 0)
    assert sample.time_ms == 1014
