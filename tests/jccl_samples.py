"""Small JCCL documents for tests."""

CONFIG_NS = "http://www.vrjuggler.org/jccl/xsd/3.0/configuration"
DEF_NS = "http://www.vrjuggler.org/jccl/xsd/3.1/definition"


def jconf(elements: str = "", *, includes: str = "", extra: str = "") -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        f'<configuration xmlns="{CONFIG_NS}" name="test">\n'
        f"{includes}{extra}"
        f"   <elements>\n{elements}   </elements>\n"
        "</configuration>\n"
    )


def jdef(
    name: str,
    body: str,
    *,
    parents: str = "<parent/>",
    version: int = 1,
    abstract: str = "false",
    more_versions: str = "",
) -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings definition.version="3.1"?>\n'
        f'<definition xmlns="{DEF_NS}" name="{name}">\n'
        f"{more_versions}"
        f'   <definition_version version="{version}" label="{name} label">\n'
        f"      <abstract>{abstract}</abstract>\n"
        "      <help>test definition</help>\n"
        f"      {parents}\n"
        "      <category>/Test</category>\n"
        f"{body}"
        "      <upgrade_transform/>\n"
        "   </definition_version>\n"
        "</definition>\n"
    )


def prop(
    name: str,
    valuetype: str = "string",
    *,
    variable: str = "false",
    values: str = "",
    extra: str = "",
) -> str:
    values = values or '<value label="v" defaultvalue=""/>'
    return (
        f'      <property valuetype="{valuetype}" variable="{variable}" name="{name}">\n'
        f"         <help>property {name}</help>\n"
        f"         {values}\n{extra}"
        "      </property>\n"
    )
