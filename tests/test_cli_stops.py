"""Outputs written together or not at all, and stops: closed output streams, an unwritable
output or a failing disk leaving neither file, Ctrl-C, SIGHUP and a gone terminal during
the cut, while the outputs are renamed in, and while loading, with their exit statuses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from cli_helpers import CUT, GROOVES, ROOT, assert_clean_failure, entry_point, run

import machinesim
import machinesim.cutting
import machinesim.nc
from machinesim.cli import main

#: grooves.nc: four 90-deg V grooves 20 um deep right across the 10 mm block: each removes
#: a triangle of depth d and width 2 d (area d^2) over 10 mm.
GROOVES_MM3 = 4 * 0.020**2 * 10.0


@pytest.mark.parametrize("closed", [(2,), (1, 2)], ids=["stderr", "stdout and stderr"])
def test_a_cut_started_with_closed_output_streams_writes_its_files(tmp_path, closed):
    # `machinesim cut ... 2>&-` (a daemon's or a cron line's closed descriptors): Python sets
    # sys.stderr to None, and the cut ended in "internal error: AttributeError: 'NoneType'
    # object has no attribute 'isatty'", exit 1, nothing written
    out, report = tmp_path / "part.ply", tmp_path / "report.json"
    done = subprocess.run(
        [*entry_point(), "cut", str(GROOVES), *CUT[:-1], "--out", str(out), "--report",
         str(report)], preexec_fn=lambda: [os.close(fd) for fd in closed], timeout=300)
    assert done.returncode == 0 and out.is_file()
    assert json.loads(report.read_text())["removed_volume_mm3"] == pytest.approx(
        GROOVES_MM3, rel=1e-9)


@pytest.mark.parametrize("bad", ["out", "report"])
def test_an_unwritable_output_leaves_neither_file(tmp_path, capsys, bad):
    paths = {"out": tmp_path / "part.ply", "report": tmp_path / "report.json"}
    paths[bad] = tmp_path / "missing folder" / paths[bad].name
    code, _, err = run(["cut", GROOVES, *CUT, "--out", paths["out"], "--report", paths["report"]],
                       capsys)
    assert_clean_failure(code, err, f"{paths[bad]}: cannot write the", "does not exist")
    assert list(tmp_path.iterdir()) == []


def test_a_failure_while_writing_leaves_neither_file(tmp_path, capsys, monkeypatch):
    """Both destinations pass the checks, then the disk fails on the second rename."""
    import machinesim._io as io

    out, report = tmp_path / "part.ply", tmp_path / "report.json"
    real = os.replace

    def second_fails(src, dst):
        if Path(dst) == report:
            raise OSError(28, "No space left on device")
        real(src, dst)

    monkeypatch.setattr(io.os, "replace", second_fails)
    code, _, err = run(["cut", GROOVES, *CUT, "--out", out, "--report", report], capsys)
    assert_clean_failure(code, err, "report.json: cannot write: No space left on device")
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_during_the_cut_exits_130_and_writes_nothing(tmp_path, capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(machinesim.cutting, "cut", interrupted)
    code, _, err = run(["cut", GROOVES, *CUT, "--out", tmp_path / "part.ply"], capsys)
    assert_clean_failure(code, err, "interrupted; nothing was written", status=130)
    assert list(tmp_path.iterdir()) == []


def test_a_stop_whose_terminal_is_gone_still_exits_with_its_status(tmp_path, monkeypatch):
    """SIGHUP as the terminal closes: the last line cannot be written (EIO, as a pty whose
    other end closed answers). The status is still 129 and nothing is written. The failed
    write had raised out of the handler: status 1, after a traceback to the same dead
    terminal (seen with the cut's stderr on a pty closed before SIGHUP)."""
    import errno

    from machinesim._interrupts import HungUp

    class Closed:
        def write(self, text):
            raise OSError(errno.EIO, "Input/output error")

        def flush(self):
            raise OSError(errno.EIO, "Input/output error")

    def hung_up(*args, **kwargs):
        raise HungUp

    monkeypatch.setattr(machinesim.cutting, "cut", hung_up)
    monkeypatch.setattr(sys, "stderr", Closed())
    assert main([str(a) for a in ["cut", GROOVES, *CUT, "--out", tmp_path / "part.ply"]]) == 129
    assert list(tmp_path.iterdir()) == []


def _cut_with_a_hook(tmp_path, hook: str, terminal: dict) -> subprocess.CompletedProcess:
    """``machinesim cut`` of the grooves to tmp_path's part.ply and report.json (each holding
    "old" before), in a process that first runs ``hook`` (Python, which may wrap ``os`` calls
    to send the process a signal at a known point), with a terminal's signal dispositions."""
    for name in ("part.ply", "report.json"):
        (tmp_path / name).write_text("old")
    code = f"{hook}\nimport sys\nfrom machinesim.cli import main\nsys.exit(main())\n"
    return subprocess.run([sys.executable, "-c", code, "cut", str(GROOVES), *CUT,
                           "--out", str(tmp_path / "part.ply"),
                           "--report", str(tmp_path / "report.json")],
                          capture_output=True, text=True, cwd=ROOT, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(ROOT)}, **terminal)


