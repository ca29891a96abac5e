"""The device registry: which class configures which element type.

It plays the part of Gadgeteer's DeviceFactory. Built-in devices (simulated devices,
keyboard/mouse, input windows, waveform) are registered when a registry is made with
:meth:`DeviceRegistry.with_builtins`; plug-ins add theirs from ``register(registry)``.
An element type registered twice keeps its first class, as in Gadgeteer.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from gadgetctl.input.device import Input
from gadgetctl.input.errors import RegistrationError
from gadgetctl.input.kinds import BASE_DEFINITIONS, DeviceKind
from gadgetctl.jccl.repository import DefinitionRepository

BUILTIN = "built-in"


@dataclass(frozen=True, slots=True)
class Registration:
    element_type: str
    device_class: type[Input]
    plugin: str  # the plug-in that registered it, or "built-in"

    @property
    def kinds(self) -> tuple[DeviceKind, ...]:
        return self.device_class.kinds()

    @property
    def class_name(self) -> str:
        return f"{self.device_class.__module__}.{self.device_class.__qualname__}"


def registration_for(device_class: object, element_type: str | None, plugin: str) -> Registration:
    """Validate a class offered for registration; raises :class:`RegistrationError`."""
    if not isinstance(device_class, type) or not issubclass(device_class, Input):
        raise RegistrationError(
            f"{device_class!r} is not a device class (a subclass of gadgetctl.input.Input)"
        )
    token = element_type if element_type is not None else device_class.ELEMENT_TYPE
    if not token:
        raise RegistrationError(
            f"{device_class.__qualname__} names no element type (set ELEMENT_TYPE)"
        )
    return Registration(token, device_class, plugin)


class DeviceRegistry:
    def __init__(self) -> None:
        self._registrations: dict[str, Registration] = {}
        #: Counts the registrations added: an answer kept with the generation it was worked
        #: out in holds while the generation is the same.
        self.generation = 0

    @classmethod
    def with_builtins(cls) -> DeviceRegistry:
        from gadgetctl.input.builtin import BUILTIN_DEVICES

        registry = cls()
        for device_class in BUILTIN_DEVICES:
            registry.add(registration_for(device_class, None, BUILTIN))
        return registry

    def register_device(
        self, device_class: type[Input], element_type: str | None = None
    ) -> Registration:
        """Register ``device_class`` for ``element_type`` (default: its ``ELEMENT_TYPE``)."""
        return self.add(registration_for(device_class, element_type, BUILTIN))

    def add(self, registration: Registration) -> Registration:
        """Add a registration; an element type already registered keeps its first class."""
        kept = self._registrations.setdefault(registration.element_type, registration)
        if kept is registration:
            self.generation += 1
        return kept

    def get(self, element_type: str) -> Registration | None:
        return self._registrations.get(element_type)

    def __contains__(self, element_type: object) -> bool:
        return element_type in self._registrations

    def __iter__(self) -> Iterator[Registration]:
        return iter(self._registrations.values())

    def create(self, element_type: str) -> Input:
        registration = self._registrations.get(element_type)
        if registration is None:
            raise RegistrationError(f"no device class is registered for {element_type}")
        return registration.device_class()


def kind_disagreements(
    element_type: str, kinds: tuple[DeviceKind, ...], repo: DefinitionRepository
) -> list[str]:
    """Where the kinds a class provides and the definition's ancestors disagree.

    A class that provides digital data needs a definition deriving from digital_device
    (or proxies could never point at it), and a definition deriving from digital_device
    needs a class that provides digital data. Empty when they agree.
    """
    problems = []
    for kind, base in BASE_DEFINITIONS.items():
        provides = kind in kinds
        derives = repo.is_a(element_type, base)
        if provides and not derives:
            problems.append(
                f"the class provides {kind} data but {element_type} does not derive from {base}"
            )
        elif derives and not provides:
            problems.append(
                f"{element_type} derives from {base} but the class provides no {kind} data"
            )
    return problems
