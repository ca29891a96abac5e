"""Hostile DTrack datagrams: counts, ids and numbers beyond the protocol's limits are bad lines,
counted and skipped; they never fault the device nor grow its units."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from DTrack_drv.standalone import DTrackLimits, DTrackUnits, parse_frame, parse_frames

from gadgetctl.input.testing.configs import configuration

EYE = "[1 0 0 0 1 0 0 0 1]"
BODY = f"[0 1.0][1 2 3]{EYE}"
POISON = [
    "6dcal 2000000",
    f"6d 1 [3000000 1.0][1 2 3 0 0 0]{EYE}",
    "6d " + "9" * 4301 + f" {BODY}",
    f"6d 1 [{'7' * 5000} 1.0][1 2 3]{EYE}",
    "fr " + "1" * 5000,
    "fr 4294967296",  # the counter is 32 bits
    "glcal 9999999",
    f"6df2 5000000 1 [0 1.0 8 2][1 2 3]{EYE}[0 0 0]",
    f"6df2 1 1 [0 1.0 4000000000 0][1 2 3]{EYE}[0]",
    f"6df2 1 1 [0 1.0 8 100000][1 2 3]{EYE}[0 0 0]",
    f"6dmt2 1 1 [0 1.0 {'1' * 4400} 2.5][1 2 3]{EYE}[1][1 2 3 4 5 6]",
    f"6di 1 [128 2 0.5][1 2 3]{EYE}",
    f"6dmt 1 [999999 1.0 1][1 2 3]{EYE}",
    "3d 1 [1000000 1.0][1 2 3]",
    f"gl 1 [5000000 1.0 0 0][0 0 0]{EYE}",
    f"6d 1 [\N{SUPERSCRIPT TWO} 1.0][1 2 3]{EYE}",  # a digit to str.isdigit, not to int()
    f"6d \N{SUPERSCRIPT TWO} {BODY} {BODY}",
]


@pytest.mark.parametrize("line", POISON, ids=lambda line: line[:24])
@pytest.mark.parametrize("fast", [True, False], ids=["fast", "general"])
def test_a_line_beyond_the_limits_is_a_bad_line(line: str, fast: bool) -> None:
    text = f"fr 5\r\n{line}\r\n6d 1 {BODY}\r\nts 1.5\r\n"
    frame = parse_frame(text, fast=fast)
    assert frame is not None and frame.bad_lines == 1
    assert frame.frame == 5 and frame.timestamp == 1.5 and len(frame.bodies) == 1
    assert frame.calibrated_bodies is None and frame.calibrated_flysticks is None


def test_the_limits_can_be_raised_and_lowered() -> None:
    line = f"fr 1\r\n6d 1 [300 1.0][1 2 3]{EYE}\r\n6dcal 400\r\n"
    assert parse_frame(line).bad_lines == 2  # type: ignore[union-attr]
    wide = DTrackLimits(objects=1000)
    frame = parse_frame(line, limits=wide)
    assert frame is not None and frame.bad_lines == 0 and frame.bodies.ids.tolist() == [300]
    units = DTrackUnits(limits=wide)
    units.update(frame)
    assert units.counts == (0, 0, 400)
    narrow = DTrackUnits(limits=DTrackLimits(objects=4))  # frames parsed with wider limits
    narrow.update(frame)
    assert narrow.counts == (0, 0, 4)


def test_units_stay_small_after_poison_between_good_frames() -> None:
    texts = []
    for n in range(1, 31):
        texts.append(f"fr {n}\r\n6dcal 2\r\n6d 2 [0 1.0][1 2 3]{EYE} [1 0.5][4 5 6]{EYE}\r\n")
        if n % 10 == 0:
            texts.append(f"fr {n}\r\n{POISON[n // 10 - 1]}\r\n")
    frames = parse_frames(texts)
    units = DTrackUnits(extra_units=True)
    merged = units.merge([f for f in frames if f is not None])
    assert units.counts == (0, 0, 2)
    assert merged.positions.shape == (33, 2, 4, 4)


# -- the device over loopback UDP, in a process of its own to measure its memory -------------------

CHILD = textwrap.dedent(
    """
    import json, socket, sys
    from pathlib import Path
    from gadgetctl.input import DeviceKind, InputManager, ManagerOptions
    from gadgetctl.input.testing import frames_until

    path, poison = Path(sys.argv[1]), json.loads(sys.argv[2])
    options = ManagerOptions(retry_interval=None, entry_points=False)
    manager, configuration = InputManager.from_files([path], options=options)
    try:
        manager.configure(configuration)
        device = manager.device("DT")
        port = device.port
        eye = "[1 0 0 0 1 0 0 0 1]"
        good = 0
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            def send_good(n):
                tx.sendto(f"fr {n}\\r\\n6d 1 [0 1.0][{n} 2 3]{eye}\\r\\n".encode(), ("127.0.0.1", port))

            for n in range(1, 31):
                send_good(n)
                good += 1
                frames_until(manager, lambda: device.store.total(DeviceKind.POSITION) >= good)
                if n % 10 == 0:
                    tx.sendto(poison[n // 10 - 1].encode(), ("127.0.0.1", port))
                    frames_until(manager, lambda: device.counters["datagrams"] >= good + n // 10)
        state, faults = manager.status("DT").state, device.faults
        # exact counts once sampling stopped: the last poison is counted received before it
        # is counted bad, and this thread may read between the two
        manager.shutdown()
        latest = device.store.latest(DeviceKind.POSITION)
        result = {
            "state": state,
            "faults": faults,
            "positions": device.store.total(DeviceKind.POSITION),
            "units": len(latest.values),
            "last_x": float(latest.values[0][0][3]),
            "counters": device.counters,
            # VmHWM, this process's own peak: ru_maxrss after a fork and exec starts from the
            # parent's resident set (the test runner's, hundreds of MB late in a full run)
            "maxrss_mb": next(
                int(line.split()[1]) for line in Path("/proc/self/status").read_text().splitlines()
                if line.startswith("VmHWM:")
            ) / 1024,
        }
    finally:
        manager.shutdown()
    print(json.dumps(result))
    """
)


@pytest.mark.timeout(120)
def test_the_device_delivers_good_frames_around_poison_with_bounded_memory(tmp_path: Path) -> None:
    config = tmp_path / "dt.jconf"
    config.write_text(
        configuration(
            "DTrack_drv", '<dtrack name="DT" version="1"><receive_port>0</receive_port></dtrack>'
        )
    )
    poison = [
        "6dcal 2000000\r\n",
        f"6d 1 [3000000 1.0][1 2 3 0 0 0]{EYE}\r\n",
        "6d " + "9" * 4400 + f" {BODY}\r\n",
    ]
    # Without the limits the first poison alone needs gigabytes: cap the address space so a
    # regression fails here instead of exhausting the machine.
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    limit = "import resource; resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))\n"
    result = subprocess.run(
        [sys.executable, "-c", limit + CHILD, str(config), json.dumps(poison)],
        capture_output=True,
        text=True,
        timeout=110,
        env=env,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads(result.stdout.splitlines()[-1])
    assert report["state"] == "running" and report["faults"] == 0
    assert report["positions"] == 30 and report["units"] == 1
    assert report["last_x"] == pytest.approx(0.030)  # the last good frame's body, x = 30 mm
    counters = report["counters"]
    assert counters["datagrams"] == 33 and counters["bad_datagrams"] == 3
    assert report["maxrss_mb"] < 400, report
