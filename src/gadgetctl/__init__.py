"""gadgetctl: configuration and diagnostics toolkit for Gadgeteer-style VR input devices.

The package is a library first: ``gadgetctl.jccl`` (definitions and configurations),
``gadgetctl.input`` (the embedded input manager) and ``gadgetctl.diagnostics`` carry no
CLI or terminal dependencies. ``gadgetctl.cli`` is a thin layer over them.
"""

__version__ = "0.1.0"
