"""`gadgetctl monitor`, `gadgetctl replay` and `gadgetctl demo` without a terminal: NDJSON
streams, tables, recordings interrupted by signals, replay fidelity and speed, faults."""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO, write

WAVEFORM = REPO / "examples" / "waveform.jconf"
ALL_DEVICES = REPO / "examples" / "all_devices.jconf"
RATES = {"Waveform Sticks": 200.0, "Waveform Tracker": 120.0, "Waveform Noise": 1000.0}

pytestmark = pytest.mark.timeout(90)


def gadgetctl(*args: str | Path, timeout: float = 60, **kwargs) -> subprocess.CompletedProcess:
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("GADGETCTL_DEBUG", None)
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", *map(str, args)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        stdin=subprocess.DEVNULL,
        **kwargs,
    )


def records(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def samples_by_unit(recs: list[dict]) -> dict[tuple[str, str, int], list[dict]]:
    found: dict[tuple[str, str, int], list[dict]] = {}
    for r in recs:
        if r["type"] == "sample":
            found.setdefault((r["device"], r["kind"], r["unit"]), []).append(r)
    return found


def by_device(recs: list[dict]) -> dict[str, list[float]]:
    """Distinct sampling instants per device."""
    found: dict[str, set[float]] = {}
    for r in recs:
        if r["type"] == "sample":
            found.setdefault(r["device"], set()).add(r["timestamp"])
    return {name: sorted(stamps) for name, stamps in found.items()}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> Path:
    """Two seconds of the waveform example, recorded."""
    path = tmp_path_factory.mktemp("rec") / "waveform.ndjson"
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "--duration",
        "2",
        "--format",
        "table",
        "--interval",
        "10",
        "--record",
        path,
    )
    assert result.returncode == 0, result.stderr
    return path


# --------------------------------------------------------------------------- ndjson


def test_ndjson_stream_has_every_device_at_its_rate_in_order_without_drops():
    result = gadgetctl("monitor", WAVEFORM, "--duration", "2", "--format", "ndjson")
    assert result.returncode == 0, result.stderr
    recs = records(result.stdout)
    assert recs[0]["type"] == "header" and recs[0]["format"] == "gadgetctl-recording"
    assert all(r["v"] == 1 for r in recs)
    assert [r["type"] for r in recs[-2:]] == ["stats", "end"]
    units = samples_by_unit(recs)
    for key, rows in units.items():
        stamps = [r["timestamp"] for r in rows]
        assert all(b > a for a, b in itertools.pairwise(stamps)), (
            f"{key}: timestamps not increasing"
        )
    instants = by_device(recs)
    assert set(instants) == set(RATES)
    for name, stamps in instants.items():
        rate = (len(stamps) - 1) / (stamps[-1] - stamps[0])
        assert rate == pytest.approx(RATES[name], rel=0.02), name
        assert stamps[-1] - stamps[0] > 1.8
        gaps = [b - a for a, b in itertools.pairwise(stamps)]
        assert max(gaps) < 1.5 / RATES[name], f"{name}: a sample is missing"
    stats = recs[-2]["devices"]
    assert set(stats) == set(RATES)
    for name, entry in stats.items():
        assert entry["dropped"] == 0 and entry["faults"] == 0
        assert entry["mean_rate"] == pytest.approx(RATES[name], rel=0.02)
        assert entry["samples"] == len(instants[name])
        for field in ("p50_interval", "p99_interval", "max_gap", "jitter", "state"):
            assert field in entry
    assert recs[-1]["reason"] == "closed"
    assert recs[-1]["samples"] == sum(len(v) for v in units.values())


