"""Conformance: the trackd reader against a segment laid out by the C compiler from CAVELib's
published structures, not by our emulator's ``struct`` formats.

Sources:

* The trackd shared-memory structures as published with CAVELib (Dave Pape's CAVE programming
  notes, quoted in VR Juggler's ``Open/Trackd/trackdmem.h``) and read independently by CalVR's
  ``TrackerShmem.h``: a tracker header of seven ``uint32_t`` (version, sensor count, byte offset
  of the sensor array, size of one sensor, a two-word timestamp, command), sensors of six
  ``float`` (x, y, z, azim, elev, roll), a two-word timestamp and two ``int32_t`` (calibrated,
  frame); a controller header of eight ``uint32_t`` (version, button offset, valuator offset,
  button count, valuator count, timestamp, command), ``int32_t`` buttons and ``float`` valuators.
  A C program compiled here declares those structures and fills a System V segment with them,
  so offsets, padding and byte order are the compiler's.
* CAVELib's orientation: azimuth about Y, elevation about X, roll about Z, composed
  ``Ry(azim) * Rx(elev) * Rz(roll)`` (VR Juggler's ``aTrackdSensor::getSensorPos`` writes the
  same product with quaternions). The expected matrices below are built from quaternions, not
  with the driver's own matrix product.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from Trackd_drv.standalone import (
    TrackdSegment,
    decode_controller,
    decode_tracker,
    segment_id,
    sensor_matrix,
)

pytestmark = pytest.mark.timeout(60)

WRITER_C = r"""
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ipc.h>
#include <sys/shm.h>

struct sensor { float x, y, z, azim, elev, roll; uint32_t timestamp[2]; int32_t calibrated, frame; };
struct tracker_header { uint32_t version, count, offset, size, timestamp[2], command; };
struct controller_header { uint32_t version, button_offset, valuator_offset, buttons, valuators,
                           timestamp[2], command; };

static void *make(key_t key, size_t size) {
    int id = shmget(key, size, IPC_CREAT | IPC_EXCL | 0600);
    if (id < 0) { perror("shmget"); exit(2); }
    void *at = shmat(id, NULL, 0);
    if (at == (void *)-1) { perror("shmat"); exit(2); }
    memset(at, 0, size);
    return at;
}

int main(int argc, char **argv) {
    key_t tracker_key = (key_t)strtol(argv[1], NULL, 0);
    key_t controller_key = (key_t)strtol(argv[2], NULL, 0);
    /* the sensor array starts after a gap, as a daemon may leave one */
    size_t offset = sizeof(struct tracker_header) + 12;
    char *t = make(tracker_key, offset + 2 * sizeof(struct sensor));
    struct tracker_header *th = (struct tracker_header *)t;
    th->version = 1; th->count = 2; th->offset = offset; th->size = sizeof(struct sensor);
    struct sensor *s = (struct sensor *)(t + offset);
    s[0].x = 1.5f; s[0].y = 5.25f; s[0].z = -2.0f;
    s[0].azim = 30.0f; s[0].elev = -20.0f; s[0].roll = 45.0f; s[0].calibrated = 1; s[0].frame = 7;
    s[1].x = -0.5f; s[1].y = 4.0f; s[1].z = 0.25f;
    s[1].azim = 170.0f; s[1].elev = 60.0f; s[1].roll = -90.0f; s[1].frame = 8;
    size_t buttons = sizeof(struct controller_header);
    size_t valuators = buttons + 3 * sizeof(int32_t);
    char *c = make(controller_key, valuators + 2 * sizeof(float));
    struct controller_header *ch = (struct controller_header *)c;
    ch->version = 1; ch->button_offset = buttons; ch->valuator_offset = valuators;
    ch->buttons = 3; ch->valuators = 2;
    int32_t *b = (int32_t *)(c + buttons); b[0] = 0; b[1] = 1; b[2] = 1;
    float *v = (float *)(c + valuators); v[0] = -0.75f; v[1] = 0.5f;
    printf("%zu %zu\n", offset, sizeof(struct sensor));
    return 0;
}
"""


def quaternion(axis: tuple[float, float, float], degrees: float) -> np.ndarray:
    half = math.radians(degrees) / 2
    return np.array([math.cos(half), *(math.sin(half) * np.array(axis))])


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )


def rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def cavelib_rotation(azim: float, elev: float, roll: float) -> np.ndarray:
    q = multiply(
        multiply(quaternion((0, 1, 0), azim), quaternion((1, 0, 0), elev)),
        quaternion((0, 0, 1), roll),
    )
    return rotation(q)


@pytest.fixture
def segments(tmp_path: Path):
    compiler = shutil.which("cc") or shutil.which("gcc")
    assert compiler, "a C compiler is needed to lay out CAVELib's structures"
    (tmp_path / "writer.c").write_text(WRITER_C)
    program = tmp_path / "writer"
    subprocess.run(
        [compiler, "-o", str(program), str(tmp_path / "writer.c")], check=True, timeout=60
    )
    base = 0x4C000000 + ((os.getpid() & 0xFFFF) << 4)
    keys = next(
        (base + 2 * i, base + 2 * i + 1)
        for i in range(8)
        if segment_id(base + 2 * i) is None and segment_id(base + 2 * i + 1) is None
    )
    done = subprocess.run(
        [str(program), str(keys[0]), str(keys[1])],
        capture_output=True,
        text=True,
        timeout=30,
    )
    try:
        assert done.returncode == 0, done.stderr
        yield keys, [int(word) for word in done.stdout.split()]
    finally:
        import sysv_ipc

        for key in keys:
            found = segment_id(key)
            if found is not None:
                sysv_ipc.remove_shared_memory(found)


def test_a_segment_laid_out_by_c_reads_as_cavelib_defines_it(segments) -> None:
    (tracker_key, controller_key), (_offset, sensor_size) = segments
    assert sensor_size == 40
    reader = TrackdSegment(tracker_key)
    reader.open()
    try:
        state = decode_tracker(reader.read())
    finally:
        reader.close()
    assert len(state.sensors) == 2
    first, second = state.sensors
    assert (first.x, first.y, first.z) == (1.5, 5.25, -2.0)
    assert (second.x, second.y, second.z) == (-0.5, 4.0, 0.25)
    for reading in (first, second):
        matrix = sensor_matrix(reading)
        expected = cavelib_rotation(reading.azim, reading.elev, reading.roll)
        np.testing.assert_allclose(matrix[:3, :3], expected, atol=1e-6)
        np.testing.assert_allclose(matrix[:3, 3], (reading.x, reading.y, reading.z))

    controls = TrackdSegment(controller_key)
    controls.open()
    try:
        controller = decode_controller(controls.read())
    finally:
        controls.close()
    assert list(controller.buttons) == [0, 1, 1]
    assert list(controller.valuators) == pytest.approx([-0.75, 0.5])
