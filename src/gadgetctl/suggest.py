"""Suggestions ("did you mean ...?"): the names closest to a mistyped one, for every command and check
that takes element, driver, definition, property or diagnostic code names.

Matching ignores case (``waveform stick`` finds ``Waveform Sticks``) and gives the
candidates as they are spelled.
"""

from __future__ import annotations

import math
from bisect import bisect_left, bisect_right
from collections import Counter
from collections.abc import Callable, Iterable
from difflib import SequenceMatcher, get_close_matches
from typing import Any

CUTOFF = 0.6


def close_names(
    word: str, candidates: Iterable[str], *, n: int = 3, cutoff: float = CUTOFF
) -> list[str]:
    """Up to ``n`` candidates that look like ``word``, the closest first."""
    spelled: dict[str, str] = {}
    for candidate in candidates:
        spelled.setdefault(candidate.lower(), candidate)
    return [spelled[m] for m in get_close_matches(word.lower(), list(spelled), n=n, cutoff=cutoff)]


def did_you_mean(
    word: str,
    candidates: Iterable[str],
    *,
    n: int = 3,
    cutoff: float = CUTOFF,
    quote: Callable[[str], str] = repr,
) -> str | None:
    """``"did you mean 'a' or 'b'?"``, or None when nothing is close."""
    close = close_names(word, candidates, n=n, cutoff=cutoff)
    if not close:
        return None
    quoted = [quote(c) for c in close]
    listed = quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} or {quoted[-1]}"
    return f"did you mean {listed}?"


def with_suggestion(message: str, word: str, candidates: Iterable[str], **options: object) -> str:
    """``message`` followed by ``" (did you mean ...?)"`` when something is close."""
    suggestion = did_you_mean(word, candidates, **options)  # type: ignore[arg-type]
    return f"{message} ({suggestion})" if suggestion else message


class CloseNames:
    """:func:`close_names` over one fixed set of candidates asked about many times (a check
    with a finding per element), without comparing every candidate for every question.

    Answers are memoised. With few candidates of a length that can reach ``cutoff``, all of
    them are compared, as :func:`difflib.get_close_matches` does. With many, an index of
    character counts gives every candidate at once an upper bound of its similarity (the
    bound difflib's ``quick_ratio`` computes one by one); candidates are then compared best
    bound first, stopping as soon as no remaining bound can beat the ``n``-th match found,
    so the answer is the one difflib gives, unless more than :attr:`COMPARISONS` candidates
    tie near the top (then the best found so far, each a real close match).
    """

    EXHAUSTIVE = 400  # candidates of a feasible length compared one by one, at most
    COMPARISONS = 32  # full comparisons per question with the index

    def __init__(self, candidates: Iterable[str], *, ignore_case: bool = True) -> None:
        self._ignore_case = ignore_case
        spelled: dict[str, str] = {}
        for candidate in candidates:
            spelled.setdefault(self._fold(candidate), candidate)
        self._spelled = spelled
        self._keys = sorted(spelled, key=len)  # by length: a feasible length range is a slice
        self._key_lengths = [len(k) for k in self._keys]
        self._counts: Any = None  # numpy (candidates x characters) counts, made on first need
        self._columns: dict[str, int] = {}
        self._memo: dict[tuple[str, int, float], list[str]] = {}

    def _fold(self, text: str) -> str:
        return text.lower() if self._ignore_case else text

    def __call__(self, word: str, *, n: int = 3, cutoff: float = CUTOFF) -> list[str]:
        """Up to ``n`` candidates that look like ``word``, the closest first."""
        key = (word, n, cutoff)
        found = self._memo.get(key)
        if found is None:
            folded = self._fold(word)
            start, stop = self._window(len(folded), cutoff)
            if stop - start <= self.EXHAUSTIVE:
                matches = get_close_matches(folded, self._keys[start:stop], n=n, cutoff=cutoff)
            else:
                matches = self._bounded(folded, start, stop, n, cutoff)
            found = [self._spelled[m] for m in matches]
            if len(self._memo) < 65536:
                self._memo[key] = found
        return list(found)

    def _window(self, size: int, cutoff: float) -> tuple[int, int]:
        """The slice of candidates whose length can reach ``cutoff`` (difflib's first test,
        2 * min(a, b) / (a + b) >= cutoff, with a margin)."""
        if cutoff <= 0 or not size:
            return 0, len(self._keys)
        low, high = math.floor(size * cutoff / (2 - cutoff)), math.ceil(size * (2 - cutoff) / cutoff)
        return bisect_left(self._key_lengths, low), bisect_right(self._key_lengths, high)

    def _bounded(self, word: str, start: int, stop: int, n: int, cutoff: float) -> list[str]:
        import numpy as np

        if self._counts is None:
            columns = self._columns
            for key in self._keys:
                for char in key:
                    columns.setdefault(char, len(columns))
            counts = np.zeros((len(self._keys), max(1, len(columns))), dtype=np.uint16)
            for row, key in enumerate(self._keys):
                for char in key:
                    counts[row, columns[char]] += 1
            self._counts = counts
            self._lengths = np.asarray(self._key_lengths, dtype=np.float64)
            width = max(self._key_lengths, default=0)
            self._left = np.zeros((len(self._keys), width), dtype=np.uint32)  # code points, left-aligned
            self._right = np.zeros((len(self._keys), width), dtype=np.uint32)  # and right-aligned
            for row, key in enumerate(self._keys):
                codes = [ord(c) for c in key]
                self._left[row, :len(codes)] = codes
                self._right[row, width - len(codes):] = codes
        shared = np.zeros(stop - start, dtype=np.float64)
        for char, count in Counter(word).items():
            column = self._columns.get(char)
            if column is not None:
                shared += np.minimum(self._counts[start:stop, column], count)
        bound = 2.0 * shared / (len(word) + self._lengths[start:stop])
        hopeful = np.flatnonzero(bound >= cutoff)
        # Among equal bounds (names made of the same characters), those agreeing with the
        # word letter for letter from either end come first: the likely best matches.
        codes = np.asarray([ord(c) for c in word], dtype=np.uint32)[:self._left.shape[1]]
        rows = hopeful + start
        aligned = (self._left[rows, :len(codes)] == codes).sum(axis=1)
        aligned += (self._right[rows, self._right.shape[1] - len(codes):] == codes).sum(axis=1)
        order = hopeful[np.lexsort((-aligned, -bound[hopeful]))]
        matcher = SequenceMatcher()
        matcher.set_seq2(word)
        best: list[tuple[float, str]] = []
        for compared, index in enumerate(order.tolist()):
            if compared >= self.COMPARISONS or (len(best) >= n and bound[index] < best[n - 1][0]):
                break
            candidate = self._keys[start + index]
            matcher.set_seq1(candidate)
            score = matcher.ratio()
            if score >= cutoff:
                best.append((score, candidate))
                best.sort(reverse=True)
        return [candidate for _, candidate in best[:n]]
