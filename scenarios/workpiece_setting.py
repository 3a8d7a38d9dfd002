"""Paper 002 replay: a robot-loaded workpiece, its setting errors found and compensated.

Run: ``.venv/bin/python scenarios/workpiece_setting.py`` (``make demo``: the report after
about 2 min on 2 idle cores, its error budget after about 7; each step shown on stderr;
times in docs/procedures/workpiece_setting.md and docs/budget.md; ``--budget off`` stops
at the report; ``--quick``: smaller crown windows, as the tests run it) with options

    --robot-repeatability-um R  the robot that loads each workpiece (default 30, the
                                paper's LR Mate 200iD); its landings are drawn with --seed
    --delta-um x,y,z            or give the setting error: position (um) ...
    --rot-deg alpha,beta,gamma  ... and rotations (deg), the same for both workpieces
    --crown-delta-um, --crown-rot-deg  the same for the crown only (the grooves keep
                                theirs; default: its landing, 100 um higher and
                                tilted 1.93 deg about X, the tilt behind the paper's S
                                before, docs/procedures/workpiece_setting.md)
    --errors FILE.toml          inject this error model in both loads instead of the
                                default C-axis centre (any ErrorModel); the options above,
                                when given, set the workpiece setting on top of it
    --realism ideal|noise_only|lab  what the lab has besides the injected errors: lab =
                                instrument imperfections, artefact errors, the machine's
                                background errors (`machinesim.realism`). Default lab;
                                --noise off without it: ideal
    --budget on|off             error budget of the "after" figures (the crown's, the
                                grooves' spread): each source switched off in turn (one
                                more run of each load each, the crown "after" only, cut
                                again only where the source changes the program or the
                                machine: five more crown cuts, about 5 min on 2 cores;
                                default on, run after the report is written and printed,
                                so an interrupted budget leaves it whole)
    --jobs N                    the budget's reruns at a time, each on a worker process
                                (default 1: one after the other, in this process; the
                                same budget to the bit either way; 2 on 2 free cores:
                                1.34 times faster at 1.7 times the memory, docs/budget.md)
    --nose-correction on|off    keep the nose arc's lowest point on the path (default on),
                                or the tip as the paper's eq 7 does (off)
    --all-layers                cut all ten 1 um finishing layers of the crown, not only the
                                last (about ten times longer; the same part)
    --quick                     smaller crown windows (the same passes and feed sweeps:
                                every row reaches a window either way; it saves the
                                booleans' size and readings, docs/procedures/
                                workpiece_setting.md, "Cut")
    --noise on|off --seed N --out DIR   (default reports/workpiece_setting)

On `robonano_a0ib` the robot sets two workpieces on the C table: a block for the crossing
grooves (section 3.1) and the roughly machined diamond crown (3.2), each with three
reference spheres. Each load is a lab of its own (`machinesim.Lab`: the robot's landing is
the truth of that load); on each the procedure
(`machinesim.procedures.workpiece_setting.RobotLoadedWorkpiece`) probes the spheres,
identifies the setting and the C centre, rewrites the NC program (eqs 5-7; and model-based,
compared) and machines its experiment before and after compensation, read with the laser
microscope. Prints Table 3 of the paper beside the simulated one, the groove depths, the
identification and its cross-check by the generic fit, the machining times and the
compensation routes, and writes the report folder (summary.json in the schema of
docs/reports.md, tables, plots, PLY parts, NC programs, HTML views).
"""

from __future__ import annotations

import machinesim.scenario_start  # noqa: F401  (first: Ctrl-C while loading is one line)

import math
import sys
from functools import partial

import numpy as np

