"""Driver health end to end (issue 16 item 3): every bundled driver's emulator, playing its
``garbage`` scenario over the real transport, makes the driver count what it skipped, and the
monitor shows those counters (``Input.health()``) in the live view, in ``--format table`` and
in the ndjson statistics.

Each case points the driver's own ``example.jconf`` at a fresh emulator and

* renders the live view (``LiveView``, the function the terminal dashboard draws with; the
  terminal itself is covered through tmux by DTrack's ``test_monitor_health.py``) of an
  in-process session until the device's ``health:`` shows the garbage counted;
* runs ``gadgetctl monitor --format table --record FILE`` until a table row shows them, stops
  it with SIGINT as a user would, and reads the counters again from the recording's final
  ``stats`` record (the ndjson statistics). SDL's virtual joysticks exist only in the process
  that attaches them, so SdlJoystick_drv's monitor runs in this process, through the same
  ``run`` the command calls, stopped once the device has counted the garbage.

VRPN_drv is not here: its emulator serves well-formed VRPN only (no garbage scenario).
"""

from __future__ import annotations

import io
import itertools
import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from gadgetctl.input.testing import wait_until

REPO = Path(__file__).resolve().parents[1]
DRIVERS = REPO / "drivers"
WAIT = 30.0  # seconds a condition may take on a loaded machine before the test fails

pytestmark = pytest.mark.timeout(120)


# --------------------------------------------------------------------------- the cases


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


_key_counter = itertools.count()


def free_shm_key() -> int:
    """A System V key no segment uses now (per process and call, as the Trackd tests pick)."""
    taken = {
        int(fields[0])
        for fields in (
            line.split() for line in Path("/proc/sysvipc/shm").read_text().splitlines()[1:]
        )
        if fields
    }
    while True:
        key = 0x48000000 + ((os.getpid() & 0xFFFF) << 8) + (next(_key_counter) & 0xFF)
        if key not in taken:
            return key


def set_property(text: str, name: str, value: str, *, old: str | None = None) -> str:
    """``text`` with the (first, or the one holding ``old``) ``<name>`` value replaced."""
    pattern = rf"<{name}>{re.escape(old) if old is not None else '[^<]*'}</{name}>"
    new, found = re.subn(pattern, f"<{name}>{value}</{name}>", text, count=1)
    assert found, f"no <{name}> in the example"
    return new


@dataclass(frozen=True)
class Case:
    """A driver, its emulator playing ``garbage``, and the counters that must rise."""

    driver: str
    devices: tuple[str, ...]
    counters: tuple[str, ...]  # each must be non-zero for every device
    emulator: Callable[[Path], Any]  # tmp directory -> emulator (not started)
    point: Callable[[str, Any, Path], str]  # example text, started emulator, tmp -> text
    in_process: bool = False  # the emulator is seen only by its own process (SDL)


def emulator_class(driver: str, name: str) -> type:
    module = __import__(f"{driver}.emulator", fromlist=[name])
    return getattr(module, name)


def serial(
    driver: str, cls: str, device: str, counters=("bad_records", "skipped_bytes"), **options
) -> Case:
    """A serial device: the emulator's pty behind a link in tmp, written as ``port``."""
    return Case(
        driver,
        (device,),
        counters,
        lambda tmp: emulator_class(driver, cls)(scenario="garbage", link=tmp / "tty", **options),
        lambda text, emu, tmp: set_property(text, "port", str(tmp / "tty")),
    )


def udp_sender(driver: str, cls: str, device: str, prop: str, counters: tuple[str, ...]) -> Case:
    """A device that sends datagrams to the port the driver binds (``prop``)."""
    port = {}

    def make(tmp: Path) -> Any:
        port["n"] = free_udp_port()
        return emulator_class(driver, cls)(port["n"], scenario="garbage")

    return Case(
        driver,
        (device,),
        counters,
        make,
        lambda text, emu, tmp: set_property(text, prop, str(port["n"])),
    )


def trackd(tmp: Path) -> Any:
    return emulator_class("Trackd_drv", "TrackdEmulator")(
        free_shm_key(), free_shm_key(), scenario="garbage"
    )


def point_trackd(text: str, emu: Any, tmp: Path) -> str:
    text = set_property(text, "shared_memory_key", str(emu.sensor_key), old="4148")
    return set_property(text, "shared_memory_key", str(emu.controller_key), old="4147")


