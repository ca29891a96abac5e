"""Namespaces, processing-instruction names and file-format versions of JCCL files."""

CONFIG_NS = "http://www.vrjuggler.org/jccl/xsd/3.0/configuration"
DEFINITION_NS = "http://www.vrjuggler.org/jccl/xsd/3.1/definition"
OLD_DEFINITION_NS = "http://www.vrjuggler.org/jccl/xsd/3.0/definition"
XSL_NS = "http://www.w3.org/1999/XSL/Transform"
XSI_NS = "http://www.w3.org/2001/XMLSchema-instance"

SETTINGS_PI = "org-vrjuggler-jccl-settings"
CONFIG_FORMAT = "3.0"
DEFINITION_FORMAT = "3.1"
# Pseudo-attributes naming the file-format version, current name first, legacy second.
CONFIG_VERSION_KEYS = ("configuration.version", "config.db.version")
DEFINITION_VERSION_KEYS = ("definition.version", "desc.db.version")


def cfg(tag: str) -> str:
    """Clark notation for a tag in the configuration namespace."""
    return f"{{{CONFIG_NS}}}{tag}"


def dfn(tag: str) -> str:
    """Clark notation for a tag in the definition namespace."""
    return f"{{{DEFINITION_NS}}}{tag}"
