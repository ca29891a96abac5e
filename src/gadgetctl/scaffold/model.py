"""What a generated driver is made of: its names, device types and transport.

Only the standard library is used here, so the command line can offer the choices
without importing anything else.
"""

from __future__ import annotations

import keyword
import re
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.errors import GadgetctlError

#: Device types a generated driver can provide, in the order the command line lists them.
TYPE_NAMES = ("analog", "digital", "position", "glove", "gesture", "command", "string", "hat")
#: How a generated driver reaches its device.
TRANSPORT_NAMES = ("serial", "udp", "tcp", "file", "none")
DEFAULT_TYPES = ("digital",)
DEFAULT_TRANSPORT = "serial"
#: Longest NAME (and element type) accepted: generated lines stay within 88 columns.
MAX_NAME = 32
MAX_VENDOR = 40
PLUGIN_SUFFIX = "_drv"


class ScaffoldError(GadgetctlError):
    """A request that cannot be generated (a bad name, an existing directory); exit code 2."""


@dataclass(frozen=True)
class DeviceType:
    """One device type a driver provides, and how the placeholder protocol carries it."""

    name: str
    device_class: str  # the gadgetctl.input class the wrapper derives from
    parent: str | None  # the standard base definition the .jdef names as parent
    units: int  # units the placeholder device reports
    width: int  # numbers per unit in a record; 0 for text
    number: str  # how the numbers are read: int, float or str
    layout: str  # what the numbers of a unit are, for comments
    proxy: str | None  # the proxy element type for one unit, if there is a usable one
    unit_label: str  # for proxy and alias names: "Button" -> "AcmeWand Button 0"
    category: str | None  # the .jdef category when this is the driver's main type


DEVICE_TYPES: dict[str, DeviceType] = {
    t.name: t
    for t in (
        DeviceType(
            "analog",
            "Analog",
            "analog_device",
            2,
            1,
            "float",
            "axes, from -1 to 1",
            "analog_proxy",
            "Axis",
            "/Devices/Analog",
        ),
        DeviceType(
            "digital",
            "Digital",
            "digital_device",
            4,
            1,
            "int",
            "buttons: 0 released, 1 pressed",
            "digital_proxy",
            "Button",
            "/Devices/Digital",
        ),
        DeviceType(
            "position",
            "Position",
            "positional_device",
            2,
            6,
            "float",
            "x y z in meters, yaw pitch roll in degrees",
            "position_proxy",
            "Sensor",
            "/Devices/Positional",
        ),
        DeviceType(
            "glove",
            "Glove",
            "glove_device",
            1,
            24,
            "float",
            "6 x 4 joint angles in radians",
            "glove_proxy",
            "Glove",
            "/Devices/Glove",
        ),
        # Gestures have no base definition, and the standard gesture_proxy only accepts
        # simulated_glove_gesture devices, so the example configuration has no proxy for them.
        DeviceType(
            "gesture",
            "Gesture",
            None,
            1,
            1,
            "int",
            "gesture number, -1 for none",
            None,
            "Gesture",
            None,
        ),
        DeviceType(
            "command",
            "Command",
            "command_device",
            1,
            1,
            "int",
            "command number",
            "command_proxy",
            "Command",
            None,
        ),
        DeviceType(
            "string",
            "String",
            "string_device",
            1,
            0,
            "str",
            "text: the rest of the line",
            "string_proxy",
            "Text",
            None,
        ),
        DeviceType(
            "hat",
            "Hat",
            "hat_device",
            1,
            1,
            "int",
            "hat bits: 1 up, 2 right, 4 down, 8 left",
            "hat_proxy",
            "Hat",
            None,
        ),
    )
}


@dataclass(frozen=True)
class Property:
    """A property the generated .jdef declares, with the value example.jconf gives it."""

    name: str
    valuetype: str  # string, integer, float, boolean, configelementpointer
    label: str
    help: str
    default: str | None = None
    example: str | None = None  # value written in example.jconf (None: not written)
    variable: bool = False
    allowed_types: tuple[str, ...] = ()
    examples: tuple[str, ...] = ()  # several values (variable properties)


@dataclass(frozen=True)
class Transport:
    name: str
    phrase: str  # "a serial line"


TRANSPORTS: dict[str, Transport] = {
    t.name: t
    for t in (
        Transport("serial", "a serial line"),
        Transport("udp", "UDP datagrams"),
        Transport("tcp", "a TCP connection"),
        Transport("file", "a device file (a FIFO works)"),
        Transport("none", "no port: the driver makes its own data"),
    )
}