def test_ndjson_sample_records_carry_values_and_raw_values():
    result = gadgetctl("monitor", WAVEFORM, "--duration", "0.5", "--format", "ndjson")
    recs = records(result.stdout)
    header = recs[0]["info"]
    sticks = header["elements"]["Waveform Sticks"]
    assert sticks["element"] == "device" and sticks["type"] == "waveform_device"
    assert sticks["min"] == -1.0 and sticks["max"] == 1.0 and sticks["units"]["analog"] == 2
    assert header["elements"]["VJWand"] == {
        "element": "alias",
        "type": "alias",
        "proxy": "Wand Proxy",
    }
    assert header["elements"]["Wand Proxy"]["device"] == "Waveform Tracker"
    analog = next(
        r
        for r in recs
        if r["type"] == "sample" and r["kind"] == "analog" and r["device"] == "Waveform Sticks"
    )
    assert analog["value"] == pytest.approx((analog["raw"] + 1.0) / 2.0)
    position = next(r for r in recs if r["type"] == "sample" and r["kind"] == "position")
    assert len(position["value"]) == 4 and position["value"][3] == [0.0, 0.0, 0.0, 1.0]
    assert position["value"][1][3] == pytest.approx(
        1.6
    )  # centered at 1.5 m, raised 10 cm by the filter
    statuses = [r for r in recs if r["type"] == "status"]
    assert {r["name"] for r in statuses} >= {"Waveform Sticks", "VJWand", "Wand Proxy"}
    assert all(r["state"] in ("running", "active") for r in statuses)


def test_ndjson_per_frame_and_selected_proxies():
    # 10 frames a second for a second of wall clock (a loaded machine may run fewer)
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "VJ*",
        "Waveform Noise",
        "--rate",
        "10",
        "--duration",
        "1",
        "--format",
        "ndjson",
        "--per-frame",
    )
    assert result.returncode == 0, result.stderr
    recs = records(result.stdout)
    frames = [r for r in recs if r["type"] == "frame"]
    assert 5 <= len(frames) <= 12
    assert not [r for r in recs if r["type"] == "sample"]
    numbers = [f["frame"] for f in frames]
    assert numbers == sorted(numbers)
    last = frames[-1]["devices"]
    assert set(last) == {
        "Waveform Noise",
        "VJAnalog0",
        "VJAnalog1",
        "VJButton0",
        "VJButton1",
        "VJWand",
        "VJHead",
        "VJNoise",
    }
    # each frame counts the samples since the previous one (1 kHz: about 100 at 10 frames/s,
    # more in a frame after a stall); together they are the device's samples of the run
    counts = [f["devices"]["Waveform Noise"]["count"] for f in frames]
    assert all(isinstance(c, int) and c >= 0 for c in counts) and sum(counts) >= 100
    assert 0.0 <= last["VJAnalog0"]["values"]["analog"]["0"] <= 1.0
    assert last["VJButton0"]["values"]["digital"]["0"] in (0, 1, 2, 3)
    assert len(last["VJWand"]["values"]["position"]["0"]) == 4


def test_selected_aliases_stream_one_sample_per_frame_with_new_data():
    # 10 frames in the second (--duration is wall-clock: a loaded machine may run fewer), each
    # with new data from the 120 Hz tracker: one alias sample per frame, never the tracker's
    # 120 samples a second
    result = gadgetctl(
        "monitor", WAVEFORM, "VJWand", "--rate", "10", "--duration", "1", "--format", "ndjson"
    )
    recs = records(result.stdout)
    samples = [r for r in recs if r["type"] == "sample"]
    assert samples and {r["device"] for r in samples} == {"VJWand"}
    assert {r["kind"] for r in samples} == {"position"}
    assert 5 <= len(samples) <= 12
    stamps = [r["timestamp"] for r in samples]
    assert stamps == sorted(set(stamps))


# --------------------------------------------------------------------------- table, stats, demo


def test_table_is_the_default_without_a_terminal_and_stats_are_printed():
    started = time.monotonic()
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform*",
        "--duration",
        "1.2",
        "--interval",
        "0.5",
        "--stats",
        "--units",
        "centimeters",
    )
    assert result.returncode == 0, result.stderr
    assert time.monotonic() - started < 15
    out = result.stdout
    assert out.count("NAME ") >= 2 and "\x1b" not in out
    assert "Waveform Noise" in out and "running" in out and " cm" in out
    assert "statistics:" in out and "MEAN Hz" in out
    # the statistics' row (a table row above it shows 1000.0 too when its window rate does)
    statistics = out.split("statistics:", 1)[1]
    line = next(line for line in statistics.splitlines() if line.startswith("Waveform Noise"))
    assert "1000.0" in line.split()  # its mean rate
    assert line.split()[-2] == "0"  # no faults


