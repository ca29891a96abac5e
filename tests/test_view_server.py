"""The page's server: --allow refuses other clients before anything is sent; a taken port is
a one-line usage error."""

from __future__ import annotations

import ipaddress
import socket
import subprocess
import sys

import pytest

from gadgetctl.input.manager import InputManager
from gadgetctl.monitor.session import MonitorSession

pytestmark = pytest.mark.timeout(90)

CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="one">
<elements>
<waveform_device name="Tracker" version="1"><rate>60</rate></waveform_device>
<position_proxy name="TrackerProxy" version="1"><device>Tracker</device><unit>0</unit></position_proxy>
</elements>
</configuration>
"""


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "one.jconf"
    path.write_text(CONFIG, encoding="utf-8")
    return path


def serve(config, allow):
    from gadgetctl.view.server import ViewServer

    manager, configuration = InputManager.from_files([config])
    session = MonitorSession(manager, configuration, rate=60)
    session.start()
    refused = []
    server = ViewServer(
        session,
        configuration,
        port=0,
        allow=[ipaddress.ip_network(a) for a in allow],
        on_refused=refused.append,
    )
    return manager, server, refused


def first_message(port: int):
    """What a viser client at 127.0.0.1 gets first: ('message', size) or ('closed', code)."""
    import viser
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    with connect(
        f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], open_timeout=20
    ) as ws:
        try:
            return "message", len(ws.recv(timeout=20))
        except ConnectionClosed as closed:
            return "closed", closed.rcvd.code if closed.rcvd else None


@pytest.mark.parametrize(
    ("allow", "expected"), [(["10.0.0.0/8"], "closed"), (["127.0.0.0/8"], "message")]
)
def test_allow_closes_other_clients_before_anything_is_sent(config, allow, expected):
    manager, server, refused = serve(config, allow)
    try:
        kind, detail = first_message(server.port)
        assert kind == expected
        if expected == "closed":
            assert detail == 1008
            assert refused == ["127.0.0.1"] and server.refused == 1
        else:
            assert detail > 0 and refused == []
    finally:
        server.stop()
        manager.shutdown()


def test_a_taken_port_is_a_usage_error(config):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run(
            [
                sys.executable,
                "-m",
                "gadgetctl",
                "view",
                str(config),
                "--port",
                str(port),
                "--no-check",
                "--duration",
                "5",
            ],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        f"gadgetctl: error: cannot serve the page on 127.0.0.1:{port}: the port is taken"
    ]
    assert "Traceback" not in done.stderr
