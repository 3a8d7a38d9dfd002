"""The ``machinesim`` command line.

    machinesim machines
    machinesim view MACHINE | PART.ply | REPORT_DIR [--html FILE]
    machinesim cut PROGRAM --machine NAME --tool SPEC --stock SPEC [--errors ERRORS.toml]
                   --out PART.ply [--report REPORT.json] [--roi X0,X1,Y0,Y1 ...]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from machinesim._io import write_atomic
from machinesim.exceptions import InputError, MachineSimError
from machinesim.viewer.cli import add_view_parser, run_view

EXAMPLES = """examples:
  machinesim machines
  machinesim cut grooves.nc --machine grooving_4axis --tool v:90 --stock block:10x10x2 \\
      --errors models/errors/example.toml --out part.ply --report report.json
  machinesim cut prisms.nc --machine planer_4axis --tool v:90 --stock block:40x10x2@-20,-5,0 \\
      --out prisms.ply --roi 0,1,0,1 --roi 10,11,0,1
"""


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="machinesim", description="A virtual multi-axis ultraprecision machine tool.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EXAMPLES)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("machines", help="list the shipped machines with their axes and travel",
                   description="List the shipped machines with their axes and travel.")
    cut = sub.add_parser(
        "cut", help="cut an NC program on a machine with errors",
        description="Run an NC program on a machine (with injected errors) and write the "
                    "machined part as an exact float64 PLY.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EXAMPLES)
    cut.add_argument("program", type=Path,
                     help="FANUC-style NC program (mm, deg), e.g. grooves.nc")
    cut.add_argument("--machine", required=True,
                     help="machine name (see 'machinesim machines') or a .urdf path, "
                          "e.g. robonano_a0ib")
    cut.add_argument("--tool", required=True,
                     help="tool spec in mm/deg: v:ANGLE (V tool, e.g. v:90), "
                          "nose:RADIUS:ANGLE (round nose, e.g. nose:2.0:90), "
                          "ball:RADIUS (ball end mill, e.g. ball:2.0)")
    cut.add_argument("--stock", required=True,
                     help="stock spec in mm: block:LxWxH (e.g. block:10x10x2, top face at "
                          "z = 0) or cylinder:RxH (e.g. cylinder:5x2), optionally placed "
                          "with @x,y,z (e.g. block:10x10x2@-5,-5,0)")
    cut.add_argument("--errors", type=Path, default=None,
                     help="injected errors, TOML with units in every key "
                          "(e.g. models/errors/example.toml); default: none")
    cut.add_argument("--out", type=Path, required=True,
                     help="where to write the part: .ply (float64, exact) or .stl/.glb "
                          "(display only)")
    cut.add_argument("--report", type=Path, default=None,
                     help="where to write the cut report as JSON (units in every key)")
    cut.add_argument("--roi", action="append", default=None, metavar="X0,X1,Y0,Y1",
                     help="cut only in this window (mm, workpiece frame); repeatable; "
                          "e.g. --roi 0,1,0,1")
    cut.add_argument("--quiet", action="store_true", help="no progress bar")
    add_view_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "machines":
            return _machines()
        if args.command == "view":
            return run_view(args)
        return _cut(args)
    except MachineSimError as exc:
        print(f"machinesim: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("machinesim: interrupted; nothing was written", file=sys.stderr)
        return 130


def _machines() -> int:
    from machinesim.machines import machines_summary

    print("\n".join(machines_summary()))
    return 0


def _roi(texts):
    if not texts:
        return None
    windows = []
    for text in texts:
        try:
            values = [float(v) * 1e-3 for v in text.split(",")]
        except ValueError:
            values = []
        if len(values) != 4 or values[0] >= values[1] or values[2] >= values[3]:
            raise InputError(f"--roi {text!r}: expected X0,X1,Y0,Y1 in mm with X0 < X1 and "
                             "Y0 < Y1, e.g. 0,1,0,1")
        windows.append(tuple(values))
    return windows


def _progress_bar(quiet: bool):
    if quiet or not sys.stderr.isatty():
        return None

    def show(done: int, total: int) -> None:
        width = 40
        filled = width * done // max(total, 1)
        sys.stderr.write(f"\r  cutting [{'#' * filled}{'.' * (width - filled)}] "
                         f"{done}/{total} sweeps")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def _cut(args) -> int:
    from machinesim.cutting import cut
    from machinesim.errors import ErrorModel
    from machinesim.nc import read_program

    suffix = args.out.suffix.lower()
    if suffix not in (".ply", ".stl", ".glb"):
        raise InputError(f"--out {args.out}: expected a .ply, .stl or .glb file name")
    program = read_program(args.program)
    errors = ErrorModel.from_toml(args.errors) if args.errors else None
    part, report = cut(program, args.machine, tool=args.tool, stock=args.stock, errors=errors,
                       roi=_roi(args.roi), progress=_progress_bar(args.quiet))
    {".ply": part.export_ply, ".stl": part.export_stl, ".glb": part.export_glb}[suffix](args.out)
    summary = report.to_dict()
    if args.report:
        write_atomic(args.report, json.dumps(summary, indent=2) + "\n")
    print(f"wrote {args.out}: removed {summary['removed_volume_mm3']:.6g} mm^3 in "
          f"{report.sweeps} sweeps ({report.engine}); "
          f"machining time {report.machining_time_s:.1f} s")
    for what, items in (("rapid that cuts at line", report.rapids_that_cut),
                        ("outside travel:", report.limit_violations)):
        for item in items:
            print(f"warning: {what} {item}", file=sys.stderr)
    if report.empty_cut:
        print("warning: the program removed no material (does it reach the stock?)",
              file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