from machinesim import Lab, WorkpieceSetting, load_machine
from machinesim._arguments import typed_number
from machinesim.budget import error_budget
from machinesim.cam.crown import PARK, groove_rapids_crash
from machinesim.compensation import program_axes
from machinesim.exceptions import InputError
from machinesim.experiment import run
from machinesim.identification.workpiece_setting import nose_shift
from machinesim.loading import LANDING_REACH, RobotLoader
from machinesim.procedures.sphere_probing import probing_miss
from machinesim.procedures.workpiece_setting import (
    EXPERIMENTS,
    NOSE,
    RobotLoadedWorkpiece,
    eqs_5_to_7_program,
    model_based_program,
)
from machinesim.realism import Realism
from machinesim.report import ReportFolder
from machinesim.rotations import rotation_xyz
from machinesim.scenario_runs import (
    injected_errors,
    jobs_option,
    parse_floats,
    progress_printer,
    scenario_arguments,
    scenario_status,
)
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM
from machinesim.workpiece_setting_budget import (
    TIP_VS_NOSE,
    budget_figures,
    crown_rerun,
)
from machinesim.workpiece_setting_report import (
    combined,
    fit_table,
    groove_plot,
    groove_table,
    identification_table,
    table3_table,
    time_table,
    views,
)

UM, MM = M_PER_UM, M_PER_MM
#: Default repeatability of the loading robot, um (paper 002's LR Mate 200iD).
ROBOT_REPEATABILITY_UM = 30.0
#: The largest --robot-repeatability-um, um (whole): beyond it `RobotLoader` refuses the
#: robot (its landing 3 standard deviations out turns the part past 180 deg).
LARGEST_ROBOT_UM = math.floor(RobotLoader.largest_repeatability(RobotLoader.lever) / UM)
#: Default C-axis centre error (location.C.EX0C, EY0C), um: chosen to match the paper's
#: magnitude, not taken from it (section 3.2.3 blames its edge distances, 138-163 um longer
#: before compensation, on the C table centre, without a value). Every side face is cut with
#: the tool on the machine's +X side, so the crown comes out centred on the true C axis:
#: face k moves out by e . n_k - e_x and every opposite-edge distance grows by -2 e_x, here
#: 150 um (docs/procedures/workpiece_setting.md).
C_CENTRE_UM = (-75.0, 5.0)
#: How the rough crown stands on its base against its drawing, added to the robot's landing
#: of the crown: chosen to match the paper's magnitudes, not taken from it. The crown and its
#: spheres were rough-cut in one setting on an ordinary machine tool (section 3.2.1), so the
#: spheres carry both and the identification sees them as the setting's z and alpha.
#: Tilt: the paper's eight inclinations before compensation fit -0.51 + 1.93 sin(45 k deg)
#: (least squares; opposite faces change oppositely, a tilt's signature, which a C centre
#: cannot give): 1.93 deg about X. Height: with the C centre above, face k's passes stand
#: e . n_k - e_x out, up to 150 um (30 um higher on an 11.31 deg face), and the tilt lowers
#: the faces on the -Y side by up to 67 um, where the rough faces stand 51 um (10 um along
#: the normal) out: 100 um lifts every face into the passes, so all eight are cut before
#: compensation, as the paper reads them (docs/procedures/workpiece_setting.md).
CROWN_HEIGHT_UM = 100.0
CROWN_TILT_DEG = 1.93
#: The lab without --realism: the paper's imperfections all on.
DEFAULT_REALISM = "lab"


def setting_parameters(setting: WorkpieceSetting) -> dict[str, float]:
    """A workpiece setting as error parameters (SI)."""
    return {**{f"workpiece.{a}": float(v) for a, v in zip("xyz", setting.delta, strict=True)},
            "workpiece.alpha": setting.alpha, "workpiece.beta": setting.beta,
            "workpiece.gamma": setting.gamma}


