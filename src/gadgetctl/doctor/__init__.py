"""`gadgetctl doctor`: why no data arrive. Which definitions and driver plug-ins are found
and whether they load, and for each configured device whether its port, UDP port or server
can be used by this user; without a configuration, an overview of the system.

The library side only: no typer or rich here. :func:`diagnose` builds a
:class:`DoctorReport`; :func:`render_text` prints it.
"""

from gadgetctl.doctor.model import DeviceReport, DoctorReport, PluginReport, PortCheck, Status
from gadgetctl.doctor.render import render_text
from gadgetctl.doctor.run import DoctorOptions, diagnose

__all__ = [
    "DeviceReport",
    "DoctorOptions",
    "DoctorReport",
    "PluginReport",
    "PortCheck",
    "Status",
    "diagnose",
    "render_text",
]
