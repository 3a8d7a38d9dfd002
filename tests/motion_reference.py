"""The line-by-line motion planner as it was before vectorisation (issue 12), kept verbatim
as the reference the vectorised `machinesim.motion.plan` is held to, segment by segment.

Not part of the package: only tests import it. Its module docstring follows.

Motion: an NC program becomes a sampled axis trajectory q(t).

The controller interpolates G01 (and G00) linearly in *axis* space, so a move that turns a
rotary axis sweeps the tool along a curve in the workpiece frame. Such a move is split into
sub-steps until the chord between consecutive samples stays within ``chord_tolerance`` of
the true path for every point of the tool (the edge and the tool's extreme points): the
midpoint of each sub-step is evaluated through the kinematics and compared with the chord.

Feed and time (FANUC rule, feed per minute, G94): a move's length is
``sqrt(sum(d_linear_mm**2) + sum(d_rotary_deg**2))`` and takes ``length / F`` minutes, so F
reads as mm/min for linear moves and deg/min for pure rotary moves. A rapid runs every axis
at its own rapid rate (the URDF velocity limit) and takes as long as its slowest axis. A
dwell takes its time. Servo follow-up errors enter through a `ServoModel` (ideal by default).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import InputError, NCProgramError
from machinesim.tolerances import CHORD_TOLERANCE_M

#: A move is split into at most this many sub-steps: beyond it the request is unreasonable
#: (a 1 nm chord over a full turn at 1 m radius needs ~70,000).
MAX_SUBSTEPS = 1_000_000
_M_PER_MM = 1e-3
_RAD_PER_DEG = np.pi / 180.0


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


@dataclass(frozen=True)
class Trajectory:
    """The sampled motion of a whole program on one machine.

    Attributes
    ----------
    axes : tuple of str
        Axis letters, configuration order.
    segments : tuple of Segment
    duration : float
        Machining time, s.
    cutting_time : float
        Time spent in feed (G01) moves, s.
    notes : tuple of str
        What the planner had to say (moves of axes the machine lacks are errors, not notes).
    """

    axes: tuple[str, ...]
    segments: tuple[Segment, ...]
    duration: float
    cutting_time: float
    notes: tuple[str, ...] = field(default=())

    @property
    def substeps(self) -> int:
        """Number of sub-steps over all moves."""
        return sum(len(s.q) - 1 for s in self.segments)


def move_duration(kind: str, start: np.ndarray, end: np.ndarray, rotary: np.ndarray,
                  rapid_rate: np.ndarray, feed_m_per_s: float | None, dwell_s: float) -> float:
    """Time of one move by the rules in the module docstring, s."""
    if kind == "dwell":
        return float(dwell_s)
    delta = np.abs(end - start)
    if kind == "rapid":
        return float(np.max(delta / rapid_rate)) if delta.size else 0.0
    # FANUC: degrees count as millimetres in the feed length
    scaled = np.where(rotary, delta / _RAD_PER_DEG, delta / _M_PER_MM)
    length_mm = float(np.sqrt(np.sum(scaled**2)))
    if length_mm == 0.0:
        return 0.0
    feed_mm_per_s = feed_m_per_s / _M_PER_MM
    return length_mm / feed_mm_per_s


def plan(program, machine, errors=None, *, start=None, tool_points=None,
         chord_tolerance: float = CHORD_TOLERANCE_M, servo: ServoModel | None = None,
         ) -> Trajectory:
    """Sample ``program`` on ``machine`` into a `Trajectory`.

    Parameters
    ----------
    program : machinesim.nc.Program
    machine : machinesim.Machine
    errors : ErrorModel, optional
        The machine's errors: the chord check follows the real (erroneous) tool path.
    start : array_like, shape (n_axes,), optional
        Axis values before the first block (default zeros); axes the program never sets
        stay there.
    tool_points : ndarray, shape (k, 3), optional
        Points of the tool in the tool_tip frame (m) whose paths must stay within the chord
        tolerance; the edge (origin) is always included.
    chord_tolerance : float
        Largest allowed distance, m, between a sub-step's chord and the true path.
    servo : ServoModel, optional
        Follow-up model applied to each move's samples (default: ideal).
    """
    axes = machine.axes
    index = {a: i for i, a in enumerate(axes)}
    q = np.zeros(len(axes)) if start is None else np.array(start, dtype=np.float64)
    if q.shape != (len(axes),):
        raise InputError(f"start must have shape ({len(axes)},) for axes {''.join(axes)}, "
                         f"got {q.shape}")
    if chord_tolerance <= 0.0:
        raise InputError(f"chord_tolerance must be positive, got {chord_tolerance}")
    points = np.zeros((1, 3)) if tool_points is None else np.vstack(
        [np.zeros((1, 3)), np.asarray(tool_points, dtype=np.float64).reshape(-1, 3)])
    servo = servo or IdealServo()
    segments, t_now, cutting = [], 0.0, 0.0
    for move in program.moves:
        end = q.copy()
        for letter, value in move.target.items():
            if letter not in index:
                raise NCProgramError(
                    f"axis {letter} is not on {machine.name} (axes {''.join(axes)})",
                    source=program.source, line=move.line, key=letter)
            end[index[letter]] = value
        if move.kind == "linear" and move.feed_m_per_s is None and np.any(end != q):
            raise NCProgramError("a feed move (G01, or an arc: G02/G03) with no feed rate F given "
                                 "so far; expected an F word in its block or one before it",
                                 source=program.source, line=move.line, key="F")
        duration = move_duration(move.kind, q, end, machine.rotary, machine.rapid_rate,
                                 move.feed_m_per_s, move.dwell_s)
        steps = 1
        if move.kind != "dwell" and np.any(end[machine.rotary] != q[machine.rotary]):
            steps = _substeps(machine, errors, q, end, points, chord_tolerance,
                              (program.source, move.line))
        fractions = np.linspace(0.0, 1.0, steps + 1)
        samples = q + fractions[:, None] * (end - q)
        times = t_now + fractions * duration
        segments.append(Segment(move.kind, frozen(samples, copy=False),
                                frozen(times, copy=False), move.line))
        t_now += duration
        if move.kind == "linear":
            cutting += duration
        q = end
    return Trajectory(tuple(axes), tuple(_followed(segments, servo,
                                                   getattr(program, "exact_stops", ()))),
                      t_now, cutting)


def _followed(segments, servo, exact_stops=()):
    """The segments as the servo reaches them: consecutive feed moves as one motion (each
    later move's first sample is the one before's last) unless the one before ends in an
    exact stop, a rapid or a dwell alone; each motion's last sample in position (its
    command)."""
    if type(servo) is IdealServo:
        return segments
    stops = set(int(i) for i in exact_stops)
    groups = []
    for i, segment in enumerate(segments):
        if (groups and segment.kind == "linear" and groups[-1][-1].kind == "linear"
                and i - 1 not in stops):
            groups[-1].append(segment)
        else:
            groups.append([segment])
    out = []
    for group in groups:
        times = np.concatenate([group[0].t] + [g.t[1:] for g in group[1:]])
        samples = np.concatenate([group[0].q] + [g.q[1:] for g in group[1:]])
        reached = np.array(servo.follow(times, samples), dtype=np.float64)
        reached[-1] = samples[-1]  # the motion ends in position
        at = 0
        for g in group:
            rows = len(g.t)
            out.append(Segment(g.kind, frozen(reached[at:at + rows]), frozen(g.t, copy=False),
                               g.line))
            at += rows - 1
    return out


def _substeps(machine, errors, start, end, points, tolerance, where) -> int:
    """Fewest uniform sub-steps whose chords all stay within ``tolerance`` of the path.

    The chord's deviation from an arc (its sagitta) falls as 1/n**2: one evaluation at a
    coarse n predicts the n needed, which is then checked (and raised by 10 % until it holds).
    Deviations are measured at sub-step midpoints, where an arc's sagitta peaks.
    """
    delta = end - start

    def deviation(n: int) -> float:
        f = np.linspace(0.0, 1.0, n + 1)
        mid = (f[:-1] + f[1:]) / 2
        nodes = machine.tool_pose(start + f[:, None] * delta, errors)
        middle = machine.tool_pose(start + mid[:, None] * delta, errors)
        p_nodes = nodes[:, :3, :3] @ points.T + nodes[:, :3, 3:4]  # (n+1, 3, k)
        p_mid = middle[:, :3, :3] @ points.T + middle[:, :3, 3:4]
        return float(np.max(np.linalg.norm(p_mid - (p_nodes[:-1] + p_nodes[1:]) / 2, axis=1)))

    n = 8
    d = deviation(n)
    if d <= tolerance:
        return n if n == 1 else _fewest(deviation, n, tolerance)
    n = int(np.ceil(n * np.sqrt(d / tolerance)))
    while True:
        if n > MAX_SUBSTEPS:
            raise NCProgramError(
                f"a rotary move would need more than {MAX_SUBSTEPS} sub-steps to keep the "
                f"chord within {tolerance * 1e9:g} nm; raise chord_tolerance "
                "(--chord-nm on the command line)",
                source=where[0], line=where[1])
        if deviation(n) <= tolerance:
            return n
        n = int(np.ceil(n * 1.1))


def _fewest(deviation, n: int, tolerance: float) -> int:
    """Smallest n' <= n with deviation(n') <= tolerance (deviation falls as n grows)."""
    lo, hi = 0, n
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if deviation(mid) <= tolerance:
            hi = mid
        else:
            lo = mid
    return hi


__all__ = ["CHORD_TOLERANCE_M", "IdealServo", "Segment", "ServoModel", "Trajectory",
           "move_duration", "plan"]
