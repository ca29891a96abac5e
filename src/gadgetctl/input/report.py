"""The report of `gadgetctl config pending`: pending elements, stupefied proxies and
driver/device diagnostics of a configured input manager."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from gadgetctl.diagnostics import Diagnostic, Severity, sort_key
from gadgetctl.input.manager import InputManager
from gadgetctl.input.pending import PendingEntry, PendingKind
from gadgetctl.input.status import ElementKind
from gadgetctl.safetext import printable

_PLURALS = {
    "device": "devices",
    "proxy": "proxies",
    "alias": "aliases",
    "input_manager": "input_managers",
}


@dataclass(frozen=True)
class StupefiedProxy:
    name: str
    type: str
    device: str
    reason: str
    diagnostic: Diagnostic

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "type": self.type,
            "device": self.device,
            "reason": self.reason,
            "code": self.diagnostic.code,
            "path": self.diagnostic.path,
            "line": self.diagnostic.line,
            "column": self.diagnostic.column,
        }


@dataclass
class PendingReport:
    pending: list[PendingEntry] = field(default_factory=list)
    #: Elements of a type with no definition: VR Juggler drops them when loading. Shown,
    #: but no problem of the input manager (validate reports them as CFG010).
    unknown: list[PendingEntry] = field(default_factory=list)
    stupefied: list[StupefiedProxy] = field(default_factory=list)
    diagnostics: list[Diagnostic] = field(default_factory=list)  # drivers, devices, filters
    #: Elements gadgetctl runs that VR Juggler would leave pending (documented differences,
    #: DRV044, information only).
    differences: list[Diagnostic] = field(default_factory=list)
    configured: Counter[str] = field(default_factory=Counter)  # kind -> count

    @property
    def problems(self) -> bool:
        return bool(
            self.pending
            or self.stupefied
            or any(d.severity is Severity.ERROR for d in self.diagnostics)
        )

    def all_diagnostics(self) -> list[Diagnostic]:
        found = (
            [e.diagnostic() for e in self.pending]
            + [_unknown_diagnostic(e) for e in self.unknown]
            + [s.diagnostic for s in self.stupefied]
            + self.diagnostics
            + self.differences
        )
        return sorted(found, key=sort_key)

    def summary(self) -> str:
        configured = ", ".join(
            f"{n} {_PLURALS[kind] if n != 1 else kind}"
            for kind, n in sorted(self.configured.items())
        )
        unknown = f", {len(self.unknown)} of unknown type" if self.unknown else ""
        differing = (
            f"; {len(self.differences)} active that VR Juggler would leave pending"
            if self.differences
            else ""
        )
        return (
            f"configured: {configured or 'nothing'}; {len(self.pending)} pending, "
            f"{len(self.stupefied)} stupefied prox{'y' if len(self.stupefied) == 1 else 'ies'}{unknown}"
            f"{differing}"
        )

    def text(self) -> str:
        lines = []
        for d in self.all_diagnostics():
            lines.append(f"{d.location}: {d.severity.value} {d.code} {d.message}")
            if d.hint:
                lines.append(f"    hint: {d.hint}")
        lines.append(self.summary())
        return "\n".join(map(printable, lines))  # names, paths, reasons: one line each

    def to_dict(self) -> dict[str, object]:
        return {
            "pending": [e.to_dict() for e in self.pending],
            "unknown_type": [e.to_dict() for e in self.unknown],
            "stupefied": [s.to_dict() for s in self.stupefied],
            "diagnostics": [d.to_dict() for d in sorted(self.diagnostics, key=sort_key)],
            "vrjuggler_pending": [d.to_dict() for d in sorted(self.differences, key=sort_key)],
            "configured": dict(self.configured),
        }


def _unknown_diagnostic(entry: PendingEntry) -> Diagnostic:
    loc = entry.element.location
    return Diagnostic.make(
        "DRV040",
        f"{entry.name} is of type {entry.type}, which has no definition: "
        "VR Juggler drops it when loading",
        loc.path,
        loc.line,
        loc.column,
        severity=Severity.INFO,
        hint=entry.hint,
    )


def pending_report(manager: InputManager) -> PendingReport:
    entries = manager.pending()
    report = PendingReport(
        pending=[e for e in entries if e.kind is not PendingKind.NO_DEFINITION],
        unknown=[e for e in entries if e.kind is PendingKind.NO_DEFINITION],
        diagnostics=manager.diagnostics,
    )
    for status in manager.statuses():
        if status.state == "pending" or status.kind is None:
            continue
        report.configured[status.kind.value] += 1
        if status.note:
            element = manager.element(status.name)
            loc = element.location if element is not None else None
            report.differences.append(
                Diagnostic.make(
                    "DRV044",
                    f"{status.name} ({status.type}) is {status.state} (VR Juggler would leave it pending: "
                    f"{status.note})",
                    loc.path if loc else None,
                    loc.line if loc else None,
                    loc.column if loc else None,
                )
            )
        if status.kind is ElementKind.PROXY and status.reason:
            proxy = manager.proxies[status.name]
            element = manager.proxy_element(status.name)
            loc = element.location if element is not None else None
            diagnostic = Diagnostic.make(
                "DRV043",
                f"{status.name} ({status.type}) is stupefied: {status.reason}",
                loc.path if loc else None,
                loc.line if loc else None,
                loc.column if loc else None,
            )
            report.stupefied.append(
                StupefiedProxy(
                    status.name, status.type, proxy.device_name, status.reason, diagnostic
                )
            )
    return report
