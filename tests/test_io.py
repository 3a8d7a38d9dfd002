"""Files: atomic writes with ordinary permissions, several written together, every
file-system problem an InputError naming the path, JSON without NaN, export units."""

from __future__ import annotations

import errno
import json
import math
import os
import signal
import struct
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from machinesim import _interrupts, _io, _json, _staged
from machinesim.exceptions import InputError, MachineSimError
from machinesim.workpiece import EXPORT_UNITS, stock_from_spec


def test_new_files_get_the_umask_permissions_and_old_ones_keep_theirs(tmp_path):
    umask = os.umask(0o022)
    try:
        target = tmp_path / "a.txt"
        _io.write_atomic(target, "one")
        assert target.stat().st_mode & 0o777 == 0o644
        target.chmod(0o600)
        _io.write_atomic(target, b"two")
        assert target.read_bytes() == b"two" and target.stat().st_mode & 0o777 == 0o600
    finally:
        os.umask(umask)


def test_an_interrupted_write_leaves_the_old_file_and_no_debris(tmp_path, monkeypatch):
    target = tmp_path / "part.ply"
    target.write_text("old")

    def fail(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(_io.os, "replace", fail)
    with pytest.raises(KeyboardInterrupt):
        _io.write_atomic(target, "new")
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply"]


# ------------------------------------------------------------- file-system errors, named


def test_a_missing_folder_a_folder_and_a_file_as_folder_are_input_errors(tmp_path):
    (tmp_path / "folder").mkdir()
    (tmp_path / "file").write_text("x")
    cases = {
        tmp_path / "missing" / "part.ply": "the folder '.*missing' does not exist",
        tmp_path / "folder": "is a folder",
        tmp_path / "file" / "part.ply": "the folder '.*file' is not a folder",
    }
    for path, words in cases.items():
        with pytest.raises(InputError, match=words) as raised:
            _io.write_atomic(path, "data")
        assert raised.value.source == str(path)
        # also an OSError: callers written for open() still catch it
        assert isinstance(raised.value, OSError) and isinstance(raised.value, MachineSimError)
        with pytest.raises(InputError, match=words) as checked:
            _io.check_writable(path, "part")
        # said once: the message is not wrapped in a second "cannot write" of itself
        assert str(checked.value).count(str(path)) == 1
        assert str(checked.value).count("cannot write") <= 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "folder"]
    assert list((tmp_path / "folder").iterdir()) == []


def _locked_folder(tmp_path) -> Path:
    """A folder this process cannot create files in: a read-only one, or as root /sys."""
    if os.geteuid() != 0:
        folder = tmp_path / "locked"
        folder.mkdir()
        folder.chmod(0o500)
        return folder
    try:
        os.close(os.open("/sys/machinesim-probe", os.O_CREAT | os.O_WRONLY))
    except OSError:
        return Path("/sys")
    os.unlink("/sys/machinesim-probe")
    pytest.skip("running as root with a writable /sys: no folder refuses writes")


def test_a_folder_that_refuses_writes_is_an_input_error(tmp_path):
    folder = _locked_folder(tmp_path)
    try:
        with pytest.raises(InputError, match="part.ply: cannot write the part in the folder"):
            _io.check_writable(folder / "part.ply", "part")
        with pytest.raises(InputError, match="part.ply: cannot write"):
            _io.write_atomic(folder / "part.ply", "data")
    finally:
        if folder.is_relative_to(tmp_path):
            folder.chmod(0o700)


