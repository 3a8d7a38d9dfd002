"""The checks a `Program` makes on construction, so that every program, however it was made
(read, built, from arrays, unpickled), follows the NC language and can be written back as
text: the modal rules of its moves (`_check`, vectorised) and the form of what it carries
(states and first lines, M codes, exact stops).

Internal to `machinesim.nc.program`; the rules are listed in `Program`'s docstring.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from machinesim.exceptions import NCProgramError
from machinesim.nc.moves import (
    AXES,
    KIND_DWELL,
    KIND_LINEAR,
    MOVE_KINDS,
    PROGRAM_END,
    SUBPROGRAM_CODES,
    FrozenMapping,
    _is_int,
    feed_problem,
)

if TYPE_CHECKING:
    from machinesim.nc.program import Program


def _states(states: Mapping[str, int] | None, source: str,
            name: str = "states") -> FrozenMapping:
    if states is None:
        return FrozenMapping()
    if not isinstance(states, Mapping) or not all(
        isinstance(k, str) and _is_int(v) and v >= 1 for k, v in states.items()
    ):
        raise NCProgramError(f"{name} must map words (str) to first lines (int >= 1), got "
                             f"{states!r}", source=source, key=name)
    return FrozenMapping(states.items())


def _line_words(words: Mapping[int, str] | None, source: str, name: str) -> FrozenMapping:
    """``words`` (line -> a word as written) checked, as a read-only mapping."""
    if words is None:
        return FrozenMapping()
    if not isinstance(words, Mapping) or not all(
        _is_int(k) and k >= 1 and isinstance(v, str) for k, v in words.items()
    ):
        raise NCProgramError(f"{name} must map lines (int >= 1) to words (str), got "
                             f"{words!r:.200}", source=source, key=name)
    return FrozenMapping(words.items())


def _exact_stops(stops: Any, n: int, source: str) -> np.ndarray:
    """The exact-stop move indices as a sorted, unique int64 array within ``0..n-1``."""
    try:
        index = np.asarray(stops, dtype=np.int64).reshape(-1)
    except (TypeError, ValueError, OverflowError) as error:
        raise NCProgramError(f"exact_stops must be move indices (int): {error}", source=source,
                             key="exact_stops") from None
    index = np.unique(index)
    if index.size and (index[0] < 0 or index[-1] >= n):
        bad = int(index[0] if index[0] < 0 else index[-1])
        raise NCProgramError(f"exact_stops must be move indices 0..{n - 1}, got {bad}",
                             source=source, key="exact_stops")
    return index


def _arc_lengths(lengths: Any, n: int, source: str) -> np.ndarray:
    """The arc length (m) of each of ``n`` moves as a float64 array, NaN where the move is
    no arc's chord: None for none; otherwise finite lengths >= 0 or NaN, one per move."""
    if lengths is None:
        return np.full(n, np.nan)
    try:
        out = np.asarray(lengths, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as error:
        raise NCProgramError(f"arc_lengths must be lengths (m): {error}", source=source,
                             key="arc_lengths") from None
    if out.shape != (n,):
        raise NCProgramError(f"arc_lengths must have shape ({n},), got {out.shape}",
                             source=source, key="arc_lengths")
    bad = ~np.isnan(out) & ~((out >= 0.0) & (out < np.inf))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise NCProgramError(f"arc_lengths must be lengths >= 0 (m) or NaN (no arc), got "
                             f"{out[i]!r} for move {i}", source=source, key="arc_lengths")
    return out


def _length_digit(digit: Any, source: str) -> float | None:
    """``Program.length_digit``: None, or a length > 0 (m)."""
    if digit is None:
        return None
    try:
        value = float(digit)
    except (TypeError, ValueError):
        value = math.nan
    if not 0.0 < value < math.inf:
        raise NCProgramError(f"length_digit must be None or a length > 0 (m), the value of "
                             f"the last digit of the text's finest length word, got "
                             f"{digit!r}", source=source, key="length_digit")
    return value


def _m_codes(m_codes: Mapping[int, Iterable[int]], n: int, source: str) -> FrozenMapping:
    if not isinstance(m_codes, Mapping):
        raise NCProgramError(f"m_codes must map move indices to M codes, got "
                             f"{type(m_codes).__name__}", source=source, key="m_codes")
    items = []
    for index in sorted(m_codes):
        codes = tuple(m_codes[index])
        if not _is_int(index) or not 0 <= index < n:
            raise NCProgramError(f"m_codes index {index!r} is not a move index (0..{n - 1})",
                                 source=source, key="m_codes")
        if not all(_is_int(c) and c >= 0 for c in codes):
            raise NCProgramError(f"m_codes must be ints >= 0, got {codes!r} for move {index}",
                                 source=source, key="m_codes")
        if codes:
            items.append((index, codes))
    return FrozenMapping(items)


def _check(program: Program) -> None:
    """The modal rules of the NC language, vectorised; the first broken rule is raised.

    Each rule is first tested on the whole array and only located when broken, so that a
    program of 10^6 moves is checked in a few passes.
    """
    t, kinds, feeds = program._targets, program._kinds, program._feeds
    dwells, lines, spindles = program._dwells, program._lines, program._spindles
    n = len(kinds)
    if n == 0:
        return
    failures: list[tuple[int, int, str, str]] = []  # (move, rule order, message, key)

    def first(mask: np.ndarray, order: int, message, key) -> None:
        if not mask.any():
            return
        i = int(np.argmax(mask))
        failures.append((i, order, message(i) if callable(message) else message,
                         key(i) if callable(key) else key))

    first(lines < 1, 0, lambda i: f"line must be an int >= 1, got {int(lines[i])}", "line")
    if (kinds.view(np.uint8) > 2).any():
        i = int(np.argmax(kinds.view(np.uint8) > 2))
        raise NCProgramError(f"move {i}: kind must be one of {MOVE_KINDS}, got code "
                             f"{int(kinds[i])}", source=program.source, key="kind")
    unset = np.isnan(t)
    if np.isinf(t).any():
        first(np.isinf(t).any(axis=1), 2, "axis values must be finite (NaN: no value yet)",
              "target")
    moving = kinds != KIND_DWELL
    columns = [unset[:, k] for k in range(len(AXES))]  # per column: cheap reductions
    nothing = columns[0].copy()
    for column in columns[1:]:
        nothing &= column
    first(moving & nothing, 3,
          lambda i: f"a {MOVE_KINDS[kinds[i]]} move needs at least one axis value", "target")
    has_feed = ~np.isnan(feeds)
    linear = kinds == KIND_LINEAR
    first(has_feed & ~(linear & (feeds > 0.0) & (feeds < math.inf)), 4,
          lambda i: feed_problem(MOVE_KINDS[kinds[i]], float(feeds[i])), "feed_m_per_s")
    first(~((dwells >= 0.0) & (dwells < math.inf)) | ((dwells != 0.0) & moving), 5,
          lambda i: f"dwell_s must be >= 0 for a dwell and 0.0 otherwise, got "
                    f"{float(dwells[i])!r} for a {MOVE_KINDS[kinds[i]]} move", "dwell_s")
    first(program._blocks < -1, 6, "block_number must be None or an int >= 0",
          "block_number")
    has_spindle = ~np.isnan(spindles)
    first(has_spindle & ~((spindles >= 0.0) & (spindles < math.inf)), 7,
          lambda i: f"spindle_rpm must be >= 0, got {float(spindles[i])!r}", "spindle_rpm")
    # a column, once set, stays set: its NaNs all come before its first value
    if any(column[int(np.argmin(column)):].any() for column in columns if not column.all()):
        dropped = np.zeros(n, dtype=bool)
        dropped[1:] = (unset[1:] & ~unset[:-1]).any(axis=1)
        first(dropped, 8,
              lambda i: f"move {i} drops axis {_dropped_axis(unset, i)} from its target; "
                        "targets are modal and keep every axis given so far",
              lambda i: _dropped_axis(unset, i))
    dwelling = np.flatnonzero(~moving)
    if dwelling.size:
        here = t[dwelling]
        before = np.where((dwelling > 0)[:, None], t[np.maximum(dwelling - 1, 0)], np.nan)
        moved = ~((here == before) | (np.isnan(here) & np.isnan(before))).all(axis=1)
        if moved.any():
            k = int(np.argmax(moved))
            failures.append((int(dwelling[k]), 9,
                             f"move {int(dwelling[k])} is a dwell but its target "
                             f"{_target_text(here[k])} differs from the position before it "
                             f"{_target_text(before[k])}", "target"))
    fed = linear & has_feed
    if fed.any():
        fed_before = np.zeros(n, dtype=bool)
        fed_before[1:] = np.logical_or.accumulate(fed)[:-1]
        first(linear & ~has_feed & fed_before, 10,
              lambda i: f"move {i} is linear without feed after a linear move with feed; F is "
                        "modal", "feed_m_per_s")
    if has_spindle.any():
        first(np.concatenate([[False], has_spindle[:-1] & ~has_spindle[1:]]), 11,
              lambda i: f"move {i} has no spindle speed after one with spindle speed; S is "
                        "modal", "spindle_rpm")
    for index, codes in program._m_codes.items():
        calls = [c for c in codes if c in SUBPROGRAM_CODES]
        if calls:
            failures.append((index, 12, f"move {index} carries M{calls[0]}, a subprogram call "
                                        "or return: the reader expands those into moves, a "
                                        "move cannot carry them", f"M{calls[0]}"))
        ends = [c for c in codes if c in PROGRAM_END]
        if ends and index < n - 1:
            failures.append((index, 12, f"move {index} ends the program (M{ends[0]:02d}) but "
                                        f"{n - 1 - index} move(s) follow it", f"M{ends[0]:02d}"))
    if failures:
        index, _, message, key = min(failures, key=lambda f: (f[0], f[1]))
        line = int(lines[index]) if lines[index] >= 1 else None
        block = int(program._blocks[index]) if line is not None else -1
        raise NCProgramError(message, source=program.source, line=line, key=key,
                             block=block if block >= 0 else None)


def _dropped_axis(unset: np.ndarray, i: int) -> str:
    return AXES[int(np.argmax(unset[i] & ~unset[i - 1]))]


def _target_text(row: np.ndarray) -> str:
    return str({a: float(v) for a, v in zip(AXES, row, strict=True) if v == v})