def test_demo_prints_a_readable_table_and_exits_0_without_a_terminal():
    started = time.monotonic()
    result = gadgetctl("demo", "--duration", "1.5")
    assert result.returncode == 0, result.stderr
    assert time.monotonic() - started < 20
    assert "waveform.jconf" in result.stdout and "Waveform Sticks" in result.stdout
    assert "statistics:" in result.stdout and "\x1b" not in result.stdout


# --------------------------------------------------------------------------- usage errors


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["monitor", "missing.jconf"], "no such configuration file"),
        (["monitor", "Waveform*"], "no configuration given"),
        (["monitor", WAVEFORM, "Nobody"], "matches 'Nobody'"),
        (["monitor", WAVEFORM, "--format", "live"], "needs a terminal"),
        (["monitor", WAVEFORM, "--rate", "0"], "--rate"),
        (["replay", REPO / "README.md"], "not a gadgetctl recording"),
        (["replay", "missing.ndjson"], "cannot read"),
        (["replay", REPO / "README.md", "--summary"], "not a gadgetctl recording"),
    ],
)
def test_usage_errors_exit_2_with_one_line(args, message):
    result = gadgetctl(*args)
    assert result.returncode == 2, result.stderr
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr


def test_unreadable_configuration_is_a_usage_error(tmp_path):
    bad = write(tmp_path / "bad.jconf", "<configuration><elements><broken")
    result = gadgetctl("monitor", bad, "--duration", "0.2")
    assert result.returncode == 2
    assert "cannot load the configuration" in result.stderr and "Traceback" not in result.stderr


def test_existing_record_file_needs_overwrite(tmp_path):
    target = write(tmp_path / "old.ndjson", "keep me\n")
    result = gadgetctl("monitor", WAVEFORM, "--duration", "0.2", "--record", target)
    assert result.returncode == 2 and "--overwrite" in result.stderr
    assert target.read_text() == "keep me\n"
    result = gadgetctl("monitor", WAVEFORM, "--duration", "0.3", "--record", target, "--overwrite")
    assert result.returncode == 0
    assert records(target.read_text())[0]["type"] == "header"


# --------------------------------------------------------------------------- recording and signals


@pytest.mark.parametrize(
    ("signum", "reason"), [(signal.SIGINT, "interrupted"), (signal.SIGTERM, "terminated")]
)
def test_interrupted_recording_is_complete_and_summarised(tmp_path, signum, reason):
    path = tmp_path / "interrupted.ndjson"
    env = {**os.environ, "NO_COLOR": "1"}
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            str(WAVEFORM),
            "--format",
            "table",
            "--interval",
            "100",
            "--record",
            str(path),
        ],
        cwd=REPO,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            if path.exists() and path.read_text(errors="replace").count('"type":"sample"') > 500:
                break
            time.sleep(0.05)
        else:
            pytest.fail("the monitor never recorded")
        process.send_signal(signum)
        _, err = process.communicate(timeout=20)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode in (0, 1), err
    recs = records(path.read_text())
    assert recs[-1]["type"] == "end" and recs[-1]["reason"] == reason
    assert recs[-2]["type"] == "stats"
    summary = gadgetctl("replay", path, "--summary")
    assert summary.returncode == 0, summary.stderr
    assert "Waveform Noise" in summary.stdout and "error" not in summary.stdout
    as_json = json.loads(gadgetctl("replay", path, "--summary", "--format", "ndjson").stdout)
    assert as_json["end_reason"] == reason and not as_json["problems"]


# --------------------------------------------------------------------------- replay


def _relative(rows: list[dict]) -> list[float]:
    return [r["timestamp"] - rows[0]["timestamp"] for r in rows]


