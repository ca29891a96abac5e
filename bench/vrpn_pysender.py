"""The least a Python program can do to send what bench/vrpn_csender.c sends: for
bench/bench_vrpn.py --part csender, the floor of a Python sender's cost (no input manager, no
devices, constant poses packed with struct).

Accepts CLIENTS direct TCP clients, exchanges cookies, describes one tracker and the
Pos_Quat type, then every 1/RATE s sends each client SENSORS pose messages (88 bytes each,
one send per client), for SECONDS. Prints the port, then "ready".

    python bench/vrpn_pysender.py CLIENTS SENSORS RATE SECONDS
"""

from __future__ import annotations

import socket
import struct
import sys
import time

COOKIE = b"vrpn: ver. 07.38  0".ljust(24, b"\0")
HEADER = struct.Struct(">IIIiiI")
POSE = struct.Struct(">iI7d")


def header(length: int, sender: int, type_id: int) -> bytes:
    moment = time.time()
    seconds = int(moment)
    return HEADER.pack(length, seconds, int((moment - seconds) * 1e6), sender, type_id, 0)


def describe(kind: int, ident: int, name: str) -> bytes:
    raw = name.encode() + b"\0"
    body = 4 + len(raw)
    padded = (body + 7) & ~7
    return header(24 + body, ident, kind) + (struct.pack(">I", len(raw)) + raw).ljust(padded, b"\0")


def main() -> None:
    clients, sensors = int(sys.argv[1]), int(sys.argv[2])
    rate, seconds = float(sys.argv[3]), float(sys.argv[4])
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen(64)
    print(listener.getsockname()[1], flush=True)
    setup = describe(-1, 0, "Tracker0") + describe(-2, 6, "vrpn_Tracker Pos_Quat")
    connections = []
    for _ in range(clients):
        connection, _ = listener.accept()
        connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        cookie = b""
        while len(cookie) < 24:
            more = connection.recv(24 - len(cookie))
            if not more:
                return
            cookie += more
        connection.sendall(COOKIE + setup)
        connection.setblocking(False)
        connections.append(connection)
    print("ready", flush=True)
    period = 1.0 / rate
    due = time.monotonic()
    for tick in range(int(seconds * rate)):
        due += period
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        t = tick / rate
        data = b"".join(
            header(88, 0, 6) + POSE.pack(s, 0, 0.5 * t, 1.5, -0.25 * s, 0.0, 0.0, 0.0, 1.0)
            for s in range(sensors)
        )
        for connection in connections:
            try:
                connection.send(data)
            except OSError:  # a full or closed socket: the message is dropped, as in C
                pass


if __name__ == "__main__":
    main()
