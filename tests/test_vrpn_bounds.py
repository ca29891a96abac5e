"""Bounds on what a VRPN peer controls: sender and type names (issue 24, item 1) and sensor
ids (item 12), each counted and reported when a peer goes past them."""

from __future__ import annotations

import json
import socket
import struct
import time

import pytest
from vrpn_peers import COOKIE, RawServer, describe, frame

from gadgetctl.vrpn import codecs
from gadgetctl.vrpn.endpoint import Endpoint
from gadgetctl.vrpn.wire import MAX_IDS, SENDER_DESCRIPTION, TYPE_DESCRIPTION, StreamDecoder

pytestmark = pytest.mark.timeout(60)


def test_ever_new_names_under_the_same_ids_never_grow_the_tables() -> None:
    left, right = socket.socketpair()
    with left, right:
        endpoint = Endpoint(left)
        # a setup with 10 senders, then 5,000 descriptions renaming them over and over
        stream = b"".join(describe(-1, i, f"Setup{i}") for i in range(10))
        stream += describe(-2, 0, codecs.TRACKER_POS_QUAT)
        stream += b"".join(describe(-1, i % 10, f"Name{i}") for i in range(5000))
        stream += b"".join(describe(-2, 1 + i % 10, f"type {i}") for i in range(5000))
        endpoint.translate(StreamDecoder().feed(stream))
        senders = endpoint.setup_senders | endpoint.later_senders
        assert len(senders) <= 10 and len(endpoint.remote_senders) == 10
        assert len(endpoint.remote_types) == 11
        assert endpoint.counters["renamed_senders"] == 5000
        assert endpoint.counters["renamed_types"] == 4990  # the first ten were new
        assert senders == {f"Name{i}" for i in range(4990, 5000)}
        assert len(senders) <= MAX_IDS


def _stray_sensor_server(conn: socket.socket, _n: int) -> None:
    """Tracker0 with sensors 0 and 1, and once a report for sensor 2**31 - 1."""
    conn.sendall(
        COOKIE
        + describe(SENDER_DESCRIPTION, 0, "Tracker0")
        + describe(TYPE_DESCRIPTION, 0, codecs.TRACKER_POS_QUAT)
    )
    stray = struct.pack(">ii3d4d", 2**31 - 1, 0, 0, 0, 0, 0, 0, 0, 1)
    sent_stray = False
    deadline = time.monotonic() + 8
    tick = 0
    while time.monotonic() < deadline:
        now = time.time()
        sec, usec = int(now), int(now % 1 * 1e6)
        out = b""
        for sensor in (0, 1):
            payload = codecs.encode_pose(sensor, (float(sensor), 0.0, 0.0))
            out += struct.pack(">IiiiiI", 24 + 64, sec, usec, 0, 0, 0) + payload
        if not sent_stray and tick == 3:
            out += frame(0, 0, stray)
            sent_stray = True
        conn.sendall(out)
        tick += 1
        time.sleep(0.02)


def test_a_report_for_a_huge_sensor_id_is_reported_and_the_watch_runs(cli) -> None:
    with RawServer(_stray_sensor_server) as server:
        result = cli(
            "monitor",
            f"vrpn:Tracker0@tcp://127.0.0.1:{server.port}",
            "--duration",
            "0.5",
            "--format",
            "ndjson",
        )
    assert result.exit_code == 0, result.stderr
    assert "tracker_count" not in result.stderr and "Traceback" not in result.stderr
    assert "sensor 2147483647 (sensors are 0 to 1023)" in result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines() if line.strip()]
    name = f"Tracker0@tcp://127.0.0.1:{server.port}"
    assert records[0]["info"]["elements"][name]["units"] == {"position": 2}
    statuses = {r["name"]: r["state"] for r in records if r["type"] == "status"}
    assert statuses[name] == "running"