CASES = [
    udp_sender("DTrack_drv", "DTrackEmulator", "DTrack", "receive_port", ("bad_datagrams",)),
    Case(  # an emulated Motive: it also answers the connect request that asks its version
        "OptiTrack_drv",
        ("OptiTrack",),
        ("bad_datagrams",),
        lambda tmp: emulator_class("OptiTrack_drv", "OptiTrackEmulator")(
            free_udp_port(), scenario="garbage", command_port=0
        ),
        lambda text, emu, tmp: set_property(
            set_property(text, "port", str(emu.port)),
            "command_port",
            str(emu.command_address[1]),
        ),
    ),
    udp_sender("TUIO_drv", "TuioEmulator", "Touch Table", "port", ("bad_datagrams",)),
    Case(
        "ElexolEther24_drv",
        ("IO Board",),
        ("bad_replies",),
        lambda tmp: emulator_class("ElexolEther24_drv", "Ether24Emulator")(0, scenario="garbage"),
        lambda text, emu, tmp: set_property(text, "ip_address", emu.address),
    ),
    Case(
        "MotionStar_drv",
        ("MotionStar",),
        ("bad_packets", "skipped_bytes"),
        lambda tmp: emulator_class("MotionStar_drv", "MotionStarEmulator")(scenario="garbage"),
        lambda text, emu, tmp: set_property(text, "server_port", emu.address.rpartition(":")[2]),
    ),
    Case(
        "LinuxJoydev_drv",
        ("Joystick",),
        ("skipped_bytes", "resyncs"),
        lambda tmp: emulator_class("LinuxJoydev_drv", "JoydevEmulator")(
            tmp / "js0", scenario="garbage"
        ),
        lambda text, emu, tmp: set_property(text, "port_name", str(tmp / "js0")),
    ),
    Case(
        "Trackd_drv",
        ("TrackdSensorDev", "TrackdControllerDev"),
        ("bad_records",),
        trackd,
        point_trackd,
    ),
    serial(
        "PinchGlove_drv",
        "PinchGloveEmulator",
        "PinchGlove",
        ("bad_frames", "skipped_bytes"),
        rate=20.0,
    ),
    serial("Fastrak_drv", "FastrakEmulator", "Fastrak"),
    serial("Flock_drv", "FlockEmulator", "Flock"),
    serial("IBox_drv", "IBoxEmulator", "IBox"),
    serial("IS900_drv", "IS900Emulator", "IS900"),
    serial("ThreeDMouse_drv", "ThreeDMouseEmulator", "3D Mouse"),
    serial("SpaceBall_drv", "SpaceBallEmulator", "SpaceMouse"),
    serial("SerialEncoder_drv", "SerialEncoderEmulator", "Table Encoders"),
    serial("DataGlove_drv", "DataGloveEmulator", "DataGlove"),
    serial("DataGloveUltraWireless_drv", "UltraGloveEmulator", "Ultra Gloves"),
    serial("Wanda_drv", "WandaEmulator", "Wanda"),
    Case(
        "SdlJoystick_drv",
        ("Gamepad",),
        ("bad_hats",),
        lambda tmp: emulator_class("SdlJoystick_drv", "SdlJoystickEmulator")(scenario="garbage"),
        lambda text, emu, tmp: set_property(text, "device", str(emu.index), old="0"),
        in_process=True,
    ),
]


def test_every_bundled_driver_with_a_garbage_scenario_is_a_case() -> None:
    """A new driver whose emulator has a garbage scenario must join the cases."""
    drivers = sorted(path.parent.name for path in DRIVERS.glob("*_drv/emulator.py"))
    with_garbage = {
        driver
        for driver in drivers
        if "garbage" in __import__(f"{driver}.emulator", fromlist=["SCENARIOS"]).SCENARIOS
    }
    assert with_garbage == {case.driver for case in CASES}
    assert "VRPN_drv" in drivers and "VRPN_drv" not in with_garbage  # see the module's docstring


# --------------------------------------------------------------------------- reading health


def counted(text: str) -> dict[str, float]:
    """The counters of a ``health: a 1, b 2, last fault ...`` part of a row or view line."""
    found = re.search(r"health: (.*?)(?:  |$)", text)
    if found is None:
        return {}
    return {
        name: float(n)
        for name, n in re.findall(r"(?:^|, )(\w+) (\d+(?:\.\d+)?)(?=,|$)", found.group(1))
    }


def shows_all(health: dict[str, float], case: Case) -> bool:
    return all(health.get(name, 0) > 0 for name in case.counters)


