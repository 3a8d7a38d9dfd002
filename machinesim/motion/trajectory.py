"""The planner's output: a `Trajectory` holding every sample of a program in a few arrays,
and the `Segment` view of one move, made on demand."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Protocol, overload

import numpy as np

from machinesim.nc.program import MOVE_KINDS, move_index


class ServoModel(Protocol):
    """Turns commanded axis values over time into the values the axes really reach."""

    def follow(self, t: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Actual axis values (N, n_axes) for commanded ``q`` (N, n_axes) at times ``t`` (N,)."""
        ...


class IdealServo:
    """Axes that follow their command exactly (no follow-up error)."""

    def follow(self, t: np.ndarray, q: np.ndarray) -> np.ndarray:
        return q


@dataclass(frozen=True)
class Segment:
    """One programmed move, sampled.

    Attributes
    ----------
    kind : {"rapid", "linear", "dwell"}
    q : ndarray, shape (k + 1, n_axes)
        Axis values from the start to the end of the move, SI; ``k`` sub-steps.
    t : ndarray, shape (k + 1,)
        Time of each sample, s, from the start of the program.
    line : int
        Source line of the block.
    """

    kind: str
    q: np.ndarray
    t: np.ndarray
    line: int

    @property
    def duration(self) -> float:
        """Time the move takes, s."""
        return float(self.t[-1] - self.t[0])


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The sampled motion of a whole program on one machine.

    The samples of all moves are held end to end in ``q`` and ``t``: move ``i`` is rows
    ``offsets[i]:offsets[i + 1]``, from its start to its end, so the sample that ends one
    move and the one that starts the next are both there (as in `Segment`). A program of
    10^6 moves costs a few arrays, not 10^6 objects; `segments` gives the moves as `Segment`
    views on demand.

    Attributes
    ----------
    axes : tuple of str
        Axis letters, configuration order.
    q : ndarray, shape (S, n_axes)
        Every sample, SI, read-only.
    t : ndarray, shape (S,)
        Time of each sample, s, read-only.
    offsets : ndarray, shape (M + 1,), int64
        First row of each move in ``q`` and ``t``; ``offsets[-1] == S``.
    kinds : ndarray, shape (M,), int8
        Kind of each move, an index into ``machinesim.nc.MOVE_KINDS`` (0 rapid, 1 linear,
        2 dwell).
    lines : ndarray, shape (M,), int64
        Source line of each move.
    duration : float
        Machining time, s.
    cutting_time : float
        Time spent in feed (G01) moves, s.
    notes : tuple of str
        What the planner had to say (moves of axes the machine lacks are errors, not notes).
    peak_lag : ndarray, shape (n_axes,), or None
        Each axis' largest |command - reached| over the samples, SI, with the lag each
        motion still has when its command ends (before the axes settle there); None when
        the axes follow exactly (no servo model).
    """

    axes: tuple[str, ...]
    q: np.ndarray
    t: np.ndarray
    offsets: np.ndarray
    kinds: np.ndarray
    lines: np.ndarray
    duration: float
    cutting_time: float
    notes: tuple[str, ...] = field(default=())
    peak_lag: np.ndarray | None = None

    @property
    def segments(self) -> Segments:
        """The moves as a read-only sequence of `Segment` (views into ``q`` and ``t``)."""
        return Segments(self)

    @property
    def substeps(self) -> int:
        """Number of sub-steps over all moves."""
        return int(len(self.t) - len(self.kinds))

    def __len__(self) -> int:
        """Number of moves."""
        return len(self.kinds)

    def segment(self, i: int) -> Segment:
        """Move ``i`` as a `Segment` (views, no copy)."""
        i = move_index(i, len(self.kinds))
        a, b = int(self.offsets[i]), int(self.offsets[i + 1])
        return Segment(MOVE_KINDS[self.kinds[i]], self.q[a:b], self.t[a:b], int(self.lines[i]))

    def rows(self, kinds=("rapid", "linear", "dwell")) -> np.ndarray:
        """Row indices of ``q`` and ``t`` of the moves of the given kinds, in order."""
        codes = [MOVE_KINDS.index(k) for k in kinds]
        chosen = np.isin(self.kinds, codes)
        counts = np.diff(self.offsets)[chosen]
        firsts = self.offsets[:-1][chosen]
        if not counts.size:
            return np.zeros(0, dtype=np.int64)
        ends = np.cumsum(counts)
        return np.repeat(firsts - (ends - counts), counts) + np.arange(ends[-1])


class Segments(Sequence):
    """The moves of a `Trajectory` as `Segment` views, made on demand (a tuple's interface:
    ``len``, indexing, slicing (a tuple), iteration)."""

    __slots__ = ("_trajectory",)

    def __init__(self, trajectory: Trajectory) -> None:
        self._trajectory = trajectory

    def __len__(self) -> int:
        return len(self._trajectory.kinds)

    @overload
    def __getitem__(self, index: int) -> Segment: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[Segment, ...]: ...

    def __getitem__(self, index):
        if isinstance(index, slice):
            return tuple(self._trajectory.segment(i) for i in range(*index.indices(len(self))))
        return self._trajectory.segment(index)

    def __iter__(self) -> Iterator[Segment]:
        tr = self._trajectory
        bounds = tr.offsets.tolist()
        lines = tr.lines.tolist()
        kinds = [MOVE_KINDS[k] for k in tr.kinds.tolist()]
        q, t = tr.q, tr.t
        for i, kind in enumerate(kinds):
            a, b = bounds[i], bounds[i + 1]
            yield Segment(kind, q[a:b], t[a:b], lines[i])

    def __repr__(self) -> str:
        return f"Segments({len(self)} moves)"
