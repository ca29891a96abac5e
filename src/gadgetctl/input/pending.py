"""Why an element is pending: the input manager could not configure it (yet).

Every pending element has exactly one reason, with the DRV code that explains it
(`gadgetctl explain DRV030`). Nothing is left pending without one.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.configuration import ConfigElement


class PendingKind(StrEnum):
    NO_DRIVER = "no driver"
    DRIVER_FAILED = "driver failed to load"
    CONFIG_FAILED = "configuration failed"
    START_FAILED = "start failed"
    MISSING_TARGET = "pointer target missing"
    WAITING = "waiting for another element"
    UNSUPPORTED = "not supported"
    TOO_OLD = "element version too old"
    BAD_ALIAS = "alias does not point at a proxy"
    NO_DEFINITION = "no definition"


CODES: dict[PendingKind, str] = {
    PendingKind.NO_DRIVER: "DRV030",
    PendingKind.DRIVER_FAILED: "DRV031",
    PendingKind.CONFIG_FAILED: "DRV032",
    PendingKind.START_FAILED: "DRV033",
    PendingKind.MISSING_TARGET: "DRV034",
    PendingKind.WAITING: "DRV035",
    PendingKind.UNSUPPORTED: "DRV036",
    PendingKind.TOO_OLD: "DRV037",
    PendingKind.BAD_ALIAS: "DRV039",
    PendingKind.NO_DEFINITION: "DRV040",
}

#: Reasons that only go away when something else changes; they are retried on every pass.
#: The others (configuration and start failures) are retried by retry_pending() or after
#: the manager's retry interval, so a device that cannot open its port is not hammered.
CHEAP_TO_RETRY = frozenset(set(PendingKind) - {PendingKind.CONFIG_FAILED, PendingKind.START_FAILED})


@dataclass(frozen=True)
class PendingEntry:
    element: ConfigElement
    kind: PendingKind
    message: str
    hint: str | None = None

    @property
    def name(self) -> str:
        return self.element.full_name

    @property
    def type(self) -> str:
        return self.element.type

    @property
    def code(self) -> str:
        return CODES[self.kind]

    def diagnostic(self) -> Diagnostic:
        loc = self.element.location
        return Diagnostic.make(
            self.code,
            f"{self.name} ({self.type}) stays pending: {self.message}",
            loc.path,
            loc.line,
            loc.column,
            hint=self.hint,
        )

    def to_dict(self) -> dict[str, object]:
        loc = self.element.location
        return {
            "name": self.name,
            "type": self.type,
            "reason": self.kind.value,
            "code": self.code,
            "message": self.message,
            "hint": self.hint,
            "path": loc.path,
            "line": loc.line,
            "column": loc.column,
        }