def example(case: Case, emu: Any, tmp: Path) -> Path:
    text = case.point((DRIVERS / case.driver / "example.jconf").read_text(), emu, tmp)
    path = tmp / "example.jconf"
    path.write_text(text)
    return path


@pytest.fixture(params=CASES, ids=[case.driver for case in CASES])
def case(request) -> Case:
    return request.param


# --------------------------------------------------------------------------- the view


#: A device's line of the live view while it runs (``{}``: its name, escaped).
RUNNING = r"{}\s+\S+\s+running\b"


def test_the_live_view_shows_the_garbage_counted(case: Case, tmp_path: Path) -> None:
    from rich.console import Console

    from gadgetctl.cli.monitor_live import LiveView
    from gadgetctl.input.manager import InputManager
    from gadgetctl.monitor.session import MonitorSession

    with case.emulator(tmp_path) as emu:
        manager, configuration = InputManager.from_files([example(case, emu, tmp_path)])
        try:
            session = MonitorSession(manager, configuration, selectors=list(case.devices))
            session.start()
            view = LiveView(session, Console(file=io.StringIO(), width=250, height=60))
            lines: dict[str, str] = {}

            def rendered() -> bool:
                session.step()
                for line in view.text(250, 60).splitlines():
                    for name in case.devices:
                        if line.startswith(f"{name} ") and " health: " in line:
                            lines[name] = line
                # running once a record decodes (before, a device that read only junk yet is
                # rightly shown undecodable), and it stays running through the garbage
                return len(lines) == len(case.devices) and all(
                    shows_all(counted(line), case)
                    and re.match(RUNNING.format(re.escape(name)), line)
                    for name, line in lines.items()
                )

            assert wait_until(rendered, timeout=WAIT, pause=0.02), lines
        finally:
            manager.shutdown()
    for name, line in lines.items():
        assert re.match(RUNNING.format(re.escape(name)), line), line  # garbage is no fault


# --------------------------------------------------------------------------- table and ndjson


class Lines:
    """The lines a child process writes to a pipe, gathered by a thread."""

    def __init__(self, stream) -> None:
        self.lines: list[str] = []
        self._thread = threading.Thread(target=self._read, args=(stream,), daemon=True)
        self._thread.start()

    def _read(self, stream) -> None:
        for line in stream:
            self.lines.append(line.rstrip("\n"))

    def join(self) -> None:
        self._thread.join(timeout=WAIT)


def device_rows(lines: list[str], case: Case) -> dict[str, str]:
    """The newest table row of each of the case's devices."""
    rows: dict[str, str] = {}
    for line in lines:
        for name in case.devices:
            if re.match(rf"{re.escape(name)}\s+device\s", line):
                rows[name] = line
    return rows


def shown_in(rows: dict[str, str], case: Case) -> bool:
    return len(rows) == len(case.devices) and all(
        shows_all(counted(row), case) for row in rows.values()
    )


def monitor_child(case: Case, config: Path, record: Path, *, status: int = 0) -> list[str]:
    """``gadgetctl monitor`` until its table shows the counters, then Ctrl-C; the table lines
    (``status``: the exit status expected, 1 when a device faulted)."""
    command = [
        sys.executable,
        "-m",
        "gadgetctl",
        "monitor",
        str(config),
        *case.devices,
        "--format",
        "table",
        "--interval",
        "0.2",
        "--record",
        str(record),
        "--no-check",
    ]
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out, err = Lines(child.stdout), Lines(child.stderr)
    try:
        shown = wait_until(
            lambda: shown_in(device_rows(out.lines[-60:], case), case) or child.poll() is not None,
            timeout=WAIT,
            pause=0.05,
        )
        assert shown and child.poll() is None, (out.lines[-5:], err.lines[-20:])
        child.send_signal(signal.SIGINT)  # Ctrl-C: the statistics are still written
        assert child.wait(timeout=WAIT) == status, err.lines[-20:]
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        out.join()
        err.join()
    return out.lines


def monitor_here(case: Case, config: Path, record: Path, capsys) -> list[str]:
    """The command's own ``run`` in this process, stopped once the devices counted the
    garbage (the table printed at the end then shows it); the table lines."""
    from gadgetctl.cli.monitor_run import OutputFormat, RunOptions, run
    from gadgetctl.input.manager import InputManager
    from gadgetctl.monitor.session import MonitorSession

    manager, configuration = InputManager.from_files([config])
    session = MonitorSession(
        manager, configuration, selectors=list(case.devices), info={"config": [str(config)]}
    )
    session.start()
    deadline = time.monotonic() + WAIT

    def stop_when_counted(session: MonitorSession, moment: float) -> None:
        devices = [manager.device(name) for name in case.devices]
        if time.monotonic() > deadline or all(
            d is not None and shows_all(d.health(), case) for d in devices
        ):
            session.stop()

    session.add_consumer(stop_when_counted)
    capsys.readouterr()
    status = run(session, RunOptions(format=OutputFormat.table, record=record, interval=0.2))
    assert status == 0
    return capsys.readouterr().out.splitlines()


