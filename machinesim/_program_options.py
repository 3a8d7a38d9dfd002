"""How the command line reads an NC program: the options ``cut`` and ``view`` share.

``--tools``, ``--integer-input`` and ``--chord-nm`` mean the same in both commands, and a
program is read the same way for both (`read_for_machine`): G28 returns to the machine's
home, arcs are split as finely as the finest tool is drawn unless ``--chord-nm`` says.
"""

from __future__ import annotations

import argparse

from machinesim._arguments import typed_number
from machinesim._io import check_readable_file, input_path


def add_reading_options(parser) -> None:
    """Add ``--tools``, ``--integer-input`` and ``--chord-nm`` to ``parser`` (an argparse
    parser or argument group)."""
    parser.add_argument("--tools", type=input_path, default=None, metavar="TOOLS.toml",
                        help="tool table for T/D/H words and G43/G44 (TOML, units in keys); "
                             "T/M06 change the cut to a tool's length and shape (docs/nc.md)")
    parser.add_argument("--integer-input", choices=("calculator", "increment", "is-b", "is-c"),
                        default=None,
                        help="how an axis number without decimal point reads: calculator "
                             "(X10 is 10 mm, the default), or in least input increments: "
                             "increment (X10 is 10 nm), is-b (FANUC IS-B: 0.01 mm), is-c "
                             "(IS-C: 0.001 mm)")
    parser.add_argument("--chord-nm", type=typed_number, default=None, metavar="NM",
                        help="largest distance of the chords arcs and rotary moves are cut "
                             "as from the true path, nm, from 1 (the axes' resolution) to "
                             "1e9; default: a tenth of the finest "
                             "tool's own facet tolerance, at least 1 nm (1 nm for V and nose "
                             "tools, 100 nm for ball and flat end mills)")


def check_reading_options(args: argparse.Namespace) -> None:
    """Refuse a ``--chord-nm`` outside 1 nm .. 1 m (`machinesim.tools.check_path_chord`, as
    the Python API's ``chord_tolerance``) and an unreadable ``--tools`` (before any work)."""
    from machinesim.tools import check_path_chord

    if args.chord_nm is not None:
        check_path_chord(args.chord_nm, "--chord-nm", "nm", "NM")
    if args.tools is not None:
        check_readable_file(args.tools, "tool table (--tools)")


def table_tools(table) -> list:
    """The tools a tool table's ``shape`` entries name (none without a table)."""
    from machinesim.nc.tooltable import table_tool

    entries = table.tools.values() if table is not None else ()
    return [table_tool(entry.shape) for entry in entries if entry.shape is not None]


def read_for_machine(args: argparse.Namespace, path, machine, tool):
    """(program, chord tolerance in m) of the NC program at ``path``, read with ``args``'s
    reading options for ``machine`` cutting with ``tool`` (and the table's tools)."""
    from machinesim.nc import read_program
    from machinesim.nc.tooltable import tool_table
    from machinesim.tools import path_chord_tolerance

    reading = {}
    table = tool_table(args.tools)  # read once: for the reader and for the chord
    if table is not None:
        reading["tools"] = table
    if args.integer_input is not None:
        reading["integer_input"] = args.integer_input
    # the machine starts at its home and G28 returns there: Z at the top of its travel
    reading["reference"] = dict(zip(machine.axes, machine.home.tolist(), strict=True))
    # arcs and rotary moves as fine as the finest tool is drawn (a tenth of its facets)
    chord = path_chord_tolerance([tool, *table_tools(table)])
    if args.chord_nm is not None:
        chord = args.chord_nm * 1e-9
    return read_program(path, chord_tolerance=chord, **reading), chord


