"""Record what a real VRPN server sends to one client, byte for byte.

Usage: python capture.py PORT MODE OUT_PREFIX   (MODE: tcp or lob)

A raw-socket client written from the protocol notes only (no gadgetctl code): it connects
(direct TCP, or the UDP connection request with a TCP call-back and a UDP channel), sends its
cookie, describes its senders and the ping type, pings each device, and records every byte the
server sends until the server closes the connection: OUT_PREFIX.tcp holds the TCP stream
(cookie included), OUT_PREFIX.udp the datagrams, each preceded by its length (uint32 BE).
"""

import select
import socket
import struct
import sys
import time

DEVICES = ["Tracker0", "Button0", "Analog0", "Dial0", "Text0"]
COOKIE = b"vrpn: ver. 07.38  0" + b"\0" * 5


def message(type_id: int, sender: int, payload: bytes = b"") -> bytes:
    pad = -len(payload) % 8
    return (
        struct.pack(">IiiiiI", 24 + len(payload), 0, 0, sender, type_id, 0) + payload + b"\0" * pad
    )


def description(kind: int, ident: int, name: str) -> bytes:
    raw = name.encode() + b"\0"
    return message(kind, ident, struct.pack(">I", len(raw)) + raw)


def main() -> None:
    port, mode, out = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    udp = None
    if mode == "tcp":
        tcp = socket.create_connection(("127.0.0.1", port), timeout=5)
    else:
        listener = socket.socket()
        listener.bind(("127.0.0.1", 0))
        listener.listen(1)
        lob = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        lob.sendto(f"127.0.0.1 {listener.getsockname()[1]}".encode() + b"\0", ("127.0.0.1", port))
        listener.settimeout(5)
        tcp, _ = listener.accept()
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        udp.bind(("127.0.0.1", 0))
    tcp.sendall(COOKIE)
    hello = b""
    if udp is not None:
        hello += message(-3, udp.getsockname()[1], b"127.0.0.1\0")
    for ident, name in enumerate(DEVICES):
        hello += description(-1, ident, name)
    hello += description(-2, 0, "vrpn_Base ping_message")
    for ident in range(len(DEVICES)):
        hello += message(0, ident)
    tcp.sendall(hello)
    stream = bytearray()
    datagrams = []
    deadline = time.monotonic() + 10
    sockets = [tcp] + ([udp] if udp is not None else [])
    while time.monotonic() < deadline:
        ready, _, _ = select.select(sockets, [], [], 0.5)
        if udp in ready:
            datagrams.append(udp.recv(65536))
        if tcp in ready:
            data = tcp.recv(65536)
            if not data:
                break
            stream += data
    with open(out + ".tcp", "wb") as f:
        f.write(stream)
    if udp is not None:
        with open(out + ".udp", "wb") as f:
            for d in datagrams:
                f.write(struct.pack(">I", len(d)) + d)
    print(f"{len(stream)} TCP bytes, {len(datagrams)} datagrams")


if __name__ == "__main__":
    main()
