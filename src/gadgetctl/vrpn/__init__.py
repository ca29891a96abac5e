"""A standalone implementation of the VRPN network protocol (client and server sides).

Knows nothing of the rest of gadgetctl (a test enforces it), like the standalone half of a
driver. Written from the protocol facts in the project's reference, not from VRPN's code.

* :mod:`.wire`: cookie, header framing, system messages, the lob datagram;
* :mod:`.names`: ``Device@host[:port]`` and ``Device@tcp://host:port``;
* :mod:`.codecs`: Tracker, Button, Analog, Dial and Text payloads;
* :mod:`.client`: :class:`VrpnClient` (lob or direct TCP, UDP channel, reconnection);
* :mod:`.server`: :class:`VrpnServer` (TCP and lob clients, bounded per-client buffers);
* :mod:`.logfile`: :class:`LogReader` / :class:`LogWriter` for ``.vrpn`` log files.

See ``docs/vrpn.md``.
"""

from .client import VrpnClient
from .codecs import (
    AnalogChannels,
    ButtonChange,
    ButtonStates,
    CodecError,
    DialUpdate,
    TextReport,
    TrackerAcceleration,
    TrackerPose,
    TrackerVelocity,
    decode,
)
from .endpoint import ConnectionDropped
from .logfile import LogFormatError, LogReader, LogWriter
from .names import DeviceName, Location, VrpnNameError, parse_device_name, parse_location
from .server import ServerClient, VrpnServer
from .wire import DEFAULT_PORT, FramingError, Message

__all__ = [
    "DEFAULT_PORT",
    "AnalogChannels",
    "ButtonChange",
    "ButtonStates",
    "CodecError",
    "ConnectionDropped",
    "DeviceName",
    "DialUpdate",
    "FramingError",
    "Location",
    "LogFormatError",
    "LogReader",
    "LogWriter",
    "Message",
    "ServerClient",
    "TextReport",
    "TrackerAcceleration",
    "TrackerPose",
    "TrackerVelocity",
    "VrpnClient",
    "VrpnNameError",
    "VrpnServer",
    "decode",
    "parse_device_name",
    "parse_location",
]