def loads(args) -> dict:
    """The error model of each load: the robot's landings (drawn with --seed, grooves first,
    as before; the crown's `CROWN_HEIGHT_UM` higher and `CROWN_TILT_DEG` tilted about X)
    or --delta-um/--rot-deg (the crown's by --crown-delta-um/--crown-rot-deg), over
    --errors when given, else over the default C centre `C_CENTRE_UM` (`injected_errors`)."""
    repeatability = (ROBOT_REPEATABILITY_UM if args.robot_repeatability_um is None
                     else args.robot_repeatability_um)
    if args.robot_repeatability_um is not None and (args.delta_um or args.rot_deg):
        raise InputError("--robot-repeatability-um with --delta-um or --rot-deg: the setting "
                         "is either the robot's landing or the one given; expected one of "
                         "them", key="robot-repeatability-um")
    if not (math.isfinite(repeatability) and repeatability >= 0.0):
        raise InputError(f"--robot-repeatability-um {repeatability!r}: expected a length in "
                         "um, 0 or more", key="robot-repeatability-um")
    if repeatability > LARGEST_ROBOT_UM:  # RobotLoader's own refusal names its field, in m
        raise InputError(
            f"--robot-repeatability-um {repeatability:g}: a robot that lands the part "
            f"{LANDING_REACH:g} standard deviations out beyond what a workpiece setting takes "
            f"(1 m, 180 deg over its {RobotLoader.lever / 1e-3:g} mm grip); expected a "
            f"length in um, 0 to {LARGEST_ROBOT_UM:d}", key="robot-repeatability-um")
    robot = RobotLoader(repeatability * UM)
    rng = np.random.default_rng(args.seed)
    landed = {load: setting_parameters(robot.land(rng)) for load in EXPERIMENTS}
    landed["crown"]["workpiece.z"] += CROWN_HEIGHT_UM * UM
    landed["crown"]["workpiece.alpha"] += math.radians(CROWN_TILT_DEG)
    centre = {"location.C.EX0C": C_CENTRE_UM[0] * UM, "location.C.EY0C": C_CENTRE_UM[1] * UM}
    if args.delta_um or args.rot_deg:
        given = dict.fromkeys(EXPERIMENTS, _given_setting(args.delta_um, args.rot_deg, ""))
    elif args.robot_repeatability_um is not None:
        given = landed
    else:
        given = dict.fromkeys(EXPERIMENTS, {})
    if args.crown_delta_um or args.crown_rot_deg:
        given = {**given, "crown": _given_setting(args.crown_delta_um, args.crown_rot_deg,
                                                  "crown-")}
    if args.errors is not None:  # the file read (and noted) once, for both loads
        read = injected_errors(args, {}, {}, "robonano_a0ib")
        errors = {load: read.with_parameters(given[load]) if given[load] else read
                  for load in EXPERIMENTS}
    else:
        errors = {load: injected_errors(args, {**landed[load], **centre}, given[load],
                                        "robonano_a0ib")
                  for load in EXPERIMENTS}
    _check_grooves_landing(args, errors["grooves"].workpiece, repeatability)
    for load in EXPERIMENTS:  # the crown's is probed only after the grooves' whole run
        _check_probing(args, load, errors[load].workpiece, repeatability)
    return errors


def _check_grooves_landing(args, setting: WorkpieceSetting, repeatability: float) -> None:
    """Refuse a setting of the grooves' block that the groove program's rapids would run
    into (`groove_rapids_crash`): a crash on a real machine, and here a cut of thousands of
    tiny sweeps that ran past 5 min (--robot-repeatability-um 3000 landed the block 531 um
    high)."""
    crash = groove_rapids_crash(setting)
    if crash is None:
        return
    tilt = math.degrees(math.acos(min(1.0, rotation_xyz(setting.alpha, setting.beta,
                                                        setting.gamma)[2, 2])))
    source, key = _setting_source(args, repeatability)
    raise InputError(
        f"{source} sets the grooves' block {setting.delta[2] / UM:.1f} um high and tilted "
        f"{tilt:.3g} deg: {crash}, so the rapids would run into the block (a crash on a "
        "real machine). Expected a setting "
        "within that: a smaller repeatability, another seed, or --delta-um/--rot-deg",
        key=key)


def _setting_source(args, repeatability: float, prefix: str = "") -> tuple[str, str]:
    """What set a load's workpiece setting, in words, and the key of a refusal: the options
    given (``prefix`` ``"crown-"`` for the crown's own), else the ``--errors`` file, else
    the robot's landing."""
    given = [(f"{prefix}{name}", text) for name, text in
             (("delta-um", getattr(args, f"{prefix}delta_um".replace("-", "_"))),
              ("rot-deg", getattr(args, f"{prefix}rot_deg".replace("-", "_")))) if text]
    if given:
        return ", ".join(f"--{n} {t}" for n, t in given), given[0][0]
    if prefix:
        return _setting_source(args, repeatability)
    if args.errors is not None and args.robot_repeatability_um is None:
        return f"--errors {args.errors}", "errors"
    return (f"the robot's landing (--robot-repeatability-um {repeatability:g}, --seed "
            f"{args.seed})"), "robot-repeatability-um"