def test_a_full_disk_is_an_input_error_and_leaves_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "report.json"
    target.write_text("old")

    def full(_fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(_io.os, "fsync", full)
    with pytest.raises(InputError, match="report.json: cannot write: No space left on device"):
        _io.write_atomic(target, "new")
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_a_full_disk_as_the_journal_is_written_leaves_no_journal(tmp_path, monkeypatch):
    # two files are renamed in under a journal; a disk that fills as the journal is flushed
    # had left an empty .NAME.PID@HOST-XXXX.set beside the old files
    (tmp_path / "part.ply").write_text("old part")
    (tmp_path / "report.json").write_text("old report")
    real_fsync = os.fsync
    calls = []

    def full_on_the_journal(fd):
        calls.append(fd)
        if os.readlink(f"/proc/self/fd/{fd}").endswith(".set"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real_fsync(fd)

    monkeypatch.setattr(_io.os, "fsync", full_on_the_journal)
    with pytest.raises(InputError, match="part.ply: cannot write: No space left on device"):
        _io.write_together([(tmp_path / "part.ply", "new part"),
                            (tmp_path / "report.json", "new report")])
    assert len(calls) == 3  # the two staged files, then the journal
    assert (tmp_path / "part.ply").read_text() == "old part"
    assert (tmp_path / "report.json").read_text() == "old report"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]


def test_readable_file_checks_name_the_path(tmp_path):
    (tmp_path / "dir").mkdir()
    with pytest.raises(InputError, match="nope.nc: no such file; expected the NC program"):
        _io.check_readable_file(tmp_path / "nope.nc", "NC program")
    # a symbolic link in a loop, or to nothing, was "no such file", though ls shows it
    (tmp_path / "loop.toml").symlink_to("loop.toml")
    (tmp_path / "moved.toml").symlink_to("errors/moved.toml")
    with pytest.raises(InputError) as raised:
        _io.check_readable_file(tmp_path / "loop.toml", "error model (--errors)")
    assert str(raised.value) == (f"{tmp_path / 'loop.toml'}: cannot be reached: too many "
                                 "levels of symbolic links (a loop); expected the error model "
                                 "(--errors)")
    with pytest.raises(InputError) as raised:
        _io.check_readable_file(tmp_path / "moved.toml", "tool table")
    assert str(raised.value) == (f"{tmp_path / 'moved.toml'}: is a symbolic link to "
                                 "'errors/moved.toml', which does not exist; expected the tool "
                                 "table")
    with pytest.raises(InputError) as raised:  # was wrapped: "cannot read ...: .../dir: is a"
        _io.check_readable_file(tmp_path / "dir", "NC program")
    assert str(raised.value) == f"{tmp_path / 'dir'}: is a folder; expected the NC program file"
    fifo = tmp_path / "pipe.nc"
    os.mkfifo(fifo)
    with pytest.raises(InputError) as raised:
        _io.check_readable_file(fifo, "NC program")  # opening it would block forever
    assert str(raised.value) == (f"{fifo}: is a named pipe (FIFO), not a regular file; "
                                 "expected the NC program")
    link = tmp_path / "zero.nc"
    link.symlink_to(os.devnull)
    with pytest.raises(InputError) as raised:
        _io.check_readable_file(link, "NC program")
    assert str(raised.value) == (f"{link}: links to {os.devnull}, a character device, not a "
                                 "regular file; expected the NC program")


# ------------------------------------------------------------------- written together


def test_files_written_together_all_appear(tmp_path):
    part, report = tmp_path / "part.ply", tmp_path / "report.json"
    _io.write_together([(part, b"\x00\x01"), (report, "{}\n")])
    assert part.read_bytes() == b"\x00\x01" and report.read_text() == "{}\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]


def test_when_the_second_rename_fails_the_first_file_is_put_back(tmp_path, monkeypatch):
    part, report = tmp_path / "part.ply", tmp_path / "report.json"
    part.write_text("old part")  # the first file existed: it gets its old contents back
    real = os.replace

    def second_fails(src, dst):
        if Path(dst) == report:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real(src, dst)

    monkeypatch.setattr(_io.os, "replace", second_fails)
    with pytest.raises(InputError, match="report.json: cannot write: Input/output error"):
        _io.write_together([(part, "new part"), (report, "new report")])
    assert part.read_text() == "old part"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply"]
    part.unlink()  # the first file is new: it is removed again
    with pytest.raises(InputError):
        _io.write_together([(part, "new part"), (report, "new report")])
    assert list(tmp_path.iterdir()) == []


def test_an_interrupt_between_the_renames_leaves_neither_file(tmp_path, monkeypatch):
    part, report = tmp_path / "part.ply", tmp_path / "report.json"
    real = os.replace

    def interrupted(src, dst):
        if Path(dst) == report:
            raise KeyboardInterrupt
        real(src, dst)

    monkeypatch.setattr(_io.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        _io.write_together([(part, "part"), (report, "report")])
    assert list(tmp_path.iterdir()) == []


def test_a_real_ctrl_c_during_the_renames_is_held_until_both_files_are_new(tmp_path,
                                                                              monkeypatch):
    """A SIGINT arriving as the last rename returns (a campaign stopped while its
    campaign.nc and summary were renamed into place): it rolled the first file back and
    left the second new, its old contents gone, or left .NAME.old files behind."""
    part, report = tmp_path / "part.ply", tmp_path / "report.json"
    part.write_text("old part")
    report.write_text("old report")
    real = os.replace

    def renamed_then_stopped(src, dst):
        real(src, dst)
        if Path(dst) == report:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.5)  # the handler runs here, at the latest

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        monkeypatch.setattr(_io.os, "replace", renamed_then_stopped)
        with pytest.raises(KeyboardInterrupt):
            _io.write_together([(part, "new part"), (report, "new report")])
    finally:
        signal.signal(signal.SIGINT, before)
    assert (part.read_text(), report.read_text()) == ("new part", "new report")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply", "report.json"]


def test_a_ctrl_c_a_library_swallowed_still_stops_the_write(tmp_path):
    """A real SIGINT caught by ``except BaseException`` (as trimesh's optional imports do):
    the handler remembers it, nothing is written, and leaving puts Python's handler back."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with _interrupts.ctrl_c_remembered():
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)  # the handler raises here, at the latest
            except BaseException:  # noqa: BLE001 - the library that swallows it
                pass
            with pytest.raises(KeyboardInterrupt):
                _io.write_together([(tmp_path / "part.ply", "part")])
        assert signal.signal(signal.SIGINT, before) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, before)
    assert list(tmp_path.iterdir()) == []
    _io.write_together([(tmp_path / "part.ply", "part")])  # outside the block: written
    assert (tmp_path / "part.ply").read_text() == "part"


@pytest.mark.parametrize("signum, raised", [(signal.SIGTERM, _interrupts.Terminated),
                                             (signal.SIGHUP, _interrupts.HungUp)],
                         ids=["SIGTERM", "SIGHUP"])
def test_a_sigterm_a_library_swallowed_stops_the_write_as_what_it_was(tmp_path, signum, raised):
    """A real SIGTERM (SIGHUP) caught by a library, as a weakref callback's is (Python
    prints it as "Exception ignored" and goes on): the write after it and a staged folder's
    swap stop as `Terminated` (`HungUp`), so the command says "terminated", status 143
    (129). They raised a plain KeyboardInterrupt: a `kill` of a campaign as it assembled
    its results ended in "machinesim: interrupted; ...", status 130."""
    before = signal.signal(signum, signal.SIG_DFL)
    try:
        with _interrupts.ctrl_c_remembered():
            staged = _staged.StagedFolder(tmp_path / "report")
            try:
                os.kill(os.getpid(), signum)
                time.sleep(1.0)  # the handler raises here, at the latest
            except BaseException:  # noqa: BLE001 - the library that swallows it
                pass
            stops = []
            for stopped_step in (lambda: _io.write_together([(tmp_path / "part.ply", "part")]),
                                 staged.commit):
                try:
                    stopped_step()
                except KeyboardInterrupt as stop:  # a plain one fails below, not the session
                    stops.append(stop)
            staged.discard()
    finally:
        signal.signal(signum, before)
    assert [type(stop) for stop in stops] == [raised, raised]
    assert [_interrupts.stopped(stop)[1] for stop in stops] == [128 + signum] * 2
    assert list(tmp_path.iterdir()) == []


def test_a_stop_in_a_finaliser_is_remembered_and_not_reported(tmp_path):
    """A real SIGTERM landing in a ``__del__`` (as one did in a WeakKeyDictionary's callback
    while a campaign assembled its results): Python reports such an exception through
    `sys.unraisablehook` ("Exception ignored in: ...", a traceback, "Terminated:" on stderr
    before the command's one line) and goes on. It is remembered (the write after it stops
    as `Terminated`) and not reported; another exception there still is, and the hook is
    put back on leaving."""
    reported = []

    def record(unraisable):
        reported.append(unraisable)

    before_hook = sys.unraisablehook
    sys.unraisablehook = record

    class Finalised:
        def __init__(self, signum=None):
            self.signum = signum

        def __del__(self):
            if self.signum is None:
                raise ValueError("not a stop")
            os.kill(os.getpid(), self.signum)
            time.sleep(1.0)  # the handler raises here, at the latest

    before = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with _interrupts.ctrl_c_remembered():
            Finalised()
            Finalised(signal.SIGTERM)
            with pytest.raises(_interrupts.Terminated):
                _io.write_together([(tmp_path / "part.ply", "part")])
        assert sys.unraisablehook is record
    finally:
        signal.signal(signal.SIGTERM, before)
        sys.unraisablehook = before_hook
    assert [type(r.exc_value) for r in reported] == [ValueError]
    assert list(tmp_path.iterdir()) == []


def _a_real_signal_stops_the_write(tmp_path, signum, raised):
    """Send the process `signum` within `ctrl_c_remembered`: it is raised as `raised`, and
    a write after it is stopped (nothing written); leaving puts the default action back.
    Gives what was raised."""
    before = signal.signal(signum, signal.SIG_DFL)
    try:
        with _interrupts.ctrl_c_remembered():
            with pytest.raises(raised) as stop:
                os.kill(os.getpid(), signum)
                time.sleep(1.0)  # the handler raises here, at the latest
            with pytest.raises(KeyboardInterrupt):
                _io.write_together([(tmp_path / "part.ply", "part")])
        assert signal.getsignal(signum) is signal.SIG_DFL
    finally:
        signal.signal(signum, before)
    assert list(tmp_path.iterdir()) == []
    return stop.value


def test_sigterm_is_raised_as_terminated_and_stops_the_write(tmp_path):
    """A real SIGTERM within the block: raised as `Terminated` (a KeyboardInterrupt, so every
    clean-up a Ctrl-C has runs), status 143 and its own word; nothing is written after it,
    and leaving puts the default action back (the process ended where it stood before)."""
    stop = _a_real_signal_stops_the_write(tmp_path, signal.SIGTERM, _interrupts.Terminated)
    assert _interrupts.stopped(stop) == ("terminated", 128 + 15)
    assert _interrupts.stopped(KeyboardInterrupt()) == ("interrupted", 128 + 2)


def test_sighup_is_raised_as_hung_up_and_stops_the_write(tmp_path):
    """A real SIGHUP (the terminal closed) within the block: raised as `HungUp` (a
    `Terminated`, so a live viewer's caller stops too), status 129 and its own word; nothing
    is written after it, and leaving puts the default action back."""
    stop = _a_real_signal_stops_the_write(tmp_path, signal.SIGHUP, _interrupts.HungUp)
    assert isinstance(stop, _interrupts.Terminated)
    assert _interrupts.stopped(stop) == ("hung up", 128 + 1)


def test_a_write_removes_the_temporary_files_of_killed_runs_and_only_theirs(tmp_path):
    """SIGKILL (nothing can run) while a part is staged leaves its temporary file: never
    renamed, so no reader takes it for the part, but it stayed for good, one per killed
    run. The next write of the same file removes it; a live run's is left alone."""
    import subprocess
    import sys

    part = tmp_path / "part.ply"
    part.write_text("old")
    code = ("import os, sys, time\nfrom machinesim import _io\nreal = os.fsync\n"
            "def fsync(fd):\n    real(fd)\n    print('staged', flush=True)\n"
            "    time.sleep(60)\nos.fsync = fsync\n_io.write_atomic(sys.argv[1], 'killed')\n")
    root = Path(__file__).resolve().parents[1]
    killed = subprocess.Popen([sys.executable, "-c", code, str(part)], stdout=subprocess.PIPE,
                              text=True, env={**os.environ, "PYTHONPATH": str(root)})
    try:
        assert killed.stdout.readline() == "staged\n"
    finally:
        killed.kill()
        killed.wait()
    left = [p.name for p in tmp_path.iterdir() if p.name != "part.ply"]
    assert len(left) == 1 and left[0].startswith(".part.ply.") and left[0].endswith(".tmp")
    # pytest's parent: running
    live = tmp_path / f".part.ply.{os.getppid()}@{_io.process_space()}-abcd1234.tmp"
    live.write_text("being written")
    _io.write_atomic(part, "new")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["part.ply", live.name])
    assert part.read_text() == "new"


