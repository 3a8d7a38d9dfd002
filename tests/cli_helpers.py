"""What the command line's test files (tests/test_cli.py, test_cli_servo.py) share (not
collected: no test_ prefix): a cut's usual options, `machinesim ARGV` run in this process and
a refusal's checks."""

from __future__ import annotations

from machinesim.cli import main

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
