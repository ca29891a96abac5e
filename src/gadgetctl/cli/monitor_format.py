"""The views a monitor session can run in (shared by `monitor`, `replay`, `demo` and the
runner, without importing any of them), and how positions are written."""

from __future__ import annotations

from enum import StrEnum


class OutputFormat(StrEnum):
    live = "live"
    table = "table"
    ndjson = "ndjson"
    events = "events"


class PoseFormat(StrEnum):
    """``--pose``: see :mod:`gadgetctl.monitor.poses`."""

    matrix = "matrix"
    quaternion = "quaternion"
    euler = "euler"
