"""Programs built in Python: `ProgramBuilder`, move by move with modal targets and feed."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from machinesim.exceptions import NCProgramError
from machinesim.nc.moves import Move, _finite, axis_values, work_offsets_si
from machinesim.nc.program import Program
from machinesim.units import M_PER_MM


class ProgramBuilder:
    """Build a `Program` in Python, with axis values in SI machine coordinates.

    Each method appends one move and returns the builder, so calls chain::

        ProgramBuilder(number=1).rapid(X=0.0, Z=1e-3).linear(X=0.01, feed_mm_per_min=100.0)
            .dwell(0.5).build()

    Targets are modal as in NC: an axis keeps its value until given a new one. Feed and
    spindle speed are modal too. A block with M codes but no motion is ``dwell(0.0,
    m_codes=(...))``.

    Parameters
    ----------
    number : int, optional
        The O number.
    work_offsets : mapping, optional
        {"G54": {"X": m, ...}}; the axis values given to the builder are machine values
        (offset already applied), the offsets only matter to the writer.
    source : str
        Name of the program in messages.
    """

    def __init__(
        self,
        number: int | None = None,
        *,
        work_offsets: Mapping[str, Mapping[str, float]] | None = None,
        source: str = "<builder>",
    ) -> None:
        self._number = number
        self._offsets = work_offsets_si(work_offsets, source=source)
        self._source = source
        self._moves: list[Move] = []
        self._target: dict[str, float] = {}
        self._feed: float | None = None
        self._spindle: float | None = None
        self._stops: list[int] = []

    def spindle(self, rpm: float) -> ProgramBuilder:
        """Set the modal spindle speed (rev/min) for the moves that follow."""
        self._spindle = rpm
        return self

    def rapid(self, *, block_number: int | None = None, m_codes: Iterable[int] = (),
              **axes: float) -> ProgramBuilder:
        """Append a rapid move (G00) to the given axis values (m, rad)."""
        return self._motion("rapid", None, block_number, m_codes, axes)

    def linear(
        self,
        *,
        feed_mm_per_min: float | None = None,
        feed_m_per_s: float | None = None,
        block_number: int | None = None,
        m_codes: Iterable[int] = (),
        exact_stop: bool = False,
        **axes: float,
    ) -> ProgramBuilder:
        """Append a linear move (G01); the feed (one of the two units) is modal, and the
        first linear move is refused without one. With ``exact_stop`` the move ends in
        position (G09: `Program.exact_stops`)."""
        if feed_mm_per_min is not None and feed_m_per_s is not None:
            raise NCProgramError("give the feed once: feed_mm_per_min or feed_m_per_s",
                                 source=self._source, key="feed")
        if feed_mm_per_min is not None:
            self._feed = self._positive(feed_mm_per_min, "feed_mm_per_min") * (M_PER_MM / 60.0)
        elif feed_m_per_s is not None:
            self._feed = self._positive(feed_m_per_s, "feed_m_per_s")
        elif self._feed is None:
            # as a G01 before any F: the planner refused it, naming the move's line and
            # 'no feed rate F', neither of which the builder's caller wrote
            raise NCProgramError("a linear move needs a feed and none was given before it: "
                                 "give feed_mm_per_min (or feed_m_per_s) on the first "
                                 "linear move; the moves after it keep it until given another",
                                 source=self._source, line=len(self._moves) + 1,
                                 key="feed_mm_per_min")
        self._motion("linear", self._feed, block_number, m_codes, axes)
        if exact_stop:
            self._stops.append(len(self._moves) - 1)
        return self

    def _positive(self, feed: float, key: str) -> float:
        """``feed`` as given to `linear`, refused (naming ``key``, in its unit) unless a
        finite number above zero: it had been refused by the move, in m/s, with a message
        that named neither the argument nor its unit."""
        line = len(self._moves) + 1
        value = _finite(feed, "feed", source=self._source, line=line, key=key)
        if value <= 0.0:
            raise NCProgramError(f"{key} must be > 0, got {value!r}", source=self._source,
                                 line=line, key=key)
        return value

    def dwell(self, seconds: float, *, block_number: int | None = None,
              m_codes: Iterable[int] = ()) -> ProgramBuilder:
        """Append a dwell (G04) of ``seconds`` at the current position."""
        self._append("dwell", self._target, None, seconds, block_number, m_codes)
        return self

    def _motion(self, kind: str, feed: float | None, block_number: int | None,
                m_codes: Iterable[int], axes: Mapping[str, float]) -> ProgramBuilder:
        if not axes:
            raise NCProgramError(f"a {kind} move needs at least one axis value",
                                 source=self._source, line=len(self._moves) + 1, key=kind)
        given = axis_values(axes, source=self._source, line=len(self._moves) + 1)
        self._append(kind, {**self._target, **given}, feed, 0.0, block_number, m_codes)
        return self

    def _append(self, kind: str, target: Mapping[str, float], feed: float | None,
                dwell_s: float, block_number: int | None, m_codes: Iterable[int]) -> None:
        move = Move(kind, target, feed, dwell_s, len(self._moves) + 1, block_number,
                    self._spindle, tuple(m_codes))
        self._moves.append(move)
        self._target = dict(move.target)

    def build(self) -> Program:
        """The program built so far (the builder can go on)."""
        program = Program(tuple(self._moves), self._number, self._source, self._offsets)
        if not self._stops:
            return program
        return Program.from_arrays(
            program.targets, program.kinds, program.feeds, program.dwells, program.lines,
            spindles=program.spindles, block_numbers=program.block_numbers,
            m_codes=program.m_codes, number=program.number, source=program.source,
            work_offsets=program.work_offsets, exact_stops=self._stops)
