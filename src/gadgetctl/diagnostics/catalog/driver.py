"""Diagnostic codes of the `driver` category: driver plug-ins, devices, proxies and the
elements the input manager leaves pending."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.levels import Category, Severity

C = Category.DRIVER
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = []

# -- plug-ins -----------------------------------------------------------------------------

CODES += [
    Code(
        "DRV001",
        C,
        E,
        "driver plug-in not found",
        "A driver value (or `gadgetctl drivers load NAME`) names a plug-in that is in none of the "
        "places plug-ins are looked for: installed entry points, the bundled drivers, "
        "GADGETCTL_DRIVER_PATH, --driver-path and the input_manager's driver_path. The devices "
        "that plug-in would handle stay pending.",
        "<driver>Joystick_drv</driver>   (no Joystick_drv package or module anywhere)",
        "Write the plug-in's package or module name without a platform extension or _d suffix, "
        "and add its directory to driver_path or GADGETCTL_DRIVER_PATH.",
    ),
    Code(
        "DRV002",
        C,
        E,
        "plug-in API version mismatch",
        "The plug-in declares, in GADGETCTL_API_VERSION, a plug-in API other than the one this "
        "gadgetctl provides. It is refused before any of its code runs, as Gadgeteer refuses a "
        "driver built against another library version.",
        "GADGETCTL_API_VERSION = 2   (this gadgetctl provides version 1)",
        "Use a plug-in release written for this gadgetctl, or port the plug-in and update the number.",
    ),
    Code(
        "DRV003",
        C,
        E,
        "plug-in failed to import",
        "Importing the plug-in raised an exception (a syntax error, a missing dependency, an error "
        "in module-level code). The message names the exception and the plug-in file and line. "
        "Other plug-ins still load.",
        "ModuleNotFoundError: No module named 'usb'   (at drivers/Foo_drv/wrapper.py:3)",
        "Fix the plug-in or install what it needs; `gadgetctl drivers load NAME` retries one plug-in.",
    ),
    Code(
        "DRV004",
        C,
        E,
        "plug-in registration failed",
        "The plug-in has no register(registry) function, register() raised, registered something "
        "that is not a device class, or registered nothing at all.",
        "def register(registry):\n    registry.register_device(FooDevice())   # an instance, not the class",
        "register(registry) must call registry.register_device(DeviceClass) for each class; the "
        "class derives from gadgetctl.input device types and sets ELEMENT_TYPE.",
    ),
    Code(
        "DRV005",
        C,
        E,
        "registered element type has no definition",
        "A plug-in registers a device class for an element type no .jdef defines. Configurations "
        "could never contain such elements, usually because ELEMENT_TYPE is misspelt or the "
        "plug-in's own .jdef is missing. VR Juggler only shows this as elements stuck in its "
        "pending list.",
        'ELEMENT_TYPE = "button_devise"   (the definition is button_device)',
        "Make ELEMENT_TYPE equal the definition's name, or put the .jdef in the plug-in's folder.",
    ),
    Code(
        "DRV006",
        C,
        E,
        "device types disagree with the definition",
        "The kinds of data a device class provides must match its element type's ancestors: a "
        "class providing digital data needs a definition deriving from digital_device (else no "
        "digital proxy may point at it), and a definition deriving from digital_device needs a "
        "class that provides digital data. Checked for analog, digital, position, glove, hat, "
        "command, string and keyboard/mouse.",
        "class Foo(Analog) for element type foo whose only parent is digital_device",
        "Derive the class from the right device types, or fix the definition's <parent> list.",
    ),
    Code(
        "DRV007",
        C,
        E,
        "plug-in declares no API version",
        "The plug-in has no GADGETCTL_API_VERSION, so gadgetctl cannot tell which plug-in API it "
        "was written for.",
        "(no GADGETCTL_API_VERSION = 1 in __init__.py)",
        "Add GADGETCTL_API_VERSION = 1 as a literal assignment at the top of the plug-in.",
    ),
    Code(
        "DRV008",
        C,
        W,
        "plug-in metadata disagree with its registrations",
        "ELEMENT_TYPES in the plug-in's source (read by `gadgetctl drivers list` without importing "
        "it) does not describe what register() actually registers: a type missing, a type "
        "declared but not registered, or different device types.",
        'ELEMENT_TYPES = {"foo": ("digital",)} but the class provides digital and analog data',
        "Update ELEMENT_TYPES so listings show what the plug-in really provides.",
    ),
    Code(
        "DRV009",
        C,
        W,
        "element type already handled",
        "Two plug-ins (or a plug-in and a built-in device) register the same element type. As in "
        "Gadgeteer, the first registration stays and the later one is ignored.",
        "two plug-ins both registering linux_joydev",
        "Load only one of them, or give one of them its own element type.",
    ),
    Code(
        "DRV010",
        C,
        W,
        "driver directory does not exist",
        "A driver_path or driver_scan_path value of an input_manager element (after expanding "
        "environment variables) is not a directory, so no plug-in can be found there.",
        "<driver_path>${HOME}/gadget-drivers</driver_path>   (no such directory)",
        "Fix the path; relative paths are taken from the configuration file's directory.",
    ),
    Code(
        "DRV011",
        C,
        E,
        "plug-in in a place other users can write to",
        "The plug-in's directory, folder or one of its files can be written by other users "
        "(world-writable, or owned by another user than root and you). Anyone of them could "
        "put code there that gadgetctl would run as you, so the plug-in is not imported. "
        "Installed and bundled plug-ins are not concerned.",
        "<driver_path>/tmp/drivers</driver_path>   (/tmp/drivers is mode 777)",
        "Make the directory writable only by you (chmod o-w DIR), or accept it for one run "
        "with --trust-driver-path.",
    ),
]

# -- device and proxy configuration ---------------------------------------------------------

CODES += [
    Code(
        "DRV020",
        C,
        E,
        "analog range empty or inverted",
        "An analog device's max is not greater than its min. Analog proxies normalise raw values "
        "as (value - min) / (max - min); VR Juggler divides by zero when they are equal. gadgetctl "
        "reads 0.0 instead and reports this.",
        "<min>0.0</min> <max>0.0</max>",
        "Set min and max to the device's real range, max greater than min.",
    ),
    Code(
        "DRV022",
        C,
        W,
        "position filter skipped",
        "A position_filters entry cannot be used: position_calibration_filter (whose calibration "
        "files gadgetctl cannot read) or a type that is not a position filter. The other filters "
        "still apply, in order.",
        "<position_filters><position_calibration_filter .../></position_filters>",
        "Use position_transform_filter or full_position_transform_filter.",
    ),
    Code(
        "DRV023",
        C,
        W,
        "key bindings do not fit the device",
        "A simulated device has a different number of key bindings than it uses: "
        "simulated_positional_device needs exactly 12 key_pair entries (missing ones leave "
        "movements without a key), simulated_digital_glove uses at most 10, and "
        "simulated_analog_device needs a decrement_keypress for every increment_keypress.",
        "simulated_positional_device with 6 key_pair entries",
        "Add or remove key_modifier_pair entries so each slot is bound.",
    ),
    Code(
        "DRV024",
        C,
        W,
        "driver finds a setting suspect",
        "A driver accepted the element but something in it will not give what was meant: "
        "position units that disagree with what the hardware reports, a value the hardware "
        "clamps. The device still runs; the message says what the driver found and what "
        "happens instead. (A proxy reading a unit the device does not have is CFG034.)",
        "motion_star 'Tracker': measurement_rate 200 Hz is outside 20-144 Hz",
        "Correct the value the message names.",
    ),
]

# -- pending elements -----------------------------------------------------------------------

CODES += [
    Code(
        "DRV030",
        C,
        E,
        "no driver handles the element type",
        "No loaded driver plug-in or built-in device handles this element type, so the element "
        "stays pending (VR Juggler shows it only in its STALE pending-list dump). The hint names "
        "discoverable plug-ins that provide the type.",
        '<linux_joydev name="Joystick"> without <driver>LinuxJoydev_drv</driver> in an input_manager',
        "Add the driver to an input_manager element (and its directory to driver_path).",
    ),
    Code(
        "DRV031",
        C,
        E,
        "the element's driver failed to load",
        "The plug-in that provides this element type was found but could not be loaded; the "
        "message carries its error (see also its DRV002-DRV007 diagnostic).",
        "driver LinuxJoydev_drv provides linux_joydev but failed to load: import failed: ...",
        "Fix the plug-in; `gadgetctl drivers load NAME` shows the details.",
    ),
    Code(
        "DRV032",
        C,
        E,
        "device or proxy configuration failed",
        "The device class (or proxy) rejected the element: a required property is empty or out "
        "of range, or the element is too old for the driver. The message gives the driver's reason.",
        "simulated_digital_device: keyboard_mouse_proxy is empty",
        "Correct the property the message names.",
    ),
    Code(
        "DRV033",
        C,
        E,
        "device failed to start",
        "The device was configured but opening it failed (port missing, permission denied, "
        "server unreachable). The element stays pending and is retried periodically.",
        "the device failed to start: FileNotFoundError: /dev/input/js0",
        "Connect the device, fix the port or address, or check permissions.",
    ),
    Code(
        "DRV034",
        C,
        E,
        "pointer target missing",
        "The element points (configelementpointer property) at an element that is not in the "
        "configuration, so it cannot be configured. Proxies are exempt: a proxy of a missing "
        "device is created stupefied instead.",
        "<keyboard_mouse_proxy>Sim Keyboard Proxy</keyboard_mouse_proxy>   (no such element)",
        "Fix the name or add the element it should point at.",
    ),
    Code(
        "DRV035",
        C,
        E,
        "waiting for another element",
        "The element points at an element that is itself pending, or that the input manager "
        "does not configure (not an input element). It is configured as soon as its target is.",
        "simulated_relative_position whose base_frame_proxy points at a pending proxy",
        "Resolve the target's own problem (its pending reason is quoted).",
    ),
    Code(
        "DRV036",
        C,
        W,
        "element type not supported by gadgetctl",
        "Gadgeteer's input manager handles this element type, but gadgetctl does not implement "
        "it (the input logger, the event emitter).",
        '<gadget_logger name="Logger">',
        "Nothing to fix for VR Juggler; gadgetctl ignores this element's function.",
    ),
    Code(
        "DRV037",
        C,
        E,
        "element version too old",
        "The element was written for an older version of its definition that the run time "
        "refuses (input_manager version 1, keyboard_mouse_device version 1).",
        '<input_manager name="IM" version="1"> with full driver file paths',
        "Upgrade the configuration with `gadgetctl upgrade`.",
    ),
    Code(
        "DRV039",
        C,
        E,
        "alias does not point at a proxy",
        "An alias must name a proxy. One that names another alias or a device never resolves "
        "(VR Juggler follows only one alias hop).",
        '<alias name="VJWand"><proxy>WandAlias</proxy></alias>   (WandAlias is an alias)',
        "Point the alias at the proxy itself.",
    ),
    Code(
        "DRV040",
        C,
        E,
        "element type has no definition",
        "The element's type is not defined by any loaded .jdef, so nothing about it can be read. "
        "VR Juggler drops such elements at load time with only a warning. `gadgetctl config "
        "pending` and `gadgetctl monitor` show them as of unknown type (not as pending "
        "devices, and no reason to exit 1); `gadgetctl validate` reports them as CFG010.",
        '<my_tracker name="T"> with no my_tracker.jdef on the search path',
        "Add the definition's directory with --definitions or the configuration's definition_path.",
    ),
]

# -- run time ---------------------------------------------------------------------------------

CODES += [
    Code(
        "DRV041",
        C,
        W,
        "device did not stop cleanly",
        "Stopping a device failed or its sampling thread did not end within the stop timeout "
        "(a sample() blocked in I/O without a timeout). The thread is abandoned; it cannot keep "
        "the process alive.",
        "sampling thread did not stop within 2 s",
        "Give the driver's reads a timeout, or close the connection in stop_sampling().",
    ),
    Code(
        "DRV042",
        C,
        E,
        "device faulted",
        "The device's sample() or update raised; the device is restarted after a back-off "
        "delay while the other devices go on. The error is kept in its status.",
        "faulted: OSError: [Errno 5] Input/output error",
        "Check the device's connection; a driver bug shows as the same error over and over.",
    ),
    Code(
        "DRV043",
        C,
        W,
        "proxy stupefied",
        "A proxy has no data source: its device is missing or pending, provides no data of the "
        "proxy's type, or has no such unit. It returns the neutral value (OFF, 0.0, identity) "
        "instead, as in VR Juggler, and revives when its device appears.",
        "digital_proxy VJButton0Proxy: device 'SimWandButtons' is not configured",
        "Point the proxy at a configured device of the right type and an existing unit.",
    ),
    Code(
        "DRV044",
        C,
        I,
        "active in gadgetctl, pending in VR Juggler",
        "gadgetctl's input manager runs the element, but VR Juggler would leave it pending: a "
        'documented difference (docs/configurations.md, "Pending elements"). Gesture proxies, '
        "which Gadgeteer never constructs, and command and string proxies, which VR Juggler "
        "keeps pending until their device is active, are bound at once and stupefied until "
        "their device is active; elements waiting for them follow. `gadgetctl validate` "
        'reports the same elements as CFG041 or CFG031, saying "in VR Juggler (gadgetctl runs '
        'it)".',
        '<gesture_proxy name="Gesture Proxy"><device>Glove Gestures</device></gesture_proxy>',
        "Nothing to fix for gadgetctl. For VR Juggler, read the element from the device "
        "directly (gesture) or make sure the device configures (command, string).",
    ),
    Code(
        "DRV045",
        C,
        E,
        "device receives data it cannot decode",
        "The device runs and data arrives, but none of it decodes: every datagram since the "
        "first (or for over a second since the last good one) was bad, or a serial driver "
        "read only junk and no record yet. The status shows "
        "`undecodable` with the count and the first error instead of `running`, and "
        "`gadgetctl monitor` ends with exit status 1. Wrong protocol version, wrong port (another "
        "program's traffic) or a sender the driver does not understand.",
        "undecodable: 518 bad datagrams, none decoded; first: rigid body marker count 973541338 "
        "is outside 0..20",
        "Check what sends to the device's port and which protocol version it speaks; the "
        "first error says where decoding stopped.",
    ),
]

# -- connections (`gadgetctl doctor`) ---------------------------------------------------------

CODES += [
    Code(
        "DRV100",
        C,
        E,
        "device port does not exist",
        "The file or serial port a device element names (from its plug-in's TRANSPORTS metadata, "
        "or the usual upstream property) is not there, or is a symlink to nothing. The driver "
        "cannot open it, so the device never delivers data. The hint lists the serial ports or "
        "joystick devices that do exist.",
        "<port_name>/dev/input/js0</port_name>   (no joystick plugged in, or joydev not loaded)",
        "Plug the device in, correct the path, or start the plug-in's emulator "
        "(`gadgetctl emulate DRIVER`) and point the element at what it prints.",
    ),
    Code(
        "DRV101",
        C,
        E,
        "device port not accessible to this user",
        "The port exists but this user may not read it (and, for a serial port, write it). "
        "Device files usually belong to a group such as input or dialout; the hint names the "
        "group the file's owner grants access to.",
        "/dev/input/js0 is crw-rw---- root:input and the user is not in group input",
        "Add yourself to the group the hint names (sudo usermod -aG GROUP $USER, then log in "
        "again), or have a udev rule grant access.",
    ),
    Code(
        "DRV102",
        C,
        E,
        "device port is not a device",
        "The path exists but is not a character device or a FIFO: a directory, a socket, or (for "
        "a serial port) a regular file that cannot be configured as a line. A regular file given "
        "to a file-reading driver is a warning: it is read once to its end, then nothing comes.",
        "<port>/dev/serial</port>   (a directory)",
        "Name the device node itself (for example /dev/ttyUSB0 or /dev/input/js0).",
    ),
    Code(
        "DRV103",
        C,
        E,
        "UDP port cannot be bound",
        "The driver receives on a local UDP port, and binding that port failed: another program "
        "holds it (another VR Juggler application, a second gadgetctl, a tracker SDK), it is "
        "below 1024 and needs privileges, or the address is not local. The driver would get no "
        "datagrams.",
        "receive_port 5000 while another application already listens on UDP 5000",
        "Stop the other program (`ss -ulpn` shows it) or configure another port on both the "
        "tracker and the element.",
    ),
    Code(
        "DRV104",
        C,
        E,
        "TCP server does not answer",
        "`gadgetctl doctor --probe` connected to the host and port the element names and the "
        "connection was refused, timed out, or the host name does not resolve. The driver would "
        "fail to start the same way. Without --probe doctor never touches the network.",
        "<address>tracker.lab</address> <server_port>6000</server_port>   (connection refused)",
        "Check that the server is running and reachable, and the address and port in the element.",
    ),
    Code(
        "DRV105",
        C,
        I,
        "connection not checked",
        "Doctor cannot tell how this device reaches its hardware: its plug-in declares no "
        "TRANSPORTS metadata and gadgetctl knows no usual property for the element type, or the "
        "check needs a network probe that was not asked for.",
        "a motionnode element (no bundled driver declares how it connects)",
        "Add TRANSPORTS to the plug-in's __init__.py (see docs/architecture.md), or check the "
        "connection by hand.",
    ),
    Code(
        "DRV106",
        C,
        E,
        "connection property empty or out of range",
        "A property that names the device's port, host or path is empty, or a port number is "
        "not between 1 and 65535, so the driver has nowhere to connect.",
        "<receive_port>0</receive_port>",
        "Write the port, host or path the device really uses.",
    ),
    Code(
        "DRV107",
        C,
        W,
        "TRANSPORTS names an unknown property",
        "A plug-in's TRANSPORTS metadata names a property that the element type's definition "
        "does not have, so doctor cannot read where the device is connected.",
        'TRANSPORTS = {"foo": {"kind": "serial", "port": "serial_port"}}   (foo has port, not serial_port)',
        "Make the TRANSPORTS values the property names of the element type's .jdef.",
    ),
    Code(
        "DRV110",
        C,
        E,
        "VRPN device name unusable",
        "A VRPN device is written Device@host, Device@host:port or Device@tcp://host:port (port "
        "3883 when none is given). This one cannot be read, or its host name does not resolve, so "
        "the driver has no server to connect to.",
        "<tracker_server>Tracker0</tracker_server>   (no @host)",
        "Write the device name the server uses, '@', and the server's host.",
    ),
    Code(
        "DRV111",
        C,
        E,
        "VRPN server does not answer",
        "`gadgetctl doctor --probe` asked for a VRPN connection at the host and port of a VRPN "
        "device name (as VRPN clients do: a UDP request the server answers by connecting back, or "
        "direct TCP for tcp:// names) and no VRPN server answered in time, refused the "
        "connection, or the peer was not VRPN 07.",
        "<tracker_server>Tracker0@tracker-pc</tracker_server>   (vrpn_server not running)",
        "Start the server (vrpn_server, gadgetctl serve, the tracking software's VRPN output), "
        "check the port, and that no firewall drops UDP 3883 or the TCP connection back.",
    ),
    Code(
        "DRV112",
        C,
        E,
        "VRPN server does not serve the device",
        "A VRPN server answered, but it does not announce the device the name asks for (the part "
        "before '@'). VRPN clients only ever say \"No response from server\" for this; doctor "
        "lists the names the server does announce.",
        "<tracker_server>Tracker1@localhost</tracker_server>   (the server announces Tracker0)",
        "Use one of the announced names, or configure the server to serve the device.",
    ),
    Code(
        "DRV108",
        C,
        E,
        "stale emulator link or FIFO",
        "The port is a symlink to a pseudo-terminal, or a FIFO, that no live emulator holds: "
        "an emulator stopped without clean-up (killed) left it behind. A FIFO nobody writes "
        "gives a driver no data; a pts number is soon reused by somebody's terminal, and a "
        "driver would write its handshake into that terminal. Held by another program than a "
        "gadgetctl emulator (socat, a test tool), it is only a warning naming the program.",
        "/tmp/gadgetctl-pinch -> /dev/pts/3, now the terminal of bash (pid 4242)",
        "Remove the link or FIFO and start the emulator again (`gadgetctl emulate DRIVER`); "
        "emulators remove what they made on Ctrl-C, SIGTERM and SIGHUP.",
    ),
    Code(
        "DRV120",
        C,
        E,
        "VRPN serve port cannot be bound",
        "`gadgetctl serve` listens on one TCP and one UDP port with the same number (VRPN's "
        "default 3883), and one of them cannot be bound: another program holds it (a "
        "vrpn_server, a second gadgetctl serve), the port is below 1024 and needs privileges, or "
        "the --bind address is not one of this machine's. The message names the process holding "
        "the port when this user may see it.",
        "gadgetctl serve lab.jconf --port 3883   (a vrpn_server already runs on 3883)",
        "Stop the other server, or serve on another --port and write NAME@host:PORT in the "
        "clients; `gadgetctl doctor --serve-port PORT` checks a port beforehand.",
    ),
]