@pytest.mark.parametrize("speed", [1, 10])
def test_replay_reproduces_every_sample_sequence(recorded, speed):
    result = gadgetctl("replay", recorded, "--speed", str(speed), "--format", "ndjson")
    assert result.returncode == 0, result.stderr
    original = samples_by_unit(records(recorded.read_text()))
    replayed_recs = records(result.stdout)
    replayed = samples_by_unit(replayed_recs)
    assert set(replayed) == set(original)
    for key, rows in original.items():
        again = replayed[key]
        assert [(r["value"], r.get("raw")) for r in again] == [
            (r["value"], r.get("raw")) for r in rows
        ], key
        assert [t * speed for t in _relative(again)] == pytest.approx(_relative(rows), abs=1e-6), (
            key
        )
    # the samples span the recording's time scaled by the speed (the wall-clock side, how
    # closely the replay keeps to that schedule on a given machine, is bench/bench_replay.py)
    stamps = sorted(r["timestamp"] for r in replayed_recs if r["type"] == "sample")
    recorded_stamps = sorted(
        r["timestamp"] for r in records(recorded.read_text()) if r["type"] == "sample"
    )
    assert (stamps[-1] - stamps[0]) * speed == pytest.approx(
        recorded_stamps[-1] - recorded_stamps[0], abs=1e-6
    )
    assert [r["type"] for r in replayed_recs[-2:]] == ["stats", "end"]
    assert replayed_recs[-1]["timestamp"] >= stamps[-1] and replayed_recs[-1]["reason"] == "closed"


def test_replay_against_another_configuration_with_a_name_mapping(tmp_path, recorded):
    text = (
        WAVEFORM.read_text()
        .replace('"Waveform Sticks"', '"Lab Joystick"')
        .replace("<device>Waveform Sticks</device>", "<device>Lab Joystick</device>")
    )
    other = write(tmp_path / "other.jconf", text)
    result = gadgetctl(
        "replay",
        recorded,
        "--config",
        other,
        "--map",
        "Waveform Sticks=Lab Joystick",
        "--format",
        "ndjson",
        "Stick X Proxy",
        "Lab Joystick",
    )
    assert result.returncode == 0, result.stderr
    recs = records(result.stdout)
    proxy = [r for r in recs if r["type"] == "sample" and r["device"] == "Stick X Proxy"]
    device = [
        r
        for r in recs
        if r["type"] == "sample"
        and r["device"] == "Lab Joystick"
        and r["kind"] == "analog"
        and r["unit"] == 0
    ]
    original = samples_by_unit(records(recorded.read_text()))[("Waveform Sticks", "analog", 0)]
    assert [r["value"] for r in device] == [r["value"] for r in original]
    recorded_values = {r["value"] for r in original}
    assert (
        len(proxy) > 50 and {r["value"] for r in proxy} <= recorded_values
    )  # normalised by the proxy
    assert recs[0]["info"]["elements"]["Lab Joystick"]["type"] == "waveform_device"


def test_replay_refuses_mapping_names_that_are_not_recorded(recorded):
    result = gadgetctl(
        "replay",
        recorded,
        "--map",
        "Ghost=Other",
        "--speed",
        "20",
        "--format",
        "table",
        "--interval",
        "10",
    )
    assert result.returncode == 2 and result.stdout == ""
    assert "'Ghost' is not a device of the recording" in result.stderr


def test_replay_usage_errors(recorded):
    assert gadgetctl("replay", recorded, "--map", "nonsense").returncode == 2
    assert gadgetctl("replay", recorded, "--speed", "0").returncode == 2
    result = gadgetctl("replay", recorded, "--config", "missing.jconf")
    assert result.returncode == 2 and "no such configuration file" in result.stderr


def test_replay_loop_runs_until_the_duration(recorded):
    result = gadgetctl(
        "replay",
        recorded,
        "--speed",
        "10",
        "--loop",
        "--duration",
        "1",
        "--format",
        "ndjson",
        "Waveform Sticks",
    )
    assert result.returncode == 0, result.stderr
    stamps = by_device(records(result.stdout))["Waveform Sticks"]
    assert len(stamps) > 600  # 400 samples per pass, about five passes in a second at x10
    assert all(b > a for a, b in itertools.pairwise(stamps))


# --------------------------------------------------------------------------- faults


