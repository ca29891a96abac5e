"""Diagnostic codes of the `definition` category: .jdef files and the search path."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.levels import Category, Severity

C = Category.DEFINITION
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = [
    Code(
        "DEF001",
        C,
        E,
        "default does not parse as the property's value type",
        'A <value defaultvalue="..."> of an integer, float or boolean property does not parse as '
        "that type. VR Juggler's run time would read a garbled default as 0 (numbers) or true "
        "(booleans). Booleans are true, false, 1 or 0.",
        '<property valuetype="integer" variable="false" name="baud">\n'
        '  <help>...</help>\n  <value label="Baud" defaultvalue="9600 bps"/>\n</property>',
        "Write a default of the property's type.",
    ),
    Code(
        "DEF002",
        C,
        E,
        "enumeration value does not parse as the property's value type",
        'An <enum value="..."> of an integer, float or boolean property does not parse as that '
        "type, so choosing that label would configure a garbled value.",
        '<enum label="Fast" value="high"/>   (in an integer property)',
        "Give the enumeration entry a value of the property's type.",
    ),
    Code(
        "DEF003",
        C,
        W,
        "variable property without exactly one template value",
        'A property with variable="true" takes any number of values; its single <value> is the '
        "template (label and default) for new entries. More than one <value> suggests the "
        "property was meant to have a fixed count.",
        '<property valuetype="float" variable="true" name="gains">\n'
        '  <value label="Gain 1"/>\n  <value label="Gain 2"/>\n</property>',
        'Keep one <value>, or set variable="false" for a fixed number of values.',
    ),
    Code(
        "DEF004",
        C,
        W,
        "allowed type names no known definition",
        "An <allowed_type> names an element type that no definition on the search path defines, "
        "so no element can ever satisfy it. The standard VR Juggler set has some of these left "
        "over from renamed types (e.g. DigProxy, event_window_proxy). In an older version of a "
        "definition this is reported as a note only.",
        "<allowed_type>DigProxy</allowed_type>",
        "Name the type that exists now (digital_proxy), or add its definition to the search path.",
    ),
    Code(
        "DEF005",
        C,
        E,
        "parent definition not found",
        "A <parent> names a definition that is not on the search path. VR Juggler warns about it "
        "only at a debug level and skips the parent, so inherited properties silently vanish.",
        "<parent>positional_devise</parent>",
        "Fix the name or add the parent's .jdef to the search path (see `gadgetctl defs path`).",
    ),
    Code(
        "DEF006",
        C,
        E,
        "inheritance cycle",
        "The definition is its own ancestor through its parents. VR Juggler's C++ code recurses "
        "forever on such a set; gadgetctl reports the cycle and ignores the closing edge.",
        "a.jdef: <parent>b</parent>    b.jdef: <parent>a</parent>",
        "Remove one of the parent links of the cycle.",
    ),
    Code(
        "DEF007",
        C,
        E,
        "duplicate property name",
        "Two properties of one definition version have the same name. Element values would be "
        "ambiguous; VR Juggler asserts in debug builds.",
        '<property ... name="port"> ... <property ... name="port">',
        "Rename or remove one of them.",
    ),
    Code(
        "DEF008",
        C,
        E,
        "inherited property redefined with another value type",
        "A property has the name of a property inherited from a parent but a different "
        "valuetype. The child's definition wins, so code written for the parent type reads "
        "values of the wrong type.",
        "parent: position_filters (configelement); child: position_filters (string)",
        "Use another name, or the parent's value type.",
    ),
    Code(
        "DEF009",
        C,
        W,
        "definition versions out of order",
        "definition_version entries should be listed oldest first. Tools that take the last "
        "entry as the newest (VRJConfig does) would pick the wrong one.",
        '<definition_version version="2"> ... <definition_version version="1">',
        "List the versions in increasing order.",
    ),
    Code(
        "DEF010",
        C,
        E,
        "duplicate definition version",
        "Two definition_version entries have the same version number; only the first is used.",
        '<definition_version version="2"> ... <definition_version version="2">',
        "Give each version its own number.",
    ),
    Code(
        "DEF011",
        C,
        W,
        "version step without an upgrade transform",
        "A newer version's <upgrade_transform> is empty, so elements written for the older "
        "version cannot be upgraded automatically (`gadgetctl upgrade`, VRJConfig).",
        '<definition_version version="2"> ... <upgrade_transform/>',
        "Write an XSLT 1.0 stylesheet that converts a version N-1 element into version N.",
    ),
    Code(
        "DEF020",
        C,
        W,
        "definition file on the search path skipped",
        "A .jdef file in a search-path directory could not be read or is not a definition, so "
        "its types are unknown to every check.",
        "$JCCL_DEFINITION_PATH/broken.jdef (not well-formed)",
        "Validate that file with `gadgetctl validate FILE` and fix it.",
    ),
    Code(
        "DEF021",
        C,
        I,
        "definition shadowed by an earlier search-path entry",
        "The same definition name and version is provided by two search-path entries; the "
        "earlier one wins and the later one is ignored.",
        "definitions/dtrack.jdef and $JCCL_DEFINITION_PATH/dtrack.jdef, both version 1",
        "Remove one copy, or give the newer one a higher version.",
    ),
    Code(
        "DEF022",
        C,
        W,
        "undefined environment variable in the search path",
        "A search-path entry refers to an environment variable that is not set. VR Juggler "
        "silently replaces it by an empty string, which usually points somewhere unintended.",
        "JCCL_DEFINITION_PATH='${MY_DEFS}/jdef'",
        "Set the variable, or fix the entry.",
    ),
    Code(
        "DEF023",
        C,
        W,
        "search-path directory does not exist",
        "A definition directory named by JCCL_DEFINITION_PATH, VJ_BASE_DIR or a configuration's "
        "<definition_path> does not exist. VR Juggler skips it silently.",
        "<definition_path><dir>defs</dir></definition_path>   (no such directory)",
        "Create the directory or fix the path.",
    ),
]
