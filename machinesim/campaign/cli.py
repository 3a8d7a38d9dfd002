"""``machinesim campaign``: the command-line front of `machinesim.campaign.run`.

`add_campaign_parser` registers the subcommand on ``machinesim``'s parser; `run_campaign`
runs it. ``python -m machinesim.campaign.cli ...`` runs it alone.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from machinesim._arguments import ArgumentParser
from machinesim._interrupts import ctrl_c_remembered, stopped
from machinesim.campaign.distributions import LAB_PARAMETERS, parse_vary
from machinesim.campaign.shipped import PROCEDURES
from machinesim.campaign.spec import MAX_TRIALS, check_whole
from machinesim.exceptions import (
    FileError,
    InputError,
    MachineSimError,
    brief,
    printable,
    say,
    warnings_as_lines,
)

__all__ = ["add_campaign_parser", "interrupted", "main", "run_campaign"]

EXAMPLES = """\
DIST (every number with its unit: m mm um nm rad mrad urad deg arcsec; 0 needs none):
  normal:MEAN,STD       e.g. normal:0,5um
  uniform:LOW,HIGH      e.g. uniform:-10um,10um
  fixed:VALUE or VALUE  e.g. 30um
PARAM: an error parameter of the procedure's machine (tool.y, workpiece.alpha,
  location.C.EX0C, ...) or a lab parameter: {lab};
  one the procedure never reads (an instrument it does not use, a robot where none loads
  the workpiece, tool_geometry.nose_radius for a V tool) is refused before any trial runs

procedures:
{procedures}
  package.module:ClassName: a procedure of your own (docs/procedures/your_own.md), with
    --machine NAME and, optionally, --errors FILE.toml (the errors --vary is set on); its
    module is looked for in the current folder too (local workers are started with it),
    and with --scheduler it must import on every worker of that cluster

examples:
  # paper 000: e_ys and r against the microscope's noise, 20 trials on 2 local workers
  machinesim campaign tool_rotation_arm --trials 20 --workers 2 \\
      --vary microscope.sigma=uniform:5nm,100nm --out reports/campaign_arm_noise
  # paper 002: the crown against the loading robot's repeatability (10 to 100 um)
  machinesim campaign workpiece_setting --quick --trials 10 \\
      --vary robot.repeatability=uniform:10um,100um --out reports/campaign_crown
  # probing only (no cutting after): the identification's errors and z-scores
  machinesim campaign workpiece_setting --identify-only --trials 50 \\
      --vary robot.repeatability=100um --out reports/campaign_probing
  # on a running Dask cluster
  machinesim campaign tool_rotation_arm --trials 1000 --scheduler tcp://10.0.0.5:8786 \\
      --vary tool.y=normal:-178um,20um --out reports/campaign_big

Run again with the same --out to finish an interrupted campaign (only the missing trials
run) or to extend it to more trials; DIR gets campaign.nc (xarray, netCDF), summary.json,
summary.md, hist_<figure>.png, z_scores.png and trials/ (one file per trial).
"""


def _epilog() -> str:
    procedures = "\n".join(f"  {name}: {entry.about}" for name, entry in PROCEDURES.items())
    return EXAMPLES.format(lab=", ".join(LAB_PARAMETERS), procedures=procedures)


def _folder(text: str) -> Path:
    """An argparse type for the campaign folder: an empty ``--out`` (an unset shell variable)
    is refused, where ``Path("")`` is the current folder and the campaign's files went there."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is empty; expected the campaign folder "
                                         "(give . for the current one)")
    return Path(text)


def _whole(text: str) -> int | str:
    """A whole-number option (--trials, --workers, --seed) as an int, or its text as given
    when it is not one: refused then as the campaign refuses it in Python (`check_whole`,
    naming the option), one line naming what is expected, not argparse's "invalid int
    value: '1e3'"."""
    try:
        return int(text)
    except ValueError:
        return text


