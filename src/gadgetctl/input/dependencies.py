"""The elements an element points at (its ``configelementpointer`` values, embedded
elements included), which must be configured before it, as in JCCL's default
dependency checker."""

from __future__ import annotations

from gadgetctl.jccl.configuration import ConfigElement
from gadgetctl.jccl.repository import DefinitionRepository


def pointer_targets(element: ConfigElement, repo: DefinitionRepository) -> list[tuple[str, str]]:
    """``(property, target name)`` for every non-empty pointer value, in order."""
    result: list[tuple[str, str]] = []
    for current in (element, *element.embedded()):
        for name in repo.pointer_properties(current.type):
            result.extend((name, text) for text in current.texts(name) if text)
    return result
