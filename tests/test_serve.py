"""`gadgetctl serve` against gadgetctl's own VRPN client over loopback: what clients read is
what the input manager produced (the serve --record file is the reference), many clients
at once by both ways of connecting, --allow, a taken port, clean exits on signals."""

from __future__ import annotations

import itertools
import json
import signal
import socket

import numpy as np
import pytest

from gadgetctl.input.testing import wait_until
from gadgetctl.input.transforms import matrices_from_pos_quat
from gadgetctl.vrpn import VrpnClient

from conftest import write
from serve_process import ServeProcess

CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="serve test">
   <elements>
      <waveform_device name="Lab Tracker" version="1">
         <rate>{rate}</rate>
         <position_path>circle</position_path>
         <position_path>spin</position_path>
         <position_path>figure_eight</position_path>
         <position_period>2.0</position_period>
         <event_period>0.0</event_period>
      </waveform_device>
      <waveform_device name="Lab Buttons" version="1">
         <rate>200.0</rate>
         <analog_waveform>sine</analog_waveform>
         <button_period>0.2</button_period>
         <button_period>0.3</button_period>
         <event_period>0.0</event_period>
      </waveform_device>
      <position_proxy name="Wand Proxy" version="1"><device>Lab Tracker</device><unit>1</unit></position_proxy>
      <alias name="VJWand" version="1"><proxy>Wand Proxy</proxy></alias>
   </elements>
