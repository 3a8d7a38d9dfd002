"""The ``machinesim`` command line.

    machinesim machines
    machinesim view MACHINE | PART.ply | REPORT_DIR [--html FILE]
    machinesim cut PROGRAM --machine NAME --tool SPEC --stock SPEC [--errors ERRORS.toml]
                   [--servo SERVO.toml] --out PART.ply [--report REPORT.json]
                   [--roi X0,X1,Y0,Y1 ...] [--tools TOOLS.toml]
                   [--integer-input calculator|increment|is-b|is-c]
                   [--chord-nm NM] [--allow-overtravel] [--allow-holder-contact]
                   [--check-runs turning|all|off]

Exit status: 0 done; 2 the input cannot be used (the message names the file, line, key or
value; nothing was written); 1 anything else (one line, never a traceback; set
``MACHINESIM_TRACEBACK=1`` to see it); 130 interrupted (nothing was written, or the line names
the files written whole before the stop; a campaign keeps its finished trials, says so, and
resumes when run again). Heavy modules are imported inside `main`, so that even an interrupt
while they load ends cleanly.
"""

from __future__ import annotations

import machinesim._cli_start as _cli_start  # first: a Ctrl-C while the rest loads is one line

import argparse
import math
import os
import sys
import time
from pathlib import Path

from machinesim._arguments import ArgumentParser
from machinesim._interrupts import ctrl_c_remembered, stopped, written_before
from machinesim._io import (
    check_readable_file,
    check_writable,
    file_name,
    input_path,
    named,
    stdout_to_null,
    write_together,
)
from machinesim._json import json_text
from machinesim._log_lines import LOG_AFTER_S, LOG_EVERY_S, log_lines
from machinesim._memory import OUT_OF_MEMORY, memory_capped
from machinesim._program_options import (
    add_reading_options,
    after_end_note,
    check_reading_options,
    chord_note,
    end_note,
    integer_note,
    read_for_machine,
    unit_note,
    work_offset_notes,
)
from machinesim.exceptions import (
    AxisLimitError,
    HolderContactError,
    InputError,
    MachineSimError,
    printable,
    say,
    warnings_as_lines,
)
from machinesim.report import check_units
from machinesim.units import typed_float

EXAMPLES = """examples (from the repository's folder):
  machinesim machines
  machinesim cut models/examples/grooves.nc --machine grooving_4axis --tool v:90 \\
      --stock block:10x10x2 --errors models/errors/example.toml --out part.ply \\
      --report report.json
  machinesim cut models/examples/grooves.nc --machine grooving_4axis --tool v:90 \\
      --stock block:10x10x2 --out window.ply --roi 4,5,1,3
"""

#: Part file formats by suffix: (format, what the CLI says about the file).
PART_FORMATS = {
    ".ply": ("ply", "PLY, float64 metres: exact"),
    ".stl": ("stl", "binary STL, millimetres, float32: display only"),
    ".glb": ("glb", "binary glTF, millimetres, float32: display only"),
}
#: Exit status when the input cannot be used.
EXIT_INPUT = 2