# -- names ---------------------------------------------------------------------------------

_SNAKE = re.compile(r"[a-z][a-z0-9]*(?:_[a-z0-9]+)*")
_CAMEL_BOUNDARY = re.compile(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z])")
#: Names the generated code imports or defines besides the driver's own.
_RESERVED_CAMEL = frozenset(
    {
        *(t.device_class for t in DEVICE_TYPES.values()),
        "Input",
        "SamplingMode",
        "DeviceConfigError",
        "ElementAccess",
        "Path",
        "Template",
    }
)


def camel_to_snake(name: str) -> str:
    """``AcmeWand`` -> ``acme_wand``, ``MyHTTPGlove`` -> ``my_http_glove``."""
    return _CAMEL_BOUNDARY.sub("_", name).lower()


def snake_to_camel(name: str) -> str:
    """``acme_wand`` -> ``AcmeWand``, ``wand2_x`` -> ``Wand2X``."""
    return "".join(part[:1].upper() + part[1:] for part in name.split("_"))


@dataclass(frozen=True)
class DriverNames:
    """Everything named after NAME: ``AcmeWand`` gives the plug-in ``AcmeWand_drv``, the
    element type ``acme_wand`` and classes ``AcmeWand``, ``AcmeWandDevice``..."""

    camel: str
    element_type: str

    @property
    def plugin(self) -> str:
        return self.camel + PLUGIN_SUFFIX

    @property
    def distribution(self) -> str:
        return "gadgetctl-" + self.element_type.replace("_", "-")

    @classmethod
    def parse(cls, name: str) -> DriverNames:
        """Check NAME (CamelCase or snake_case, optionally ending in ``_drv``) and derive
        the names from it; raises :class:`ScaffoldError` with the reason."""
        raw = name.strip()
        base = raw[: -len(PLUGIN_SUFFIX)] if raw.endswith(PLUGIN_SUFFIX) else raw
        if not base:
            raise ScaffoldError("NAME is empty: give the device's name, e.g. AcmeWand")
        if not (base.isascii() and base.isidentifier()):
            raise ScaffoldError(
                f"NAME {raw!r} is not a valid name: use ASCII letters, digits and underscores, "
                "starting with a letter (e.g. AcmeWand or acme_wand)"
            )
        if base.startswith("_") or "__" in base or base.endswith("_"):
            raise ScaffoldError(f"NAME {raw!r} may not start or end with '_' or contain '__'")
        if "_" in base or base.islower():
            if not _SNAKE.fullmatch(base):
                raise ScaffoldError(
                    f"NAME {raw!r} mixes cases with underscores: write it in CamelCase "
                    f"({snake_to_camel(base.lower())}) or snake_case ({base.lower()})"
                )
            camel, element_type = snake_to_camel(base), base
        else:
            if not base[0].isupper():
                raise ScaffoldError(
                    f"NAME {raw!r}: a CamelCase name starts with a capital letter "
                    f"({base[0].upper() + base[1:]})"
                )
            camel, element_type = base, camel_to_snake(base)
        names = cls(camel, element_type)
        names._check()
        return names

    def _check(self) -> None:
        shown = f"{self.camel} (plug-in {self.plugin}, element type {self.element_type})"
        if len(self.camel) > MAX_NAME or len(self.element_type) > MAX_NAME:
            raise ScaffoldError(f"NAME {shown} is too long: at most {MAX_NAME} characters")
        if self.element_type.lower().startswith("xml"):
            raise ScaffoldError(
                f"NAME {shown}: XML reserves names starting with 'xml'; "
                "the element type cannot be one"
            )
        for word in (self.camel, self.element_type):
            if keyword.iskeyword(word) or keyword.issoftkeyword(word):
                raise ScaffoldError(f"NAME {shown}: {word!r} is a Python keyword")
        if self.camel in _RESERVED_CAMEL:
            raise ScaffoldError(
                f"NAME {shown}: {self.camel} is a name the generated code "
                "already uses; choose a more specific name"
            )
        clash = standard_clash(self)
        if clash:
            raise ScaffoldError(f"NAME {shown} clashes with {clash}; choose another name")


