"""Diagnostic codes of the `config` category."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.model import Category, Severity

C = Category.CONFIG
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = []

CODES += [
    Code("CFG001", C, E, "included file not found",
         "An <include> names a file that exists neither relative to the including file's "
         "directory nor relative to the working directory. VR Juggler prints an error and goes "
         "on without it, so the elements it would have provided are missing.",
         "<include>sim.wand.mixin.jconf</include>   (no such file)",
         "Fix the name or the path; relative names are resolved against the including file."),
    Code("CFG002", C, E, "include cycle",
         "A configuration includes itself, directly or through other files. VR Juggler recurses "
         "until it crashes; gadgetctl loads each file once and reports the cycle.",
         "a.jconf: <include>b.jconf</include>   b.jconf: <include>a.jconf</include>",
         "Remove one include of the cycle."),
    Code("CFG003", C, W, "undefined environment variable in a path",
         "An include name, a definition directory or a driver path refers to an environment "
         "variable that is not set. VR Juggler silently replaces it by an empty string.",
         "<driver_path>${GADGET_DRIVERS}/lib</driver_path>   (GADGET_DRIVERS not set)",
         "Set the variable or write the path out."),
]
