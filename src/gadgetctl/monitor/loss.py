"""What a monitor run lost or could not decode: the reasons `gadgetctl monitor` ends with
exit status 1 although every device still runs.

A selected device *lost data* when the kernel dropped datagrams meant for it (its socket's
receive buffer was full) or when more samples arrived between two frames than its store
keeps (the per-frame cap): both are in its DROPPED column. It *decoded nothing* when data
arrived for it and none of that data decoded. Loss can be accepted (``--accept-loss``);
decoding nothing cannot.
"""

from __future__ import annotations

from collections.abc import Iterable

from gadgetctl.input.device import DeviceState, Input
from gadgetctl.safetext import printable
from gadgetctl.wording import counted

#: The option of `gadgetctl monitor` that accepts loss (named in the reason).
ACCEPT_LOSS_OPTION = "--accept-loss"


def lost_data(name: str, device: Input) -> str | None:
    """One line saying what ``device`` lost since it was made, or None when it lost nothing."""
    store = device.store
    capped = store.most_dropped()
    kernel = device.transport_dropped()
    if not capped and not kernel:
        return None
    parts = []
    if kernel:
        parts.append(f"{counted(kernel, 'datagram')} dropped by the kernel (receive buffer full)")
    if capped:
        parts.append(f"{counted(capped, 'sample')} over the per-frame cap of {store.cap}")
    return f"{name}: lost data: {' and '.join(parts)} ({ACCEPT_LOSS_OPTION} accepts loss)"


def decoded_nothing(name: str, device: Input) -> str | None:
    """One line when data arrived for ``device`` and none of it decoded (unless its status
    already says so: ``undecodable``), else None."""
    ledger = device.datagram_ledger()
    if ledger is None or not ledger.datagrams or ledger.decoded_count:
        return None
    if device.shown_state()[0] is DeviceState.UNDECODABLE:
        return None  # reported with its status
    error = ledger.first_error
    first = f"; first: {printable(error)}" if error else ""
    return (
        f"{name}: decoded nothing: {counted(ledger.datagrams, 'datagram')} received, "
        f"{ledger.bad_count} bad{first}"
    )


def run_problems(devices: Iterable[tuple[str, Input]], *, accept_loss: bool = False) -> list[str]:
    """The lines of every device of ``devices`` (name, device) that decoded nothing, and,
    unless ``accept_loss``, of every one that lost data."""
    problems: list[str] = []
    for name, device in devices:
        nothing = decoded_nothing(name, device)
        if nothing:
            problems.append(nothing)
        if not accept_loss:
            lost = lost_data(name, device)
            if lost:
                problems.append(lost)
    return problems
