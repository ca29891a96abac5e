"""`gadgetctl lsp` as a command: without its extra it says what to install."""

from __future__ import annotations

import contextlib
import json
import socket
import subprocess
import sys
from collections.abc import Iterator


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


@contextlib.contextmanager
def _tcp_server() -> Iterator[tuple[subprocess.Popen, int]]:
    """`gadgetctl lsp --tcp 0` and the port it says it listens on; killed if still running."""
    server = subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", "lsp", "--tcp", "0"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        said = server.stderr.readline().decode()
        assert said.startswith("gadgetctl lsp: listening on 127.0.0.1:"), said
        yield server, int(said.rsplit(":", 1)[1])
    finally:
        if server.poll() is None:
            server.kill()
            server.wait(timeout=30)
        server.stderr.close()


def test_tcp_serves_one_client_on_loopback():
    with _tcp_server() as (server, port):
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


def _lsp_on_stdin(data: bytes) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", "lsp"], input=data, capture_output=True, timeout=60
    )


def test_a_message_announcing_gigabytes_ends_the_session_in_one_line():
    """pygls reads as many bytes as Content-Length says: 100 GB ended in a MemoryError."""
    done = _lsp_on_stdin(b"Content-Length: 99999999999\r\n\r\n{}")
    assert done.returncode == 2
    assert done.stderr.decode() == (
        "gadgetctl: error: lsp: a message announces 99999999999 bytes, over the limit of "
        "64 MiB; the session ends\n"
    )
    digits = _lsp_on_stdin(b"Content-Length: " + b"9" * 500 + b"\r\n\r\n{}")
    assert digits.returncode == 2
    assert b"announces a number of 500 digits" in digits.stderr
    assert digits.stderr.count(b"\n") == 1


def test_a_header_line_without_end_ends_the_session_in_one_line():
    done = _lsp_on_stdin(b"Content-Length: 2" + b" " * 100_000)
    assert done.returncode == 2
    assert done.stderr.decode() == (
        "gadgetctl: error: lsp: a header line is longer than 1024 bytes; the session ends\n"
    )


def test_a_message_that_is_not_json_is_logged_in_one_line_and_the_session_goes_on():
    broken = b'Content-Length: 5\r\n\r\n{"a":'
    done = _lsp_on_stdin(
        broken
        + _message(
            {
                "jsonrpc": "2.0",
                "id": 1,
                "method": "initialize",
                "params": {"processId": None, "rootUri": None, "capabilities": {}},
            }
        )
    )
    assert done.returncode == 0
    assert done.stderr.decode().splitlines() == [
        "gadgetctl lsp: error: Unable to handle message "
        "(JSONDecodeError: Expecting value: line 1 column 6 (char 5))"
    ]
    assert b'"id": 1' in done.stdout and b"hoverProvider" in done.stdout  # answered after it


def test_a_tcp_client_announcing_gigabytes_is_not_buffered():
    """On --tcp anyone on the machine may connect: a client announcing 1 GiB and sending it
    was buffered whole; the session ends at the announcement."""
    with _tcp_server() as (server, port):
        with socket.create_connection(("127.0.0.1", port), timeout=30) as peer:
            peer.sendall(b"Content-Length: %d\r\n\r\n" % (1 << 30) + b"x" * 65536)
            assert server.wait(timeout=30) == 2
        assert server.stderr.read().decode() == (
            "gadgetctl: error: lsp: a message announces 1073741824 bytes, over the limit of "
            "64 MiB; the session ends\n"
        )
