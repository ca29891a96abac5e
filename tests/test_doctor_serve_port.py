"""`doctor --serve-port` and `serve` on a taken port name the process holding it."""

from __future__ import annotations

import json
import socket
import subprocess
import sys

import pytest

from gadgetctl.doctor.owners import port_owners

from conftest import REPO

HOLDER = """
import socket, sys, time
kind = socket.SOCK_STREAM if sys.argv[1] == "tcp" else socket.SOCK_DGRAM
s = socket.socket(socket.AF_INET, kind)
s.bind(("127.0.0.1", 0))
if kind == socket.SOCK_STREAM:
    s.listen()
print(s.getsockname()[1], flush=True)
sys.stdin.read()
"""


@pytest.fixture(params=["tcp", "udp"])
def holder(request, tmp_path):
    script = tmp_path / "port_holder.py"
    script.write_text(HOLDER)
    process = subprocess.Popen(
        [sys.executable, str(script), request.param],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        port = int(process.stdout.readline())
        yield request.param, port, process.pid
    finally:
        process.stdin.close()
        process.wait(timeout=10)


@pytest.mark.timeout(30)
def test_port_owners_finds_the_process(holder):
    protocol, port, pid = holder
    owners = port_owners(protocol, port)
    assert [o.pid for o in owners] == [pid]
    assert "port_holder.py" in owners[0].command


@pytest.mark.timeout(30)
def test_a_free_port_has_no_owner():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    assert port_owners("tcp", port) == [] and port_owners("udp", port) == []


@pytest.mark.timeout(60)
def test_doctor_serve_port_names_the_holder(cli, holder):
    protocol, port, pid = holder
    result = cli("doctor", "--serve-port", f"127.0.0.1:{port}", "--format", "json", cwd=REPO)
    assert result.exit_code == 1
    report = json.loads(result.stdout)
    check = report["serve_port"]
    assert check["status"] == "problem" and check["code"] == "DRV120"
    assert f"{protocol.upper()} port {port} is taken by python" in check["detail"]
    assert f"(pid {pid})" in check["detail"]
    assert [d["code"] for d in report["diagnostics"]] == ["DRV120"]


@pytest.mark.timeout(60)
def test_doctor_serve_port_free_and_bad(cli):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    result = cli("doctor", "--serve-port", str(port), cwd=REPO)
    assert result.exit_code == 0, result.stdout
    assert f"TCP and UDP port {port} are free on 127.0.0.1" in result.stdout
    bad = cli("doctor", "--serve-port", "127.0.0.1:http", cwd=REPO)
    assert bad.exit_code == 2 and "expected PORT or ADDR:PORT" in bad.stderr