def test_a_write_leaves_the_temporary_files_of_another_hosts_runs(tmp_path, monkeypatch):
    """A folder shared with another host (NFS) or container holds its live runs' temporary
    files, whose PID is no process here: the cleaner of killed runs' files removed them,
    and that run's rename then failed. Another host's staged file is left alone."""
    import socket
    import subprocess
    import sys

    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    dead = ended.pid  # no process here (unless reused within this test)
    assert not _io.pid_alive(dead)
    part = tmp_path / "part.ply"
    with monkeypatch.context() as other_host:  # the other host's run, staging part.ply
        other_host.setattr(socket, "gethostname", lambda: "another-host")
        other_host.setattr(os, "getpid", lambda: dead)
        staged = Path(_io._stage(part, b"the other host's part"))
    _io.write_atomic(part, "ours")
    assert staged.read_bytes() == b"the other host's part"
    assert part.read_text() == "ours"
    os.replace(staged, part)  # the other host's rename goes through
    assert part.read_bytes() == b"the other host's part"


def test_a_write_leaves_the_temporary_files_of_a_host_of_the_same_name(tmp_path, monkeypatch):
    """Two hosts may share a name (a distribution's default) and the first PID namespace's
    number (the same on every Linux host): their machine ids tell them apart."""
    import subprocess
    import sys

    other_id = tmp_path / "machine-id"
    other_id.write_text("0123456789abcdef0123456789abcdef\n")
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    part = tmp_path / "part.ply"
    with monkeypatch.context() as other_host:
        other_host.setattr(_io, "MACHINE_ID_FILE", str(other_id), raising=False)
        other_host.setattr(os, "getpid", lambda: ended.pid)
        staged = Path(_io._stage(part, b"theirs"))
    _io.write_atomic(part, "ours")
    assert staged.read_bytes() == b"theirs" and part.read_text() == "ours"