def standard_clash(names: DriverNames) -> str | None:
    """What ``names`` clashes with among the standard definitions, built-in devices,
    bundled plug-ins and upstream Gadgeteer drivers, or None."""
    from gadgetctl.input.plugins.catalog import UPSTREAM_DRIVERS
    from gadgetctl.resources import definitions_dir, drivers_dir

    element_type = names.element_type.lower()
    definitions = {p.stem.lower() for p in definitions_dir().glob("*.jdef")}
    if element_type in definitions:
        return f"the standard definition {names.element_type}"
    upstream_types = {t.lower() for types in UPSTREAM_DRIVERS.values() for t in types}
    if element_type in upstream_types:
        return f"the element type {names.element_type} of an upstream Gadgeteer driver"
    plugin = names.plugin.lower()
    bundled = {p.name.lower() for p in drivers_dir().iterdir()} if drivers_dir().is_dir() else set()
    if plugin in bundled:
        return f"the bundled driver plug-in {names.plugin}"
    if plugin in {p.lower() for p in UPSTREAM_DRIVERS}:
        return f"the upstream Gadgeteer driver plug-in {names.plugin}"
    return None


# -- the request -----------------------------------------------------------------------------


def parse_types(types: list[str] | tuple[str, ...]) -> tuple[str, ...]:
    """Device types in the order given, without repeats; DEFAULT_TYPES when none."""
    found: list[str] = []
    for raw in types:
        name = str(raw).strip().lower()
        if name not in DEVICE_TYPES:
            raise ScaffoldError(f"unknown device type {raw!r}; choose from {', '.join(TYPE_NAMES)}")
        if name not in found:
            found.append(name)
    return tuple(found) or DEFAULT_TYPES


def parse_transport(transport: str) -> str:
    name = str(transport).strip().lower()
    if name not in TRANSPORTS:
        raise ScaffoldError(
            f"unknown transport {transport!r}; choose from {', '.join(TRANSPORT_NAMES)}"
        )
    return name


