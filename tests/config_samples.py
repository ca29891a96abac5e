"""A small hand-written definition set and helpers for configuration-check tests.

The types mirror the shapes of the standard VR Juggler ones (proxies, aliases, devices with
inheritance, simulated devices, filters, versioned types with upgrade transforms) but are
written here so that the tests do not depend on the bundled definitions.
"""

from __future__ import annotations

from pathlib import Path

from jccl_samples import CONFIG_NS, DEF_NS

XSL = "http://www.w3.org/1999/XSL/Transform"


def prop(
    name: str,
    valuetype: str = "string",
    *,
    count: int | None = 1,
    defaults: tuple = ("",),
    labels: tuple = (),
    allowed: tuple = (),
    enum: dict | None = None,
    editable: bool = False,
) -> str:
    """A <property>; ``count=None`` makes it variable (one template value)."""
    values = []
    slots = 1 if count is None else count
    for i in range(slots):
        label = labels[i] if i < len(labels) else f"{name} {i}"
        default = defaults[i] if i < len(defaults) else defaults[-1]
        attr = "" if default is None else f' defaultvalue="{default}"'
        values.append(f'<value label="{label}"{attr}/>')
    text = "".join(values) + "".join(f"<allowed_type>{t}</allowed_type>" for t in allowed)
    if enum:
        entries = "".join(f'<enum label="{k}" value="{v}"/>' for k, v in enum.items())
        text += f'<enumeration editable="{str(editable).lower()}">{entries}</enumeration>'
    variable = "true" if count is None else "false"
    return (
        f'<property valuetype="{valuetype}" variable="{variable}" name="{name}">'
        f"<help>{name}</help>{text}</property>"
    )


def version(
    number: int, *props: str, parents: tuple = (), abstract: bool = False, transform: str = ""
) -> str:
    parent_tags = "".join(f"<parent>{p}</parent>" for p in parents) or "<parent/>"
    return (
        f'<definition_version version="{number}" label="v{number}">'
        f"<abstract>{str(abstract).lower()}</abstract><help>test</help>{parent_tags}"
        f"<category>/Test</category>{''.join(props)}<upgrade_transform>{transform}</upgrade_transform>"
        "</definition_version>"
    )


def definition(name: str, *versions: str) -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings definition.version="3.1"?>\n'
        f'<definition xmlns="{DEF_NS}" name="{name}">{"".join(versions)}</definition>\n'
    )


def transform(
    type_name: str, number: int, body: str = '<xsl:copy-of select="./*"/>', after: str = ""
) -> str:
    """An upgrade stylesheet that rebuilds the element as version ``number``."""
    return (
        f'<xsl:stylesheet xmlns:xsl="{XSL}" xmlns:jconf="{CONFIG_NS}" version="1.0">'
        f'<xsl:template match="/"><xsl:apply-templates/></xsl:template>'
        f'<xsl:template match="jconf:{type_name}">'
        f'<xsl:element namespace="{CONFIG_NS}" name="{type_name}">'
        f'<xsl:attribute name="name"><xsl:value-of select="@name"/></xsl:attribute>'
        f'<xsl:attribute name="version">{number}</xsl:attribute>{body}</xsl:element>{after}'
        "</xsl:template></xsl:stylesheet>"
    )