def _check_probing(args, load: str, setting: WorkpieceSetting, repeatability: float) -> None:
    """Refuse, before anything is probed or cut, a load whose setting puts a reference
    sphere beyond the probe's reach (`probing_miss`): the probe refused it after the scans
    missed, naming a 'centre' in metres and no option (--delta-um 800,0,3 or 12000,-8,3,
    --rot-deg 0.01,-0.02,28.6: rad taken for deg), and the crown's only after the grooves'
    whole run."""
    miss = probing_miss(RobotLoadedWorkpiece(load).spheres, setting)
    if miss is None:
        return
    source, key = _setting_source(args, repeatability, "crown-" if load == "crown" else "")
    what = "the grooves' block" if load == "grooves" else "the crown"
    raise InputError(f"{source} sets {what} so that {miss}. Expected a setting "
                     "within that: a smaller repeatability, another seed, or smaller "
                     "--delta-um/--rot-deg", key=key)


def _given_setting(delta_um, rot_deg, prefix: str) -> dict[str, float]:
    """A setting given on the command line (--{prefix}delta-um, --{prefix}rot-deg)."""
    delta = np.array(parse_floats(delta_um or "0,0,0", 3, f"--{prefix}delta-um")) * UM
    angles = np.radians(parse_floats(rot_deg or "0,0,0", 3, f"--{prefix}rot-deg"))
    try:
        return setting_parameters(WorkpieceSetting(delta, *angles))
    except InputError as error:  # named by the option given, in its units
        given = [(f"{prefix}{name}", text) for name, text in
                 (("delta-um", delta_um), ("rot-deg", rot_deg)) if text]
        raise InputError(", ".join(f"--{name} {text}" for name, text in given) + ": "
                         + error.message, key=given[0][0]) from None


def main(argv=None) -> int:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/workpiece_setting")
    parser.add_argument("--robot-repeatability-um", type=typed_number, default=None,
                        help="repeatability of the loading robot (um, default "
                        f"{ROBOT_REPEATABILITY_UM:g}; 0 to {LARGEST_ROBOT_UM:d})")
    parser.add_argument("--delta-um", help="position error x,y,z (um) instead of a draw")
    parser.add_argument("--rot-deg", help="rotation errors alpha,beta,gamma (deg)")
    parser.add_argument("--crown-delta-um", help="the crown's position error x,y,z (um) "
                        "instead of its draw (the grooves keep theirs)")
    parser.add_argument("--crown-rot-deg", help="the crown's rotation errors (deg)")
    parser.add_argument("--nose-correction", choices=("on", "off"), default="on",
                        help="put the nose arc's lowest point on the path (default on), "
                        "or the tip as the paper's eq 7 (off)")
    if "--realism" not in parser._option_string_actions:
        parser.add_argument("--realism", choices=("ideal", "noise_only", "lab"),
                            default=None, help="what the lab has besides the injected "
                            "errors (default lab; --noise off without it: ideal)")
    parser.add_argument("--budget", choices=("on", "off"), default="on",
                        help="error budget of the after figures: one more run of each "
                        "load per source, after the report (default on)")
    parser.add_argument("--all-layers", action="store_true",
                        help="cut every finishing layer of the crown, not only the last")
    parser.add_argument("--quick", action="store_true", help="smaller crown windows")
    jobs_option(parser)
    args = parser.parse_args(argv)
    return scenario_status(report, args, "workpiece_setting")


