"""Configurations for driver tests, and the input managers and command lines run on them.

A configuration is written from element snippets (:func:`configuration`, :func:`proxy`,
:func:`alias`) or copied from the VR Juggler corpus beside the checkout and pointed at an
emulator (:func:`corpus_copy`, :func:`rewritten`); :class:`InputManagers` builds the managers a
test runs and shuts them down. :mod:`~gadgetctl.input.testing.commands` runs the command
line on them.
"""

from __future__ import annotations

import contextlib
import fcntl
import socket
import tempfile
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from gadgetctl.input.manager import InputManager, ManagerOptions

# -- configurations -------------------------------------------------------------------------

CONFIGURATION_HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="{name}">\n'
    "<elements>\n"
    '<input_manager name="IM" version="2"><driver>{driver}</driver></input_manager>\n'
)
CONFIGURATION_TAIL = "</elements>\n</configuration>\n"


def configuration(driver: str, body: str, name: str = "test") -> str:
    """A .jconf whose input manager loads ``driver``, with the elements of ``body``."""
    return CONFIGURATION_HEAD.format(name=name, driver=driver) + body + CONFIGURATION_TAIL


def proxy(kind: str, name: str, device: str, unit: int) -> str:
    """A ``<kind>_proxy`` element for ``unit`` of ``device``."""
    return (
        f'<{kind}_proxy name="{name}" version="1"><device>{device}</device>'
        f"<unit>{unit}</unit></{kind}_proxy>\n"
    )


def alias(name: str, target: str) -> str:
    """An ``alias`` element naming the proxy ``target``."""
    return f'<alias name="{name}" version="1"><proxy>{target}</proxy></alias>\n'


def checkout() -> Path:
    """The root of the source checkout this module runs from (tests run from a checkout)."""
    return Path(__file__).resolve().parents[4]


def corpus_configs() -> Path:
    """VR Juggler's configFiles in the corpus beside this checkout (``../shared/corpus``)."""
    return checkout().parent / "shared/corpus/vrjuggler/modules/vrjuggler/data/configFiles"


def corpus_file(name: str) -> Path:
    """A configuration of the corpus; a missing corpus fails the test (never a skip)."""
    path = corpus_configs() / name
    assert path.is_file(), f"the VR Juggler corpus is missing: {path}"
    return path


def corpus_copy(name: str, directory: Path, *changes: tuple[str, str]) -> Path:
    """The corpus configuration ``name`` copied into ``directory`` with ``changes`` made (see
    :func:`rewritten`)."""
    return rewritten(corpus_file(name), directory, *changes)


def rewritten(source: Path, directory: Path, *changes: tuple[str, str]) -> Path:
    """``source`` copied into ``directory`` with only the given texts replaced, each of which
    must stand in it exactly once (a corpus file pointed at an emulator's pty or port)."""
    text = source.read_text(encoding="utf-8")
    for old, new in changes:
        assert text.count(old) == 1, f"{old!r} not found once in {source}"
        text = text.replace(old, new)
    path = directory / source.name
    path.write_text(text, encoding="utf-8")
    return path


#: The lock of the tests that use fixed addresses (an example's default port, Motive's UDP
#: 1510 and 1511, /tmp/gadgetctl-pinch): two test runs on one machine take turns there.
FIXED_ADDRESSES_LOCK = Path(tempfile.gettempdir()) / "gadgetctl-quickstart-tests.lock"


@contextlib.contextmanager
def fixed_addresses() -> Iterator[None]:
    """Hold :data:`FIXED_ADDRESSES_LOCK` (waiting for the test run that holds it)."""
    with open(FIXED_ADDRESSES_LOCK, "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def free_udp_port() -> int:
    """A UDP port the OS has just handed out on loopback (free again once returned)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


# -- input managers -------------------------------------------------------------------------


class InputManagers:
    """Configured input managers for one test, each shut down by :meth:`close`.

    Call it with configurations: a ``str`` is a body of elements (written to a file whose
    input manager loads ``driver``), a :class:`~pathlib.Path` a file as it is. ``tune`` sets
    class attributes of device classes by element type (short timings) through ``patch``
    (pytest's ``monkeypatch.setattr``, so they are put back); the plug-ins are then loaded
    before the configuration, and must load. ``ready`` asserts that nothing is left pending.
    """

    def __init__(
        self,
        directory: Path,
        driver: str,
        *,
        options: ManagerOptions | None = None,
        tune: Mapping[str, Mapping[str, object]] | None = None,
        patch: Callable[[object, str, object], object] | None = None,
        ready: bool = False,
    ) -> None:
        from gadgetctl.input.manager import ManagerOptions

        if tune and patch is None:
            raise ValueError("tune needs a patch that puts the attributes back")
        self.directory = directory
        self.driver = driver
        self.options = options or ManagerOptions(retry_interval=None, entry_points=False)
        self.tune = dict(tune or {})
        self.patch = patch
        self.ready = ready
        self.made: list[InputManager] = []

    def write(self, body: str, name: str | None = None) -> Path:
        """``body`` as a configuration file (``test<N>.jconf`` unless named)."""
        path = self.directory / (
            name or f"test{len(list(self.directory.glob('test*.jconf')))}.jconf"
        )
        path.write_text(configuration(self.driver, body))
        return path

    def __call__(
        self,
        *configs: str | Path,
        drivers: tuple[str, ...] = (),
        tune: Mapping[str, Mapping[str, object]] | None = None,
        peer_timeout: float | None = None,
        ready: bool | None = None,
        options: ManagerOptions | None = None,
    ) -> InputManager:
        """A configured, running manager; ``peer_timeout`` is then set on every device."""
        from gadgetctl.input.manager import InputManager

        paths = [self.write(c) if isinstance(c, str) else c for c in configs]
        manager, loaded_configuration = InputManager.from_files(
            paths, options=options or self.options
        )
        self.made.append(manager)
        tuning = {**self.tune, **(tune or {})}
        if tuning or drivers:
            for driver in drivers or (self.driver,):
                loaded = manager.loader.load_name(driver, manager.search)
                assert loaded.ok, [d.message for d in loaded.diagnostics]
        for element_type, values in tuning.items():
            registration = manager.registry.get(element_type)
            assert registration is not None, f"no device class for {element_type}"
            for name, value in values.items():
                assert self.patch is not None
                self.patch(registration.device_class, name, value)
        manager.configure(loaded_configuration)
        if self.ready if ready is None else ready:
            assert not manager.pending(), [(p.name, p.message) for p in manager.pending()]
        if peer_timeout is not None:
            for device in manager.devices.values():
                device.peer_timeout = peer_timeout
        return manager

    def close(self) -> None:
        for manager in self.made:
            manager.shutdown()

    def __enter__(self) -> InputManagers:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def pending_reasons(manager: InputManager) -> dict[str, str]:
    """Why each pending element of ``manager`` is pending, by name."""
    return {p.name: p.message for p in manager.pending()}


def pending_in(path: Path, options: ManagerOptions | None = None) -> dict[str, str]:
    """:func:`pending_reasons` once ``path`` is configured in an input manager of its own
    (``retry_interval=None`` unless ``options`` say otherwise), shut down before this returns."""
    from gadgetctl.input.manager import InputManager, ManagerOptions

    options = options or ManagerOptions(retry_interval=None)
    manager, loaded = InputManager.from_files([path], options=options)
    try:
        manager.configure(loaded)
        return pending_reasons(manager)
    finally:
        manager.shutdown()
