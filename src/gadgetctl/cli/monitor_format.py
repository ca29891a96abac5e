"""The views a monitor session can run in (shared by `monitor`, `replay`, `demo` and the
runner, without importing any of them)."""

from __future__ import annotations

from enum import StrEnum


class OutputFormat(StrEnum):
    live = "live"
    table = "table"
    ndjson = "ndjson"
