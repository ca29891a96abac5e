"""Diagnostic codes of the `config` category."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.levels import Category, Severity

C = Category.CONFIG
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = []

CODES += [
    Code(
        "CFG001",
        C,
        E,
        "included file not found",
        "An <include> names a file that exists neither relative to the including file's "
        "directory nor relative to the working directory. VR Juggler prints an error and goes "
        "on without it, so the elements it would have provided are missing.",
        "<include>sim.wand.mixin.jconf</include>   (no such file)",
        "Fix the name or the path; relative names are resolved against the including file.",
    ),
    Code(
        "CFG002",
        C,
        E,
        "include cycle",
        "A configuration includes itself, directly or through other files. VR Juggler recurses "
        "until it crashes; gadgetctl loads each file once and reports the cycle.",
        "a.jconf: <include>b.jconf</include>   b.jconf: <include>a.jconf</include>",
        "Remove one include of the cycle.",
    ),
    Code(
        "CFG003",
        C,
        W,
        "undefined environment variable in a path",
        "An include name, a definition directory or a driver path refers to an environment "
        "variable that is not set. VR Juggler silently replaces it by an empty string.",
        "<driver_path>${GADGET_DRIVERS}/lib</driver_path>   (GADGET_DRIVERS not set)",
        "Set the variable or write the path out.",
    ),
]

# -- element types, versions and names ------------------------------------------------
CODES += [
    Code(
        "CFG010",
        C,
        E,
        "element type has no definition",
        "The element's tag names a type that no definition on the search path defines. VR "
        "Juggler drops such an element when it loads the file, with a warning most people never "
        "see, so everything that refers to it silently fails too.",
        '<positional_proxy name="Head" version="1">   (the type is position_proxy)',
        "Fix the tag, or add the type's .jdef to the search path (--definitions DIR, "
        "JCCL_DEFINITION_PATH or <definition_path>).",
    ),
    Code(
        "CFG011",
        C,
        E,
        "instance of an abstract type",
        "The element's definition is abstract: it exists only as a base of other types (e.g. "
        "input_device, positional_device, proxy). VRJConfig refuses such an element and no part "
        "of VR Juggler's run time handles it, so it stays pending.",
        '<positional_device name="Tracker" version="1"/>',
        "Use a concrete type derived from it, such as flock or simulated_positional_device.",
    ),
    Code(
        "CFG012",
        C,
        W,
        "element older than its definition",
        "The element declares a version older than the newest version of its definition. VR "
        "Juggler's run time reads it against the newest definition anyway, so renamed or "
        "reshaped properties are silently ignored, and a few element types (input_manager, "
        "cluster_manager, keyboard_mouse_device and some drivers) refuse old "
        "versions outright. The element is checked against the rules of the version it "
        "declares.",
        '<input_manager name="Input" version="1">   (input_manager is at version 2)',
        "Run `gadgetctl upgrade FILE`, which applies the definitions' upgrade transforms.",
    ),
    Code(
        "CFG013",
        C,
        W,
        "element newer than any known definition version",
        "The element declares a version that no definition on the search path has. It was "
        "written for newer definitions than the ones gadgetctl (or VR Juggler) is using; it is "
        "checked against the newest known version.",
        '<display_window name="W" version="9">   (newest known: 6)',
        "Add the newer definitions to the search path, or fix the version attribute.",
    ),
    Code(
        "CFG014",
        C,
        E,
        "element version missing or not a number",
        "Every element carries the version of the definition it was written for. VR Juggler's "
        "run time reads a missing or garbled version as 0, which the version-checking parts of "
        "VR Juggler refuse; VRJConfig refuses to load the file.",
        '<alias name="VJHead">',
        'Add version="N" with the definition\'s version (see `gadgetctl defs show TYPE`).',
    ),
    Code(
        "CFG015",
        C,
        E,
        "element without a name",
        "The element has no name attribute, or an empty one. Pointers find elements by name, "
        "VR Juggler registers devices and proxies by name, and VRJConfig refuses the file.",
        '<position_proxy version="1">',
        'Give the element a unique name="...".',
    ),
]

# -- properties and values --------------------------------------------------------------
CODES += [
    Code(
        "CFG020",
        C,
        E,
        "unknown property",
        "The element carries a property its definition does not have, typically a misspelling. "
        "VR Juggler ignores it without a word, so the setting never takes effect.",
        "<simulated_analog_device ...><min_value>0</min_value>   (the property is min)",
        "Use the property name from the definition (close names are suggested).",
    ),
    Code(
        "CFG021",
        C,
        W,
        "property dropped by a newer definition version",
        "The property was defined by an older version of the element's type (or of a type it "
        "inherits from) and has since been removed. VR Juggler ignores it; it is dead text "
        "that suggests a setting that no longer exists.",
        "<device_host>head-node</device_host>   (input_device dropped device_host in version 2)",
        "Remove the property; `gadgetctl upgrade --drop-removed FILE` removes every such property.",
    ),
    Code(
        "CFG022",
        C,
        E,
        "property of a newer version in an older element",
        "The element declares a version whose definition lacks the property, but a newer version "
        "defines it. The version attribute is most likely wrong; upgrading the element from the "
        "declared version would add the property a second time.",
        '<opengl_frame_buffer_config version="4"> with gl_context_profile_mask (added in 5)',
        "Set the version attribute to the version the element was really written for.",
    ),
    Code(
        "CFG023",
        C,
        E,
        "more values than the property has",
        "A fixed-count property has more values than its definition has slots. VR Juggler reads "
        "only the first ones and ignores the rest; VRJConfig deletes them.",
        "<pre_translate>0</pre_translate> written four times (three slots: x, y, z)",
        "Remove the extra values.",
    ),
    Code(
        "CFG024",
        C,
        I,
        "fewer values than the property has",
        "A fixed-count property has fewer values than its definition has slots. The missing "
        "slots take their defaults, which the message names; write them out if a default is "
        "not what you want.",
        "<origin>0</origin>   (two slots: x and y)",
        "Write a value for every slot.",
    ),
    Code(
        "CFG025",
        C,
        E,
        "value is not a number",
        "A value of an integer or float property does not parse as one. VR Juggler reads the "
        "leading number and ignores the rest, or 0 when there is none, without a word; an empty "
        "tag such as <port/> is read as 0, not as the default.",
        "<command_port />   (read as 0)\n<unit>1.5</unit>   (read as 1)",
        "Write a number of the property's type, or remove the tag to get the default.",
    ),
    Code(
        "CFG026",
        C,
        W,
        "boolean value other than true, false, 1 or 0",
        "VR Juggler's run time treats exactly false and 0 as false and anything else as true: "
        "False, FALSE, no, off and the empty string are all read as true. VRJConfig reads only "
        "true (any case) and 1 as true, so the two disagree.",
        "<stereo>False</stereo>   (read as true)",
        "Write true or false in lower case.",
    ),
    Code(
        "CFG027",
        C,
        E,
        "enumeration label in the wrong case",
        "The value matches one of the property's enumeration labels except for case. Labels are "
        "case-sensitive, so VR Juggler does not substitute the label's value and reads the text "
        "itself, usually as 0. In an editable enumeration (input_manager's driver) any text is "
        "taken as written, so there it is only a suggestion (info), and none at all when a "
        "plug-in or element has the value's exact name (OptiTrack_drv is a real plug-in that "
        "the list spells Optitrack_drv).",
        "<device_units>feet</device_units>   (the label is Feet = 0.3048; read as 0.0)",
        "Write the label exactly as the definition spells it.",
    ),
    Code(
        "CFG028",
        C,
        W,
        "value outside a fixed enumeration",
        "The property has a non-editable enumeration and the value is neither one of its labels "
        "nor one of its values. VR Juggler uses the raw value anyway; VRJConfig does not offer "
        "it, and it is most often a typo.",
        "<hemisphere>Upper</hemisphere>   (choices: Forward Hemisphere, Aft Hemisphere, ...)",
        "Use one of the listed choices.",
    ),
    Code(
        "CFG029",
        C,
        E,
        "value of the wrong kind",
        "A configelement property must hold one embedded element and nothing else; any other "
        "property holds text. VR Juggler reads an embedded element where text is expected as "
        "empty text, and text where an element is expected as no element.",
        '<device><position_proxy name="p" version="1"/></device>   (device is a pointer)',
        "Write a name for a pointer, or embed one element in a configelement property.",
    ),
]

# -- embedded elements and pointers ----------------------------------------------------
CODES += [
    Code(
        "CFG030",
        C,
        E,
        "embedded element of a type the property does not allow",
        "An embedded element's type is neither one of the property's allowed types nor derived "
        "from one. VR Juggler asks a factory for the type and skips what it does not know, so "
        "the embedded element usually has no effect.",
        '<position_filters><alias name="x" version="1"/></position_filters>',
        "Embed an element of an allowed type (the message lists them).",
    ),
    Code(
        "CFG031",
        C,
        W,
        "pointer names no element",
        "A pointer (configelementpointer) value names an element the configuration does not "
        "contain. Depending on the element, VR Juggler then keeps it pending forever (aliases, "
        "simulated devices, command and string proxies, displays) or lets it run with default "
        "data (the other proxies). When files are checked one at a time the target may come "
        "from another file loaded with this one; check them together with --together, where a "
        "missing target is an error.",
        '<alias name="VJButton0" version="1"><proxy>AppDigitalSim</proxy></alias>',
        "Fix the name, or add the element it should point to.",
    ),
    Code(
        "CFG032",
        C,
        E,
        "pointer to an element of a type the property does not allow",
        "The pointer names an element whose type is neither one of the property's allowed "
        "types nor derived from one, e.g. a position proxy pointing at a digital device. VR "
        "Juggler fails to bind the two and the proxy returns default data.",
        "<position_proxy ...><device>Wand Buttons</device>   (a simulated_digital_device)",
        "Point at an element of an allowed type (the message lists them).",
    ),
    Code(
        "CFG033",
        C,
        E,
        "required pointer is empty",
        "The element cannot work without a target but the pointer is empty or not written: an "
        "alias without a proxy stays pending, a proxy without a device returns default data "
        "forever, a simulated device without a keyboard_mouse_proxy never sees a key.",
        '<digital_proxy name="Button" version="1"><device/></digital_proxy>',
        "Name the element it should use.",
    ),
    Code(
        "CFG034",
        C,
        E,
        "proxy reads a unit its device does not have",
        "The proxy's unit is beyond the units its device publishes, as the configuration "
        "states them (a vrpn device's tracker_count, button_count and analog_count) or the "
        "device type fixes them (ten contacts and two gloves of a pinch_glove or "
        "simulated_digital_glove, one unit per key binding of a simulated digital or analog "
        "device, one per channel of a waveform_device, one position of a simulated position "
        "device). Gadgeteer publishes only that many units, so the proxy reads default data "
        "for ever (and the C++ bounds check lets the first unit past the end through). The "
        "message gives the valid range. `gadgetctl config pending` applies the same rule.",
        "<vrpn ...><button_count>14</button_count>   and   <digital_proxy ...><unit>14</unit>",
        "Use a unit within the range, or correct the count the device states.",
    ),
]

# -- the configuration as a whole --------------------------------------------------------
CODES += [
    Code(
        "CFG040",
        C,
        W,
        "duplicate element name",
        "Two elements of the configuration have the same name. VR Juggler silently keeps the "
        "one loaded last, at the first one's position, and every pointer to the name reaches "
        "that one. Within one file, or between two files that are neither included one by the "
        "other nor loaded in an order (files checked separately), it may be an accident. An "
        "including file, a later given file or a later include of a common file (a base and a "
        "role file included side by side) overriding an element, or a byte-identical copy in "
        "another file, is reported as CFG042 (info) instead.",
        'C4.base.jconf: <alias name="VJHead">  and  C4.mstar.jconf: <alias name="VJHead">',
        "Rename or remove one of them, or, when one file is meant to override the other, "
        "include the other file from it.",
    ),
    Code(
        "CFG042",
        C,
        I,
        "element overrides an element of an included or earlier file",
        "An element has the name of an element loaded before it from a file it supersedes: a "
        "file the later element's file includes (directly or not), a file given before it "
        "on the command line (--together), or a file included before it by a file that "
        "includes both (include order is load order). JCCL's rule is that the later element replaces "
        "the earlier one at the earlier one's place, and modular configurations rely on it "
        "(a mixin that replaces VJHead, a device file that redefines a tracker of its base). "
        "A byte-identical copy of an element from another file is reported the same way.",
        'site.jconf includes base.jconf and redefines its <alias name="VJHead">',
        "Nothing to do if the override is meant; otherwise rename one of the elements.",
    ),
    Code(
        "CFG041",
        C,
        E,
        "element would stay pending",
        "VR Juggler would never activate the element: it waits for an element that itself stays "
        "pending, for an embedded element (the run time only finds top-level elements), its "
        "version is refused by the part of VR Juggler that handles it, or no part handles its "
        "type at all. At run time this shows only as a STALE pending list. An element whose own "
        "pointer names no element is reported as CFG031 instead. It is a warning when the cause "
        "is a type VR Juggler never handles (gesture_proxy) or a target that may come from "
        "another file.",
        '<alias name="Wand"><proxy>WandCmd</proxy></alias> where the command_proxy WandCmd '
        "waits for a missing device",
        "Fix the cause the message names; the element follows.",
    ),
]

# -- upgrades ------------------------------------------------------------------------------
CODES += [
    Code(
        "CFG050",
        C,
        E,
        "element cannot be upgraded",
        "`gadgetctl upgrade` could not bring the element up to date: a definition version "
        "between the element's and the newest is not on the search path, a version has no "
        "upgrade transform, or the transform failed or did not produce an element of the "
        "type. The file is left unchanged.",
        '<vrpn name="Tracker" version="1">   (vrpn version 2 has no upgrade transform)',
        "Add the missing definition versions to the search path, or edit the element by hand "
        "to match the newest definition.",
    ),
]
