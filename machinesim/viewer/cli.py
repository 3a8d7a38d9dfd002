"""The ``machinesim view`` subcommand: a machine, a part or a report folder in the browser.

    machinesim view MACHINE [--program P.nc --tool SPEC --stock SPEC --errors E.toml
                            --tools T.toml --integer-input RULE --chord-nm NM]
    machinesim view PART.ply [--report REPORT.json] [--nominal NOMINAL.ply]
    machinesim view REPORT_DIR
    ... [--html FILE.html] [--screenshot FILE.png] [--port PORT] [--max-triangles N]

Without ``--html`` a live meshcat server starts on 127.0.0.1 and its URL is printed; it runs
until Ctrl-C. Heavy modules are imported only when the command runs.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time
from pathlib import Path

from machinesim._arguments import typed_number
from machinesim._interrupts import stopped
from machinesim._io import (
    check_readable_file,
    check_writable,
    file_name,
    input_path,
    named,
)
from machinesim._json import read_json
from machinesim._log_lines import LOG_AFTER_S, LOG_EVERY_S, log_lines
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
from machinesim.exceptions import InputError, printable

#: Ports browsers refuse to load a page from: the Fetch standard's "bad ports" (Chromium shows
#: ERR_UNSAFE_PORT for all but 4190 and 6679). A live viewer there serves a page no browser
#: opens, and its --screenshot failed with "the page raised: Uncaught".
BAD_PORTS = frozenset({
    1, 7, 9, 11, 13, 15, 17, 19, 20, 21, 22, 23, 25, 37, 42, 43, 53, 69, 77, 79, 87, 95, 101,
    102, 103, 104, 109, 110, 111, 113, 115, 117, 119, 123, 135, 137, 139, 143, 161, 179, 389,
    427, 465, 512, 513, 514, 515, 526, 530, 531, 532, 540, 548, 554, 556, 563, 587, 601, 636,
    989, 990, 993, 995, 1719, 1720, 1723, 2049, 3659, 4045, 4190, 5060, 5061, 6000, 6566,
    6665, 6666, 6667, 6668, 6669, 6679, 6697, 10080})

#: About how many characters of an exported page's script a triangle takes (docs/viewer.md):
#: --max-triangles takes at most `machinesim.viewer.scene.SCRIPT_CHARS_MOST` over it, as a
#: mesh of more fits in no page.
CHARS_PER_TRIANGLE = 30
#: What a program is cut with and animated over when --tool, --stock, --duration are not given.
DEFAULT_TOOL, DEFAULT_STOCK, DEFAULT_DURATION_S = "v:90", "block:10x10x2", 20.0

EXAMPLES = """examples (from the repository's folder):
  machinesim view robonano_a0ib
  machinesim view grooving_4axis --program models/examples/grooves.nc --tool v:90 \\
      --stock block:10x10x2 --errors models/errors/example.toml --html grooves.html
  machinesim view part.ply --report report.json --nominal nominal.ply
  machinesim view reports/workpiece_setting/ --html report.html   # after make demo
"""


def add_view_parser(sub) -> argparse.ArgumentParser:
    """Add the ``view`` subcommand to ``sub`` (argparse subparsers) and return its parser."""
    view = sub.add_parser(
        "view", help="show a machine, a part or a report folder in the browser",
        description="Show a machine (animated along a program), a machined part coloured by "
                    "its deviation or height, or a scenario report folder, live in the "
                    "browser (a meshcat server on 127.0.0.1) or as one self-contained HTML "
                    "file.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EXAMPLES)
    view.add_argument("target", type=named,
                      help="a machine name (see 'machinesim machines') or .urdf path, a part "
                           ".ply, or a report folder (*.ply and summary.json)")
    view.add_argument("--html", type=file_name, default=None,
                      help="write one self-contained HTML file (no server, no network) "
                           "instead of serving live")
    view.add_argument("--screenshot", type=file_name, default=None,
                      help="also render the view to this PNG with headless Chromium")
    view.add_argument("--port", type=int, default=None,
                      help="live mode: web port on 127.0.0.1 (default: first free from 7000)")
    view.add_argument("--max-triangles", type=int, default=None, metavar="N",
                      help="display budget per mesh; larger parts are decimated for display "
                           "only (default 200000)")
    part = view.add_argument_group("a part (PART.ply)")
    part.add_argument("--report", type=input_path, default=None,
                      help="cut report JSON (from 'machinesim cut --report') shown beside it")
    part.add_argument("--nominal", type=input_path, default=None,
                      help="nominal part .ply: colour by deviation from it (else by height)")
    machine = view.add_argument_group("a machine (MACHINE)")
    machine.add_argument("--program", type=input_path, default=None,
                         help="NC program to run and animate (mm, deg), e.g. grooves.nc")
    machine.add_argument("--tool", default=None,
                         help="tool spec in mm/deg: v:ANGLE, nose:RADIUS:ANGLE, ball:RADIUS, "
                              "flat:RADIUS (default v:90)")
    machine.add_argument("--stock", default=None,
                         help="stock spec in mm, e.g. block:10x10x2@-5,-5,0 (default "
                              "block:10x10x2)")
    machine.add_argument("--errors", type=input_path, default=None,
                         help="injected errors, TOML (default: none)")
    add_reading_options(machine)
    machine.add_argument("--duration", type=typed_number, default=None,
                         help="longest animation, s: a longer program plays faster "
                              "(default 20)")
    return view


def run_view(args: argparse.Namespace) -> int:
    """Run ``machinesim view`` with parsed ``args``; return the exit code.

    Raises
    ------
    MachineSimError
        For input the command cannot show (the caller prints it).
    """
    from machinesim.viewer.meshes import DISPLAY_TRIANGLES
    from machinesim.viewer.scene import SCRIPT_CHARS_MOST

    budget = DISPLAY_TRIANGLES if args.max_triangles is None else args.max_triangles
    most = SCRIPT_CHARS_MOST // CHARS_PER_TRIANGLE
    if not 1 <= budget <= most:
        # 1e9 ended in the height map's 'Expected at most 1e+08 samples in one reading
        # (MAX_SAMPLES) ...: take fewer x or y samples', 1e20 in 'out of memory: ... a cut of
        # many sweeps', neither naming the option
        raise InputError(f"--max-triangles {budget}: expected a count from 1 to "
                         f"{most:,} (a page holds about {CHARS_PER_TRIANGLE} "
                         "characters a triangle, and a browser's JavaScript engine reads at "
                         f"most {SCRIPT_CHARS_MOST:,}: more opens blank)")
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0.0):
        raise InputError(f"--duration {args.duration}: expected a positive number of seconds")
    if args.port is not None and args.html is not None:
        # an exported page starts no server: --port 7005 (or the bad port 6000) beside --html
        # had been taken and ignored, the command exiting 0
        raise InputError(f"--port {args.port} is the live server's, and --html writes a page "
                         "that needs none: give one or the other")
    if args.port is not None and not 0 < args.port < 65536:
        raise InputError(f"--port {args.port}: expected a TCP port, 1 .. 65535")
    if args.port in BAD_PORTS:
        raise InputError(f"--port {args.port}: browsers refuse to open pages on this port (a "
                         "'bad port' of the Fetch standard; Chromium: ERR_UNSAFE_PORT); "
                         "expected another, e.g. 7000")
    if args.html is not None and args.html.suffix.lower() not in (".html", ".htm"):
        raise InputError(f"--html {args.html}: expected a file name ending in .html")
    if args.screenshot is not None and args.screenshot.suffix.lower() != ".png":
        raise InputError(f"--screenshot {args.screenshot}: expected a file name ending in .png")
    for path, what in ((args.html, "page (--html)"), (args.screenshot, "image (--screenshot)")):
        if path is not None:
            check_writable(path, what)
    scene = _scene(args, budget)
    for line in scene.warnings:  # a warning may quote a file's name: escaped, as in errors
        print(f"warning: {printable(line)}", file=sys.stderr)
    if args.html is not None:
        from machinesim.viewer.scene import write_html

        write_html(scene, args.html)
        print(f"wrote {args.html} ({args.html.stat().st_size / 1e6:.1f} MB, self-contained: "
              "open it in any browser, no server needed)")
        if args.screenshot is not None:
            _screenshot(args.html.resolve().as_uri(), "true", args.screenshot)
            print(f"wrote {args.screenshot} (headless Chromium)")
        return 0
    from machinesim.viewer.live import serve

    session = serve(scene, args.port)
    shot = None  # the --screenshot PNG once written
    try:
        print(f"machinesim viewer at {session.url} (listening on 127.0.0.1 only); "
              "Ctrl-C to stop", flush=True)
        if args.screenshot is not None:
            _screenshot(session.url, f"viewer.num_messages_received >= {session.messages}",
                        args.screenshot)
            shot = args.screenshot  # before the line saying so: a Ctrl-C on reading it
            print(f"wrote {shot} (headless Chromium)", flush=True)  # keeps the PNG named
        ended = session.wait()
        if ended is None:  # Ctrl-C, which ended the server: exit 130 (it had been 0)
            raise KeyboardInterrupt
    except KeyboardInterrupt as stop:  # SIGTERM too (`Terminated`): 143
        if shot is None:
            raise  # 'machinesim: interrupted; nothing was written' (or what was)
        how, status = stopped(stop)
        print(f"machinesim: {how}; the viewer stopped, its screenshot {shot} written before",
              file=sys.stderr)
        return status
    finally:
        session.close()
    # the server ended though nobody stopped it (it crashed, or was killed): the page no
    # longer answers, and the command had exited 0 without a word; its stderr's last line
    # (a crash's exception; anything a server killed by a signal said last, which had been
    # lost) is told, the lines kept before it with MACHINESIM_TRACEBACK=1
    kept = "" if shot is None else f"; its screenshot {shot} written before"
    said = _exit_text(ended)
    if session.stderr is not None:
        if os.environ.get("MACHINESIM_TRACEBACK"):
            for line in session.stderr.lines():
                print(line, file=sys.stderr)
        last = session.stderr.last(any_line=ended < 0)
        said += f"; its last line on stderr: {last}" if last else ""
    print(f"machinesim: error: the live viewer server ended without Ctrl-C "
          f"({said}); {session.url} no longer answers{kept}", file=sys.stderr)
    return 1


def _exit_text(code: int) -> str:
    """A process's exit code (`subprocess.Popen.returncode`) in words: ``exit status 3``,
    or ``killed by SIGKILL`` for -9 (a signal ended it)."""
    if code >= 0:
        return f"exit status {code}"
    try:
        return f"killed by {signal.Signals(-code).name}"
    except ValueError:  # no signal Python names
        return f"killed by signal {-code}"


def _scene(args, budget: int):
    target = Path(args.target)
    machine_options = [f"--{name.replace('_', '-')}" for name in
                       ("program", "errors", "tool", "stock", "tools", "integer_input",
                        "chord_nm", "duration")
                       if getattr(args, name) is not None]
    part_options = [f"--{name}" for name in ("report", "nominal")
                    if getattr(args, name) is not None]
    if target.is_dir():
        from machinesim.viewer.views import report_scene

        _refuse(machine_options + part_options, "a report folder")
        if (target / "summary.json").exists():
            read_json(target / "summary.json", "report summary")
        return report_scene(target, budget)
    if target.suffix.lower() in (".stl", ".glb", ".obj", ".off", ".3mf"):
        raise InputError(f"{target}: the viewer reads parts as float64 PLY (machinesim cut "
                         f"--out part.ply), not {target.suffix}: the STL and GLB exports are "
                         "float32 millimetres, for CAD tools")
    if target.suffix.lower() == ".ply":
        from machinesim.viewer.views import part_scene

        _refuse(machine_options, "a part")
        if not target.exists():
            raise InputError(f"{target}: no such part file")
        check_readable_file(target, "part (PLY)")
        if args.nominal is not None:
            check_readable_file(args.nominal, "nominal part (--nominal)")
        report = None if args.report is None else read_json(args.report, "cut report (--report)")
        if report is not None and not isinstance(report, dict):
            raise InputError(f"expected a JSON object (a cut report), got a "
                             f"{type(report).__name__}", source=str(args.report))
        scene = part_scene(target, nominal=args.nominal, report=report,
                           title=f"part {target.name}", max_triangles=budget)
        scene.warnings += _report_mismatch(report, target, args.report)
        return scene
    from machinesim.machines import list_machines, load_machine
    from machinesim.viewer.machine import machine_scene

    if (not target.exists() and target.suffix.lower() != ".urdf"
            and ("/" in args.target or os.sep in args.target)):
        # a path is no machine name: `view reports/x/` before the scenario wrote it said
        # 'unknown machine'
        raise InputError(f"{args.target}: no such file or folder; expected a machine name "
                         "(see 'machinesim machines'), a machine's .urdf, a part .ply or a "
                         "report folder")
    if (target.is_file() and target.suffix.lower() != ".urdf"
            and args.target not in list_machines()):
        # an existing file is no machine name: say what a file may be, not 'unknown machine'
        raise InputError(f"{target}: expected a part file ending in .ply, a machine's .urdf "
                         "or a report folder (see 'machinesim view --help'); the viewer goes "
                         "by the name's ending")

    _refuse(part_options, "a machine")
    # without a program nothing is cut or animated: --tool, --stock and --duration had been
    # taken and ignored, the page showing the machine alone and the command exiting 0
    if args.program is None:
        cutting = [f"--{name}" for name in ("tool", "stock", "duration")
                   if getattr(args, name) is not None]
        reading = [f"--{name.replace('_', '-')}" for name in
                   ("tools", "integer_input", "chord_nm") if getattr(args, name) is not None]
        if reading:
            raise InputError(f"{', '.join(reading)} read a program: give one with --program")
        if cutting:
            raise InputError(f"{', '.join(cutting)} {'are' if len(cutting) > 1 else 'is'} "
                             "for the program the machine runs (the tool it cuts with, the "
                             "stock, the animation's length): give one with --program")
    check_reading_options(args)
    machine = load_machine(args.target)
    from machinesim.tool_specs import tool_from_spec
    from machinesim.workpiece import stock_from_spec

    tool = tool_from_spec(DEFAULT_TOOL if args.tool is None else args.tool, name="--tool")
    stock = stock_from_spec(DEFAULT_STOCK if args.stock is None else args.stock, name="--stock")
    program = errors = chord = None
    if args.program is not None:
        # read as `machinesim cut` reads it: the same tool table, integer input and chords
        program, chord = read_for_machine(
            args, check_readable_file(args.program, "NC program (--program)"), machine, tool)
        _refuse_tool_changes(program, tool)
        from machinesim.cutting.tool_runs import tool_notes

        # cut's notes on the tools: T1 M06 .. T2 M06 read without a table (--tool cut every
        # move), a table radius --tool has not (a 2 mm D beside flat:1); view had said nothing
        for note in tool_notes(program, tool):
            print(f"note: {printable(note)}", file=sys.stderr)
        # the notes machinesim cut gives on how the text was read and split: arcs cut as
        # chords coarser than 1 nm by default, X10 read as 10 mm, a file without M30 (cut
        # short?), text after the closing %; view had given the unit's
        if args.errors is not None:  # read before the notes: the chords' note names
            # the axes its tables bend (a misfit is refused before the notes, as cut does)
            errors = _errors_for(args.errors, machine)
        for note in (chord_note(args, program, chord, machine, errors),
                     *work_offset_notes(program),
                     unit_note(program), integer_note(program), end_note(program),
                     after_end_note(program)):
            if note:
                print(f"note: {printable(note)}", file=sys.stderr)
    if args.errors is not None:
        from machinesim.errors.notes import error_file_notes

        if errors is None:
            errors = _errors_for(args.errors, machine)
        if not errors.written:  # an empty file, or sections without keys: cut's note (view
            # had said nothing on the command line, the page's tool-path line alone telling)
            print(f"note: {printable(str(args.errors))} sets no error (no key in any section): "
                  "viewed on the machine as built, every error zero", file=sys.stderr)
        # the notes a cut's report holds on the file (cut's list, from machinesim cut's start):
        # values perhaps written in other units than their keys ask (a table far beyond any
        # machine's errors, ...), and with a program, location errors it never shows; view
        # had given none, animating such a file without a word
        for note in error_file_notes(errors, machine, program, machine.home, done=None):
            print(f"note: {printable(note)}", file=sys.stderr)
    return machine_scene(machine, program, tool=tool, stock=stock,
                         errors=errors, max_triangles=budget,
                         duration_s=DEFAULT_DURATION_S if args.duration is None else args.duration,
                         chord_tolerance=chord, progress=cut_lines())


def _errors_for(path, machine):
    """The error model at ``path``, checked against ``machine`` (a misfit refused)."""
    from machinesim.errors import ErrorModel

    errors = ErrorModel.from_toml(path)
    machine.check_errors(errors)
    return errors


def cut_lines(clock=time.monotonic, after_s: float = LOG_AFTER_S, every_s: float = LOG_EVERY_S):
    """``progress(done, total)`` for a program's view, as lines on stderr: nothing for a
    view that cuts in less than ``after_s``, then a line at most every ``every_s`` and one at
    the end once any was written (`machinesim cut`'s rule for a log), e.g.
    ``  view: 12/61 cuts (19 %), 41 s``. A 100,000-line program's view had printed nothing
    for the 10 minutes it ran before it was stopped."""
    return log_lines("view", "cuts", clock, after_s, every_s)


def _report_mismatch(report, part: Path, path) -> list[str]:
    """Lines noting a cut report (``machinesim cut --report``) that describes another file
    than ``part``, or gives it in another unit than metres: a report of another cut, whose
    figures the page would show beside this part."""
    if report is None:
        return []
    lines = []
    named = report.get("part_file")
    if isinstance(named, str) and Path(named).name != part.name:
        lines.append(f"the report {path} describes the part file {named!r}, not {part.name}: "
                     "its figures may be of another cut")
    unit = report.get("part_unit")
    if isinstance(unit, str) and unit != "m":
        lines.append(f"the report {path} gives the part in {unit!r}; a PLY part is read in "
                     "metres")
    return lines


def _refuse_tool_changes(program, tool) -> None:
    """The animation cuts with one tool (--tool): refuse a program whose tool table changes
    the tool's shape or length, rather than show a part that tool would not cut. A table
    tool of the same shape as ``tool`` (``shape = "flat:1.0"`` beside ``--tool flat:1``)
    cuts the same part and is viewed: it had been refused as another shape."""
    from machinesim.nc.tooltable import table_tool

    for change in program.tool_changes:
        other = change.shape is not None and table_tool(change.shape) != tool
        if other or change.length_m != 0.0:
            what = (f"shape {change.shape}" if other
                    else f"length {change.length_m * 1e3:g} mm")
            raise InputError(
                f"T{change.number} at line {change.line} puts a tool of {what} in the "
                "spindle; the viewer animates one tool (--tool): cut the program with "
                "'machinesim cut --tools' and view the part (machinesim view PART.ply)",
                source=program.source, line=change.line)


def _refuse(options: list[str], what: str) -> None:
    if options:
        names = " and ".join([", ".join(options[:-1]), options[-1]] if len(options) > 1
                             else options)
        raise InputError(f"{names} {'do' if len(options) > 1 else 'does'} not apply to "
                         f"{what}; see 'machinesim view --help'")


def _screenshot(url: str, ready: str, path: Path) -> None:
    from machinesim._io import write_atomic
    from machinesim.viewer.browser import screenshot

    write_atomic(path, screenshot(url, ready))


__all__ = ["add_view_parser", "run_view"]