def _parser() -> argparse.ArgumentParser:
    from machinesim.viewer.cli import add_view_parser

    parser = ArgumentParser(
        prog="machinesim", description="A virtual multi-axis ultraprecision machine tool.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EXAMPLES)
    from machinesim import __version__

    parser.add_argument("--version", action="version", version=f"machinesim {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("machines", help="list the shipped machines with their axes and travel",
                   description="List the shipped machines with their axes and travel.")
    cut = sub.add_parser(
        "cut", help="cut an NC program on a machine with errors",
        description="Run an NC program on a machine (with injected errors) and write the "
                    "machined part, and its report, together or not at all.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EXAMPLES)
    cut.add_argument("program", type=input_path,
                     help="FANUC-style NC program (mm, deg), e.g. grooves.nc")
    cut.add_argument("--machine", type=named, required=True,
                     help="machine name (see 'machinesim machines') or a .urdf path, "
                          "e.g. robonano_a0ib")
    cut.add_argument("--tool", required=True,
                     help="tool spec in mm/deg: v:ANGLE (V tool, e.g. v:90), "
                          "nose:RADIUS:ANGLE (round nose, e.g. nose:2.0:90), "
                          "ball:RADIUS (ball end mill, e.g. ball:2.0), flat:RADIUS (flat end "
                          "mill, e.g. flat:1.0 for 2 mm across); optionally :h=HEIGHT, "
                          "the height to the holder in mm (e.g. v:90:h=5, default 10); for "
                          "ball and flat also :d=DIAMETER, the shank's diameter above it in "
                          "mm, for the holder check (e.g. flat:0.5:h=3:d=4, default: as wide "
                          "as the tool)")
    cut.add_argument("--stock", required=True,
                     help="stock spec in mm: block:LxWxH (e.g. block:10x10x2, top face at "
                          "z = 0), cylinder:RxH (e.g. cylinder:5x2), spheres:LxWxH:R[:dimples] "
                          "(paper 002's three reference spheres on a block, e.g. "
                          "spheres:30x30x5:2) or crown[:OVERSIZE] (paper 002's rough crown), "
                          "optionally placed with @x,y,z (e.g. block:10x10x2@-5,-5,0)")
    cut.add_argument("--errors", type=input_path, default=None,
                     help="injected errors, TOML with units in every key "
                          "(e.g. models/errors/example.toml); default: none")
    cut.add_argument("--servo", type=input_path, default=None, metavar="SERVO.toml",
                     help="the axes' servo loops, one table per axis letter, SI with the unit "
                          "in every key (docs/cli.md); the report gives each axis' largest "
                          "following error")
    cut.add_argument("--out", type=file_name, required=True,
                     help="where to write the part: .ply (float64, metres: exact) or "
                          ".stl/.glb (float32, millimetres: display only)")
    cut.add_argument("--report", type=file_name, default=None,
                     help="where to write the cut report as JSON (units in every key)")
    cut.add_argument("--roi", action="append", default=None, metavar="X0,X1,Y0,Y1",
                     help="cut only in this window (mm, workpiece frame); repeatable; "
                          "e.g. --roi 0,1,0,1")
    add_reading_options(cut)
    cut.add_argument("--allow-overtravel", action="store_true",
                     help="cut even where an axis leaves its travel (listed in the report); "
                          "default: refuse the program and write nothing")
    cut.add_argument("--allow-holder-contact", action="store_true",
                     help="cut even where a move takes the tool deeper than its body (the "
                          "holder would hit the part): the body alone cuts, the lines are "
                          "listed; default: refuse the program and write nothing")
    cut.add_argument("--check-runs", choices=("turning", "all", "off"), default=None,
                     help="which runs of sweeps have their subtraction checked for material "
                          "the boolean kernel left inside them, and cut again one sweep at "
                          "a time where there is: those that turn the tool (default), all "
                          "(plain milling takes 16-26 %% longer) or none (docs/cutting.md)")
    cut.add_argument("--quiet", action="store_true",
                     help="no progress (a bar on a terminal, lines in a log past 10 s)")
    add_view_parser(sub)
    from machinesim.campaign.cli import add_campaign_parser

    add_campaign_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); return the exit status.

    Usage errors and ``--help`` leave through argparse's ``SystemExit`` (status 2 and 0).
    """
    _cli_start.loaded()  # Python's handler again: ctrl_c_remembered puts its own in its place
    args = None
    _closed_streams_to_null()
    try:
        with ctrl_c_remembered(), warnings_as_lines():
            args = _parser().parse_args(None if argv is None else [str(a) for a in argv])
            # past the memory there is: MemoryError, not the OOM killer (not for a viewer,
            # which may start a browser: Chromium does not start under such a cap)
            with memory_capped(args.command != "view"):
                return _command(args)
    except MachineSimError as exc:
        return _fail(f"error: {exc}", EXIT_INPUT)
    except KeyboardInterrupt as stop:  # Ctrl-C, or SIGTERM (`machinesim._interrupts.Terminated`)
        how, status = stopped(stop)
        return _fail(f"{how}; {_interrupted(args, stop)}", status)
    except BrokenPipeError:
        # the reader of our output went away (``machinesim machines | head -1``): not an error
        stdout_to_null(sys.stdout)
        return 0
    except OSError as exc:
        where = f"{exc.filename}: " if exc.filename else ""
        return _fail(f"error: {where}{exc.strerror or exc}", EXIT_INPUT)
    except MemoryError:
        kept = ""
        if args is not None and args.command == "campaign":
            # a trial ran out of memory (a29dff5: no record, so that it runs again): what
            # was kept, as after a Ctrl-C
            from machinesim.campaign.cli import interrupted

            kept = f"; {interrupted(args.out)}"
        return _fail(f"error: out of memory: {OUT_OF_MEMORY}{kept}", 1)
    except Exception as exc:
        if os.environ.get("MACHINESIM_TRACEBACK"):
            raise
        return _fail(f"internal error: {type(exc).__name__}: {exc} (a bug in machinesim: "
                     "please report it; MACHINESIM_TRACEBACK=1 shows where)", 1)
    finally:
        _cli_start.finished()  # done and said: a stop as the interpreter ends is ignored


def _closed_streams_to_null() -> None:
    """Give a standard stream the process was started without (``2>&-``, a daemon's closed
    descriptor: Python then sets ``sys.stderr`` to None) the null device, so that what would
    be said there is dropped: a cut started so had ended at its first progress or note in
    "internal error: AttributeError: 'NoneType' object has no attribute 'isatty'", exit 1,
    nothing written."""
    for name in ("stdout", "stderr"):
        if getattr(sys, name) is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))


def _command(args: argparse.Namespace) -> int:
    if args.command == "machines":
        return _machines()
    if args.command == "view":
        from machinesim.viewer.cli import run_view

        return run_view(args)
    if args.command == "campaign":
        from machinesim.campaign.cli import run_campaign

        return run_campaign(args)
    return _cut(args)


def _interrupted(args, stop: KeyboardInterrupt) -> str:
    """What a command stopped by Ctrl-C leaves: nothing, or the files it had written whole
    before (a cut's part and report when the stop came as they were renamed in, a page
    whose screenshot was being taken: `machinesim._interrupts.written_before`), but for a
    campaign its finished trials (kept so that the same command resumes)."""
    if args is not None and args.command == "campaign":
        from machinesim.campaign.cli import interrupted

        return interrupted(args.out)
    return written_before(stop)


def _fail(message: str, status: int) -> int:
    say("machinesim", message)
    return status


def _machines() -> int:
    from machinesim.machines import machines_summary

    print("\n".join(machines_summary()))
    return 0


def parse_roi(texts) -> list[tuple[float, float, float, float]] | None:
    """``--roi`` texts (mm) as windows (xmin, xmax, ymin, ymax) in m, or None for none.

    Raises
    ------
    InputError
        Naming the text when it is not four finite numbers with X0 < X1 and Y0 < Y1.
    """
    if not texts:
        return None
    windows = []
    for text in texts:
        try:
            values = [typed_float(v) * 1e-3 for v in str(text).split(",")]
        except ValueError:
            values = []
        if (len(values) != 4 or not all(math.isfinite(v) for v in values)
                or values[0] >= values[1] or values[2] >= values[3]):
            raise InputError(f"--roi {text!r}: expected X0,X1,Y0,Y1 in mm, four finite numbers "
                             "with X0 < X1 and Y0 < Y1, e.g. 0,1,0,1")
        windows.append(tuple(values))
    return windows


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # either does not exist (yet)
        return False


#: Without a terminal (a log, a pipe) a long cut says how far it is: a first line after this
#: many seconds (short cuts say nothing), then at most one every `LOG_PROGRESS_EVERY_S`.
LOG_PROGRESS_AFTER_S = LOG_AFTER_S
LOG_PROGRESS_EVERY_S = LOG_EVERY_S


def _progress_bar(quiet: bool, clock=time.monotonic):
    if quiet:
        return None
    if not sys.stderr.isatty():
        return _progress_lines(clock)

    def show(done: int, total: int, stage: str = "cutting") -> None:
        width = 40
        filled = width * done // max(total, 1)
        sys.stderr.write(f"\r  {stage} [{'#' * filled}{'.' * (width - filled)}] "
                         f"{done}/{total} sweeps")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def _progress_lines(clock):
    """Progress as whole lines for a log (`machinesim._log_lines.log_lines`), each naming the
    engine's stage ("building" its sweeps, then "cutting")."""
    return log_lines("cutting", "sweeps", clock, LOG_PROGRESS_AFTER_S, LOG_PROGRESS_EVERY_S)


def _reading_notes(args, program, chord: float, machine, errors) -> list[str]:
    """What the command line chose in reading the program that the user should know: arcs,
    rotary moves and moves that ``errors`` bend split coarser than 1 nm by default, work
    offsets it was not given, the unit of a program that selects none, a program that ends
    without M02/M30."""
    notes = [note for note in (chord_note(args, program, chord, machine, errors),) if note]
    notes += work_offset_notes(program)
    notes += [note for note in (unit_note(program), integer_note(program), end_note(program),
                                after_end_note(program))
              if note]
    return notes


def _cut(args) -> int:
    """``machinesim cut``: every input checked before cutting, both outputs written together.

    The checks that cost nothing come first (file names, folders, options), so that a
    mistake there is reported at once instead of after the cut; the part and the report are
    then encoded in memory and written together (`machinesim._io.write_together`).
    """
    suffix = args.out.suffix.lower()
    if suffix not in PART_FORMATS:
        raise InputError(f"--out {args.out}: expected a file name ending in .ply, .stl or .glb")
    file_format, description = PART_FORMATS[suffix]
    check_readable_file(args.program, "NC program")
    if args.errors is not None:
        check_readable_file(args.errors, "error model (--errors)")
    if args.servo is not None:
        check_readable_file(args.servo, "servo loops (--servo)")
    check_reading_options(args)
    outputs = [(args.out, "part (--out)")]
    if args.report is not None:
        outputs.append((args.report, "report (--report)"))
        if os.path.abspath(args.report) == os.path.abspath(args.out):
            raise InputError("--out and --report name the same file; give two file names",
                             source=str(args.out))
    inputs = [p for p in (args.program, args.errors, args.servo, args.tools,
                          Path(args.machine)) if p]
    for path, what in outputs:
        check_writable(path, what)
        if any(_same_file(path, source) for source in inputs):
            raise InputError(f"the {what} would overwrite an input file; give another name",
                             source=str(path))
    roi = parse_roi(args.roi)

    from machinesim.cutting import cut
    from machinesim.cutting.breakthrough import bottom_lost
    from machinesim.cutting.engine import EMPTY_SWEPT_REL
    from machinesim.cutting.report import NO_MOVES, NOTHING_LEFT
    from machinesim.cutting.roi import check_roi_meets
    from machinesim.cutting.windows import clip_to
    from machinesim.errors import ErrorModel
    from machinesim.machines import load_machine
    from machinesim.tool_specs import tool_from_spec
    from machinesim.workpiece import EXPORT_UNITS, stock_from_spec

    machine = load_machine(args.machine)
    tool = tool_from_spec(args.tool, name="--tool")
    stock = stock_from_spec(args.stock, name="--stock")
    # before reading the program; cut() would refuse such windows only after it
    check_roi_meets(roi, stock, given=" ".join(f"--roi {text}" for text in args.roi or ()),
                    unit="mm")
    program, chord = read_for_machine(args, args.program, machine, tool)
    errors = ErrorModel.from_toml(args.errors) if args.errors else None
    machine.check_errors(errors)  # a misfit names the user's file first, then the machine
    servo = None
    if args.servo is not None:
        from machinesim.servo import servo_from_toml

        servo = servo_from_toml(args.servo, machine)
    # a flag passed only when given, so that without it the cutter's default (refuse) holds
    options = {name: True for name in ("allow_overtravel", "allow_holder_contact")
               if getattr(args, name)}
    if args.check_runs is not None:
        options["check_runs"] = args.check_runs
    try:
        part, report = cut(program, machine, tool=tool, stock=stock, errors=errors, roi=roi,
                           start=machine.home, chord_tolerance=chord, servo=servo,
                           progress=_progress_bar(args.quiet), **options)
    except (AxisLimitError, HolderContactError) as error:
        # a program posted for IS-B read in mm leaves the travel, or goes 1000 times too deep:
        # the refusal then says how its numbers were read, as a cut's notes would
        hint = integer_note(program)
        if hint is None:
            raise
        raise type(error)(f"{error}; {hint}") from None
    summary = report.to_dict()
    summary["path_chord_tolerance_nm"] = chord * 1e9
    # the cut's notes hold those on --errors (unit slips, idle location errors: cut()'s own)
    summary["notes"] = [*summary["notes"], *_reading_notes(args, program, chord, machine,
                                                                errors)]
    if servo is not None and all(axis is None for axis in servo.axes):  # no [X] .. table
        summary["notes"].append(f"{args.servo} sets no servo loop (no axis table): every axis "
                                "followed its command exactly, a following error of 0")
    summary["part_file"] = str(args.out)
    summary["part_unit"] = EXPORT_UNITS[file_format]
    pieces, apart = _pieces(part, stock, roi)
    summary["part_pieces_count"] = len(pieces)
    through = bottom_lost(part, stock if roi is None else clip_to(stock, roi))
    summary["bottom_cut_through_mm2"] = through * 1e6
    files = [(args.out, part.encode(file_format))]
    if args.report is not None:
        check_units(summary)  # units in every key, as --report promises
        files.append((args.report, json_text(summary, "cut report")))
    write_together(files)
    print(f"wrote {args.out} ({description}): removed {summary['removed_volume_mm3']:.6g} mm^3 "
          f"in {report.sweeps} sweeps ({report.engine}); "
          f"machining time {report.machining_time_s:.1f} s")
    for entry in summary["tools"] if len(summary["tools"]) > 1 else ():
        name = ("--tool before the first change" if entry["tool"] is None
                else f"T{entry['tool']} from line {entry['line']}")
        # a run that removed nothing (it retraced an earlier tool's cut) integrates to the
        # booleans' round-off, not 0: '2.01832e-13 mm^3' had read as material removed
        volume = entry["removed_volume_mm3"]
        removed = (f"{volume:.6g} mm^3" if not entry["empty_cut"] else "nothing" if volume == 0
                   else f"nothing ({volume:.3g} mm^3 of round-off: at most "
                        f"{EMPTY_SWEPT_REL:.0e} of the volume its sweeps went through)")
        print(f"  {name}: length {entry['length_mm']:.6g} mm, removed {removed}")
    if report.peak_following_error:
        lags = ", ".join(
            f"{axis} {value * 1e6:.4f} {'urad' if rotary else 'um'}"
            for (axis, value), rotary in zip(report.peak_following_error.items(),
                                             machine.rotary, strict=True))
        print(f"  largest following error: {lags}")
    if args.report is not None:
        print(f"wrote {args.report} (cut report, JSON, units in every key)")
    # nothing of the stock left is cut()'s note (`nothing_left_note`), said as a warning
    left = [note for note in summary["notes"] if note.startswith(NOTHING_LEFT)]
    # and the program's having no moves (`no_moves_note`), once, as a warning
    still = [note for note in summary["notes"] if note.startswith(NO_MOVES)]
    for note in summary["notes"]:  # a note may quote a file's name: escaped, as in errors
        if note not in left and note not in still:
            print(f"note: {printable(note)}", file=sys.stderr)
    _warn_each(program, report.holder_contact, "holder touched the part at {}",
               "holder_contact_lines")
    _warn_each(program, report.rapids_that_cut, "rapid cut the part at {}",
               "rapids_that_cut_lines")
    _warn_each(program, report.sideways_lines, "tool dragged sideways at {} (a "
               "non-rotational tool cuts along its own X only; the part there is not what a "
               "real tool would leave)", "sideways_lines")
    for item in report.limit_violations:
        print(f"warning: outside travel: {item}", file=sys.stderr)
    if apart:
        volumes = ", ".join(f"{v * 1e9:.6g}" for v in pieces[:5]) + (
            " ..." if len(pieces) > 5 else "")
        material = "the stock in the --roi window" if roi else "the stock"
        was = "was one" if apart == 1 else f"had {apart}"
        print(f"warning: the part is in {len(pieces)} separate pieces ({volumes} mm^3), where "
              f"{material} {was}: a cut went through it (deeper than the stock, or round a "
              f"piece); {printable(args.out)} holds them all", file=sys.stderr)
    for note in left:  # a tool wider than the part, or a through cut over all of it
        print(f"warning: {note}; {printable(args.out)} holds none", file=sys.stderr)
    if through:
        print(f"warning: the cut went through the bottom of the stock (z = "
              f"{stock.bounds[0, 2] * 1e3:.6g} mm; {through * 1e6:.6g} mm^2 of its bottom face "
              "is gone): the tool reached the stock's bottom face or went below it, into what "
              "holds it (table, chuck or fixture, not modelled), as a wrong tool length or Z "
              "takes it on a machine; a through cut that is meant needs the stock on a "
              "sacrificial plate or over a relief in the fixture", file=sys.stderr)
    if report.empty_cut and report.edge_plane_lines:
        lines = ", ".join(map(str, report.edge_plane_lines[:5])) + (
            " ..." if len(report.edge_plane_lines) > 5 else "")
        print(f"warning: the program removed no material: its feeds into the stock (line "
              f"{lines}) move the tool within its edge plane (a plunge), where a V or nose "
              "tool's zero-thickness edge sweeps no volume; it cuts by moving along its own X",
              file=sys.stderr)
    elif still:  # dwells alone too
        print(f"warning: {printable(still[0])}", file=sys.stderr)
    elif report.empty_cut:
        where = "the stock in the --roi windows" if roi else "the stock"
        print(f"warning: the program removed no material (does it reach {where}?)",
              file=sys.stderr)
    return 0


#: Warning lines of one kind printed at most (a line each); past it one line counts the
#: rest, which the report lists: a V tool engraving a 10,000-block spiral had printed
#: 9,873 lines of "tool dragged sideways".
MOST_WARNING_LINES = 20


def _warn_each(program, lines, text: str, key: str) -> None:
    """One warning line on stderr per program line in ``lines`` (``text`` formatted with
    it as ``line 12 (N120)``, `Program.line_text`), the first `MOST_WARNING_LINES`, then
    one line saying how many more and where the report (``key``) lists them all."""
    for line in lines[:MOST_WARNING_LINES]:
        print(f"warning: {text.format(program.line_text(line))}", file=sys.stderr)
    if len(lines) > MOST_WARNING_LINES:
        more = len(lines) - MOST_WARNING_LINES
        print(f"warning: ... and {more} more lines as these (lines {lines[MOST_WARNING_LINES]}"
              f" to {lines[-1]}; the report, --report, lists every one as {key})",
              file=sys.stderr)


def _pieces(part, stock, roi) -> tuple[list[float], int]:
    """The volumes (m^3, largest first) of the part's separate pieces, and the number the
    material it was cut from had (the stock, or the stock in the ``roi`` windows) when the
    part has more, else 0: a groove across the block deeper than the stock cuts it in two,
    which the part file holds without a word."""
    from machinesim.cutting.windows import clip_to

    volumes = sorted((p.volume() for p in part.manifold.decompose()), reverse=True)
    if len(volumes) <= 1:
        return volumes, 0
    material = stock if roi is None else clip_to(stock, roi)
    before = len(material.manifold.decompose())
    return volumes, (before if len(volumes) > before else 0)


if __name__ == "__main__":
    sys.exit(main())