def report(args) -> None:
    machine = load_machine("robonano_a0ib")
    realism = lab_realism(args)
    errors = loads(args)
    labs = {load: Lab(machine, errors[load], seed=args.seed, realism=realism)
            for load in EXPERIMENTS}
    nose = args.nose_correction == "on"
    results = {}
    for load, lab in labs.items():
        told = progress(f"{load} load")
        results[load] = run(RobotLoadedWorkpiece(load, nose_correction=nose,
                                                 all_layers=args.all_layers,
                                                 quick=args.quick, progress=told),
                            lab, progress=told)
    folder = ReportFolder(args.out)
    told = progress("report")
    told("checking the compensation routes on the machine with the injected errors ...")
    route_rows, routes = route_check(machine, labs["crown"].reveal(), results["crown"])
    result = combined(results, routes)
    told("writing the views, tables and plots ...")
    views(folder, result)
    groove_plot(folder, results["grooves"].evaluation.details)
    table3 = table3_table(folder, results["crown"])
    grooves = groove_table(folder, results["grooves"])
    ident = identification_table(folder, results)
    check = fit_table(folder, results)
    times = time_table(folder, results["crown"])
    route_rows.append(["eqs 5-7 against model-based, tip: axis values apart",
                       f"X Y Z {routes['eq7_vs_model_xyz_nm']:.3g} nm",
                       f"B {routes['eq7_vs_model_b_deg']:.3g} deg, "
                       f"C {routes['eq7_vs_model_c_deg']:.3g} deg"])
    route_table = folder.write_table(
        "routes", ["crown program rewritten by", "nose point: depth off (nm)",
                   "across (nm)"], route_rows,
        title="Compensation routes on the machine with the injected errors (identification "
        "error included)", digits=4)
    # The report is whole before the budget's reruns begin: the folder is written (an older
    # budget in it removed) and swapped in (published), so an interrupted budget leaves a
    # complete report without one; the budget then adds its table, plot and summary rows,
    # and the folder is swapped in again.
    summary = folder.write_result(result)
    folder.publish(last=args.budget != "on")
    for text in (table3, grooves, ident, check, times, route_table, summary):
        print(text, flush=True)
    print(f"report folder: {folder.final}")
    print(f"views: {folder.final / 'crown_after.html'} (and crown_before, grooves_before, "
          "grooves_after)", flush=True)
    if args.budget == "on":
        budget = scenario_budget(machine, errors, args, realism, results)
        if budget is not None:
            text = folder.add_budget(result, budget)
            folder.publish(last=True)
            print(text)
    told("done")


#: Each step of each load, and the budget's, on stderr with the time since the scenario
#: started: the default run takes minutes, the crown's cuts most of them.
progress = progress_printer("workpiece_setting")


def lab_realism(args) -> Realism:
    """--realism, or without it: the lab as labs are (`DEFAULT_REALISM`), or nothing with
    --noise off (as before the realism switches existed)."""
    name = getattr(args, "realism", None) or (DEFAULT_REALISM if args.noise == "on"
                                              else "ideal")
    realism = getattr(Realism, name)()
    return realism.without("instrument_noise") if args.noise == "off" else realism


def scenario_budget(machine, errors, args, realism: Realism, results):
    """The error budget of the "after" figures (`machinesim.budget.error_budget`): the
    crown's (not the machining times, which come from the feeds alone) and the grooves'
    spread (their depths are not errors). Each realism switch that is on and that the
    procedure feels (`RobotLoadedWorkpiece.realism_sources`) is turned off in turn, on a
    lab of its own for each load with the same errors and seed; with
    --nose-correction off, the tip-versus-nose approximation too (the variant puts the nose
    on the path). The variants cut only the compensated crown; ``results`` are the runs with
    everything on, by load."""
    nose = args.nose_correction == "on"
    sources = ([name for name in realism.on if name in RobotLoadedWorkpiece.realism_sources]
               + ([] if nose else [TIP_VS_NOSE]))
    if not sources:
        progress("budget")(f"none: no source it shares out is on (realism {realism}), so "
                           "budget.md and budget.png are not written")
        return None
    jobs = min(args.jobs, len(sources))
    rerun = partial(crown_rerun, machine=machine, errors=errors, seed=args.seed,
                    realism=realism, nose_correction=nose, all_layers=args.all_layers,
                    quick=args.quick)
    if jobs == 1:
        progress("budget")(f"{len(sources)} sources switched off in turn, a run of each "
                           "load each; those that change the crown's program or the machine "
                           "cut it again, about 1 min each on 2 cores (--budget off skips "
                           "this)")
        return error_budget(partial(rerun, progress=progress), sources,
                            everything=budget_figures(results))
    progress("budget")(f"{len(sources)} sources switched off in turn, a run of each load "
                       f"each, {jobs} at a time on worker processes (--jobs); those that "
                       "change the crown's program or the machine cut it again, about 1 min "
                       "each on a core (--budget off skips this)")
    finished = []

    def done(source, seconds):
        finished.append(source)
        progress(f"budget, {source} off")(f"done in {seconds:.0f} s ({len(finished)} of "
                                          f"{len(sources)})")

    return error_budget(rerun, sources, everything=budget_figures(results), jobs=jobs,
                        done=done)


