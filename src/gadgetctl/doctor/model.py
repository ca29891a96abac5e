"""What doctor found: port checks, devices, plug-ins, and the whole report."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

from gadgetctl.diagnostics import Diagnostic, Severity


class Status(StrEnum):
    OK = "ok"
    WARNING = "warning"
    PROBLEM = "problem"  # data would not arrive
    UNCHECKED = "unchecked"


@dataclass(frozen=True)
class PortCheck:
    """The result of checking one connection: a path, a UDP port or a TCP server."""

    kind: str  # file, serial, udp, tcp
    target: str  # the path, "port/udp" or "host:port"
    status: Status
    detail: str  # one line: what was found
    code: str | None = None  # DRV code when status is not ok
    hint: str | None = None
    prop: str | None = None  # the element property that names the target

    def with_prop(self, prop: str) -> PortCheck:
        return PortCheck(
            self.kind, self.target, self.status, self.detail, self.code, self.hint, prop
        )

    def to_dict(self) -> dict[str, object]:
        return {
            "kind": self.kind,
            "property": self.prop,
            "target": self.target,
            "status": self.status.value,
            "detail": self.detail,
            "code": self.code,
            "hint": self.hint,
        }


@dataclass
class DeviceReport:
    """One configured device element: its driver and its connections."""

    name: str
    type: str
    path: str | None
    line: int | None
    driver: str | None  # plug-in name, "built-in", or None when nothing handles the type
    driver_ok: bool
    reason: str | None = None  # why the input manager leaves it pending
    transport_source: str | None = None  # where the port properties were read from
    checks: list[PortCheck] = field(default_factory=list)

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "type": self.type,
            "path": self.path,
            "line": self.line,
            "driver": self.driver,
            "driver_ok": self.driver_ok,
            "pending": self.reason,
            "transports_from": self.transport_source,
            "checks": [c.to_dict() for c in self.checks],
        }


@dataclass
class PluginReport:
    """A discovered plug-in and whether it loads."""

    name: str
    source: str
    path: str
    ok: bool
    error: str | None
    element_types: list[str]
    used: bool  # named by the configuration, or provides one of its element types
    shadowed_by: str | None = None

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "source": self.source,
            "path": self.path,
            "loads": self.ok,
            "error": self.error,
            "element_types": self.element_types,
            "used": self.used,
            "shadowed_by": self.shadowed_by,
        }


@dataclass
class SerialPort:
    device: str
    description: str
    hwid: str

    def to_dict(self) -> dict[str, object]:
        return {"device": self.device, "description": self.description, "hwid": self.hwid}


@dataclass
class DoctorReport:
    configurations: list[str]
    definition_path: list[dict[str, object]] = field(default_factory=list)
    driver_places: str = ""
    plugins: list[PluginReport] = field(default_factory=list)
    devices: list[DeviceReport] = field(default_factory=list)
    serial_ports: list[SerialPort] | None = None  # None: pyserial cannot list them
    joysticks: list[PortCheck] = field(default_factory=list)
    # the overview's SDL joysticks, (index, name); a string says why SDL could not be asked
    sdl_joysticks: list[tuple[int, str]] | str | None = None
    diagnostics: list[Diagnostic] = field(default_factory=list)
    serve_port: PortCheck | None = None  # --serve-port: whether `gadgetctl serve` could bind it

    @property
    def blocking(self) -> list[Diagnostic]:
        """Findings that would stop data from arriving."""
        return [d for d in self.diagnostics if d.severity is Severity.ERROR]

    @property
    def exit_code(self) -> int:
        return 1 if self.blocking else 0

    def to_dict(self) -> dict[str, object]:
        serve = {} if self.serve_port is None else {"serve_port": self.serve_port.to_dict()}
        if self.sdl_joysticks is not None:
            sdl = self.sdl_joysticks
            serve["sdl_joysticks"] = (
                {"error": sdl}
                if isinstance(sdl, str)
                else [{"index": i, "name": n} for i, n in sdl]
            )
        return {
            "configurations": self.configurations,
            "definition_path": self.definition_path,
            "driver_places": self.driver_places,
            "plugins": [p.to_dict() for p in self.plugins],
            "devices": [d.to_dict() for d in self.devices],
            "serial_ports": None
            if self.serial_ports is None
            else [p.to_dict() for p in self.serial_ports],
            "joysticks": [j.to_dict() for j in self.joysticks],
            "diagnostics": [d.to_dict() for d in self.diagnostics],
            **serve,
            "blocking": len(self.blocking),
            "exit_code": self.exit_code,
        }
