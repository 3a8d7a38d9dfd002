"""What a cut reports (`CutReport`), and the pieces of it taken from the program: how it was
read (`nc_summary`, `arc_chord_note`) and the lag of the servo loops it was run through
(`peak_following_error`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field


@dataclass(frozen=True)
class CutReport:
    """What happened while cutting, for people and for JSON.

    Attributes
    ----------
    removed_volume_m3 : float
        Integrated over the cut (`machinesim.cutting.engine.removed_volume`).
    machining_time_s, cutting_time_s : float
        From the feeds (motion's FANUC rule), all moves and feed moves only.
    sweeps : int
        Sweeps (sub-steps of any move, rapids included) that reached the stock and were cut.
    substeps : int
        Sub-steps of all moves, rapids included.
    rapids_that_cut : tuple of int
        Source lines of rapids (G00) whose sweep met material present at that time; they are
        cut like any move (a crash shows in the part).
    limit_violations : tuple of str
        Axis values outside their travel, with their lines (only with ``allow_overtravel``:
        otherwise `cut` raises `AxisLimitError`).
    sideways_sweeps : int
        Sweeps that drag a non-rotational tool sideways (across its cutting edge).
    sideways_lines : tuple of int
        Source lines of the feed moves among those sweeps that drag the tool sideways by
        more than `tolerances.SIDEWAYS_WARN_RAD` (1 deg): a real V or nose tool does not cut
        cleanly there (it rubs with its flank), so the part there is not what the machine
        would leave. (A rapid that cuts is listed in ``rapids_that_cut``; one that only
        grazes the stock's box is harmless.)
    empty_cut : bool
        True when nothing was removed, judged against the volume the sweeps that reach the
        stock could remove (`EngineReport.swept_volume`), not against the stock.
    engine : str
        How the material was removed: "relief" (straight grooves across a block, meshed as a
        height field) or "boolean" (sweeps subtracted); both exact (`engine.remove`).
    elapsed_s : float
        Wall time of the simulation.
    notes : tuple of str
        What a reader of the part should know: how the program was read and cut, sheets
        left, and nothing of the stock left (`nothing_left_note`).
    holder_contact : tuple of int
        Source lines of moves in which the top of the tool's body, where its holder begins,
        came below the top of the stock over it (`EngineReport.holder_contact`).
    engine_s : float
        Wall time of the material removal alone (`EngineReport.elapsed_s`).
    nc : Mapping
        How the program was read (`nc_summary`): ``integer_input``, the modal ``states``
        seen with their first lines, and the ``tool_table`` path; empty when unknown.
    thin_sheets : int
        Sheets of stock under a picometre thick that round-off left where sweeps' faces
        coincide, found on the finished part and cut away (`machinesim.cutting.sheets`;
        when their faces make more than `sheets.MOST_REMOVED` patches they are left, and a
        note says so).
    tools : tuple of Mapping
        One entry per run of moves cut by one tool (`Program.tool_changes`): ``tool``
        (its number, None for the cut's own tool before any change), ``line`` (where it
        was put in, None before any change), ``length_m``, ``removed_volume_m3``,
        ``empty_cut`` (the run removed nothing: its volume at most the booleans' round-off,
        `EngineReport.empty_cut`, as the run of a tool that only retraces what an earlier
        tool cut) and ``engine``.
    peak_following_error : Mapping
        With servo loops: axis letter -> largest |command - reached| over the program's
        samples (m, rad for a rotary axis); empty without.
    """

    removed_volume_m3: float
    machining_time_s: float
    cutting_time_s: float
    sweeps: int
    substeps: int
    rapids_that_cut: tuple[int, ...]
    limit_violations: tuple[str, ...]
    sideways_sweeps: int
    empty_cut: bool
    engine: str
    elapsed_s: float
    notes: tuple[str, ...] = field(default=())
    holder_contact: tuple[int, ...] = field(default=())
    engine_s: float = 0.0
    nc: Mapping = field(default_factory=dict, hash=False)
    tools: tuple = field(default=(), hash=False)
    thin_sheets: int = 0
    sideways_lines: tuple[int, ...] = field(default=())
    edge_plane_lines: tuple[int, ...] = field(default=())
    peak_following_error: Mapping = field(default_factory=dict, hash=False)

    def __repr__(self) -> str:
        lines = [("rapids that cut at line", self.rapids_that_cut),
                 ("holder contact at line", self.holder_contact),
                 ("sideways at line", self.sideways_lines)]
        flagged = [f"{what}{'' if len(at) == 1 else 's'} {_lines(at)}"
                   for what, at in lines if at]
        if self.limit_violations:
            flagged.append(_count(self.limit_violations, "limit violation"))
        if self.empty_cut:
            flagged.append("empty cut")
        return (f"CutReport({self.engine} engine: removed "
                f"{self.removed_volume_m3 * 1e9:.6g} mm^3 in {self.sweeps} of "
                f"{self.substeps} sub-steps, machining {self.machining_time_s:.6g} s "
                f"(cutting {self.cutting_time_s:.6g} s), {_count(self.tools, 'tool run')}, "
                f"{_count(range(self.thin_sheets), 'thin sheet')} cut away"
                f"{following_note(self.peak_following_error)}"
                f"{''.join('; ' + f for f in flagged)}; {_count(self.notes, 'note')}; "
                f"took {self.elapsed_s:.3g} s)")

    def to_dict(self) -> dict:
        """JSON-ready dict, every key with its unit."""
        return {
            "removed_volume_mm3": self.removed_volume_m3 * 1e9,
            "machining_time_s": self.machining_time_s,
            "cutting_time_s": self.cutting_time_s,
            "sweeps_count": self.sweeps,
            "substeps_count": self.substeps,
            "rapids_that_cut_lines": list(self.rapids_that_cut),
            "limit_violations": list(self.limit_violations),
            "holder_contact_lines": list(self.holder_contact),
            "sideways_sweeps_count": self.sideways_sweeps,
            "sideways_lines": list(self.sideways_lines),
            "edge_plane_lines": list(self.edge_plane_lines),
            "thin_sheets_count": self.thin_sheets,
            "empty_cut": self.empty_cut,
            "engine": self.engine,
            "elapsed_s": self.elapsed_s,
            "engine_s": self.engine_s,
            "notes": list(self.notes),
            "nc": {"integer_input": self.nc.get("integer_input"),
                   "integer_words": [dict(w) for w in self.nc.get("integer_words", ())],
                   "states": [dict(state) for state in self.nc.get("states", ())],
                   "units": [dict(unit) for unit in self.nc.get("units", ())],
                   "tool_table": self.nc.get("tool_table")},
            "tools": [{"tool": t["tool"], "line": t["line"], "length_mm": t["length_m"] * 1e3,
                       "removed_volume_mm3": t["removed_volume_m3"] * 1e9,
                       "empty_cut": t["empty_cut"], "engine": t["engine"]}
                      for t in self.tools],
            "peak_following_error_um_or_urad": {axis: value * 1e6 for axis, value
                                                in self.peak_following_error.items()},
        }


def _count(items, what: str) -> str:
    return f"{len(items)} {what}{'' if len(items) == 1 else 's'}"


def _lines(lines, most: int = 5) -> str:
    """Source lines for a repr, the first ``most`` of them and how many more."""
    shown = ", ".join(str(line) for line in lines[:most])
    return shown if len(lines) <= most else f"{shown} and {len(lines) - most} more"


def following_note(peak: Mapping) -> str:
    """``, peak following error X 1.2, C 0.4 um or urad`` for a report's repr; empty
    without servo loops (no entry, or every entry zero)."""
    if not any(peak.values()):
        return ""
    listed = ", ".join(f"{axis} {value * 1e6:.3g}" for axis, value in peak.items())
    return f", peak following error {listed} um or urad"


def peak_following_error(trajectory, machine) -> dict:
    """Axis letter -> largest |command - reached| (m, rad) of ``trajectory``
    (`Trajectory.peak_lag`); {} when it was planned without servo loops."""
    if trajectory.peak_lag is None:
        return {}
    return {axis: float(lag) for axis, lag in zip(machine.axes, trajectory.peak_lag.tolist(),
                                                   strict=True)}


def nc_summary(program) -> dict:
    """How ``program`` was read, for `CutReport.nc`: ``integer_input`` (None when not read
    from text), ``integer_words`` (the letters of non-zero lengths and angles written
    without a decimal point, read as ``integer_input`` says, with their first lines),
    ``states`` (the words read as modal states without geometric effect, G40,
    G80, G05.1 Q1, G08 P1, T1, and G09, G61, G64, ..., as ``{"word", "line"}`` in the order
    of their first lines), ``units`` (G20 and G21 as selected, the same way; none when the text
    selected neither and its lengths were read in mm) and ``tool_table`` (the path of the
    table the T, H and D words used, or None). A program that is not a `Program` (moves
    built in Python) gives Nones and no states."""
    def first_lines(words) -> tuple:
        return tuple({"word": word, "line": int(line)} for word, line in
                     sorted(words.items(), key=lambda item: (item[1], item[0])))

    return {"integer_input": getattr(program, "integer_input", None),
            "integer_words": first_lines(getattr(program, "integer_words", {}) or {}),
            "states": first_lines(getattr(program, "states", {}) or {}),
            "units": first_lines(getattr(program, "unit_words", {}) or {}),
            "tool_table": getattr(program, "tool_table", None)}


#: Two chord tolerances (m) are the same when they agree to this share: the round-off of
#: ``0.1 * 1e-6`` against a written ``1e-7``.
SAME_CHORD_SHARE = 1e-9


def arc_chord_note(program, chord_tolerance: float, *, takes_path: bool = True) -> str:
    """A note when ``program``'s arcs were read as chords within another tolerance than the
    ``chord_tolerance`` (m) the cut follows (`Program.arc_chord_tolerance`), else ''.

    The cut cannot split them again: finer, it runs sqrt(cut / read) times as many sweeps
    on them (`parse_program`'s 1 nm under a ball or flat end mill's 100 nm: ten times) for
    a part that differs by less than the cut's tolerance; coarser, the part follows its
    arcs only within the tolerance they were read with. Every cut of a program says it
    through this: `machinesim.cutting.cut`, ``cut_turned`` and the viewer's
    (`machinesim.viewer.machine_scene`); ``takes_path`` False leaves out the advice to give
    the file's path, which only `cut` reads at its own tolerance."""
    read = getattr(program, "arc_chord_tolerance", None)
    if read is None or abs(read - chord_tolerance) <= SAME_CHORD_SHARE * chord_tolerance:
        return ""
    many = program.arc_blocks != 1
    blocks = f"{program.arc_blocks} arc block{'s were' if many else ' was'}"
    said = (f"the program's {blocks} read as chords within {read * 1e9:.4g} nm, "
            f"{'finer' if read < chord_tolerance else 'coarser'} than the "
            f"{chord_tolerance * 1e9:.4g} nm this cut follows")
    if read < chord_tolerance:
        return (f"{said}: about {math.sqrt(chord_tolerance / read):.3g} times as many sweeps "
                f"on them, for a part within {chord_tolerance * 1e9:.4g} nm of the same; read "
                f"it with read_program/parse_program(..., chord_tolerance="
                f"{chord_tolerance:.4g}) (machinesim.tools.path_chord_tolerance([tool]))"
                + (", or give cut() the file's path (docs/cutting.md)" if takes_path else ""))
    return (f"{said}: the part follows them only within {read * 1e9:.4g} nm (read with "
            f"chord_tolerance={chord_tolerance:.4g} to follow them as closely)")


#: How `nothing_left_note` begins, with or without windows: ``machinesim cut`` prints that
#: note as a warning.
NOTHING_LEFT = "nothing of the stock"


def nothing_left_note(part, removed_m3: float, roi=None) -> str:
    """A note when ``part`` has no faces, else '': the cut removed all of the stock (of the
    stock in the ``roi`` windows, which `cut` refuses when none overlaps it, so there was
    material to remove), as a face mill wider than the part taken below its bottom does. A
    part file of it holds no faces, which ``machinesim view`` refuses. The one rule for it:
    `machinesim.cutting.cut` and ``cut_turned`` add it to their notes, and the viewer
    (`machinesim.viewer.machine_scene`) warns it when its last stage is empty."""
    if part.triangle_count:
        return ""
    material = "the stock" if roi is None else "the stock in the roi windows"
    return (f"nothing of {material} is left: the cut removed all of it "
            f"({removed_m3 * 1e9:.6g} mm^3), and the part has no faces (a tool wider than "
            "the part, or a depth below its bottom?)")


#: How `no_moves_note` begins: ``machinesim cut`` prints that note as a warning.
NO_MOVES = "the program has no moves"


def no_moves_note(program) -> str:
    """A note when ``program`` has no move that runs (a comment and M30, dwells alone), else
    '': nothing was removed because nothing moved, not because the moves miss the stock.
    `machinesim.cutting.cut` adds it to its notes; ``machinesim cut`` had said it alone, as
    a warning, and a cut from Python gave ``empty_cut=True`` with no note."""
    from machinesim.nc.moves import KIND_DWELL

    if (program.kinds != KIND_DWELL).any():
        return ""
    return (f"{NO_MOVES} ({program.source} holds no G00/G01/G02/G03 block that runs), so "
            "nothing was removed")


__all__ = ["NOTHING_LEFT", "NO_MOVES", "CutReport", "arc_chord_note", "following_note",
           "nc_summary", "no_moves_note", "nothing_left_note", "peak_following_error"]
