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


#: close_names answers by (word, candidates, n, cutoff): a check asks about the same unknown
#: names against the same names again and again (every run of validate in one process).
#: Kept for up to _CLOSE_NAMES_KEPT questions of at most _CLOSE_NAMES_WIDEST candidates.
_CLOSE_NAMES: dict[tuple[str, tuple[str, ...], int, float], tuple[str, ...]] = {}
_CLOSE_NAMES_KEPT = 1024
_CLOSE_NAMES_WIDEST = 2048


def close_names(
    word: str, candidates: Iterable[str], *, n: int = 3, cutoff: float = CUTOFF
) -> list[str]:
    """Up to ``n`` candidates that look like ``word``, the closest first."""
    names = tuple(candidates)
    key = (word, names, n, cutoff)
    found = _CLOSE_NAMES.get(key)
    if found is None:
        spelled: dict[str, str] = {}
        for candidate in names:
            spelled.setdefault(candidate.lower(), candidate)
        matches = get_close_matches(word.lower(), list(spelled), n=n, cutoff=cutoff)
        found = tuple(spelled[m] for m in matches)
        if len(names) <= _CLOSE_NAMES_WIDEST:
            if len(_CLOSE_NAMES) >= _CLOSE_NAMES_KEPT:
                _CLOSE_NAMES.pop(next(iter(_CLOSE_NAMES)))
            _CLOSE_NAMES[key] = found
    return list(found)


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

    That bound still costs a pass over the candidates per question, so a check asking about
    thousands of names would take time quadratic in them. Once more than :attr:`NEAR_AFTER`
    questions were asked, a second index answers most of them without that pass: every
    candidate is filed under itself and each of its one-letter deletions, which finds all the
    candidates one insertion, deletion or substitution away from a word (their indel distance
    is at most 2) by looking up the word and its one-letter deletions. Any other candidate
    differs from the word by more (see :func:`_outside_bound`), which caps its similarity;
    when the near candidates' answer beats that cap (or no cap reaches ``cutoff``), it is
    difflib's answer, ties ordered as difflib orders them. Otherwise the bounded pass runs.
    """

    EXHAUSTIVE = 400  # candidates of a feasible length compared one by one, at most
    COMPARISONS = 32  # full comparisons per question with the index
    NEAR_AFTER = 8  # questions answered by the bounded pass before the near index is built

    def __init__(self, candidates: Iterable[str], *, ignore_case: bool = True) -> None:
        self._ignore_case = ignore_case
        names = list(candidates)
        folded = [name.lower() for name in names] if ignore_case else names
        spelled = dict(zip(folded, names, strict=True))
        if len(spelled) != len(names):  # some fold alike: the first one spelled wins
            spelled = {}
            for key, name in zip(folded, names, strict=True):
                spelled.setdefault(key, name)
        self._spelled = spelled
        self._keys = sorted(spelled, key=len)  # by length: a feasible length range is a slice
        self._key_lengths = [len(k) for k in self._keys]
        self._counts: Any = None  # numpy (candidates x characters) counts, made on first need
        self._columns: dict[str, int] = {}
        self._memo: dict[tuple[str, int, float], list[str]] = {}
        self._lengths_present = sorted(set(self._key_lengths))
        self._asked = 0
        self._alphabet: frozenset[str] | None = None  # every letter of every candidate
        self._near: Any = None  # (sorted hashes of candidates and their deletions, their rows)

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
            elif self._shares_too_little(folded, start, cutoff):
                matches = []
            else:
                self._asked += 1
                matches = (
                    self._nearby(folded, start, stop, n, cutoff)
                    if self._asked > self.NEAR_AFTER
                    else None
                )
                if matches is None:
                    matches = self._bounded(folded, start, stop, n, cutoff)
            found = [self._spelled[m] for m in matches]
            if len(self._memo) < 65536:
                self._memo[key] = found
        return list(found)

    def _shares_too_little(self, word: str, start: int, cutoff: float) -> bool:
        """Whether no candidate can reach ``cutoff`` because too few of the word's letters occur
        in any of them (a word unlike every name, such as one naming nothing, is then
        answered without the index)."""
        if self._alphabet is None:
            self._alphabet = frozenset("".join(self._keys))
        shared = sum(1 for char in word if char in self._alphabet)
        shortest = self._key_lengths[start] if start < len(self._key_lengths) else 0
        return 2.0 * shared / (len(word) + shortest) < cutoff if word else False

    def _window(self, size: int, cutoff: float) -> tuple[int, int]:
        """The slice of candidates whose length can reach ``cutoff`` (difflib's first test,
        2 * min(a, b) / (a + b) >= cutoff, with a margin)."""
        if cutoff <= 0 or not size:
            return 0, len(self._keys)
        low, high = (
            math.floor(size * cutoff / (2 - cutoff)),
            math.ceil(size * (2 - cutoff) / cutoff),
        )
        return bisect_left(self._key_lengths, low), bisect_right(self._key_lengths, high)

    def _bounded(self, word: str, start: int, stop: int, n: int, cutoff: float) -> list[str]:
        import numpy as np

        if self._counts is None:
            self._index_counts(np)
        shared = np.zeros(stop - start, dtype=np.float64)
        for char, count in Counter(word).items():
            column = self._columns.get(char)
            if column is not None:
                shared += np.minimum(self._counts[start:stop, column], count)
        bound = 2.0 * shared / (len(word) + self._lengths[start:stop])
        hopeful = np.flatnonzero(bound >= cutoff)
        # Among equal bounds (names made of the same characters), those agreeing with the
        # word letter for letter from either end come first: the likely best matches.
        codes = np.asarray([ord(c) for c in word], dtype=np.uint32)[: self._left.shape[1]]
        rows = hopeful + start
        aligned = (self._left[rows, : len(codes)] == codes).sum(axis=1)
        aligned += (self._right[rows, self._right.shape[1] - len(codes) :] == codes).sum(axis=1)
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

    def _index_counts(self, np) -> None:
        """Character counts and left/right-aligned code points of every candidate (numpy)."""
        keys = self._keys
        lengths = np.asarray(self._key_lengths, dtype=np.int64)
        codes = np.frombuffer("".join(keys).encode("utf-32-le"), dtype=np.uint32)
        rows = np.repeat(np.arange(len(keys)), lengths)
        chars, columns = np.unique(codes, return_inverse=True)
        self._columns = {chr(c): i for i, c in enumerate(chars.tolist())}
        width_columns = max(1, len(chars))
        flat = np.bincount(rows * width_columns + columns, minlength=len(keys) * width_columns)
        self._counts = flat.astype(np.uint16).reshape(len(keys), width_columns)
        self._lengths = lengths.astype(np.float64)
        width = max(self._key_lengths, default=0)
        position = np.arange(len(codes)) - np.repeat(np.cumsum(lengths) - lengths, lengths)
        self._left = np.zeros((len(keys), width), dtype=np.uint32)  # code points, left-aligned
        self._right = np.zeros((len(keys), width), dtype=np.uint32)  # and right-aligned
        self._left[rows, position] = codes
        self._right[rows, width - np.repeat(lengths, lengths) + position] = codes

    def _nearby(self, word: str, start: int, stop: int, n: int, cutoff: float) -> list[str] | None:
        """The answer from the candidates near ``word``, or None when they cannot prove it.

        The near candidates are compared best bound first (their similarity is at most
        1 - d / (a + b) for the indel distance d the index tells), stopping once no bound can
        beat the ``n``-th match: a few comparisons, not one per candidate. When the best match
        beats every candidate the index did not find, it is difflib's first; places left
        empty are filled with candidates near that best match (each a real close match),
        unless nothing outside can reach ``cutoff`` anyway."""
        near = self._near_rows(word, start, stop)
        if not near and self._outside_bound(len(word), cutoff) >= cutoff:
            return None
        matcher = SequenceMatcher()
        matcher.set_seq2(word)
        best: list[tuple[float, str]] = []  # the top n (score, candidate), best first
        order = sorted(
            (_at_most(len(word), len(self._keys[row]), distance), self._keys[row])
            for row, distance in near.items()
        )
        for bound, candidate in reversed(order):
            if bound < cutoff or (len(best) >= n and (bound, candidate) < best[n - 1]):
                break  # (ties in score are ordered by candidate, as difflib orders them)
            matcher.set_seq1(candidate)
            score = matcher.ratio()
            if score >= cutoff:
                best.append((score, candidate))
                best.sort(reverse=True)
        best = best[:n]
        cap = self._outside_bound(len(word), cutoff)
        margin = 1e-9
        if best and best[0][0] <= cap + margin:
            return None  # a candidate the index missed may be closer
        if len(best) < n and cap >= cutoff - margin:
            best += self._beside([c for _, c in best], matcher, start, stop, n - len(best), cutoff)
            if len(best) < n:
                return None
        return [candidate for _, candidate in best]

    def _beside(
        self,
        found: list[str],
        matcher: SequenceMatcher,
        start: int,
        stop: int,
        wanted: int,
        cutoff: float,
    ) -> list[tuple[float, str]]:
        """Up to ``wanted`` more close matches of the matcher's word among the candidates near
        the best match found, the nearest to it first (at most :attr:`COMPARISONS`
        comparisons)."""
        import numpy as np

        seen = set(found)
        extra: list[tuple[float, str]] = []
        rows, distances = self._near_arrays(found[0], start, stop)
        for compared, row in enumerate(rows[np.lexsort((-rows, distances))].tolist()):
            if compared >= self.COMPARISONS or len(extra) >= wanted:
                break
            candidate = self._keys[row]
            if candidate in seen:
                continue
            matcher.set_seq1(candidate)
            score = matcher.ratio()
            if score >= cutoff:
                extra.append((score, candidate))
        return sorted(extra, reverse=True)

    def _near_rows(self, word: str, start: int, stop: int) -> dict[int, int]:
        """Candidates (rows in ``start:stop``) at indel distance 2 or less from ``word``, with
        that distance: equal (0); one is the other with a letter deleted (1); both give one
        string with a letter deleted (2, a substitution)."""
        rows, distances = self._near_arrays(word, start, stop)
        return dict(zip(rows.tolist(), distances.tolist(), strict=True))

    def _index_near(self, np) -> None:
        """Every candidate filed under its hash and the hashes of its one-letter deletions."""
        hashes, rows, deleted = [], [], []
        for row, key in enumerate(self._keys):
            variants = {key[:i] + key[i + 1 :] for i in range(len(key))}
            hashes.append(hash(key))
            hashes.extend(hash(v) for v in variants)
            rows.extend([row] * (len(variants) + 1))
            deleted.append(0)
            deleted.extend([1] * len(variants))
        hashes_array = np.asarray(hashes, dtype=np.int64)
        order = np.argsort(hashes_array, kind="stable")
        self._near = (
            hashes_array[order],
            np.asarray(rows, dtype=np.int64)[order],
            np.asarray(deleted, dtype=np.int8)[order],
        )

    def _near_arrays(self, word: str, start: int, stop: int) -> tuple[Any, Any]:
        """:meth:`_near_rows` as two numpy arrays: rows (each once) and their distances."""
        import numpy as np

        if self._near is None:
            self._index_near(np)
        table, table_rows, table_deleted = self._near
        probes = [word, *{word[:i] + word[i + 1 :] for i in range(len(word))} - {word}]
        hashes = np.asarray([hash(p) for p in probes], dtype=np.int64)
        lows = np.searchsorted(table, hashes, "left")
        counts = np.searchsorted(table, hashes, "right") - lows
        total = int(counts.sum())
        if not total:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        ends = np.cumsum(counts)
        positions = np.arange(total) - np.repeat(ends - counts, counts) + np.repeat(lows, counts)
        rows = table_rows[positions]
        distances = (np.repeat(np.arange(len(probes)), counts) > 0) + table_deleted[positions]
        keep = (rows >= start) & (rows < stop)
        rows, distances = rows[keep], distances[keep].astype(np.int64)
        order = np.lexsort((distances, rows))  # by row, the smallest distance first
        rows, distances = rows[order], distances[order]
        first = np.ones(len(rows), dtype=bool)
        first[1:] = rows[1:] != rows[:-1]
        return rows[first], distances[first]

    def _outside_bound(self, size: int, cutoff: float) -> float:
        """The highest similarity a candidate not found near a word of ``size`` letters can
        have. ``ratio`` is at most 1 - d / (a + b) for the indel distance d of the two strings
        (insertions plus deletions: a + b - 2 x their longest common subsequence). A candidate
        the near index misses has d >= 3 when a + b is odd, d >= 4 when even, except d = 2 for
        a length difference of exactly 2 (two insertions); and d is at least the length
        difference."""
        cap = 0.0
        for length in self._lengths_present:
            total = size + length
            if not total or 2 * min(size, length) / total < cutoff:
                continue
            difference = abs(size - length)
            least = 3 if total % 2 else (2 if difference == 2 else 4)
            cap = max(cap, _at_most(size, length, max(difference, least)))
        return cap


#: CloseNames by their candidates, for sets small enough to be compared exhaustively.
_SHARED_CLOSE_NAMES: dict[tuple[str, ...], CloseNames] = {}
_SHARED_CLOSE_NAMES_KEPT = 256


def shared_close_names(candidates: Iterable[str]) -> CloseNames:
    """A :class:`CloseNames` over ``candidates``, shared by every caller with the same
    candidates when there are at most ``CloseNames.EXHAUSTIVE`` of them (their answers are
    then exactly difflib's, whatever was asked before): a process that checks the same
    configurations again compares each unknown name once."""
    names = tuple(candidates)
    if len(names) > CloseNames.EXHAUSTIVE:
        return CloseNames(names)
    found = _SHARED_CLOSE_NAMES.get(names)
    if found is None:
        if len(_SHARED_CLOSE_NAMES) >= _SHARED_CLOSE_NAMES_KEPT:
            _SHARED_CLOSE_NAMES.pop(next(iter(_SHARED_CLOSE_NAMES)))
        found = _SHARED_CLOSE_NAMES[names] = CloseNames(names)
    return found


def _at_most(size: int, length: int, distance: int) -> float:
    """difflib's ratio of two strings of these lengths whose indel distance is ``distance``
    if it found their longest common subsequence (it finds no more), computed as difflib does."""
    total = size + length
    return 2.0 * ((total - distance) // 2) / total if total else 1.0