def test_a_sigterm_during_a_folder_swap_waits_for_the_swap(tmp_path, monkeypatch):
    """SIGTERM while the staged folder is renamed in: the swap finishes (the new folder in
    place, no staging or old folder beside it), and `Terminated` is raised after."""
    target = tmp_path / "report"
    target.mkdir()
    (target / "old.txt").write_text("old")
    before = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    real = os.rename

    def rename_then_term(src, dst):
        real(src, dst)
        if Path(dst) == target:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.2)  # a handler that raised would do so here

    try:
        with _interrupts.ctrl_c_remembered():
            staged = _staged.StagedFolder(target)
            (staged.path / "new.txt").write_text("new")
            monkeypatch.setattr(_io.os, "rename", rename_then_term)
            with pytest.raises(_interrupts.Terminated):
                staged.commit()
    finally:
        signal.signal(signal.SIGTERM, before)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]
    assert sorted(p.name for p in target.iterdir()) == ["new.txt"]


def test_the_same_file_twice_is_refused_before_writing(tmp_path):
    with pytest.raises(InputError, match="the same file is named twice"):
        _io.write_together([(tmp_path / "a", "1"), (tmp_path / ".." / tmp_path.name / "a", "2")])
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------- JSON


def _no_constants(name):
    raise AssertionError(f"{name} in JSON text")


