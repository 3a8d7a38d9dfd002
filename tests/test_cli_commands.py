"""The command line's commands and options as parsed: `machines`, each command's help and
--version, a misspelt option named with the one meant, an option given twice, an empty
name refused as empty, `python -m machinesim`, and a long cut's progress as log lines."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest
from cli_helpers import CUT, GROOVES, ROOT, run

import machinesim
import machinesim.cutting
import machinesim.nc
from machinesim.cli import main


def test_machines_lists_each_machine_with_its_axes(capsys):
    assert main(["machines"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in out] == [
        ["grooving_4axis", "XYZC"], ["planer_4axis", "XYZA"], ["robonano_a0ib", "XYZBC"],
        ["robonano_ui", "XYZABC"], ["sts_lathe", "XZC"]]
    assert "A -45..45 deg" in out[1]


def test_help_documents_every_cut_option_with_an_example(capsys):
    with pytest.raises(SystemExit):
        main(["cut", "--help"])
    out = capsys.readouterr().out
    for option in ("--machine", "--tool", "--stock", "--errors", "--out", "--report", "--roi",
                   "--tools", "--integer-input", "--allow-overtravel"):
        assert option in out
    assert "e.g. block:10x10x2" in out and "e.g. v:90" in out
    assert ":d=" in out and "flat:0.5:h=3:d=4" in " ".join(out.split())  # docs/cli.md's --tool
    assert "millimetres" in out and "metres" in out


def test_cut_help_names_every_stock_form_and_each_example_builds(capsys):
    # the help named block and cylinder only, while --stock reads spheres and crown too
    # (docs/cli.md); each e.g. of the help must be a stock the command builds
    with pytest.raises(SystemExit):
        main(["cut", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    stock = text[text.index("--stock STOCK stock spec"):text.index("--errors ERRORS injected")]
    for form in ("block:LxWxH", "cylinder:RxH", "spheres:LxWxH:R[:dimples]",
                 "crown[:OVERSIZE]"):
        assert form in stock, form
    from machinesim.workpiece import stock_from_spec
    examples = re.findall(r"e\.g\. ([a-z]+:[0-9x.:]+(?:@[-0-9.]+,[-0-9.]+,[-0-9.]+)?)", stock)
    assert len(examples) == 4, examples
    for example in examples:
        assert stock_from_spec(example).volume > 0.0, example


def test_an_empty_file_or_machine_name_is_refused_as_empty_not_as_the_current_folder(
        tmp_path, capsys):
    # Path('') is '.': `cut '' ...` said "'.': is a folder; expected the NC program file",
    # quoting a '.' never typed, `view ''` showed the current folder, and a scenario's
    # --out '' wrote its report over the current folder (an unset shell variable each)
    from machinesim.scenario_runs import scenario_arguments

    out = ["--out", tmp_path / "part.ply"]
    cases = [
        (["cut", "", *CUT, *out], "cut", "program", "a file name"),
        # (CUT without its own --machine: an option given twice is refused as such)
        (["cut", GROOVES, *CUT[2:], *out, "--machine", ""], "cut", "--machine",
         "a name or a path"),
        (["cut", GROOVES, *CUT, *out, "--errors", ""], "cut", "--errors", "a file name"),
        (["cut", GROOVES, *CUT, *out, "--servo", ""], "cut", "--servo", "a file name"),
        (["cut", GROOVES, *CUT, *out, "--tools", ""], "cut", "--tools", "a file name"),
        (["view", "", "--html", tmp_path / "v.html"], "view", "target", "a name or a path"),
        (["view", "part.ply", "--report", ""], "view", "--report", "a file name"),
        (["view", "part.ply", "--nominal", ""], "view", "--nominal", "a file name"),
        (["view", "grooving_4axis", "--program", ""], "view", "--program", "a file name"),
        (["view", "grooving_4axis", "--errors", ""], "view", "--errors", "a file name"),
        (["view", "grooving_4axis", "--program", GROOVES, "--tools", ""], "view", "--tools",
         "a file name"),
    ]
    for argv, command, option, expected in cases:
        code, _, err = run(argv, capsys)
        assert code == 2, (argv, err)
        assert err.splitlines()[-1] == (f"machinesim {command}: error: argument {option}: "
                                        f"'' is empty; expected {expected}"), (argv, err)
        assert "'.'" not in err and "Traceback" not in err, err
    for option, expected in (("--out", "a folder name"), ("--errors", "a file name")):
        with pytest.raises(SystemExit) as stop:
            scenario_arguments("a scenario", "reports/x").parse_args([option, ""])
        assert stop.value.code == 2
        assert capsys.readouterr().err.splitlines()[-1].endswith(
            f"error: argument {option}: '' is empty; expected {expected}")
    assert list(tmp_path.iterdir()) == []


def test_python_dash_m_machinesim_is_the_command_line():
    """``python -m machinesim`` runs the command, as a user without the script on PATH
    types it (it had said "No module named machinesim.__main__")."""
    result = subprocess.run([sys.executable, "-m", "machinesim", "machines"], cwd=ROOT,
                            capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    assert tuple(line.split()[0] for line in result.stdout.splitlines()) == \
        machinesim.list_machines()


def test_version_prints_the_installed_packages_version(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"machinesim {version('machinesim')}"


@pytest.mark.parametrize("argv, hint", [
    (["cut", "a.nc", "--machine", "grooving_4axis", "--tol", "v:90", "--stock", "block:1x1x1",
      "--out", "x.ply"], "--tol is not an option here; did you mean --tool?"),
    (["cut", "a.nc", "--machine", "grooving_4axis", "--tool", "v:90", "--stock", "block:1x1x1",
      "--out", "x.ply", "--rio", "1"], "--rio is not an option here; did you mean --roi?"),
    (["view", "grooving_4axis", "--progam", "x.nc"],
     "--progam is not an option here; did you mean --program?"),
])
def test_a_misspelt_option_is_named_with_the_one_meant(argv, hint, capsys):
    # argparse alone said only "the following arguments are required: --tool", or listed
    # the word without the option it resembles
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    assert err.splitlines()[-1].endswith(hint), err


CUT_WORDS = ["cut", "a.nc", "--machine", "grooving_4axis", "--tool", "v:90", "--stock",
       "block:1x1x1", "--out", "x.ply"]
CAMPAIGN_WORDS = ["campaign", "tool_rotation_arm", "--trials", "2", "--out", "c"]


@pytest.mark.parametrize("argv, refusal", [
    (CUT_WORDS + ["--tool", "ball:2"], "argument --tool: given 2 times (--tool v:90, "
     "--tool ball:2); give it once: only the last would count"),
    (CUT_WORDS + ["--report=r.json", "--repo", "s.json"], "argument --report: given 2 times "
     "(--report=r.json, --repo s.json); give it once: only the last would count"),
    (CAMPAIGN_WORDS + ["--seed", "1", "--vary", "a=1", "--seed", "2"], "argument --seed: "
     "given 2 times (--seed 1, --seed 2); give it once: only the last would count"),
])
def test_an_option_given_twice_is_refused_naming_both(argv, refusal, capsys):
    # argparse kept the last and dropped the others without a word: --seed 1 --seed 2 ran
    # seed 2
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    assert err.splitlines()[-1].endswith(f"error: {refusal}"), err


def test_options_that_add_up_and_switches_may_be_repeated_and_after_double_dash_none():
    from machinesim.cli import _parser

    args = _parser().parse_args(CUT_WORDS + ["--roi", "0,1,0,1", "--roi", "1,2,1,2",
                                             "--quiet", "--quiet"])  # a switch: once or twice
    assert args.roi == ["0,1,0,1", "1,2,1,2"] and args.tool == "v:90" and args.quiet
    args = _parser().parse_args(CAMPAIGN_WORDS + ["--vary", "a=1", "--vary", "b=2", "--seed", "3"])
    assert args.vary == ["a=1", "b=2"] and args.seed == 3
    # a word after -- is no option: a program named --out
    args = _parser().parse_args(["cut", *CUT_WORDS[2:], "--", "--out"])
    assert args.program.name == "--out" and args.out.name == "x.ply"


def test_a_scenario_refuses_its_seed_given_twice(capsys):
    from machinesim.scenario_runs import scenario_arguments

    parser = scenario_arguments("a scenario", "out")
    assert parser.parse_args(["--seed", "1", "--noise", "off"]).seed == 1
    with pytest.raises(SystemExit) as exited:
        parser.parse_args(["--seed", "1", "--seed", "2"])
    assert exited.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1].endswith(
        "error: argument --seed: given 2 times (--seed 1, --seed 2); give it once: only the "
        "last would count")


def test_a_long_cut_without_a_terminal_logs_its_progress_as_lines(capsys):
    """stderr not a terminal (a log): a cut shorter than LOG_PROGRESS_AFTER_S says nothing,
    a longer one a line once it is due, then at most one per LOG_PROGRESS_EVERY_S, and one
    at the end (clock by hand: 0, 5, 12, 20, 41, 50 s)."""
    from machinesim import cli

    times = iter([0.0, 5.0, 9.0])
    show = cli._progress_bar(False, clock=lambda: next(times))
    show(0, 100)
    show(100, 100)  # done at 9 s: shorter than 10 s, nothing said
    assert capsys.readouterr().err == ""
    times = iter([0.0, 5.0, 12.0, 20.0, 41.0, 50.0])
    show = cli._progress_bar(False, clock=lambda: next(times))
    for done in (0, 10, 30, 60, 100):
        show(done, 100)
    assert capsys.readouterr().err.splitlines() == [
        "  cutting: 10/100 sweeps (10 %), 12 s",   # first due at 10 s
        "  cutting: 100/100 sweeps (100 %), 50 s",  # 20 and 41 s: before 12 + 30 s
    ]
    assert cli._progress_bar(True) is None  # --quiet


def test_a_log_names_the_stage_building_the_sweeps_before_cutting(capsys):
    """The sweeps of a ball end mill take tens of seconds to build before the cut (a raster
    of 3,819: 22 s, said nothing): the engine's stage is named in the line."""
    from machinesim import cli

    times = iter([0.0, 11.0, 20.0, 45.0])
    show = cli._progress_bar(False, clock=lambda: next(times))
    show(500, 3848, stage="building")
    show(3848, 3848, stage="building")
    show(3819, 3819)
    assert capsys.readouterr().err.splitlines() == [
        "  building: 500/3848 sweeps (12 %), 11 s",
        "  building: 3848/3848 sweeps (100 %), 20 s",
        "  cutting: 3819/3819 sweeps (100 %), 45 s",
    ]
