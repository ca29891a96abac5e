"""A plug-in written for a plug-in API gadgetctl does not provide."""

GADGETCTL_API_VERSION = 99
PLUGIN_NAME = "WrongApi_drv"
ELEMENT_TYPES = {"wrong_api_device": ("analog",)}

raise RuntimeError("WrongApi_drv must be refused before it is imported")


def register(registry):
    pass
