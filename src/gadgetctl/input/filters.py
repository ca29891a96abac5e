"""Position filters: ``position_transform_filter`` and ``full_position_transform_filter``.

Semantics (reference section 7.4), for a sample matrix M in device units:

* position_transform_filter: ``Pre · S(M · Post)`` where Pre = T(pre_translate)·R(pre_rotation),
  Post = T(post_translate)·R(post_rotation), R = Rx·Ry·Rz of Euler angles in degrees, and S
  multiplies the translation column by the scale (``device_units``, or ``custom_scale``
  when device_units is exactly 0). post_translate is therefore in device units and
  pre_translate in meters.
* full_position_transform_filter: ``Pre · M · Post`` with 16 row-major values each.

Filters run in list order. Because S(X) = D·X·D⁻¹ with D = diag(s, s, s, 1), a whole
chain with non-zero scales folds into one left and one right matrix, so filtering a batch
of samples costs two batched matrix products however long the chain is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.input.errors import DeviceConfigError
from gadgetctl.input.transforms import euler_xyz_degrees, from_row_major, translation
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.configuration import ConfigElement

TRANSFORM_FILTER = "position_transform_filter"
FULL_TRANSFORM_FILTER = "full_position_transform_filter"
CALIBRATION_FILTER = "position_calibration_filter"
FILTERS_PROPERTY = "position_filters"


@dataclass(frozen=True)
class PositionFilter:
    """``Pre · D · M · Post · D⁻¹``: ``scale`` is the s of D (1.0 for full transform filters)."""

    name: str
    pre: np.ndarray
    post: np.ndarray
    scale: float = 1.0

    def apply(self, matrices: np.ndarray) -> np.ndarray:
        """Filter one matrix (4, 4) or a batch (..., 4, 4); the input is left untouched."""
        result = matrices @ self.post
        if self.scale != 1.0:
            result[..., :3, 3] *= self.scale
        return self.pre @ result

    @property
    def left(self) -> np.ndarray:
        return self.pre @ np.diag((self.scale, self.scale, self.scale, 1.0))

    @property
    def right(self) -> np.ndarray | None:
        if self.scale == 0.0:
            return None
        return self.post @ np.diag((1 / self.scale, 1 / self.scale, 1 / self.scale, 1.0))


@dataclass(frozen=True)
class FilterChain:
    """Filters applied in order; folded into two matrices when every scale is non-zero."""

    filters: tuple[PositionFilter, ...] = ()
    diagnostics: tuple[Diagnostic, ...] = field(default=(), compare=False)

    def __bool__(self) -> bool:
        return bool(self.filters)

    def __len__(self) -> int:
        return len(self.filters)

    @cached_property
    def _folded(self) -> tuple[np.ndarray, np.ndarray] | None:
        left, right = np.eye(4), np.eye(4)
        for f in self.filters:
            r = f.right
            if r is None:
                return None
            left = f.left @ left
            right = right @ r
        return left, right

    @property
    def folded(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(left, right) with ``apply(M) == left @ M @ right``; None when a scale is 0."""
        return self._folded

    def apply(self, matrices: np.ndarray) -> np.ndarray:
        """Filter one matrix (4, 4) or a batch (..., 4, 4)."""
        if not self.filters:
            return matrices
        folded = self._folded
        if folded is not None:
            return folded[0] @ matrices @ folded[1]
        for f in self.filters:
            matrices = f.apply(matrices)
        return matrices


#: The chain without filters (immutable), shared by every device and proxy that has none.
NO_FILTERS = FilterChain()


def transform_filter(access: ElementAccess) -> PositionFilter:
    pre_t, pre_r = access.floats("pre_translate"), access.floats("pre_rotation")
    post_t, post_r = access.floats("post_translate"), access.floats("post_rotation")
    units = access.float("device_units")
    scale = access.float("custom_scale") if units == 0.0 else units
    pre = translation(*pre_t[:3]) @ euler_xyz_degrees(*pre_r[:3])
    post = translation(*post_t[:3]) @ euler_xyz_degrees(*post_r[:3])
    return PositionFilter(access.name, pre, post, scale)


def full_transform_filter(access: ElementAccess) -> PositionFilter:
    return PositionFilter(
        access.name,
        from_row_major(access.floats("pre_xform")[:16]),
        from_row_major(access.floats("post_xform")[:16]),
    )


_BUILDERS = {TRANSFORM_FILTER: transform_filter, FULL_TRANSFORM_FILTER: full_transform_filter}


def build_filter(element: ConfigElement, access: ElementAccess) -> PositionFilter:
    """One filter from its embedded element; raises :class:`DeviceConfigError` if unusable."""
    builder = _BUILDERS.get(element.type)
    if builder is None:
        if element.type == CALIBRATION_FILTER:
            raise DeviceConfigError("position_calibration_filter is not supported by gadgetctl")
        raise DeviceConfigError(f"{element.type} is not a position filter type")
    child = ElementAccess(element, access.repo)
    try:
        return builder(child)
    except (KeyError, ValueError) as err:
        raise DeviceConfigError(f"filter {element.full_name!r} cannot be read: {err}") from None


def build_chain(access: ElementAccess, prop: str = FILTERS_PROPERTY) -> FilterChain:
    """The filters of ``prop``; unusable ones are skipped with a DRV diagnostic each (none:
    :data:`NO_FILTERS`)."""
    if not access.has(prop) or not access.count(prop):
        return NO_FILTERS  # (the usual element: no filters written)
    filters: list[PositionFilter] = []
    diagnostics: list[Diagnostic] = []
    for element in access.children(prop):
        try:
            filters.append(build_filter(element, access))
        except DeviceConfigError as err:
            loc = element.location
            diagnostics.append(
                Diagnostic.make(
                    "DRV022",
                    f"{access.name}: filter skipped: {err}",
                    loc.path,
                    loc.line,
                    loc.column,
                )
            )
    if not filters and not diagnostics:
        return NO_FILTERS
    return FilterChain(tuple(filters), tuple(diagnostics))
