"""Chains of findings: elements of one type, each repeating the mistake of the element it
points at (an alias naming an alias that names an alias...), are one problem and are
reported once, at the head of the chain, with a count of the elements behind it."""

from __future__ import annotations

from array import array
from collections.abc import Mapping, Sequence

#: In a leader array: the position follows nobody.
NO_LEADER = -1


def leaders(count: int) -> array:
    """An array of ``count`` positions that follow nobody yet (8 bytes a position, where a
    dict of ints would take about 130)."""
    return array("q", [NO_LEADER]) * count


def fold_chains(count: int, leader: Mapping[int, int] | Sequence[int]) -> dict[int, array]:
    """Positions ``0..count-1``, each following the position ``leader`` gives (if any; an
    array from :func:`leaders` or a mapping): each head (a position without a leader) with
    the positions that follow it, directly or in turn, nearest first; heads in order (those
    of cycles last). Every position is either a head or a follower of exactly one head; in a
    cycle the first position of it is its head. Linear in ``count``, in time and in memory
    (a few arrays of positions; each head's followers are an array too)."""
    if isinstance(leader, Mapping):
        given = leaders(count)
        for key, ahead in leader.items():
            if 0 <= key < count:
                # (a leader out of range makes the position a head, as no leader does)
                given[key] = ahead if 0 <= ahead < count else key
        leader = given
    # the followers of each position, in increasing order: linked lists kept in arrays
    first, last, after = leaders(count), leaders(count), leaders(count)
    chosen = []  # the heads: no leader, or one out of range or itself
    for key in range(count):
        ahead = leader[key]
        if ahead in (NO_LEADER, key) or not 0 <= ahead < count:
            chosen.append(key)
            continue
        if first[ahead] == NO_LEADER:
            first[ahead] = key
        else:
            after[last[ahead]] = key
        last[ahead] = key
    assigned = bytearray(count)
    heads: dict[int, array] = {}

    def gather(head: int) -> None:
        assigned[head] = 1
        queue = array("q", [head])
        for current in queue:  # the list grows as followers are found: breadth first
            follower = first[current]
            while follower != NO_LEADER:
                if not assigned[follower]:
                    assigned[follower] = 1
                    queue.append(follower)
                follower = after[follower]
        heads[head] = queue[1:]

    for key in chosen:
        gather(key)
    left = assigned.find(0)
    while left != -1:  # what is left hangs on cycles
        gather(left)
        left = assigned.find(0, left + 1)
    return heads
