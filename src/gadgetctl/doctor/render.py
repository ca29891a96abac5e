"""Plain-text rendering of a :class:`DoctorReport`."""

from __future__ import annotations

from gadgetctl.diagnostics.model import sort_key
from gadgetctl.doctor.model import DoctorReport, PortCheck
from gadgetctl.safetext import printable
from gadgetctl.wording import counted

_MARK = {"ok": "ok", "warning": "warn", "problem": "PROBLEM", "unchecked": "-"}


def _check_line(check: PortCheck) -> str:
    what = (
        f"{check.prop} {check.target}"
        if check.prop and check.kind in ("file", "serial", "vrpn")
        else (check.prop or check.target)
    )
    return (
        f"    {_MARK[check.status.value]:<8} {what}: {check.detail}"
        if what
        else (f"    {_MARK[check.status.value]:<8} {check.detail}")
    )


def _definitions(report: DoctorReport) -> list[str]:
    lines = ["Definition search path:"]
    for entry in report.definition_path:
        state = counted(entry["definitions"], "definition") if entry["exists"] else "missing"
        lines.append(f"    {entry['origin']}: {entry['path']} ({state})")
    return lines


def _plugins(report: DoctorReport) -> list[str]:
    """Every plug-in in the overview; for a configuration, those its devices use and those
    that fail or are shadowed, the others counted in one line."""
    lines = [f"Driver plug-ins (looked in {report.driver_places}):"]
    shown = report.plugins
    if report.configurations or report.devices:
        used = {device.driver for device in report.devices}
        shown = [p for p in report.plugins if p.name in used or p.shadowed_by or not p.ok]
    for plugin in shown:
        types = ", ".join(plugin.element_types) or "no declared element types"
        if plugin.shadowed_by:
            lines.append(
                f"    {'-':<8} {plugin.name} [{plugin.source}]: shadowed by {plugin.shadowed_by}"
            )
        elif plugin.ok:
            lines.append(f"    {'ok':<8} {plugin.name} [{plugin.source}] ({types})")
        else:
            lines.append(
                f"    {'FAILED':<8} {plugin.name} [{plugin.source}] ({types}): {plugin.error}"
            )
    if not report.plugins:
        lines.append("    none found")
    others = len(report.plugins) - len(shown)
    if others:
        lines.append(
            f"    {'ok':<8} {counted(others, 'other plug-in' if shown else 'plug-in')} found and "
            "loading, unused by the configuration (`gadgetctl drivers list` lists them)"
        )
    return lines


def _devices(report: DoctorReport) -> list[str]:
    lines = ["Configured devices:"]
    for device in report.devices:
        where = f"{device.path}:{device.line}" if device.line else device.path or "command line"
        if device.driver == "built-in" and not device.checks and not device.reason:
            lines.append(
                f"  {device.name} ({device.type}), built-in device (no connection to check), {where}"
            )
            continue
        if device.driver is None:
            driver = "no driver"
        else:
            driver = f"driver {device.driver}" + ("" if device.driver_ok else " (not loaded)")
        lines.append(f"  {device.name} ({device.type}), {driver}, {where}")
        if device.reason:
            lines.append(f"    {'PENDING':<8} {device.reason}")
        lines.extend(_check_line(c) for c in device.checks)
    if not report.devices:
        lines.append("    no input devices in the configuration")
    return lines


def _system(report: DoctorReport) -> list[str]:
    if report.serial_ports is None:
        lines = ["Serial ports: pyserial cannot list them here"]
    else:
        lines = ["Serial ports:"] + [
            f"    {p.device}  {p.description}" for p in report.serial_ports
        ]
        if not report.serial_ports:
            lines.append("    none found")
    lines.append("Joystick devices:")
    lines.extend(f"    {_MARK[c.status.value]:<8} {c.target}: {c.detail}" for c in report.joysticks)
    if not report.joysticks:
        lines.append("    none found (no /dev/input/js*; is the joydev kernel module loaded?)")
    sdl = report.sdl_joysticks
    if isinstance(sdl, str):
        lines.append(f"SDL joysticks: cannot ask SDL: {sdl}")
    elif sdl is not None:
        lines.append("SDL joysticks (the device index of sdl_joystick elements):")
        lines.extend(f"    {index}: {name}" for index, name in sdl)
        if not sdl:
            lines.append("    none found")
    return lines


def _findings(report: DoctorReport) -> list[str]:
    if not report.diagnostics:
        return []
    lines = ["Findings:"]
    for d in sorted(report.diagnostics, key=lambda d: (d.severity.rank, *sort_key(d))):
        lines.append(f"  {d.location}: {d.severity.value} {d.code} {d.message}")
        if d.hint:
            lines.append(f"      hint: {d.hint}")
    return lines


def render_text(report: DoctorReport) -> str:
    lines = _definitions(report) + _plugins(report)
    lines += _devices(report) if report.configurations or report.devices else _system(report)
    if report.serve_port is not None:
        lines += ["gadgetctl serve port:", _check_line(report.serve_port)]
    lines += _findings(report)
    blocking = len(report.blocking)
    lines.append(
        f"{blocking} finding{'s' if blocking != 1 else ''} would stop data from arriving"
        if blocking
        else "nothing found that would stop data from arriving"
    )
    return "\n".join(map(printable, lines))  # names, paths, reasons: one line each
