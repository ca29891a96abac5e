"""Elexol Ether I/O 24 driver plug-in (element types ``elexol_ether24`` and its embedded
``elexol_ether24_port``).

Talks to the board over UDP port 2424 (binary commands and replies): configures the pins of
ports A, B and C from the embedded port elements, then reads the three ports in a loop and
offers the 24 lines as digital units 0-23 (0 or 1). ``standalone.py`` holds the protocol,
``wrapper.py`` the input-manager device and ``emulator.py`` a loopback board.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "ElexolEther24_drv"
ELEMENT_TYPES = {"elexol_ether24": ("digital",)}
# Commands go to the board at ip_address, UDP port 2424 (ip_address may carry ":port"), or,
# with config_method find_mac, to the board that answers discovery with mac_address.
TRANSPORTS = {
    "elexol_ether24": {
        "kind": "udp-peer",
        "host": "ip_address",
        "mac": "mac_address",
        "method": "config_method",
    }
}


def register(registry):
    from .wrapper import Ether24Device

    registry.register_device(Ether24Device)