def test_the_table_and_the_ndjson_statistics_show_the_garbage_counted(
    case: Case, tmp_path: Path, capsys
) -> None:
    record = tmp_path / "run.ndjson"
    with case.emulator(tmp_path) as emu:
        config = example(case, emu, tmp_path)
        lines = (
            monitor_here(case, config, record, capsys)
            if case.in_process
            else monitor_child(case, config, record)
        )
    rows = device_rows(lines, case)
    assert shown_in(rows, case), rows
    stats = [
        json.loads(line) for line in record.read_text().splitlines() if '"type":"stats"' in line
    ]
    assert stats, "the recording has no stats record"
    devices = stats[-1]["devices"]
    for name in case.devices:
        health = devices[name]["health"]
        assert shows_all(health, case), (name, health)
        assert {"faults", "reconnects", "dropped"} <= health.keys(), health


# --------------------------------------------------------------------------- faults and reconnects

#: A joystick unplugged (its FIFO replaced) after every 30 events: each time the driver reads
#: the end of the file, faults, and is reconnected to the new FIFO.
UNPLUGGED = Case(
    "LinuxJoydev_drv",
    ("Joystick",),
    ("faults", "reconnects"),
    lambda tmp: emulator_class("LinuxJoydev_drv", "JoydevEmulator")(
        tmp / "js0", scenario="disconnect", disconnect_after=30
    ),
    lambda text, emu, tmp: set_property(text, "port_name", str(tmp / "js0")),
)
LAST_FAULT = re.compile(r"last fault (\d\d:\d\d:\d\d) JoystickDisconnected: \S*js0: end of file")


def clock_times(began: float, ended: float) -> set[str]:
    """The HH:MM:SS a view may print for a moment between ``began`` and ``ended``."""
    return {
        time.strftime("%H:%M:%S", time.localtime(s)) for s in range(int(began) - 1, int(ended) + 2)
    }


def test_faults_and_reconnects_show_with_the_last_reason_and_its_time(tmp_path: Path) -> None:
    from rich.console import Console

    from gadgetctl.cli.monitor_live import LiveView
    from gadgetctl.input.manager import InputManager
    from gadgetctl.monitor.session import MonitorSession

    began = time.time()
    with UNPLUGGED.emulator(tmp_path) as emu:
        manager, configuration = InputManager.from_files([example(UNPLUGGED, emu, tmp_path)])
        try:
            session = MonitorSession(manager, configuration, selectors=["Joystick"])
            session.start()
            view = LiveView(session, Console(file=io.StringIO(), width=250, height=60))
            line = ""

            def rendered() -> bool:
                nonlocal line
                session.step()
                line = next(
                    (x for x in view.text(250, 60).splitlines() if x.startswith("Joystick ")), ""
                )
                return shows_all(counted(line), UNPLUGGED) and LAST_FAULT.search(line) is not None

            assert wait_until(rendered, timeout=WAIT, pause=0.02), line
        finally:
            manager.shutdown()
    assert LAST_FAULT.search(line).group(1) in clock_times(began, time.time()), line

    record = tmp_path / "run.ndjson"
    began = time.time()
    (tmp_path / "table").mkdir()
    with UNPLUGGED.emulator(tmp_path / "table") as emu:
        lines = monitor_child(
            UNPLUGGED, example(UNPLUGGED, emu, tmp_path / "table"), record, status=1
        )
    ended = time.time()
    row = device_rows(lines, UNPLUGGED)["Joystick"]
    assert shows_all(counted(row), UNPLUGGED), row
    assert LAST_FAULT.search(row).group(1) in clock_times(began, ended), row
    stats = [json.loads(x) for x in record.read_text().splitlines() if '"type":"stats"' in x]
    health = stats[-1]["devices"]["Joystick"]["health"]
    assert health["faults"] >= 1 and health["reconnects"] >= 1, health
    assert health["last_fault"].endswith("js0: end of file"), health
    assert began <= health["last_fault_at"] <= ended, health