def _arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("procedure", help=f"one of {', '.join(PROCEDURES)}, or your own "
                        "as package.module:ClassName")
    parser.add_argument("--machine", default=None, metavar="NAME",
                        help="your own procedure's machine (not for a shipped one)")
    parser.add_argument("--errors", default=None, metavar="FILE",
                        help="your own procedure's errors, a TOML error model (default: none)")
    parser.add_argument("--trials", type=_whole, required=True, metavar="N",
                        help=f"number of trials, 1 to {MAX_TRIALS}")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_whole, default=None, metavar="K",
                       help="local Dask worker processes (default: the cores this process may use; "
                       "0: no Dask, in this process)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="run on this Dask scheduler (e.g. tcp://host:8786)")
    parser.add_argument("--vary", action="append", default=[], metavar="PARAM=DIST",
                        help="a parameter's distribution over the trials (repeatable)")
    parser.add_argument("--seed", type=_whole, default=0,
                        help="the campaign's seed: trial i is SeedSequence(seed).spawn(N)[i]")
    parser.add_argument("--noise", choices=("on", "off"), default="on",
                        help="instrument noise (default on)")
    parser.add_argument("--identify-only", action="store_true",
                        help="measure and identify only (probing-only trial): no "
                        "compensation, no figures")
    parser.add_argument("--quick", action="store_true",
                        help="the crown's smaller measuring windows (workpiece_setting only, not "
                        "with --identify-only)")
    parser.add_argument("--out", type=_folder, required=True, metavar="DIR",
                        help="campaign folder (resumed when it holds the same campaign)")
    parser.add_argument("--quiet", action="store_true", help="no progress line")
    return parser


def add_campaign_parser(sub) -> argparse.ArgumentParser:
    """Register ``campaign`` on a subparsers object of ``machinesim``'s parser."""
    return _arguments(sub.add_parser(
        "campaign", help="run a procedure as N seeded trials (Dask), with statistics",
        description="Run a procedure over N trials, each with its own drawn errors and "
        "noise (SeedSequence(seed).spawn(N)[i]), locally or on a Dask cluster; write the "
        "trials as an xarray Dataset with distributions, coverage intervals, z-scores and "
        "sensitivities.", epilog=_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter))


def run_campaign(args) -> int:
    """Run the parsed ``campaign`` command; print where the report is. MachineSimError
    propagates to the caller (``machinesim``'s main prints it as one line)."""
    from machinesim.campaign.runner import run

    # before anything else: nothing to wait for; named as options, where run names its
    # arguments (trials=0)
    for name in ("trials", "seed", "workers"):
        if getattr(args, name) is not None:
            check_whole(getattr(args, name), name, option=True)
    _check_own_options(args)
    vary = [parse_vary(text) for text in args.vary]
    if ":" in args.procedure and "" not in sys.path and os.getcwd() not in sys.path:
        # your own procedure's module, in the folder the command is run from (an installed
        # command's sys.path has its own folder, not that one), for the workers too
        sys.path.insert(0, os.getcwd())
    try:
        dataset = run(args.procedure, args.trials, vary=vary, seed=args.seed, out=args.out,
                      workers=args.workers, scheduler=args.scheduler,
                      noise=args.noise == "on", identify_only=args.identify_only,
                      quick=args.quick, progress=not args.quiet, machine=args.machine,
                      errors=args.errors)
    except FileError as error:  # a full disk said only "cannot write: No space left ..."
        kept = interrupted(args.out)
        if kept == "nothing was written":
            raise
        raise FileError(f"{error.message}; the campaign stopped; {kept} once the file can "
                        "be written", source=error.source) from None
    from machinesim.campaign.summary import failures, notes

    failed, total = int(dataset["failed"].sum()), dataset.sizes["trial"]
    print(f"campaign: {total} trial{'s' * (total != 1)} ({failed} failed) in "
          f"{printable(args.out)}: "
          "campaign.nc, summary.md, summary.json")
    noted = int((dataset["notes_count"].values > 0).sum())
    if noted:  # a fit that misfit in 30 of 1000 trials said nothing
        first = notes(dataset)[0]
        say("campaign", f"{noted} trial{'s' * (noted != 1)} gave notes of the "
            f"identification; the most common ({len(first['trials'])} of them): "
            f"{first['note']} (summary.md lists them)")
    if not failed:
        return 0
    first = failures(dataset)[0]
    which = f"{failed} trial{'s' * (failed != 1)}"
    say("campaign", f"{'every trial' if failed == total else which} "
        f"failed; the most common message ({len(first['trials'])} of them): "
        f"{first['message']} (summary.md lists every message)")
    return 1 if failed == total else 0


def _check_own_options(args) -> None:
    """Refuse --machine or --errors with a shipped procedure, and your own procedure
    without --machine, naming the option as typed: `run` refused them as the Python
    parameters ("machine=None; expected the name of the machine ... (e.g.
    machine='grooving_4axis')"), which the command line has not."""
    from machinesim.campaign.own import is_reference

    if args.procedure in PROCEDURES:
        for option, value in (("--machine", args.machine), ("--errors", args.errors)):
            if value is not None:
                entry = PROCEDURES[args.procedure]
                raise InputError(f"{option} {brief(repr(value))} is for a procedure of your "
                                 f"own; {args.procedure} runs on {entry.machine} with its "
                                 "paper's errors (vary them with --vary)", key=option)
    elif is_reference(args.procedure) and not args.machine:
        given = "not given" if args.machine is None else repr(args.machine)
        raise InputError(f"--machine {given}; expected the name of the machine procedure "
                         f"{args.procedure} is for (e.g. --machine grooving_4axis): a "
                         "campaign of your own procedure needs it", key="--machine")


def interrupted(out) -> str:
    """What a campaign stopped by Ctrl-C leaves in ``out`` (after "interrupted; "): the
    finished trial files, kept so that the same command resumes, or nothing."""
    from machinesim.campaign.results import finished_trials

    if out is None:
        return "nothing was written"
    out = Path(out)
    trials = finished_trials(out)
    if trials:
        shown = (f"trial_{trials[0]:06d}.json" if len(trials) == 1 else
                 f"trial_{trials[0]:06d}.json .. trial_{trials[-1]:06d}.json")
        gaps = trials[-1] - trials[0] + 1 - len(trials)  # workers finish out of order
        if gaps:
            shown += f", {gaps} between them not finished"
        return (f"kept the {len(trials)} finished trial file{'s' * (len(trials) > 1)} in "
                f"{out / 'trials'} ({shown}) and campaign.json: run the same command again "
                "to resume (only the missing trials run)")
    if (out / "campaign.json").is_file():
        return (f"no trial had finished; kept {out / 'campaign.json'}: run the same command "
                "again to start it over")
    return "nothing was written"


def main(argv=None) -> int:
    """``python -m machinesim.campaign.cli``: the subcommand on its own."""
    parser = _arguments(ArgumentParser(
        prog="machinesim campaign", epilog=_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter))
    args = parser.parse_args(argv)
    try:
        # a MachineSimWarning as one line, as ``machinesim campaign`` shows it
        with ctrl_c_remembered(), warnings_as_lines():
            return run_campaign(args)
    except MachineSimError as error:
        say("machinesim campaign", f"error: {error}")
        return 2
    except KeyboardInterrupt as stop:  # Ctrl-C, or SIGTERM within `ctrl_c_remembered`
        how, status = stopped(stop)
        say("machinesim campaign", f"{how}; {interrupted(args.out)}")
        return status


if __name__ == "__main__":
    sys.exit(main())