def chord_note(args: argparse.Namespace, program, chord: float, machine=None,
               errors=None) -> str | None:
    """The note for arcs and rotary moves split into chords coarser than 1 nm (the axes'
    resolution) by default, ``--chord-nm`` not given, when the program has them
    (`has_chords`): a tenth of a ball or flat end mill's facets, 100 nm; or None.

    With the ``machine`` and its ``errors``, the feeds along a linear axis whose errors vary
    along it (a straightness or angular table, `bent_axes`) count too: the planner splits
    them to the same chords (`machinesim.motion.planner`), and the note names those axes."""
    from machinesim.tolerances import CHORD_TOLERANCE_M

    if chord <= CHORD_TOLERANCE_M or args.chord_nm is not None:
        return None
    bent = bent_axes(machine, errors) if machine is not None else {}
    home = dict(zip(machine.axes, machine.home.tolist(), strict=True)) if bent else {}
    bending = [axis for axis, components in bent.items()
               if _feeds_move(program, (axis,), home, components)]
    if not bending and not has_chords(program):
        return None
    what = "arcs and rotary moves"
    if bending:
        one = len(bending) == 1
        vary = "its errors vary along it" if one else "their errors vary along them"
        what += (f", and feeds along {' and '.join(bending)} ({vary} in --errors: a "
                 "straight move there is a curve),")
    return (f"{what} were split into chords within {chord * 1e9:.4g} nm, a "
            "tenth of the tool's own facets (--chord-nm sets it; docs/cutting.md)")


def bent_axes(machine, errors) -> dict[str, list]:
    """``machine``'s linear axes whose ``errors`` vary along them (component tables: a
    straight move of such an axis is a curve, split to the chord tolerance as a rotary move
    is, `machinesim.motion.planner`), in the machine's order: name -> its components that
    vary; {} without errors. A component that takes one value along the axis (a table of
    equal values, a polynomial of its constant term alone) is not one: it moves the tool
    and bends no move, which the planner cuts as one chord."""
    if errors is None:
        return {}
    found: dict[int, list] = {}
    for var in machine.binding(errors).varying:
        if not machine.rotary[var.axis] and _varies(var.component):
            found.setdefault(var.axis, []).append(var.component)
    return {name: found[i] for i, name in enumerate(machine.axes) if i in found}


def _varies(component) -> bool:
    """Whether ``component`` (a table or a polynomial) takes more than one value."""
    import numpy as np

    values = np.asarray(component.values, dtype=np.float64)
    if component.kind == "table":
        return bool(np.ptp(values) > 0.0)
    return bool(np.any(values[1:] != 0.0))


def _bends(component, low, high):
    """Whether ``component`` takes more than one value between the axis positions ``low``
    and ``high`` (arrays, low < high), each: a polynomial that varies does on any span; a
    table where a segment the span reaches has unequal ends (beyond its first and last
    position a table is constant)."""
    import numpy as np

    if component.kind != "table":
        return np.full(len(low), _varies(component))
    positions = np.asarray(component.positions, dtype=np.float64)
    values = np.asarray(component.values, dtype=np.float64)
    # sloped[k]: the sloping segments before segment k - 1 (segment -1 lies before the
    # first position, segment n - 1 after the last, both flat)
    sloped = np.concatenate([[0, 0], np.cumsum(values[1:] != values[:-1]), [0]])
    sloped[-1] = sloped[-2]
    first = np.searchsorted(positions, low, side="right")  # segment just after low, + 1
    last = np.searchsorted(positions, high, side="left")  # segment just before high, + 1
    return sloped[last + 1] - sloped[first] > 0


def _feeds_move(program, names, home, components=None) -> bool:
    """Whether a feed move of ``program`` changes one of the axes ``names`` (those the
    program has), an axis not yet programmed standing at ``home`` (name -> value, 0.0 if
    absent); with ``components`` (of the one axis named, `bent_axes`), only a feed over
    which one of them varies (`_bends`)."""
    import numpy as np

    from machinesim.nc.program import AXES, KIND_LINEAR

    names = [name for name in names if name in AXES]
    if not names:
        return False
    values = program.targets[:, [AXES.index(a) for a in names]]
    start = np.array([home.get(name, 0.0) for name in names])
    # an axis not yet programmed stands where the cut starts (`Machine.home`)
    values = np.vstack([start[None], np.where(np.isnan(values), start[None], values)])
    feeds = program.kinds == KIND_LINEAR
    moved = (np.diff(values, axis=0) != 0.0) & feeds[:, None]
    if components is None or not moved.any():
        return bool(moved.any())
    rows = np.flatnonzero(moved[:, 0])
    low = np.minimum(values[rows, 0], values[rows + 1, 0])
    high = np.maximum(values[rows, 0], values[rows + 1, 0])
    return any(bool(_bends(component, low, high).any()) for component in components)


