"""A plug-in whose import fails: listing must not import it, loading must report it."""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "BrokenImport_drv"
ELEMENT_TYPES = {"broken_device": ("digital",)}

raise RuntimeError("BrokenImport_drv was imported")


def register(registry):
    pass
