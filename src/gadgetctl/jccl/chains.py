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
    behind: dict[int, list[int]] = {}  # position -> the positions following it, in order
    heads: dict[int, list[int]] = {}
    starts = []  # positions whose leader is out of range or themselves: heads too
    for key, ahead in sorted(leader.items()):
        if 0 <= ahead < count and ahead != key:
            followers = behind.get(ahead)
            if followers is None:
                behind[ahead] = [key]
            else:
                followers.append(key)
        else:
            starts.append(key)
    assigned = bytearray(count)
    following = behind.get

    def gather(head: int) -> None:
        assigned[head] = 1
        queue = [head]
        for current in queue:  # the list grows as followers are found: breadth first
            for follower in following(current, ()):
                if not assigned[follower]:
                    assigned[follower] = 1
                    queue.append(follower)
        heads[head] = queue[1:]

    if starts:
        chosen = sorted(set(starts).union(k for k in range(count) if k not in leader))
    else:
        chosen = [k for k in range(count) if k not in leader]
    for key in chosen:
        gather(key)
    left = assigned.find(0)
    while left != -1:  # what is left hangs on cycles
        gather(left)
        left = assigned.find(0, left + 1)
    return heads