def has_chords(program) -> bool:
    """Whether the chord tolerance shapes the cut: the program has arcs, or feed moves that
    turn a rotary axis."""
    from machinesim.nc.program import ROTARY_AXES

    # an axis not yet programmed stands at the home, where `cut` and `view` start (every
    # rotary axis at zero, `Machine.home`): a first `G01 A1.` turns A from 0, and is split
    # into sub-steps as any other; it had been skipped (its previous target NaN), and a
    # program turning its rotary axes only in such feeds got no note
    return program.arc_blocks > 0 or _feeds_move(program, ROTARY_AXES, {})


def work_offset_notes(program) -> list[str]:
    """The notes for G54..G59 words the program selects, which the command line gives no
    offsets for: each is taken as zero, the same as G54."""
    from machinesim.nc.program import WORK_OFFSETS

    return [f"{word} at line {line} selects a work offset this command is not given: "
            "taken as zero, the same as G54 (docs/nc.md)"
            for word, line in program.states.items() if word in WORK_OFFSETS]


def integer_note(program) -> str | None:
    """The note for a program read under calculator-type input whose text wrote non-zero
    lengths or angles without a decimal point (``Z-1``: 1 mm here, 1 um on a FANUC control
    without calculator-type input at IS-B), or None. It names the unit the lengths were
    read in, inches under G20 (``X3``: 3 inches, 0.0003 inch at IS-B), and each rule's
    increment in it (docs/nc.md, "Integer input")."""
    words = getattr(program, "integer_words", {}) or {}
    if getattr(program, "integer_input", None) != "calculator" or not words:
        return None
    shown = ", ".join(f"{letter} at line {line}" for letter, line in
                      sorted(words.items(), key=lambda item: (item[1], item[0])))
    if getattr(program, "unit_in_force", None) == "G20":
        unit, increments = "inches (G20)", ("0.0001 inch", "0.00001 inch", "0.0000001 inch")
    else:
        unit, increments = "mm", ("0.001 mm", "0.0001 mm", "1 nm")
    return (f"numbers without a decimal point ({shown}) were read in {unit} and deg "
            "(calculator-type input, the default); a FANUC control without it reads them "
            f"in its least input increment: give --integer-input is-b ({increments[0]}), "
            f"is-c ({increments[1]}) or increment ({increments[2]}) if the program was "
            "written for one")


def end_note(program) -> str | None:
    """The note for a program read from text whose main program has no M02 or M30 (it ran
    out at the end of the file: a FANUC control stops there with an alarm, and a file cut
    short by a transfer or an editor reads so), or None."""
    if (getattr(program, "integer_input", None) is None or not len(program)
            or getattr(program, "end_words", None)):
        return None
    return (f"the program has no M30 or M02 (its last move is at line "
            f"{int(program.lines[-1])}): it ran to the end of the file, where a FANUC "
            "control stops with an alarm; if the file was cut short (a transfer, an "
            "editor), so is the part")


def after_end_note(program) -> str | None:
    """The note for a program read from text with more text after the % that ended it
    (`machinesim.nc.tape`: a FANUC control stops reading there, and so does the reader),
    or None."""
    line = getattr(program, "after_end", None)
    if line is None:
        return None
    return (f"the text from line {line} on, after the % that ends the program, was not read "
            "(a FANUC control stops reading at that %); put a second program in a file of "
            "its own, or remove the % before it if it belongs to this one")


def unit_note(program) -> str | None:
    """The note for a program read from text that selects neither G20 nor G21 (its lengths
    are then read in mm, the reader's default: an inch program without G20 comes out 25.4
    times too small), or None."""
    if program.unit_words or not len(program):
        return None
    return ("the program selects neither G20 (inch) nor G21 (mm): its lengths were read in "
            "mm; add G20 at its start if it is written in inches")
