"""A one-button device, as in the Gadgeteer driver authoring guide (element type button_device).

Its wrapper toggles the button on every sample, so tests can watch samples flow.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Button_drv"
ELEMENT_TYPES = {"button_device": ("digital",)}


def register(registry):
    from .wrapper import ButtonDevice

    registry.register_device(ButtonDevice)