def test_json_text_refuses_nan_and_infinity_naming_the_key():
    text = _json.json_text({"a": 1.5, "b": [0.0, 2.0]})
    assert json.loads(text, parse_constant=_no_constants) == {"a": 1.5, "b": [0.0, 2.0]}
    with pytest.raises(MachineSimError, match=r"machining_time_s = nan.*b\.c\[1\] = inf"):
        _json.json_text({"machining_time_s": math.nan, "b": {"c": [1.0, math.inf]}})


@pytest.mark.parametrize(("content", "words"), [
    (bytes(range(256)), "not UTF-8 text"),
    (b'{"a": NaN}', "NaN is not a finite number"),
    (b'{"a": 1e999}', "1e999 is not a finite number"),
    (b'{"a": [1, 2}', r"line 1, column 12: not valid JSON"),
    (b"[" * 100000 + b"]" * 100000, "nested too deeply|not valid JSON"),
])
def test_read_json_names_the_file_and_what_is_wrong(tmp_path, content, words):
    path = tmp_path / "report.json"
    path.write_bytes(content)
    with pytest.raises(InputError, match=words) as raised:
        _json.read_json(path, "cut report")
    assert raised.value.source == str(path)


# ---------------------------------------------------------------------- export units


def test_stl_and_glb_are_millimetres_and_say_so_ply_stays_metres(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    part = stock_from_spec("block:1x2x3@10,20,0")  # mm: x 10..11, y 20..22, z -3..0
    part.export_stl(tmp_path / "part.stl")
    part.export_glb(tmp_path / "part.glb")
    part.export_ply(tmp_path / "part.ply")
    expected_mm = np.array([[10.0, 20.0, -3.0], [11.0, 22.0, 0.0]])
    stl = tmp_path / "part.stl"
    assert b"units: mm" in stl.read_bytes()[:80]
    mesh = trimesh.load(stl)
    np.testing.assert_allclose(mesh.bounds, expected_mm, rtol=1e-7)  # float32 coordinates
    assert mesh.volume == pytest.approx(6.0, rel=1e-6)  # mm^3
    glb = (tmp_path / "part.glb").read_bytes()
    length = struct.unpack("<I", glb[12:16])[0]
    assert json.loads(glb[20:20 + length])["asset"]["extras"]["unit"] == "mm"
    mesh = trimesh.load(tmp_path / "part.glb", force="mesh")
    np.testing.assert_allclose(mesh.bounds, expected_mm, rtol=1e-7)
    assert mesh.volume == pytest.approx(6.0, rel=1e-6)
    ply = (tmp_path / "part.ply").read_bytes()
    assert b"comment machinesim part, metres" in ply[:200]
    assert b"property double x" in ply[:200]
    assert EXPORT_UNITS == {"ply": "m", "stl": "mm", "glb": "mm"}
    for file_format in EXPORT_UNITS:
        assert part.encode(file_format) == (tmp_path / f"part.{file_format}").read_bytes()


_KILLED_BETWEEN_RENAMES = """
import os, signal, sys
from pathlib import Path
from machinesim import _io
folder, replaced = Path(sys.argv[1]), []
real = os.replace
def replace(src, dst):
    real(src, dst)
    replaced.append(dst)
    if len(replaced) == 1:  # SIGKILL between the part's rename and the report's
        os.kill(os.getpid(), signal.SIGKILL)
os.replace = replace
_io.write_together([(folder / "part.ply", "new part"), (folder / "report.json", "new report")])
"""


@pytest.mark.parametrize("old", [True, False], ids=["old files", "no files before"])
def test_a_run_killed_between_the_renames_is_undone_by_the_next_write(tmp_path, old):
    """SIGKILL (nothing can run) between the renames of files written together: the new
    part stood beside the old report (or alone), with the old part's second name
    (``.part.ply....old``) left for good. The next write beside the part undoes the killed
    run's renames from its journal (``.part.ply....set``): the old files, or none, and no
    journal or second names left."""
    import subprocess
    import sys

    if old:
        (tmp_path / "part.ply").write_text("old part")
        (tmp_path / "report.json").write_text("old report")
    killed = subprocess.run([sys.executable, "-c", _KILLED_BETWEEN_RENAMES, str(tmp_path)],
                            timeout=120)
    assert killed.returncode == -signal.SIGKILL
    assert (tmp_path / "part.ply").read_text() == "new part"  # the state the kill left
    _io.write_atomic(tmp_path / "other.txt", "x")  # any later write in the folder
    left = {p.name: p.read_text() for p in tmp_path.iterdir()
            if not p.name.startswith(".report.json.")}  # the killed run's unrenamed temp
    assert left == {"other.txt": "x", **({"part.ply": "old part", "report.json": "old report"}
                                          if old else {})}


def test_undoing_a_killed_set_leaves_a_file_written_since(tmp_path):
    """The undo takes back only the killed run's own new version (its inode): a part
    written since by another means stays."""
    import subprocess
    import sys

    (tmp_path / "part.ply").write_text("old part")
    subprocess.run([sys.executable, "-c", _KILLED_BETWEEN_RENAMES, str(tmp_path)], timeout=120)
    (tmp_path / "part.ply").unlink()
    (tmp_path / "part.ply").write_text("written since")
    _io.write_atomic(tmp_path / "other.txt", "x")
    assert (tmp_path / "part.ply").read_text() == "written since"
    assert not any(p.name.endswith((".set", ".old")) for p in tmp_path.iterdir())


_KILLED_RELATIVE = _KILLED_BETWEEN_RENAMES.replace(
    "folder, replaced = Path(sys.argv[1]), []", "folder, replaced = Path('.'), []")


def test_a_killed_set_written_by_relative_names_is_undone_from_another_folder(tmp_path,
                                                                              monkeypatch):
    """``machinesim cut ... -o part.ply`` names its files relative to its working folder.
    The journal kept the old part's second name as written (relative), so the next write
    from another working folder looked for it there: the new part stayed beside the old
    report, the journal was removed and the old part's second name left for good."""
    import subprocess
    import sys

    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "part.ply").write_text("old part")
    (folder / "report.json").write_text("old report")
    killed = subprocess.run([sys.executable, "-c", _KILLED_RELATIVE], cwd=folder, timeout=120)
    assert killed.returncode == -signal.SIGKILL
    assert (folder / "part.ply").read_text() == "new part"
    monkeypatch.chdir(tmp_path)
    _io.write_atomic(Path("out") / "other.txt", "x")
    assert (folder / "part.ply").read_text() == "old part"
    assert (folder / "report.json").read_text() == "old report"
    assert not any(p.name.endswith((".set", ".old")) for p in folder.iterdir())