FAULTY_INIT = """\
GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Faulty_drv"
ELEMENT_TYPES = {"faulty_device": ("analog",)}


def register(registry):
    from .wrapper import FaultyDevice

    registry.register_device(FaultyDevice)
"""
FAULTY_WRAPPER = '''\
from gadgetctl.input import Analog, SamplingMode


class FaultyDevice(Analog):
    """Samples for a moment, then raises in sample() and cannot be opened again."""

    ELEMENT_TYPE = "faulty_device"
    SAMPLING = SamplingMode.SCHEDULED
    sample_interval = 0.01

    def __init__(self):
        super().__init__()
        self.calls = 0
        self.starts = 0

    def start_sampling(self):
        self.starts += 1
        if self.starts > 1:
            raise OSError("device unplugged")

    def sample(self):
        self.calls += 1
        if self.calls > 20:
            raise RuntimeError("sensor exploded")
        self.add_analog_sample([0.5])
'''
FAULTY_JDEF = """\
<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings definition.version="3.1"?>
<definition xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/definition" name="faulty_device">
   <definition_version version="1" label="Faulty Device">
      <abstract>false</abstract>
      <help>A test device that fails.</help>
      <parent>analog_device</parent>
      <category>/Devices/Analog</category>
      <property valuetype="float" variable="false" name="min">
         <help>Lowest value.</help>
         <value label="Minimum" defaultvalue="0.0"/>
      </property>
      <property valuetype="float" variable="false" name="max">
         <help>Highest value.</help>
         <value label="Maximum" defaultvalue="1.0"/>
      </property>
      <upgrade_transform/>
   </definition_version>
</definition>
"""
FAULTY_CONFIG = """\
<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="faulty">
   <elements>
      <input_manager name="Input Manager" version="2">
         <driver>Faulty_drv</driver>
         <driver_path>drivers</driver_path>
      </input_manager>
      <faulty_device name="Bad Sensor" version="1"/>
      <waveform_device name="Good Wave" version="1">
         <rate>500.0</rate>
         <analog_waveform>sine</analog_waveform>
         <event_period>0.0</event_period>
      </waveform_device>
      <analog_proxy name="Bad Proxy" version="1">
         <device>Bad Sensor</device>
         <unit>0</unit>
      </analog_proxy>
   </elements>
</configuration>
"""


def faulty_configuration(directory: Path) -> Path:
    write(directory / "drivers" / "Faulty_drv" / "__init__.py", FAULTY_INIT)
    write(directory / "drivers" / "Faulty_drv" / "wrapper.py", FAULTY_WRAPPER)
    write(directory / "drivers" / "Faulty_drv" / "faulty_device.jdef", FAULTY_JDEF)
    return write(directory / "faulty.jconf", FAULTY_CONFIG)


def test_a_device_that_raises_is_faulted_in_json_and_the_others_keep_their_rate(tmp_path):
    config = faulty_configuration(tmp_path)
    result = gadgetctl("monitor", config, "--duration", "2", "--format", "ndjson")
    assert result.returncode == 1, result.stderr
    assert "Bad Sensor: faulted" in result.stderr
    recs = records(result.stdout)
    states = [
        (r["state"], r["reason"])
        for r in recs
        if r["type"] == "status" and r["name"] == "Bad Sensor"
    ]
    assert states[0] == ("running", None)
    assert ("faulted", "RuntimeError: sensor exploded") in states
    assert states[-1] == ("faulted", "OSError: device unplugged")
    stats = recs[-2]["devices"]
    assert stats["Bad Sensor"]["faults"] == 1 and stats["Bad Sensor"]["state"] == "faulted"
    assert stats["Bad Sensor"]["samples"] == 20
    assert stats["Good Wave"]["mean_rate"] == pytest.approx(500.0, rel=0.02)
    assert stats["Good Wave"]["dropped"] == 0 and stats["Good Wave"]["state"] == "running"
    good = by_device(recs)["Good Wave"]
    assert (len(good) - 1) / (good[-1] - good[0]) == pytest.approx(500.0, rel=0.02)
    assert good[-1] - good[0] > 1.8


def test_a_faulted_device_shows_in_the_table(tmp_path):
    config = faulty_configuration(tmp_path)
    result = gadgetctl("monitor", config, "--duration", "1", "--interval", "10")
    assert result.returncode == 1
    line = next(line for line in result.stdout.splitlines() if line.startswith("Bad Sensor"))
    assert "faulted" in line and "device unplugged" in line
