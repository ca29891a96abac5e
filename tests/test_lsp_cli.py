"""`gadgetctl lsp` as a command: without its extra it says what to install."""

from __future__ import annotations

import json
import socket
import subprocess
import sys


def test_without_pygls_the_command_says_which_extra_to_install():
    blocked = (
        "import sys; sys.modules['pygls'] = None; sys.argv = ['gadgetctl', 'lsp'];"
        "from gadgetctl.cli.main import run; run()"
    )
    done = subprocess.run(
        [sys.executable, "-c", blocked],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1 and "pip install 'gadgetctl[lsp]'" in done.stderr


def _message(payload: dict) -> bytes:
    body = json.dumps(payload).encode()
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


def _read_message(stream) -> dict:
    length = None
    while True:
        line = stream.readline()
        if line in (b"\r\n", b""):
            break
        name, _, value = line.decode().partition(":")
        if name.lower() == "content-length":
            length = int(value)
    assert length is not None, "no message"
    return json.loads(stream.read(length))


def test_tcp_serves_one_client_on_loopback():
    server = subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", "lsp", "--tcp", "0"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        said = server.stderr.readline().decode()
        assert said.startswith("gadgetctl lsp: listening on 127.0.0.1:"), said
        port = int(said.rsplit(":", 1)[1])
        with socket.create_connection(("127.0.0.1", port), timeout=30) as peer:
            stream = peer.makefile("rwb")
            stream.write(
                _message(
                    {
                        "jsonrpc": "2.0",
                        "id": 1,
                        "method": "initialize",
                        "params": {"processId": None, "rootUri": None, "capabilities": {}},
                    }
                )
            )
            stream.flush()
            answer = _read_message(stream)
            assert answer["id"] == 1
            capabilities = answer["result"]["capabilities"]
            assert capabilities["hoverProvider"] and capabilities["renameProvider"]
            for request in (
                {"jsonrpc": "2.0", "method": "initialized", "params": {}},
                {"jsonrpc": "2.0", "id": 2, "method": "shutdown"},
            ):
                stream.write(_message(request))
            stream.flush()
            assert _read_message(stream)["id"] == 2
            stream.write(_message({"jsonrpc": "2.0", "method": "exit"}))
            stream.flush()
        assert server.wait(timeout=30) == 0
    finally:
        if server.poll() is None:
            server.kill()
            server.wait(timeout=30)
        server.stderr.close()
