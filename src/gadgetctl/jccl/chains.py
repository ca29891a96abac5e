"""Chains of findings: elements of one type, each repeating the mistake of the element it
points at (an alias naming an alias that names an alias...), are one problem and are
reported once, at the head of the chain, with a count of the elements behind it."""

from __future__ import annotations

from collections.abc import Mapping


def fold_chains(count: int, leader: Mapping[int, int]) -> dict[int, list[int]]:
    """Positions ``0..count-1``, each following the position ``leader`` gives (if any): each
    head (a position without a leader) with the positions that follow it, directly or in
    turn, nearest first; heads in order (those of cycles last). Every position is either a head or a follower of
    exactly one head; in a cycle the first position of it is its head. Linear in ``count``."""
    behind: dict[int, list[int]] = {}
    for key in sorted(leader):
        ahead = leader[key]
        if 0 <= ahead < count and ahead != key:
            behind.setdefault(ahead, []).append(key)
    assigned = bytearray(count)
    heads: dict[int, list[int]] = {}

    def gather(head: int) -> None:
        assigned[head] = 1
        followers: list[int] = []
        queue = [head]
        for current in queue:  # the list grows as followers are found: breadth first
            for follower in behind.get(current, ()):
                if not assigned[follower]:
                    assigned[follower] = 1
                    followers.append(follower)
                    queue.append(follower)
        heads[head] = followers

    for key in range(count):
        ahead = leader.get(key)
        if ahead is None or not 0 <= ahead < count or ahead == key:
            gather(key)
    for key in range(count):  # what is left hangs on cycles
        if not assigned[key]:
            gather(key)
    return heads