def _journal_of_a_dead_run(folder, entries, first="part.ply"):
    """A journal ``.FIRST.PID@HOST-abcdefgh.set`` in ``folder`` of a run that is gone."""
    import subprocess
    import sys

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    run = f"{gone.pid}@{_io.process_space()}"
    (folder / f".{first}.{run}-abcdefgh.set").write_text(json.dumps(entries))
    return run


@pytest.mark.parametrize("kind", ["second name outside", "dot-dot",
                                  "second name of another file"])
def test_a_journal_naming_other_files_is_left_alone(tmp_path, kind):
    """A journal is a list of files to put back and second names to remove, read by the
    next write in its folder: one naming files elsewhere (a corrupt one, or one put in a
    shared folder) had that write remove them (a second name is removed whatever it is; a
    file still 'the new version', its inode, size and mtime, removed when it had no old
    one). Such a journal is not acted on, and the files it names stay. (A file of the set
    may lie in another folder, a report beside its part or not: only its identity guards it,
    and a journal is taken only from this user's own files.)"""
    folder = tmp_path / "out"
    folder.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    status = victim.stat()
    identity = [status.st_ino, status.st_size, status.st_mtime_ns]
    part = str(folder / "part.ply")
    entries = {
        "second name outside": [[part, str(victim), [1, 2, 3]]],
        "dot-dot": [[part, None, [1, 2, 3]], [f"{folder}/../victim.txt", None, identity]],
        "second name of another file": [[part, f"{folder}/../victim.txt", [1, 2, 3]]],
    }[kind]
    _journal_of_a_dead_run(folder, entries)
    _io.write_atomic(folder / "other.txt", "x")
    assert victim.read_text() == "keep me"