DEFINITIONS = {
    "input_device": definition(
        "input_device",
        version(1, prop("device_host"), abstract=True),
        version(2, abstract=True, transform=transform("input_device", 2)),
    ),
    "positional_device": definition(
        "positional_device",
        version(
            1,
            prop(
                "position_filters",
                "configelement",
                count=None,
                defaults=(None,),
                allowed=("position_transform_filter",),
            ),
            parents=("input_device",),
            abstract=True,
        ),
    ),
    "digital_device": definition(
        "digital_device", version(1, parents=("input_device",), abstract=True)
    ),
    "command_device": definition(
        "command_device", version(1, parents=("input_device",), abstract=True)
    ),
    "proxy": definition("proxy", version(1, abstract=True)),
    "position_proxy": definition(
        "position_proxy",
        version(
            1,
            prop(
                "device", "configelementpointer", defaults=(None,), allowed=("positional_device",)
            ),
            prop("unit", "integer", defaults=("0",)),
            parents=("proxy",),
        ),
    ),
    "digital_proxy": definition(
        "digital_proxy",
        version(
            1,
            prop("device", "configelementpointer", defaults=(None,), allowed=("digital_device",)),
            prop("unit", "integer", defaults=("0",)),
            parents=("proxy",),
        ),
    ),
    "command_proxy": definition(
        "command_proxy",
        version(
            1,
            prop("device", "configelementpointer", defaults=(None,), allowed=("command_device",)),
            prop("unit", "integer", defaults=("0",)),
            parents=("proxy",),
        ),
    ),
    "gesture_proxy": definition(
        "gesture_proxy",
        version(1, prop("device", "configelementpointer", defaults=(None,)), parents=("proxy",)),
    ),
    "keyboard_mouse_proxy": definition(
        "keyboard_mouse_proxy",
        version(1, prop("device", "configelementpointer", defaults=(None,)), parents=("proxy",)),
    ),
    "alias": definition(
        "alias",
        version(1, prop("proxy", "configelementpointer", defaults=(None,), allowed=("proxy",))),
    ),
    "tracker": definition(
        "tracker",
        version(
            1,
            prop("port", defaults=("/dev/ttyS0",)),
            prop("baud", "integer", defaults=("9600",), enum={"Slow": "1200", "Fast": "9600"}),
            prop("rate", "float", defaults=("60.0",)),
            prop("enabled", "boolean", defaults=("true",)),
            prop(
                "offset", "float", count=3, defaults=("0.0", "0.0", "1.5"), labels=("X", "Y", "Z")
            ),
            prop("units", "float", defaults=("1.0",), enum={"Meters": "1.0", "Feet": "0.3048"}),
            prop(
                "mode", "integer", defaults=("0",), enum={"Normal": "0", "Fast": "1"}, editable=True
            ),
            parents=("positional_device", "digital_device"),
        ),
    ),
    "cmd_box": definition("cmd_box", version(1, parents=("command_device",))),
    "position_transform_filter": definition(
        "position_transform_filter", version(1, prop("custom_scale", "float", defaults=("1.0",)))
    ),
    "scaled_filter": definition(
        "scaled_filter",
        version(
            1, prop("factor", "float", defaults=("2.0",)), parents=("position_transform_filter",)
        ),
    ),
    "other_filter": definition(
        "other_filter", version(1, prop("gain", "float", defaults=("1.0",)))
    ),
    "simulated_digital_device": definition(
        "simulated_digital_device",
        version(
            1,
            prop(
                "keyboard_mouse_proxy",
                "configelementpointer",
                defaults=(None,),
                allowed=("keyboard_mouse_proxy",),
            ),
            parents=("digital_device",),
        ),
    ),
    "input_manager": definition(
        "input_manager",
        version(1, prop("driver", count=None)),
        version(
            2,
            prop("driver_path", count=None),
            prop("driver", count=None),
            prop("driver_scan_path", count=None),
            transform=transform("input_manager", 2),
        ),
    ),
    # Three versions with upgrade transforms: v2 adds <color>, v3 renames size to extent and
    # creates a companion element after the upgraded one.
    "gizmo": definition(
        "gizmo",
        version(1, prop("size", "integer", defaults=("1",))),
        version(
            2,
            prop("size", "integer", defaults=("1",)),
            prop("color", defaults=("red",)),
            transform=transform(
                "gizmo",
                2,
                '<xsl:copy-of select="./*"/>'
                f'<xsl:element namespace="{CONFIG_NS}" name="color">red</xsl:element>',
            ),
        ),
        version(
            3,
            prop("extent", "integer", defaults=("1",)),
            prop("color", defaults=("red",)),
            transform=transform(
                "gizmo",
                3,
                f'<xsl:element namespace="{CONFIG_NS}" name="extent"><xsl:value-of select="jconf:size"/>'
                '</xsl:element><xsl:copy-of select="jconf:color"/>',
                after=f'<xsl:element namespace="{CONFIG_NS}" name="gizmo_label">'
                '<xsl:attribute name="name"><xsl:value-of select="concat(@name, \' label\')"/>'
                '</xsl:attribute><xsl:attribute name="version">1</xsl:attribute></xsl:element>',
            ),
        ),
    ),
    "gizmo_label": definition("gizmo_label", version(1)),
    "holder": definition(
        "holder",
        version(
            1,
            prop("parts", "configelement", count=None, defaults=(None,)),
            prop("target", "configelementpointer", defaults=(None,)),
        ),
    ),
}


def write_definitions(directory: Path) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    for name, text in DEFINITIONS.items():
        (directory / f"{name}.jdef").write_text(text, encoding="utf-8")
    return directory


def configuration(elements: str, *, includes: tuple = (), definition_path: tuple = ()) -> str:
    head = "".join(f"   <include>{i}</include>\n" for i in includes)
    if definition_path:
        head += (
            "   <definition_path>"
            + "".join(f"<dir>{d}</dir>" for d in definition_path)
            + "</definition_path>\n"
        )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        f'<configuration xmlns="{CONFIG_NS}" name="test">\n{head}'
        f"   <elements>\n{elements}   </elements>\n</configuration>\n"
    )
