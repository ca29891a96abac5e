"""How an element type reaches its device: the plug-in's TRANSPORTS metadata (read without
importing it), else the property names of the upstream Gadgeteer driver where they are
obvious (drivers.md, part 1)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from gadgetctl.input.plugins.discovery import PluginInfo

_SERIAL = {"kind": "serial", "port": "port", "baud": "baud"}

#: The port properties of upstream element types, used when no plug-in found declares
#: TRANSPORTS for the type (cyber_glove has no gadgetctl driver; a third-party plug-in of a
#: standard type may declare none).
KNOWN_TRANSPORTS: dict[str, list[dict[str, str]]] = {
    **{
        token: [_SERIAL]
        for token in (
            "flock",
            "fastrak",
            "intersense",
            "ibox",
            "pinch_glove",
            "puck_device",
            "data_glove",
            "data_glove_ultra_wireless",
            "serial_encoder",
            "three_d_mouse",
            "cyber_glove",
        )
    },
    "wanda": [{"kind": "serial", "port": "port"}],
    "linux_joydev": [{"kind": "file", "path": "port_name"}],
    "dtrack": [
        {"kind": "udp", "port": "receive_port", "host": "server_name", "peer_port": "command_port"}
    ],
    "TUIO_drv": [{"kind": "udp", "port": "port"}],
    "optitrack": [{"kind": "udp", "port": "port", "port_unset": "1511", "group": "239.255.42.99"}],
    "motion_star": [{"kind": "tcp", "host": "address", "port": "server_port"}],
}
UPSTREAM = "upstream property names"


@dataclass(frozen=True)
class Transport:
    """One way an element reaches its device: ``kind`` and key -> property name."""

    kind: str
    props: Mapping[str, str]

    def prop(self, key: str) -> str | None:
        return self.props.get(key)


def transports_for(token: str, plugin: PluginInfo | None) -> tuple[list[Transport], str | None]:
    """The transports of element type ``token`` and where they were read from (None: unknown)."""
    if plugin is not None and token in plugin.metadata.transports:
        specs, source = plugin.metadata.transports[token], f"TRANSPORTS of {plugin.name}"
    elif token in KNOWN_TRANSPORTS:
        specs, source = KNOWN_TRANSPORTS[token], UPSTREAM
    else:
        return [], None
    return [
        Transport(s["kind"], {k: v for k, v in s.items() if k != "kind"}) for s in specs
    ], source
