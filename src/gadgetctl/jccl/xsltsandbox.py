"""Running a stylesheet from outside the bundled set with bounded time and memory.

An upgrade stylesheet is a program: a ``.jdef`` reached through a configuration's own
``<definition_path>`` may hold one that recurses exponentially and takes all the memory
of the machine. Stylesheets of the bundled definitions run in-process (they are ours);
every other one runs in a child process (``python -m gadgetctl.jccl.xslt``, which calls
:func:`serve`) whose
address space and CPU time are limited with ``setrlimit``, and which the parent stops when
a transform takes longer than :data:`TIME_LIMIT`. The child is kept for the next transform
and replaced after a failure.

Protocol on the child's stdin/stdout: a request is two length-prefixed byte strings (the
stylesheet, the element serialised); the answer is one status byte (``R`` result, ``E``
error) and one length-prefixed byte string (the result elements inside ``<r>``, or the
error message).
"""

from __future__ import annotations

import atexit
import contextlib
import os
import select
import struct
import subprocess
import sys
import time
from collections.abc import Callable

TIME_LIMIT = 5.0  # seconds of wall-clock time per element transform
MEMORY_LIMIT = 384 * 1024 * 1024  # bytes of address space of the child
_HEADER = struct.Struct(">I")


class SandboxError(Exception):
    """The stylesheet was stopped at a limit (or the child failed); the message says which."""


def _limit_child() -> None:  # runs in the child before exec
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    cpu = int(TIME_LIMIT) * 2 + 5  # a backstop: the parent's wall-clock limit comes first
    resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 1))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


class _Child:
    def __init__(self) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "gadgetctl.jccl.xslt"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            preexec_fn=_limit_child,
            close_fds=True,
        )

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self) -> None:
        with contextlib.suppress(OSError):
            self.process.kill()
        self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            with contextlib.suppress(OSError):
                stream.close()

    def _read(self, count: int, deadline: float) -> bytes:
        fd = self.process.stdout.fileno()
        chunks, missing = [], count
        while missing:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            ready, _, _ = select.select([fd], [], [], left)
            if not ready:
                raise TimeoutError
            chunk = os.read(fd, missing)
            if not chunk:
                raise EOFError
            chunks.append(chunk)
            missing -= len(chunk)
        return b"".join(chunks)

    def call(self, stylesheet: bytes, element: bytes, time_limit: float) -> tuple[bytes, bytes]:
        stdin = self.process.stdin
        stdin.write(
            _HEADER.pack(len(stylesheet)) + stylesheet + _HEADER.pack(len(element)) + element
        )
        stdin.flush()
        deadline = time.monotonic() + time_limit
        status = self._read(1, deadline)
        (size,) = _HEADER.unpack(self._read(_HEADER.size, deadline))
        return status, self._read(size, deadline)


_child: _Child | None = None


def _stop_child() -> None:
    global _child
    if _child is not None:
        _child.stop()
        _child = None


atexit.register(_stop_child)


def run_sandboxed(stylesheet: bytes, element: bytes, *, time_limit: float = TIME_LIMIT) -> bytes:
    """The serialised ``<r>`` holding the elements ``stylesheet`` makes of ``element``.

    Raises :class:`SandboxError` when the child hits a limit and ``ValueError`` with the
    stylesheet's own error (does not compile, fails, produces nothing).
    """
    global _child
    if _child is None or not _child.alive():
        _child = _Child()
    try:
        status, payload = _child.call(stylesheet, element, time_limit)
    except TimeoutError:
        _stop_child()
        raise SandboxError(f"stopped after the time limit of {time_limit:g} s") from None
    except (EOFError, BrokenPipeError, OSError):
        _stop_child()
        raise SandboxError(
            f"stopped at the memory limit of {MEMORY_LIMIT // (1024 * 1024)} MB"
        ) from None
    if status == b"M":
        _stop_child()
        raise SandboxError(f"stopped at the memory limit of {MEMORY_LIMIT // (1024 * 1024)} MB")
    if status == b"E":
        raise ValueError(payload.decode("utf-8", "replace"))
    return payload


# --------------------------------------------------------------------------- the child


def _peak_address_space() -> int:
    """Bytes of the largest address space this process has had (``VmPeak``): the quantity
    ``RLIMIT_AS`` limits. The resident set can stay far below the limit when an allocation
    fails (mappings not yet touched count against the limit, not in the resident set), so
    judging by it called a failed allocation an ordinary error on a loaded machine."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmPeak:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def serve(handler: Callable[[bytes, bytes], bytes], errors: tuple[type[Exception], ...]) -> None:
    """The child's loop: answer each request with ``handler(stylesheet, element)``, or with
    the message of one of ``errors``; a MemoryError ends the child (the parent reports it)."""
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer

    def read_exactly(count: int) -> bytes:
        data = stdin.read(count)
        if len(data) != count:
            raise EOFError
        return data

    while True:
        try:
            stylesheet = read_exactly(_HEADER.unpack(read_exactly(_HEADER.size))[0])
            element = read_exactly(_HEADER.unpack(read_exactly(_HEADER.size))[0])
        except EOFError:
            return
        try:
            status, payload = b"R", handler(stylesheet, element)
        except errors as err:
            # libxslt reports a failed allocation as an ordinary error: near the limit it is ours
            status = b"M" if _peak_address_space() > MEMORY_LIMIT // 2 else b"E"
            payload = str(err).encode("utf-8")
        except MemoryError:
            return
        stdout.write(status + _HEADER.pack(len(payload)) + payload)
        stdout.flush()
