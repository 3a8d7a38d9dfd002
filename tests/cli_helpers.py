"""What the command line's test files (tests/test_cli_*.py) share (not collected: no test_
prefix): the example program and machine, a cut's usual options, `machinesim ARGV` run in
this process or the installed command, a refusal's checks and a cut's report read back."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from machinesim.cli import main

ROOT = Path(__file__).resolve().parents[1]
GROOVES = ROOT / "models" / "examples" / "grooves.nc"
GROOVING = ROOT / "models" / "grooving_4axis.urdf"

CUT = ["--machine", "grooving_4axis", "--tool", "v:90", "--stock", "block:10x10x2", "--quiet"]


def run(argv, capsys) -> tuple[int, str, str]:
    """Exit status, stdout and stderr of ``machinesim ARGV`` run in this process."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse: usage errors and --help
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def assert_clean_failure(code: int, err: str, *words: str, status: int = 2) -> None:
    """A refusal: the status, one line on stderr naming what is wrong, no traceback."""
    assert code == status, err
    assert "Traceback" not in err and "internal error" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("machinesim: "), err
    for word in words:
        assert word in err, f"{word!r} not in {err!r}"


def entry_point() -> list[str]:
    """The installed ``machinesim`` script (what users run), else ``python -m``."""
    script = Path(sys.executable).parent / "machinesim"
    return [str(script)] if script.exists() else [sys.executable, "-m", "machinesim.cli"]


def no_nan(constant: str):
    raise AssertionError(f"{constant} in a JSON report")


def cut_with_report(tmp_path, capsys, text: str, tool: str, stock: str):
    """Cut the NC ``text`` on grooving_4axis with ``tool`` and ``stock``; (stderr, the
    report's JSON) of a run that must succeed."""
    program, report = tmp_path / "program.nc", tmp_path / "r.json"
    program.write_text(text)
    code, _, err = run(["cut", program, "--machine", "grooving_4axis", "--tool", tool,
                        "--stock", stock, "--quiet", "--out", tmp_path / "p.ply",
                        "--report", report], capsys)
    assert code == 0, err
    return err, json.loads(report.read_text(), parse_constant=no_nan)