def test_a_closed_terminal_while_the_part_is_written_leaves_the_old_files_and_no_temporary(
        tmp_path, as_in_a_terminal):
    """SIGHUP (the terminal closed, an ssh session dropped) once the part's bytes are in its
    temporary file: handled as SIGTERM is, status 129 and one line; the old part and report
    stay and no temporary file is left. (SIGHUP's default action ended the process there:
    status -1, and .part.ply.*.tmp stayed beside the part for good.)"""
    hook = ("import os, signal, time\nreal = os.fsync\n"
            "def fsync(fd):\n    real(fd)\n    os.kill(os.getpid(), signal.SIGHUP)\n"
            "    time.sleep(5)\nos.fsync = fsync")
    result = _cut_with_a_hook(tmp_path, hook, as_in_a_terminal)
    assert_clean_failure(result.returncode, result.stderr, "machinesim: hung up; nothing was "
                         "written", status=129)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]
    assert {p.read_text() for p in tmp_path.iterdir()} == {"old"}


def test_a_ctrl_c_as_the_outputs_are_renamed_in_says_they_were_written(tmp_path,
                                                                        as_in_a_terminal):
    """SIGINT just as the report is renamed over the old one: the renames finish (the stop is
    held back until then: part and report are this run's, whole), and the line says so. It
    said 'interrupted; nothing was written' (status 130) beside this run's part and report,
    the old ones gone."""
    hook = ("import os, signal, time\nreal = os.replace\n"
            "def replace(src, dst):\n    real(src, dst)\n"
            "    if str(dst).endswith('report.json'):\n"
            "        os.kill(os.getpid(), signal.SIGINT)\n        time.sleep(0.5)\n"
            "os.replace = replace")
    result = _cut_with_a_hook(tmp_path, hook, as_in_a_terminal)
    part, report = tmp_path / "part.ply", tmp_path / "report.json"
    assert_clean_failure(result.returncode, result.stderr, status=130)
    assert result.stderr == (f"machinesim: interrupted; {part} and {report} were written "
                             "whole before it; nothing else was written\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]
    data = json.loads(report.read_text())
    assert data["part_file"] == str(part)
    assert data["removed_volume_mm3"] == pytest.approx(GROOVES_MM3, rel=1e-9)
    from machinesim.viewer.meshes import read_ply

    assert len(read_ply(part)[1]) > 0  # a whole PLY (a torn one is refused)


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs Linux /proc")
def test_ctrl_c_while_loading_exits_130_in_one_line(tmp_path, as_in_a_terminal, interrupted):
    """SIGINT once the process maps SciPy's own libraries (not numpy's scipy_openblas): only
    the viewer loads SciPy, inside `main`, so the process is importing it or building the
    page."""
    page = tmp_path / "machine.html"
    process = subprocess.Popen([*entry_point(), "view", "robonano_a0ib", "--html", str(page)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               **as_in_a_terminal)
    _, err = interrupted(process, "site-packages/scipy/")
    assert_clean_failure(process.returncode, err, "interrupted", status=130)
    assert not page.exists()


@pytest.mark.parametrize("signum", ["SIGTERM", "SIGINT"])
def test_a_stop_after_the_command_is_done_is_ignored(signum, as_in_a_terminal):
    """A stop that lands after the command's work is done and said, as the interpreter ends
    (Python puts the default actions back as it finalises, some 0.3 s after a cut): the
    process exits with the command's status. It died of the signal with no line (a parent
    saw -15: 1 of 10 SIGTERMs at random over a cut, 4 of 14 over a finished campaign's
    resume), though its files were whole and said. The child runs as the command does
    (``sys.argv[0]`` the ``machinesim`` script) and sends itself the signal once `main`
    returned."""
    child = ("import os, signal, sys, time\n"
             "sys.argv[0] = os.path.join(os.path.dirname(sys.executable), 'machinesim')\n"
             "from machinesim.cli import main\n"
             "status = main(['machines'])\n"
             f"os.kill(os.getpid(), signal.{signum})\n"
             "time.sleep(1.0)\n"
             "sys.exit(status)\n")
    done = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                          timeout=120, **as_in_a_terminal)
    assert (done.returncode, done.stderr) == (0, "")
    assert "grooving_4axis" in done.stdout
