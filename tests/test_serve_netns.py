"""Two machines: `gadgetctl serve --bind` in one network namespace, `gadgetctl monitor` with a
`vrpn` element in another, joined by a veth pair (needs root and iproute2; CI runs as root
and .ci/run installs iproute2). Samples arrive; the server killed shows the device faulted,
and once it is back samples arrive again. The namespaces are removed whatever happens."""

from __future__ import annotations

import contextlib
import json
import os
import queue
import shutil
import subprocess
import sys
import threading
import time

import pytest

from conftest import REPO, write
from serve_process import ServeProcess

pytestmark = pytest.mark.skipif(
    (os.geteuid() != 0 or shutil.which("ip") is None) and not os.environ.get("CI"),
    reason="needs root and iproute2 (CI has both)",
)

SERVER_IP, CLIENT_IP = "10.231.7.1", "10.231.7.2"

RECEIVER = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="far side">
   <elements>
      <input_manager name="Input Manager" version="2"><driver>VRPN_drv</driver></input_manager>
      <vrpn name="Remote" version="3">
         <tracker_server>Waveform_Tracker@{ip}</tracker_server>
         <button_server>VJButton0@{ip}</button_server>
         <analog_server></analog_server>
         <tracker_count>3</tracker_count><button_count>1</button_count><analog_count>0</analog_count>
      </vrpn>
      <position_proxy name="Wand" version="1"><device>Remote</device><unit>0</unit></position_proxy>
   </elements>
</configuration>
"""


def ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, timeout=30)


@contextlib.contextmanager
def two_namespaces():
    tag = f"{os.getpid() % 100000}"
    server, client = f"gsrv{tag}", f"gcli{tag}"
    made: list[str] = []
    try:
        for ns in (server, client):
            ip("netns", "add", ns)
            made.append(ns)
        ip("link", "add", f"vs{tag}", "type", "veth", "peer", "name", f"vc{tag}")
        ip("link", "set", f"vs{tag}", "netns", server)
        ip("link", "set", f"vc{tag}", "netns", client)
        for ns, dev, addr in ((server, f"vs{tag}", SERVER_IP), (client, f"vc{tag}", CLIENT_IP)):
            ip("-n", ns, "addr", "add", f"{addr}/24", "dev", dev)
            ip("-n", ns, "link", "set", dev, "up")
            ip("-n", ns, "link", "set", "lo", "up")
        yield server, client
    finally:
        for ns in made:  # deleting a namespace deletes its end of the veth pair too
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=30)


class Monitor:
    """`gadgetctl monitor CONFIG --format ndjson` in a namespace, its records read by a thread."""

    def __init__(self, namespace: str, config) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        self.process = subprocess.Popen(
            [
                "ip",
                "netns",
                "exec",
                namespace,
                sys.executable,
                "-m",
                "gadgetctl",
                "monitor",
                str(config),
                "Remote",
                "Wand",
                "--format",
                "ndjson",
            ],
            cwd=REPO,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.records: queue.Queue[tuple[float, dict]] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stdout:
            with contextlib.suppress(ValueError):
                self.records.put((time.monotonic(), json.loads(line)))

    def wait_for(self, predicate, timeout: float) -> tuple[float, dict]:
        """(arrival time, record) of the first record matching ``predicate``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                arrival, record = self.records.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                break
            if predicate(record):
                return arrival, record
        raise AssertionError(
            f"no matching record within {timeout} s (monitor alive: {self.process.poll() is None})"
        )

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
        try:
            self.process.wait(20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(10)


def is_sample(record: dict) -> bool:
    return (
        record.get("type") == "sample"
        and record.get("device") == "Remote"
        and record["kind"] == "position"
    )


def state_of(*states: str):
    return lambda r: (
        r.get("type") == "status" and r.get("name") == "Remote" and r.get("state") in states
    )


@pytest.mark.timeout(180)
def test_serve_in_one_namespace_monitor_in_another(tmp_path):
    config = write(tmp_path / "far.jconf", RECEIVER.format(ip=SERVER_IP))
    serve_args = (
        REPO / "examples" / "waveform.jconf",
        "--bind",
        SERVER_IP,
        "--port",
        "3883",
        "--allow",
        f"{CLIENT_IP}/32",
    )
    with two_namespaces() as (server_ns, client_ns):
        prefix = ["ip", "netns", "exec", server_ns]
        serve = ServeProcess(*serve_args, prefix=prefix)
        monitor = Monitor(client_ns, config)
        try:
            assert serve.listening["host"] == SERVER_IP
            monitor.wait_for(is_sample, timeout=40)
            connected = serve.wait_event("connected", timeout=20)
            assert connected["client"].startswith(CLIENT_IP + ":") and connected["detail"] == "lob"

            serve.kill()  # the server goes away without a word
            # CLOCK_MONOTONIC: the clock of the monitor's timestamps too
            killed = time.perf_counter()
            monitor.wait_for(state_of("faulted", "reconnecting"), timeout=40)
            assert "no authentication" in serve.stderr  # said on start-up: bound beyond loopback

            serve = ServeProcess(*serve_args, prefix=prefix)
            listening = time.perf_counter()  # (read as serve printed it)
            _, first = monitor.wait_for(
                lambda r: is_sample(r) and r["timestamp"] > killed, timeout=40
            )
            # the figure (within 2 s); here only a hang guard, whatever the load
            print(
                f"samples again {first['timestamp'] - listening:.2f} s after the server listened again"
            )
            assert serve.wait_event("connected", timeout=20)["client"].startswith(CLIENT_IP + ":")
        finally:
            monitor.stop()
            serve.kill()
        assert "Traceback" not in monitor.process.stderr.read()
