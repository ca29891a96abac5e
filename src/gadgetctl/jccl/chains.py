"""Chains of findings: elements of one type, each repeating the mistake of the element it
points at (an alias naming an alias that names an alias...), are one problem and are
reported once, at the head of the chain, with a count of the elements behind it."""

from __future__ import annotations

from collections import defaultdict, deque
from collections.abc import Hashable, Iterable, Mapping
from typing import TypeVar

K = TypeVar("K", bound=Hashable)


def fold_chains(keys: Iterable[K], leader: Mapping[K, K]) -> dict[K, list[K]]:
    """Each head (a key whose leader is not among ``keys``) with the keys that follow it,
    directly or in turn, nearest first; in the order of ``keys``. Every key is either a head
    or a follower of exactly one head; in a cycle the first key of it (in order) is its head.
    Linear in the number of keys."""
    keys = list(keys)
    present = set(keys)
    behind: dict[K, list[K]] = defaultdict(list)
    for key in keys:
        ahead = leader.get(key)
        if ahead is not None and ahead in present and ahead != key:
            behind[ahead].append(key)
    heads: dict[K, list[K]] = {}
    assigned: set[K] = set()

    def gather(head: K) -> None:
        assigned.add(head)
        followers: list[K] = []
        queue = deque([head])
        while queue:
            for follower in behind.get(queue.popleft(), ()):
                if follower not in assigned:
                    assigned.add(follower)
                    followers.append(follower)
                    queue.append(follower)
        heads[head] = followers

    for key in keys:
        ahead = leader.get(key)
        if ahead is None or ahead not in present or ahead == key:
            gather(key)
    for key in keys:  # what is left hangs on cycles
        if key not in assigned:
            gather(key)
    return heads
