"""What the input manager reports about each element it handles (for `gadgetctl monitor`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from gadgetctl.input.device import DeviceStats


class ElementKind(StrEnum):
    DEVICE = "device"
    PROXY = "proxy"
    ALIAS = "alias"
    INPUT_MANAGER = "input_manager"


PENDING = "pending"
ACTIVE = "active"
#: An element whose type has no definition: VR Juggler drops it when loading, so it is
#: shown as what it is rather than as a pending device (and is no reason to exit 1).
UNKNOWN_TYPE = "unknown type"


@dataclass(frozen=True)
class ElementStatus:
    """``state`` is a device state (running, faulted, reconnecting, configured, stopped),
    a proxy state (active, stupefied), ``active``, ``pending`` or ``unknown type``; ``reason`` says why when
    it is not fine (the pending reason, the fault's error, why a proxy is stupefied)."""

    name: str
    type: str
    kind: ElementKind | None
    state: str
    reason: str | None = None
    code: str | None = None
    stats: DeviceStats | None = None
    target: str | None = None  # a proxy's device, an alias's proxy
    #: For an element gadgetctl runs but VR Juggler would leave pending (a documented
    #: difference): why VR Juggler would.
    note: str | None = None

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "type": self.type,
            "kind": None if self.kind is None else self.kind.value,
            "state": self.state,
            "reason": self.reason,
            "code": self.code,
            "target": self.target,
            "vrjuggler_pending": self.note,
            "stats": None
            if self.stats is None
            else {
                "samples": self.stats.samples,
                "dropped": self.stats.dropped,
                "faults": self.stats.faults,
                "restarts": self.stats.restarts,
                "last_error": self.stats.last_error,
            },
        }