</configuration>
"""


def config(tmp_path, rate: float = 250.0):
    return write(tmp_path / "served.jconf", CONFIG.format(rate=rate))


class Collector:
    def __init__(self, location: str, devices: list[str]) -> None:
        self.client = VrpnClient(location, devices)
        self.messages = []

    def pump(self) -> None:
        self.messages += self.client.poll(0.01)

    def poses(self, sender: str) -> list:
        return [
            m for m in self.messages if m.sender == sender and m.type == "vrpn_Tracker Pos_Quat"
        ]


def recorded(path, device: str, kind: str) -> dict[int, list]:
    units: dict[int, list] = {}
    for line in path.read_text().splitlines():
        record = json.loads(line)
        if record.get("type") == "sample" and record["device"] == device and record["kind"] == kind:
            units.setdefault(record["unit"], []).append(record["value"])
    return units


@pytest.mark.timeout(90)
def test_clients_read_exactly_what_was_served(tmp_path):
    recording = tmp_path / "served.ndjson"
    with ServeProcess(config(tmp_path), "--record", recording) as serve:
        port = serve.port
        names = ["Lab_Tracker", "Lab_Buttons", "VJWand"]
        clients = [
            Collector(f"127.0.0.1:{port}", names),
            Collector(f"tcp://127.0.0.1:{port}", names),
            Collector(f"tcp://127.0.0.1:{port}", names),
        ]

        def enough() -> bool:
            for c in clients:
                c.pump()
            return all(
                len(c.poses("Lab_Tracker")) >= 3 * 200 and len(c.poses("VJWand")) >= 20
                for c in clients
            )

        wait_until(enough, timeout=40)
        for c in clients:
            c.client.close()
        assert serve.stop(signal.SIGINT) == 0, serve.stderr
    assert "Traceback" not in serve.stderr
    assert serve.events[-1]["event"] == "stopped" and serve.events[-1]["dropped"] == 0
    assert sum(e["event"] == "connected" for e in serve.events) == 3
    served = recorded(recording, "Lab Tracker", "position")
    for index, c in enumerate(clients):
        for sensor in range(3):
            matrices = np.asarray(served[sensor])
            got = [m.report for m in c.poses("Lab_Tracker") if m.report.sensor == sensor]
            positions = np.asarray([r.position for r in got])
            rebuilt = matrices_from_pos_quat(positions, np.asarray([r.quat for r in got]))
            if index > 0:
                # doubles travel unchanged and by TCP nothing is lost: the received poses are
                # a run of consecutive served ones
                # (a periodic path repeats its poses: try every served pose that matches the first)
                starts = np.nonzero(np.abs(matrices - rebuilt[0]).max(axis=(1, 2)) < 1e-9)[0]
                runs = [matrices[i : i + len(positions)] for i in starts]
                assert any(
                    len(run) == len(positions)
                    and (run[:, :3, 3] == positions).all()
                    and np.abs(run - rebuilt).max() < 1e-9
                    for run in runs
                ), f"client {index} sensor {sensor}: not a run of consecutive served poses"
            else:  # by UDP on loopback: every received one is a served one
                served_rows = {tuple(row) for row in matrices[:, :3, 3]}
                assert all(tuple(p) in served_rows for p in positions)
        # buttons: the transitions, exactly
        changes = [
            (m.report.button, m.report.state)
            for m in c.messages
            if m.sender == "Lab_Buttons" and m.type == "vrpn_Button Change"
        ]
        assert {b for b, _ in changes} == {0, 1} and {s for _, s in changes} == {0, 1}
        for button in (0, 1):
            states = [s for b, s in changes if b == button]
            assert all(a != b for a, b in itertools.pairwise(states))  # each a real transition
        # the alias serves the proxy's pose as sensor 0
        assert {m.report.sensor for m in c.poses("VJWand")} == {0}


@pytest.mark.timeout(60)
@pytest.mark.parametrize("frame_rate", ["1000", "20"])
def test_clients_are_heard_between_frames_at_any_frame_rate(tmp_path, frame_rate):
    """At 1 kHz the waits between frames are sleeps with a pass over the sockets now and
    then; at 20 Hz they watch the sockets throughout: either way a client that connects while
    frames run is accepted, answered and served, and so is a second one after it."""
    with ServeProcess(config(tmp_path), "--rate", frame_rate) as serve:
        location = f"tcp://127.0.0.1:{serve.port}"
        first = Collector(location, ["Lab_Tracker"])
        try:
            wait_until(lambda: first.pump() or len(first.poses("Lab_Tracker")) >= 30, timeout=20)
            second = Collector(location, ["Lab_Tracker"])
            try:
                wait_until(
                    lambda: second.pump() or len(second.poses("Lab_Tracker")) >= 30, timeout=20
                )
            finally:
                second.client.close()
        finally:
            first.client.close()
        assert serve.stop() == 0, serve.stderr
    assert sum(e["event"] == "connected" for e in serve.events) == 2
    for collector in (first, second):
        times = [m.timestamp for m in collector.poses("Lab_Tracker")]
        assert times == sorted(times)


@pytest.mark.timeout(60)
def test_allow_refuses_clients_outside_the_networks(tmp_path):
    with ServeProcess(config(tmp_path), "--allow", "10.0.0.0/8") as serve:
        refused = VrpnClient(f"tcp://127.0.0.1:{serve.port}", ["Lab_Tracker"])
        lob = VrpnClient(f"127.0.0.1:{serve.port}", ["Lab_Tracker"])
        try:
            assert not refused.wait_connected(1.5) and not lob.wait_connected(0.5)
        finally:
            refused.close()
            lob.close()
        assert serve.stop() == 0
    assert not any(e["event"] == "connected" for e in serve.events)
    with ServeProcess(
        config(tmp_path), "--allow", "127.0.0.0/8", "--allow", "192.168.0.0/16"
    ) as serve:
        client = VrpnClient(f"tcp://127.0.0.1:{serve.port}", ["Lab_Tracker"])
        try:
            assert client.wait_connected(10)
        finally:
            client.close()
        assert serve.stop() == 0


@pytest.mark.timeout(60)
def test_a_taken_port_is_a_one_line_error_naming_the_holder(tmp_path):
    holder = socket.socket()
    holder.bind(("127.0.0.1", 0))
    holder.listen()
    port = holder.getsockname()[1]
    try:
        import subprocess
        import sys

        from conftest import REPO

        result = subprocess.run(
            [
                sys.executable,
                "-m",
                "gadgetctl",
                "serve",
                str(config(tmp_path)),
                "--port",
                str(port),
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=40,
        )
    finally:
        holder.close()
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert (
        len(lines) == 1
        and f"cannot serve on 127.0.0.1:{port}: TCP port {port} is taken by" in lines[0]
    )
    assert "pytest" in lines[0] or "python" in lines[0]


@pytest.mark.timeout(60)
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_stops_cleanly_on_signals_with_a_client_connected(tmp_path, sig):
    recording = tmp_path / "r.ndjson"
    with ServeProcess(config(tmp_path), "--record", recording) as serve:
        client = VrpnClient(f"tcp://127.0.0.1:{serve.port}", ["Lab_Tracker"])
        try:
            assert client.wait_connected(10)
            serve.wait_event("connected")
            assert serve.stop(sig) == 0
            wait_until(lambda: (client.poll(0.01), client.state != "connected")[1], timeout=10)
        finally:
            client.close()
    stopped = serve.events[-1]
    assert stopped["event"] == "stopped" and stopped["reason"] in ("interrupted", "terminated")
    assert "Traceback" not in serve.stderr
    end = json.loads(recording.read_text().splitlines()[-1])
    assert end["type"] == "end"
