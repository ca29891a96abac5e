"""A plug-in whose device class provides analog data for a definition that is a
digital_device (and not an analog_device)."""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Mismatch_drv"
ELEMENT_TYPES = {"mismatch_device": ("analog",)}


def register(registry):
    from gadgetctl.input import Analog

    class MismatchDevice(Analog):
        ELEMENT_TYPE = "mismatch_device"

    registry.register_device(MismatchDevice)