def test_a_journal_of_the_run_with_its_own_second_names_is_still_undone(tmp_path):
    """The checks keep a journal as `_journal` writes it: killed between the renames, the
    new part gets its old version back from its second name, the report (never renamed)
    stays, and both second names go."""
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "part.ply").write_text("new part")
    (folder / "report.json").write_text("old report")
    status = (folder / "part.ply").stat()
    run = _journal_of_a_dead_run(folder, [])
    backups = [folder / f".part.ply.{run}-0123abcd.old",
               folder / f".report.json.{run}-4567cdef.old"]
    backups[0].write_text("old part")
    os.link(folder / "report.json", backups[1])
    next(folder.glob("*.set")).write_text(json.dumps(
        [[str(folder / "part.ply"), str(backups[0]),
          [status.st_ino, status.st_size, status.st_mtime_ns]],
         [str(folder / "report.json"), str(backups[1]), [1, 2, 3]]]))
    _io.write_atomic(folder / "other.txt", "x")
    assert {p.name: p.read_text() for p in folder.iterdir()} == {
        "other.txt": "x", "part.ply": "old part", "report.json": "old report"}


_KILLED_AT = """
import os, pathlib, shutil, signal, sys
from pathlib import Path
from machinesim import _io
folder, step = Path(sys.argv[1]), sys.argv[2]
def killing(real, when):
    def call(*args, **kwargs):
        if when(*args):
            os.kill(os.getpid(), signal.SIGKILL)
        return real(*args, **kwargs)
    return call
if step == "after a second name":  # the part's second name made, nothing else yet
    real_link = os.link
    def link(src, dst):
        real_link(src, dst)
        os.kill(os.getpid(), signal.SIGKILL)
    os.link = link
elif step == "removing the second names":  # both files renamed in
    pathlib.Path.unlink = killing(pathlib.Path.unlink, lambda p, *a: str(p).endswith(".old"))
_io.write_together([(folder / "part.ply", "new part"), (folder / "report.json", "new report")])
"""


@pytest.mark.parametrize("step", ["after a second name", "removing the second names"])
def test_a_run_killed_around_its_journal_leaves_no_second_names(tmp_path, step):
    """SIGKILL after the old part's second name (``.part.ply.PID@HOST-X.old``) was made and
    before the journal was written, or after the journal was removed and before the second
    names were: no journal named them, so they stayed for good, one per killed write. The
    next write leaves one whole set (old or new) and no second name or journal."""
    import subprocess
    import sys

    (tmp_path / "part.ply").write_text("old part")
    (tmp_path / "report.json").write_text("old report")
    killed = subprocess.run([sys.executable, "-c", _KILLED_AT, str(tmp_path), step],
                            timeout=120)
    assert killed.returncode == -signal.SIGKILL
    _io.write_atomic(tmp_path / "other.txt", "x")
    left = {p.name: p.read_text() for p in tmp_path.iterdir() if not p.name.endswith(".tmp")}
    kept = {"part.ply": left.pop("part.ply", None), "report.json": left.pop("report.json", None)}
    assert kept in ({"part.ply": "old part", "report.json": "old report"},
                    {"part.ply": "new part", "report.json": "new report"})
    assert left == {"other.txt": "x"}