@dataclass(frozen=True)
class DriverSpec:
    """A driver to generate."""

    names: DriverNames
    types: tuple[str, ...] = DEFAULT_TYPES
    transport: str = DEFAULT_TRANSPORT
    vendor: str = ""
    package: bool = False
    directory: Path = field(default_factory=Path)

    @classmethod
    def create(
        cls,
        name: str,
        types: list[str] | tuple[str, ...] = (),
        transport: str = DEFAULT_TRANSPORT,
        *,
        vendor: str = "",
        package: bool = False,
        directory: Path | str = ".",
    ) -> DriverSpec:
        """Check everything the command line gives; raises :class:`ScaffoldError`."""
        vendor = " ".join(vendor.split())
        if any(c in vendor for c in "<>&\"'\\") or "--" in vendor or not vendor.isprintable():
            raise ScaffoldError(
                f"--vendor {vendor!r}: use letters, digits, spaces and simple punctuation"
            )
        if len(vendor) > MAX_VENDOR:
            raise ScaffoldError(f"--vendor {vendor!r} is too long: at most {MAX_VENDOR} characters")
        return cls(
            DriverNames.parse(name),
            parse_types(types),
            parse_transport(transport),
            vendor,
            package,
            Path(directory),
        )

    # -- derived -------------------------------------------------------------------------

    @property
    def device_types(self) -> list[DeviceType]:
        return [DEVICE_TYPES[t] for t in self.types]

    @property
    def transport_info(self) -> Transport:
        return TRANSPORTS[self.transport]

    @property
    def label(self) -> str:
        """``Acme AcmeWand`` (vendor and name), for labels and docstrings."""
        return f"{self.vendor} {self.names.camel}" if self.vendor else self.names.camel

    @property
    def target(self) -> Path:
        """The directory that is created: the plug-in folder, or the project with --package."""
        return self.directory / (self.names.distribution if self.package else self.names.plugin)

    @property
    def plugin_dir(self) -> Path:
        """The plug-in folder (inside ``src/`` of the project with --package)."""
        return self.target / "src" / self.names.plugin if self.package else self.target

    @property
    def port_number(self) -> int:
        """The UDP or TCP port of the example configuration, derived from the name so that
        two generated drivers rarely pick the same one."""
        return 20000 + zlib.crc32(self.names.element_type.encode()) % 10000

    @property
    def example_address(self) -> str:
        """Where example.jconf points the device, and where the emulator is by default."""
        element_type = self.names.element_type
        return {
            "serial": f"/tmp/{element_type}-tty",
            "file": f"/tmp/{element_type}-fifo",
            "udp": str(self.port_number),
            "tcp": str(self.port_number),
            "none": "",
        }[self.transport]

    def properties(self) -> list[Property]:
        """The properties the .jdef declares (besides the inherited ones), in order."""
        props = list(self.transport_properties())
        if "analog" in self.types:
            props += [
                Property(
                    "min",
                    "float",
                    "Lowest raw value",
                    "Raw analog value that analog proxies read as 0.0 (the placeholder "
                    "protocol sends -1 to 1).",
                    "-1.0",
                    "-1.0",
                ),
                Property(
                    "max",
                    "float",
                    "Highest raw value",
                    "Raw analog value that analog proxies read as 1.0.",
                    "1.0",
                    "1.0",
                ),
            ]
        if "glove" in self.types:
            sensor = self.alias_name("position", 0) if "position" in self.types else None
            props.append(
                Property(
                    "glove_position",
                    "configelementpointer",
                    "Hand tracker proxy",
                    "Position proxy (or alias of one) of the tracker sensor on the glove, which places "
                    "the hand in space. Leave it empty for an untracked glove.",
                    None,
                    sensor,
                    allowed_types=("alias", "position_proxy"),
                )
            )
        if "gesture" in self.types:
            props.append(
                Property(
                    "gesture_names",
                    "string",
                    "Gesture name",
                    "Name of each gesture the device reports, by gesture number (0 first).",
                    "",
                    variable=True,
                    examples=("open", "fist", "point"),
                )
            )
        return props

    def transport_properties(self) -> list[Property]:
        example = self.example_address
        if self.transport == "serial":
            return [
                Property(
                    "port",
                    "string",
                    "Serial port",
                    "Serial port the device is plugged into, as the operating system names "
                    "it: /dev/ttyUSB0 or /dev/ttyS0 on Linux, COM3 on Windows. A pyserial URL "
                    "such as socket://host:port works too.",
                    "/dev/ttyUSB0",
                    example,
                ),
                Property(
                    "baud",
                    "integer",
                    "Line speed (bit/s)",
                    "Serial line speed in bits per second; it must match the device's setting.",
                    "9600",
                    "9600",
                ),
            ]
        if self.transport == "udp":
            return [
                Property(
                    "port",
                    "integer",
                    "Receive port",
                    "Local UDP port on which the driver receives the device's datagrams.",
                    example,
                    example,
                ),
                Property(
                    "listen_address",
                    "string",
                    "Receive address",
                    "Local address to receive on; empty for every network interface, "
                    "127.0.0.1 for this computer only.",
                    "",
                    "127.0.0.1",
                ),
            ]
        if self.transport == "tcp":
            return [
                Property(
                    "host",
                    "string",
                    "Device host",
                    "Host name or address of the device, which accepts the driver's TCP "
                    "connection.",
                    "localhost",
                    "127.0.0.1",
                ),
                Property(
                    "port",
                    "integer",
                    "Device port",
                    "TCP port on which the device accepts the connection.",
                    example,
                    example,
                ),
            ]
        if self.transport == "file":
            return [
                Property(
                    "path",
                    "string",
                    "Device file",
                    "Device file the driver reads, e.g. a character device under /dev; a FIFO "
                    "or any other readable file works too.",
                    f"/dev/{self.names.element_type}0",
                    example,
                ),
            ]
        return [
            Property(
                "rate",
                "float",
                "Sample rate (Hz)",
                "How many times per second the driver reads the device.",
                "60.0",
                "60.0",
            ),
        ]

    def transport_metadata(self) -> dict[str, str] | None:
        """The plug-in's ``TRANSPORTS`` entry (see docs/architecture.md), or None."""
        return {
            "serial": {"kind": "serial", "port": "port", "baud": "baud"},
            "udp": {"kind": "udp", "port": "port"},
            "tcp": {"kind": "tcp", "host": "host", "port": "port"},
            "file": {"kind": "file", "path": "path"},
        }.get(self.transport)

    def proxy_name(self, type_name: str, unit: int) -> str:
        return f"{self.names.camel} {DEVICE_TYPES[type_name].unit_label} {unit} Proxy"

    def alias_name(self, type_name: str, unit: int) -> str:
        return f"{self.names.camel}{DEVICE_TYPES[type_name].unit_label}{unit}"

    def aliases(self) -> list[tuple[str, str, str, int]]:
        """(alias, proxy, proxy type, unit) for every unit that a standard proxy can read."""
        found = []
        for device_type in self.device_types:
            if device_type.proxy is None:
                continue
            for unit in range(device_type.units):
                found.append(
                    (
                        self.alias_name(device_type.name, unit),
                        self.proxy_name(device_type.name, unit),
                        device_type.proxy,
                        unit,
                    )
                )
        return found