# ------------------------------------------------------------------------------ verification


def generating_points(machine, errors, program, wanted, nose_radius: float = 0.0
                      ) -> np.ndarray:
    """Where the nose arc's lowest point (or the tip) really goes, for checking a program.

    For each move's target: the point of the tool that generates a surface facing the
    wanted tool axis (`nose_shift`), written as the tip position that would put it there
    with the wanted orientation, in the workpiece frame of the machine with ``errors``.
    Verification only (it reads the injected errors): the procedure never calls it.

    Returns
    -------
    ndarray, shape (N, 3)
        m; compare with the nominal program's on the nominal machine.
    """
    poses = machine.tool_pose(program_axes(program, machine, start=PARK), errors)
    return poses[:, :3, 3] - nose_shift(wanted, poses[:, :3, :3], nose_radius)


def route_check(machine, errors, crown) -> tuple[list, dict]:
    """The four ways to rewrite the crown's nominal program (eqs 5-7 or model-based; tip or
    nose), each checked on the machine with the injected ``errors``: how far the nose arc's
    lowest point lands from where the nominal program puts it on the ideal machine, along
    the tool axis (depth) and across it. Verification only; the identification error is
    included. The programs are compared unrounded: the routes' own agreement, without the
    machine resolution's (1 nm, 0.00001 deg) rounding of the NC text, which adds up to half
    a step per axis."""
    nominal = crown.evaluation.programs["crown_nominal"]
    found = crown.identification.detail.found
    wanted = machine.tool_pose(program_axes(nominal, machine, start=PARK))[:, :3, :3]
    ideal = generating_points(machine, None, nominal, wanted, NOSE)
    rows, out, targets = [], {}, {}
    for label, key, nose in (("eqs 5-7, tip (the paper's)", "eq7_tip", 0.0),
                             ("eqs 5-7, nose", "eq7_nose", NOSE),
                             ("model-based, tip", "model_tip", 0.0),
                             ("model-based, nose", "model_nose", NOSE)):
        rewrite = eqs_5_to_7_program if key.startswith("eq7") else model_based_program
        program = rewrite(nominal, machine, found, nose, rounded=False)
        targets[key] = program_axes(program, machine, start=PARK)
        off = generating_points(machine, errors, program, wanted, NOSE) - ideal
        depth = np.einsum("ni,ni->n", off, wanted[:, :, 2])
        lateral = np.linalg.norm(off - depth[:, None] * wanted[:, :, 2], axis=1)
        out[f"{key}_depth_nm"] = float(np.abs(depth).max() / M_PER_NM)
        out[f"{key}_lateral_nm"] = float(lateral.max() / M_PER_NM)
        rows.append([label, out[f"{key}_depth_nm"], out[f"{key}_lateral_nm"]])
    apart = np.abs(targets["eq7_tip"] - targets["model_tip"]).max(axis=0)
    out["eq7_vs_model_xyz_nm"] = float(apart[:3].max() / M_PER_NM)
    out["eq7_vs_model_b_deg"] = float(np.degrees(apart[3]))
    out["eq7_vs_model_c_deg"] = float(np.degrees(apart[4]))
    return rows, out


if __name__ == "__main__":
    sys.exit(main())
