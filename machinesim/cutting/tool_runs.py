"""A cut's program as the cutter walks it: the trajectory's samples joined into continuous
paths, each sweep's line, move and kind (`_Moves`), and the runs of one tool between the
program's tool changes, with their notes (`_ToolSections`, `tool_notes`).

`machinesim.cutting.program.cut` builds both; the rapids, refusals and encoders read
`_Moves` too.
"""

from __future__ import annotations

import numpy as np

from machinesim.nc import MOVE_KINDS
from machinesim.nc.tooltable import table_tool
from machinesim.tools import with_nose_radius_error

__all__ = ["JOIN_TOL", "RADIUS_AGREE_M", "tool_notes"]

#: A move continues the previous one when its first axis values equal the previous end to
#: within this (m or rad): the planner's end sample, start + 1.0 * (end - start), may differ
#: from the next start by an ulp (~1e-17 at 0.1 m); 1e-12 is `tolerances.POSE_M`, the
#: agreement of two float64 kinematic chains, 1000 times below the 1 nm axis resolution.
JOIN_TOL = 1e-12
#: A tool table's radius and the cut tool's agree within this (m): the table's 1 nm digits.
RADIUS_AGREE_M = 1e-9


class _Moves:
    """The trajectory's samples as one array, joined into continuous paths.

    Each move starts where the last one ended, so its first sample repeats the last one's
    end and is dropped; a path breaks only where it does not (a servo model leaves none:
    `motion.plan` ends each motion in position, where the next starts).

    Attributes
    ----------
    q : ndarray, shape (n, n_axes)
        Axis values of the samples kept.
    line, rapid : ndarray, shape (n,)
        Source line of the move each sample ends, and whether that move is a rapid.
    breaks : ndarray of int
        Sample indices where a new path starts (`numpy.split` points).
    sweep_line, sweep_move, sweep_rapid : ndarray, shape (s,)
        Per sweep (consecutive samples of a path, in the engine's order): the line of its
        move, the move's index in the trajectory, and whether the move is a rapid.
    sweep_start : ndarray, shape (s,)
        Index of each sweep's first sample.
    """

    def __init__(self, trajectory, n_axes: int) -> None:
        moving = trajectory.kinds != MOVE_KINDS.index("dwell")
        counts = np.diff(trajectory.offsets)[moving]
        if not counts.size:
            self.q = np.zeros((0, n_axes))
            self.line = self.sweep_line = self.sweep_start = np.zeros(0, dtype=np.int64)
            self.move = self.sweep_move = np.zeros(0, dtype=np.int64)
            self.path_start = np.zeros(0, dtype=bool)
            self.rapid = self.sweep_rapid = np.zeros(0, dtype=bool)
            self.breaks = np.zeros(0, dtype=np.int64)
            return
        rows = trajectory.rows(("rapid", "linear"))
        q = trajectory.q[rows]
        line = np.repeat(trajectory.lines[moving], counts)
        rapid = np.repeat(trajectory.kinds[moving] == MOVE_KINDS.index("rapid"), counts)
        first = np.cumsum(counts) - counts
        # A move continues the last when its first sample is the last one's end, to the
        # round-off of the planner's interpolation (`JOIN_TOL`).
        joined = np.zeros(len(counts), dtype=bool)
        joined[1:] = np.all(np.abs(q[first[1:]] - q[first[1:] - 1]) <= JOIN_TOL, axis=1)
        keep = np.ones(len(q), dtype=bool)
        keep[first[joined]] = False
        starts = np.zeros(len(q), dtype=bool)
        starts[first[~joined]] = True
        self.q, self.line, self.rapid = q[keep], line[keep], rapid[keep]
        self.move = np.repeat(np.flatnonzero(moving), counts)[keep]
        self._paths(starts[keep])

    def _paths(self, path_start: np.ndarray) -> None:
        self.path_start = path_start
        self.breaks = np.flatnonzero(path_start)[1:]
        # A sweep ends at every sample that does not start a path; it belongs to that move.
        end = np.flatnonzero(~path_start)
        self.sweep_start = end - 1
        self.sweep_line = self.line[end]
        self.sweep_move = self.move[end]
        self.sweep_rapid = self.rapid[end]

    def section(self, first_move: int, stop_move: int) -> tuple[_Moves, tuple[int, int]]:
        """The samples of moves [first_move, stop_move) as their own paths, and their
        sample range [lo, hi): a section that continues the one before starts at its last
        sample (the point its first move starts from)."""
        lo, hi = (int(i) for i in np.searchsorted(self.move, [first_move, stop_move]))
        if 0 < lo < hi and not self.path_start[lo]:
            lo -= 1
        part = object.__new__(_Moves)
        part.q, part.line, part.rapid = self.q[lo:hi], self.line[lo:hi], self.rapid[lo:hi]
        part.move = self.move[lo:hi]
        starts = self.path_start[lo:hi].copy()
        starts[:1] = True
        part._paths(starts)
        return part, (lo, hi)


