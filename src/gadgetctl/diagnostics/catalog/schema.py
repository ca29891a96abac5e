"""Diagnostic codes of the `schema` category."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.levels import Category, Severity

C = Category.SCHEMA
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = [
    Code(
        "SCH001",
        C,
        E,
        "schema violation",
        "The file breaks the XML Schema of its format (configuration 3.0 or definition 3.1), "
        "for example a missing required child or attribute, an element in the wrong place, or "
        "a value of the wrong type. The message names the element path.",
        '<property valuetype="string" variable="false" name="p">\n'
        "  <help>...</help>\n  <!-- no <value> -->\n</property>",
        "Add or move the element the message names, as the schema expects.",
    ),
]
