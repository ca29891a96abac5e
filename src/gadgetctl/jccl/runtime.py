"""What VR Juggler's run time does with particular element types (reference sections 4-9).

The generic definition model cannot say these things: which proxies skip dependency checks,
which handlers refuse old element versions, which pointers an element cannot work without,
and which string properties are paths that get environment variables expanded.
"""

from __future__ import annotations

from collections.abc import Sequence

# gadget::ProxyDepChecker: these proxies count as configured even when their device is
# missing (they return default data); command_proxy and string_proxy are not among them.
STUPEFIED_PROXIES = frozenset(
    {
        "analog_proxy",
        "digital_proxy",
        "gesture_proxy",
        "glove_proxy",
        "keyboard_mouse_proxy",
        "position_proxy",
        "rumble_proxy",
        "hat_proxy",
    }
)

# cluster::ClusterDepChecker lets cluster_node elements through unconditionally.
NO_DEPENDENCY_CHECK = STUPEFIED_PROXIES | {"cluster_node"}

# Handlers of VR Juggler 3.0 that refuse elements older than a version: the element stays
# pending. Use minimum_version(), which scales these to the release the definitions describe.
MINIMUM_VERSIONS = {
    "input_manager": 2,
    "cluster_manager": 3,
    "keyboard_mouse_device": 2,
    "flock": 2,
    "motion_star": 2,
    "fastrak": 2,
}


def minimum_version(type_name: str, versions: Sequence[int]) -> int | None:
    """The oldest version of ``type_name`` the run time of the release the definitions in use
    describe accepts: VR Juggler 3.0's threshold, capped at the newest version present in
    those definitions (an older release's handlers accept their own newest elements), or
    None when the type's handler checks no version."""
    minimum = MINIMUM_VERSIONS.get(type_name)
    if minimum is None or not versions:
        return minimum
    return min(minimum, max(versions))


# Types that have a definition but that no handler accepts.
NEVER_HANDLED = {
    "gesture_proxy": "VR Juggler never handles gesture proxies (Gadgeteer's constructor for them is commented out)",
}

# Pointers an element cannot work without, as (base type, property): the rule applies to
# the base type and every type derived from it.
REQUIRED_POINTERS: tuple[tuple[str, str, str], ...] = (
    ("alias", "proxy", "the alias leads to no proxy"),
    ("proxy", "device", "the proxy is never bound and returns default data"),
    ("simulated_analog_device", "keyboard_mouse_proxy", "the simulated device never sees a key"),
    ("simulated_digital_device", "keyboard_mouse_proxy", "the simulated device never sees a key"),
    (
        "simulated_positional_device",
        "keyboard_mouse_proxy",
        "the simulated device never sees a key",
    ),
    ("simulated_digital_glove", "keyboard_mouse_proxy", "the simulated device never sees a key"),
    ("simulated_glove_gesture", "keyboard_mouse_proxy", "the simulated device never sees a key"),
    ("simulated_glove_gesture", "glove_position", "the device fails to configure"),
    ("simulated_relative_position", "base_frame_proxy", "the device has no base frame"),
    ("simulated_relative_position", "relative_proxy", "the device has nothing to follow"),
)

# Properties a newer definition version renamed, as (type, old name) -> new name: the
# upgrade transforms carry the values over. Checks that hold in every version (a required
# pointer) follow the old name in an old element, and `upgrade` renames an old name left in
# an element that already declares the newer version (its value would be lost otherwise).
RENAMED_PROPERTIES: dict[tuple[str, str], str] = {
    ("display_system", "x11_pipes"): "pipes",
    **{
        (simulated, "event_window_proxy"): "keyboard_mouse_proxy"
        for simulated in (
            "simulated_analog_device",
            "simulated_digital_device",
            "simulated_digital_glove",
            "simulated_glove_gesture",
            "simulated_positional_device",
        )
    },
}


def renamed_from(type_name: str, new_name: str) -> str | None:
    """The older name of ``type_name``'s property ``new_name``, if a version renamed it."""
    for (owner, old), new in RENAMED_PROPERTIES.items():
        if owner == type_name and new == new_name:
            return old
    return None


# String properties whose values VR Juggler passes through environment-variable expansion
# as paths, by (type, property).
PATH_PROPERTIES = frozenset(
    {
        ("input_manager", "driver_path"),
        ("input_manager", "driver_scan_path"),
        ("cluster_manager", "plugin_path"),
    }
)


def missing_target_effect(root_type: str, root_name: str, embedded: bool) -> str:
    """What the run time does with a top-level element when a pointer of it (or, with
    ``embedded``, of one of its embedded elements) finds nothing."""
    if root_type in STUPEFIED_PROXIES:
        return "the proxy stays unbound and returns default data"
    if root_type == "cluster_node":
        return (
            "on the node that uses it, the embedded element waits until an element of that "
            "name appears"
        )
    if root_type in ("command_proxy", "string_proxy"):
        return (
            f"unlike most proxies, a {root_type} waits for its device, so VR Juggler keeps it "
            "pending forever"
        )
    if embedded:
        return f"VR Juggler keeps {root_type} {root_name!r} pending until an element of that name appears"
    return "VR Juggler keeps the element pending until an element of that name appears"