class _ToolSections:
    """The tools a program cuts with, from its tool changes (`Program.tool_changes`).

    Before the first change, and for a change whose tool table entry gives no ``shape``,
    the tool is the cut's own; a change's length puts the tool's edge that far beyond
    ``tool_tip`` along the tool axis (the tool's +z, towards the holder), as a longer tool
    in the spindle does, while ``G43`` lifted Z by the same length.
    """

    def __init__(self, program, tool, errors=None) -> None:
        #: what a reader of the part should know about the tools it was cut with: the tools
        #: as given, as view notes them (the nose radius error is the machine's, and in a
        #: Lab's cut the truth: a table radius of 1 mm beside nose:1.0 had been noted as
        #: disagreeing with a tool of 1.003 mm)
        self.notes = tool_notes(program, tool)
        tool = with_nose_radius_error(tool, errors)  # every tool as it is
        built = {None: tool}
        # (first move, tool, length) of each run of moves between changes, and its name
        self.runs = [(0, tool, 0.0)]
        self.names = [(None, None)]  # (tool number, line of the change)
        for change in getattr(program, "tool_changes", ()):
            if change.shape not in built:
                built[change.shape] = with_nose_radius_error(table_tool(change.shape),
                                                             errors)
            self.runs.append((change.move, built[change.shape], float(change.length_m)))
            self.names.append((change.number, change.line))

    def setups(self) -> list:
        """Each (tool, length) the program cuts with, once, in the order of first use."""
        tools = {id(t): t for _, t, _ in self.runs}
        return [(tools[key], length)
                for key, length in dict.fromkeys((id(t), length) for _, t, length in self.runs)]

    def points(self) -> np.ndarray:
        """Every tool's vertices where it cuts, in the ``tool_tip`` frame (for the chord
        tolerance of rotary moves)."""
        return np.concatenate([np.asarray(tool.vertices(), dtype=np.float64)
                               - np.array([0.0, 0.0, length]) for tool, length in self.setups()])

    def split(self, moves: _Moves):
        """(tool, length, section moves, sample range, (number, line)) of each run with
        samples; the whole program as one section when one tool cuts it all."""
        if len(self.runs) == 1:
            yield self.runs[0][1], self.runs[0][2], moves, (0, len(moves.q)), self.names[0]
            return
        stops = [first for first, _, _ in self.runs[1:]] + [np.iinfo(np.int64).max]
        for (first, tool, length), stop, name in zip(self.runs, stops, self.names,
                                                     strict=True):
            section, (lo, hi) = moves.section(first, stop)
            if hi - lo >= 2:
                yield tool, length, section, (lo, hi), name


def tool_notes(program, tool) -> tuple[str, ...]:
    """What a reader of a part cut by ``program`` with ``tool`` (the cut's own) should know
    about the tools it was cut with: a table radius the cutting tool does not have
    (`_radius_note`, per change), several tools selected without a table (`_untabled_note`);
    each once. A cut's notes hold them, and ``machinesim view --program`` prints them."""
    notes = (_radius_note(change, tool) for change in getattr(program, "tool_changes", ()))
    return tuple(dict.fromkeys(note for note in (*notes, _untabled_note(program, tool))
                               if note))


def _radius_note(change, tool) -> str:
    """A note when a tool change gives a radius that the tool which cuts for it does not
    have: its table shape's (a D register of 2 mm beside a ball:0.5, which cuts: perhaps a
    wear offset, perhaps a slip), or, without a shape, the cut's own tool's (a 2 mm end mill
    cut as a V tool); else ''."""
    if change.radius_m is None:
        return ""
    if change.shape is not None:
        shaped = table_tool(change.shape)
        radius = getattr(shaped, "radius", getattr(shaped, "nose_radius", None))
        if radius is None or abs(radius - change.radius_m) <= RADIUS_AGREE_M:
            return ""
        return (f"T{change.number} (line {change.line}): the tool table gives radius "
                f"{change.radius_m * 1e3:g} mm and shape {change.shape!r} (radius "
                f"{radius * 1e3:g} mm); the shape cut (the radius, the D register, is not "
                "read: G41/G42 are refused)")
    radius = getattr(tool, "radius", getattr(tool, "nose_radius", None))
    if radius is not None and abs(radius - change.radius_m) <= RADIUS_AGREE_M:
        return ""
    own = "no radius" if radius is None else f"radius {radius * 1e3:g} mm"
    return (f"T{change.number} (line {change.line}): the tool table gives radius "
            f"{change.radius_m * 1e3:g} mm and no shape, so the cut's own tool ({own}, "
            f"{type(tool).__name__}) cut for it; give its shape in the table "
            "(shape = \"flat:R\", \"ball:R\", \"nose:R:ANGLE\" or \"v:ANGLE\")")


def _untabled_note(program, tool) -> str:
    """A note when a program read without a tool table selects several tools (T words):
    its T words are then only listed as states, and the cut's own tool cut every move (a
    ball finish after a flat roughing, cut as the flat), else ''."""
    if getattr(program, "tool_table", None) is not None or getattr(program, "tool_changes", ()):
        return ""
    selected = [(word, line) for word, line in getattr(program, "states", {}).items()
                if word[:1] == "T" and word[1:].isdigit() and int(word[1:]) != 0]
    if len(selected) < 2:
        return ""
    shown = ", ".join(f"{word} at line {line}" for word, line in selected)
    return (f"the program selects {len(selected)} tools ({shown}) but was read without a "
            f"tool table, so the cut's own tool ({type(tool).__name__}) cut every move; give "
            "a tool table with each tool's shape and length (--tools; read_program(..., "
            "tools=...); docs/nc.md)")
