"""Files: read with errors that name the user's path, written whole (or together) or not at all.

Every file-system problem (missing file, a folder given as a file, a folder that is not
there or cannot be written, a full disk) becomes a `FileError` (an `InputError`, and an
`OSError`) whose ``source`` is the path the user gave: the command line prints it as one
line, the Python API raises it. Nothing is renamed into place after a Ctrl-C or SIGTERM,
and a rename or folder swap under way finishes first (`machinesim._interrupts`).
"""

from __future__ import annotations

import argparse
import errno
import hashlib
import json
import math
import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path

from machinesim import _interrupts
from machinesim._interrupts import _ctrl_c_deferred
from machinesim.exceptions import FileError, InputError, MachineSimError

#: Longest file name component (bytes) where the file system does not say (POSIX NAME_MAX).
_NAME_MAX = 255
#: Characters of the final name kept in a temporary file's name, so that it stays short.
_TEMP_STEM = 64


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__


def check_readable_file(path, what: str) -> Path:
    """``path`` as a Path, after checking it is a regular file this process can read.

    Parameters
    ----------
    path : str or os.PathLike
        The file the user named.
    what : str
        What the file is, for the message (e.g. ``"NC program"``).

    Raises
    ------
    InputError
        Naming ``path`` when it does not exist, is a folder or a device, or cannot be opened;
        key 'path' when it is no file name (None, bytes, a number: `check_path`).
    """
    path = Path(check_path(path, f"reading the {what}"))
    try:
        if path.is_dir():
            raise FileError(f"is a folder; expected the {what} file", source=str(path))
        if not path.exists():
            raise FileError(f"no such file; expected the {what}", source=str(path))
        if not path.is_file():
            # a FIFO or device would block or never end: refuse it before opening
            raise FileError(f"{not_a_regular_file(path)}; expected the {what}",
                            source=str(path))
        with open(path, "rb"):
            pass
    except FileError:  # an OSError too: not wrapped in "cannot read" a second time
        raise
    except OSError as exc:
        raise FileError(f"cannot read the {what}: {_reason(exc)}", source=str(path)) from None
    return path


def not_a_regular_file(path) -> str:
    """What ``path``, which exists and is neither a regular file nor a folder, is, for a
    message: "is a named pipe (FIFO), not a regular file", and where a symbolic link leads
    ("links to /dev/zero, a character device, ..."), since ``ls`` shows the link only."""
    path = Path(path)
    mode = path.stat().st_mode
    kind = ("a named pipe (FIFO)" if stat.S_ISFIFO(mode)
            else "a character device" if stat.S_ISCHR(mode)
            else "a block device" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "a special file")
    if path.is_symlink():
        return f"links to {os.path.realpath(path)}, {kind}, not a regular file"
    return f"is {kind}, not a regular file"


def file_name(text: str) -> Path:
    """An argparse type for an output file: ``text`` as a Path, refused when it ends in a
    path separator (``Path`` drops it, and a file would be written where a folder was meant).
    """
    if not text:
        # Path('') is '.': the refusal then quoted a '.' the user never typed
        raise argparse.ArgumentTypeError("'' is empty; expected a file name")
    if text.endswith(("/", os.sep)):
        raise argparse.ArgumentTypeError(f"{text!r} ends in '/', which names a folder; "
                                         "expected a file name")
    return Path(text)


def input_path(text: str) -> Path:
    """An argparse type for a file or folder to read (a program, an error model, a tool
    table): ``text`` as a Path, refused when empty (an unset shell variable). ``Path("")`` is
    the current folder, and the refusal quoted a '.' the user never typed (``cut '' ...``:
    "'.': is a folder; expected the NC program file")."""
    if not text:
        raise argparse.ArgumentTypeError("'' is empty; expected a file name")
    return Path(text)


def named(text: str) -> str:
    """An argparse type for a name or a path (``--machine``, ``view``'s target), refused
    when empty, which read as the current folder (``view ''`` showed the folder)."""
    if not text:
        raise argparse.ArgumentTypeError("'' is empty; expected a name or a path")
    return text


def folder_path(text: str) -> Path:
    """An argparse type for a folder to write (a scenario's ``--out``), refused when empty,
    which read as the current folder."""
    if not text:
        raise argparse.ArgumentTypeError("'' is empty; expected a folder name")
    return Path(text)


def check_writable(path, what: str) -> Path:
    """``path`` as a Path, after checking a file can be written there (nothing is left behind).

    A temporary file is created in the folder and removed again: this is the test that
    counts (permissions, read-only mounts, a full folder), not a guess from mode bits.

    Raises
    ------
    InputError
        Naming ``path`` when it is a folder, its folder is missing or not a folder, the name
        is too long, or the folder cannot be written.
    """
    path = Path(path)
    folder = path.parent
    if path.name in ("", ".", ".."):
        raise FileError(f"expected a file name for the {what}", source=str(path))
    try:
        if path.is_dir():
            raise FileError(f"is a folder; expected a file name for the {what}",
                             source=str(path))
        if not folder.is_dir():
            reason = "is not a folder" if folder.exists() else "does not exist"
            raise FileError(f"cannot write the {what}: the folder {str(folder)!r} {reason}",
                             source=str(path))
        if len(os.fsencode(path.name)) > _name_max(folder):
            raise FileError(f"cannot write the {what}: the file name is longer than this "
                             f"file system allows ({_name_max(folder)} bytes)",
                             source=str(path))
        handle, temp = tempfile.mkstemp(dir=folder, prefix=_temp_prefix(path), suffix=".tmp")
        os.close(handle)
        os.unlink(temp)
    except FileError:
        raise  # an OSError too: said already, not to be wrapped in itself
    except OSError as exc:
        raise FileError(f"cannot write the {what} in the folder {str(folder)!r}: "
                         f"{_reason(exc)}", source=str(path)) from None
    return path


def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError):
        return _NAME_MAX


def _temp_head(path: Path) -> str:
    return f".{path.name[:_TEMP_STEM]}."


def _temp_prefix(path: Path) -> str:
    """The start of a temporary file's name beside ``path``: ``.NAME.PID@HOST-`` (the name
    cut to `_TEMP_STEM` characters, HOST `_process_space`), so that a later write can tell
    those of a killed run."""
    return f"{_temp_head(path)}{os.getpid()}@{_process_space()}-"


#: The host's id, stable across reboots (systemd's machine-id(5); the D-Bus copy is the same).
MACHINE_ID_FILE = "/etc/machine-id"


def _process_space() -> str:
    """Eight hex digits naming the space this process's id is counted in: the host's name,
    its machine id (`MACHINE_ID_FILE`, where there is one: two hosts may share a name, a
    distribution's default one) and, on Linux, the PID namespace
    (``/proc/self/ns/pid``; the first one's number is the same on every host). A folder
    shared by another host (NFS) or another container holds temporary files whose PID means
    nothing here: a live run's there is no process here, and was removed as a killed run's."""
    import socket

    parts = [socket.gethostname()]
    for read in (lambda: Path(MACHINE_ID_FILE).read_text(encoding="ascii").strip(),
                 lambda: os.readlink("/proc/self/ns/pid")):
        try:
            parts.append(read())
        except (OSError, ValueError):
            parts.append("")
    name = "\0".join(parts)
    return hashlib.sha1(name.encode("utf-8", "surrogateescape")).hexdigest()[:8]


#: Characters `tempfile.mkstemp` puts between a prefix and a suffix.
_TEMP_RANDOM = 8


def _clear_stale_temps(path: Path) -> None:
    """Remove the temporary files a killed run (SIGKILL, a power loss: nothing could run)
    left beside ``path``: ``.NAME.PID@HOST-XXXXXXXX.tmp`` of a process that is gone
    (`pid_alive`). They were never renamed into place, so no reader took them for ``path``,
    but they stayed for good, one per killed write. Those of live runs are left alone, and
    those of another host or PID namespace (HOST not this process's `_process_space`),
    whose process this one cannot ask about."""
    head = _temp_head(path)
    try:
        names = [e.name for e in os.scandir(path.parent) if e.name.startswith(head)]
    except OSError:
        return
    space = f"@{_process_space()}"
    for name in names:
        pid, dash, rest = name[len(head):].partition("-")
        pid, at, host = pid.partition("@")
        if (dash and pid.isdigit() and f"{at}{host}" == space and rest.endswith(".tmp")
                and len(rest) == _TEMP_RANDOM + len(".tmp") and int(pid) != os.getpid()
                and not pid_alive(int(pid))):
            try:
                os.unlink(path.parent / name)
            except OSError:
                pass


def _mode(path: Path) -> int:
    """Permissions for a new version of ``path``: the old file's, else 0666 less the umask."""
    try:
        return path.stat().st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _stage(path: Path, raw: bytes) -> str:
    """Write ``raw`` to a flushed temporary file beside ``path``; return its name. Those a
    killed run left beside ``path`` are removed first (`_clear_stale_temps`)."""
    _clear_stale_temps(path)
    handle, temp = tempfile.mkstemp(dir=path.parent, prefix=_temp_prefix(path), suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as file:
            file.write(raw)
            file.flush()
            os.fsync(file.fileno())
        os.chmod(temp, _mode(path))
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise
    return temp


def _write_error(path: Path, exc: OSError) -> FileError:
    folder = path.parent
    if exc.errno == errno.ENAMETOOLONG:
        return FileError(f"cannot write: the file name is longer than this file system allows "
                         f"({_name_max(folder)} bytes)", source=str(path))
    if not _asks(folder.is_dir):
        reason = "is not a folder" if _asks(folder.exists) else "does not exist"
        return FileError(f"cannot write: the folder {str(folder)!r} {reason}", source=str(path))
    if _asks(path.is_dir):
        return FileError("cannot write: it is a folder; expected a file name", source=str(path))
    return FileError(f"cannot write: {_reason(exc)}", source=str(path))


def _asks(question) -> bool:
    """``question()``, False when the file system cannot answer it (a name too long, no
    permission): the message then falls back to the error's own reason."""
    try:
        return question()
    except OSError:
        return False


def _raw(path, data: bytes | str, encoding: str) -> bytes:
    """The bytes to write: ``data`` encoded when text; bytes-like data as it is. Anything else
    is refused (``bytes(3)`` would write three NUL bytes)."""
    if isinstance(data, str):
        return data.encode(encoding)
    if isinstance(data, bytes | bytearray | memoryview):
        return bytes(data)
    raise InputError(f"Expected the data to write as str or bytes, got "
                     f"{type(data).__name__}", source=str(path))


def check_ending(path, ending: str, writer: str, what: str) -> None:
    """Refuse a ``path`` whose name does not end in ``.<ending>`` (any case), before anything
    is written: export_x3p("map.png") wrote x3p bytes under a picture's name without a word,
    which a viewer then failed on. ``writer`` and ``what`` (the function, what it writes)
    are for the message, as `machinesim.workpiece.Part.export_ply` words its own. A path
    that is no path (a file object, bytes, None) is refused too (`check_path`)."""
    name = check_path(path, f"{writer} writes {what} to a file name ending in .{ending}")
    suffix = os.path.splitext(name)[1]
    if suffix.lower() == f".{ending}":
        return
    found = f"ends in {suffix}" if suffix else "has no ending"
    raise InputError(f"{writer} writes {what}, and the path {found}: expected a name ending "
                     f"in .{ending}", source=name, key="path")


def check_path(path, writer: str = "the writer") -> str:
    """``path`` (str or os.PathLike of str) as a str; anything else (a file object, bytes, None)
    refused (InputError, key 'path'): it had gone on to ``Path(path)``, a TypeError traceback
    (``export_x3p(io.BytesIO(), ...)``: 'expected str, bytes or os.PathLike object, not
    BytesIO'). ``writer`` says what was to be written, for the message."""
    name = os.fspath(path) if isinstance(path, str | os.PathLike) else None
    if not isinstance(name, str):
        raise InputError(f"{writer}: expected a file name (str or pathlib.Path), got "
                         f"{type(path).__name__}", key="path")
    return name


def write_atomic(path, data: bytes | str, encoding: str = "utf-8") -> None:
    """Write ``data`` to ``path`` whole or not at all.

    The bytes go to a temporary file in the same folder, are flushed to disk, and the file is
    renamed over ``path`` (atomic on POSIX): an interrupted run leaves the old file or none,
    never half of one. The new file keeps the old file's permissions, or gets the usual ones
    (0666 less the umask) when there was none.

    Raises
    ------
    InputError
        Naming ``path`` for any file-system problem (missing folder, no permission, disk
        full); the old file, if any, is then untouched.
    """
    write_together([(path, data)], encoding)


def write_together(items: Iterable[tuple[object, bytes | str]], encoding: str = "utf-8") -> None:
    """Write several files so that either all of them are written or none is changed.

    Each file is first written whole to a temporary file beside it (see `write_atomic`).
    Only when every one is on disk are they renamed into place, one after the other; if a
    rename fails, the files already renamed get their old contents back (or are removed when
    there were none), so a part is never left without its report, nor beside an old one.

    Parameters
    ----------
    items : iterable of (path, data)
        Destinations (distinct) and their contents (bytes, or str encoded with ``encoding``).

    Raises
    ------
    InputError
        Naming the path whose write failed.
    """
    plan = [(Path(check_path(path, "writing a file")), _raw(path, data, encoding))
            for path, data in items]
    if len({os.path.abspath(p) for p, _ in plan}) != len(plan):
        raise InputError("the same file is named twice as an output: "
                         + ", ".join(str(p) for p, _ in plan), source=str(plan[0][0]))
    staged: list[tuple[Path, str]] = []
    try:
        for path, raw in plan:
            try:
                staged.append((path, _stage(path, raw)))
            except OSError as exc:
                raise _write_error(path, exc) from None
        if _interrupts._ctrl_c_seen:
            raise KeyboardInterrupt
        # a Ctrl-C or SIGTERM during the renames is held until they and the removal of the
        # old files' second names are done: one landing between a rename and its record
        # left the new file without its old one and the first put back (a report beside
        # another run's part), and one in the removals left .NAME.old files behind
        with _ctrl_c_deferred():
            _rename_all(staged)
            if _interrupts._written is not None:  # within: a stop held till now is told so
                _interrupts._written.extend(str(path) for path, _ in staged)
    finally:
        for _, temp in staged:
            Path(temp).unlink(missing_ok=True)


def _rename_all(staged: list[tuple[Path, str]]) -> None:
    """Rename every staged file into place; on any failure put the old files back."""
    done: list[tuple[Path, str | None]] = []
    failing = staged[0][0]
    try:
        for failing, temp in staged:
            backup = _backup(failing) if len(staged) > 1 else None
            try:
                os.replace(temp, failing)
            except BaseException:
                if backup is not None:
                    Path(backup).unlink(missing_ok=True)
                raise
            done.append((failing, backup))
    except BaseException as exc:
        for path, backup in reversed(done):
            if backup is not None:
                os.replace(backup, path)
            else:
                path.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise _write_error(failing, exc) from None
        raise
    for _, backup in done:
        if backup is not None:
            Path(backup).unlink(missing_ok=True)


def _backup(path: Path) -> str | None:
    """A second name for the current ``path`` (hard link, else a copy), or None if none."""
    if not path.is_file():
        return None
    name = str(path.parent / f"{_temp_prefix(path)}{secrets.token_hex(4)}.old")
    try:
        os.link(path, name)
    except OSError:
        shutil.copy2(path, name)
    return name


# ------------------------------------------------------------------- folders written whole

#: Staging folders of this process that are still being written (not stale).
_ours: set[str] = set()


def _folder_stem(target: Path) -> str:
    """The part of a staging folder's name that names ``target`` (shortened with a hash when
    its name is long, so that the sibling's name stays within the file system's limit)."""
    name = target.name
    if len(os.fsencode(name)) <= 160:
        return name
    digest = hashlib.sha1(os.fsencode(name)).hexdigest()[:12]
    return f"{name[:_TEMP_STEM]}~{digest}"


def _sibling_kind(entry: str, stem: str) -> tuple[str, int] | None:
    """(``"partial"`` or ``"old"``, pid) when ``entry`` is a staging or swapped-out folder
    of ``stem`` made in this process's PID space (``.STEM.partial-PID@HOST.TOKEN``,
    ``.STEM.old-PID@HOST.TOKEN``, HOST `_process_space`), else None: another host's or
    container's PID is no process here, and its live run's folder was removed as stale."""
    for kind in ("partial", "old"):
        head = f".{stem}.{kind}-"
        if entry.startswith(head):
            marked, _, _ = entry[len(head):].partition(".")
            pid, at, host = marked.partition("@")
            if pid.isdigit() and at and host == _process_space():
                return kind, int(pid)
    return None


def _alive(pid: int, path: Path) -> bool:
    """Whether the run that named a folder with ``pid`` may still be writing it."""
    if pid == os.getpid():
        return str(path) in _ours
    return pid_alive(pid)


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this machine may still run: False only once it is known
    to be gone (True for someone else's process, and where one cannot ask harmlessly)."""
    if os.name != "posix":  # no harmless way to ask: leave it alone
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # someone else's process
        return True
    return True


def clear_stale_folders(target) -> None:
    """Remove the staging folders a killed run (SIGKILL, power loss) left beside ``target``.

    A run killed in the middle of a swap may have left the previous folder under its
    swapped-out name and none under ``target``: it is put back. Folders of runs that are
    still alive are left alone.
    """
    target = Path(target)
    stem = _folder_stem(target)
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return
    for entry in entries:
        found = _sibling_kind(entry.name, stem)
        if found is None or _alive(found[1], Path(entry.path)):
            continue
        if found[0] == "old" and not os.path.lexists(target):
            try:
                os.rename(entry.path, target)
                continue
            except OSError:
                pass
        shutil.rmtree(entry.path, ignore_errors=True)


def _link_or_copy(source: str, destination: str) -> None:
    # every file of a report is replaced by renaming a new one over it (`write_atomic`), so
    # a hard link is never written through; a copy where links are not possible
    try:
        os.link(source, destination)
    except OSError:
        shutil.copy2(source, destination)


def stdout_to_null(stream) -> None:
    """Send ``stream``'s file descriptor (stdout) to the null device: its reader went away
    (``... | head -1``), and what is still written, or flushed at exit, must not raise
    BrokenPipeError again (the signal module's notes on SIGPIPE)."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, stream.fileno())
    os.close(null)


def _refuse_working_folder(given: Path, target: Path) -> None:
    """Refuse a folder to be replaced whole (`StagedFolder`) that is the working directory
    or holds it: ``scenario --out .`` swapped the working directory out and removed it, then
    ended in a FileNotFoundError traceback (exit 1) once it looked up the now missing
    working directory, and the shell it ran in stood in the removed folder, seeing none of
    the report."""
    try:
        here = Path(os.path.realpath(os.getcwd()))
    except OSError:  # the working directory is gone already: nothing to protect
        return
    if here == target or target in here.parents:
        where = "is" if here == target else "holds"
        raise InputError(f"{str(given)!r} {where} the working directory "
                         f"({str(here)!r}); the report replaces its folder whole, "
                         "which would remove the folder this command and its shell stand "
                         "in: expected a folder apart from it, e.g. --out report",
                         key="out")


class StagedFolder:
    """A folder written whole or not at all.

    Its files are written into a staging folder beside it (``.NAME.partial-PID@HOST.TOKEN``, in
    the same parent, so on the same file system); `commit` swaps that folder in: the old
    folder is renamed aside, the staging folder renamed to the name, the old one removed. A
    Ctrl-C during the swap is held back until it is done. `discard` removes the staging
    folder and leaves the old folder as it was. Staging folders of killed runs are removed
    when the next one begins (`clear_stale_folders`).

    Parameters
    ----------
    path : str or os.PathLike
        The folder (its parent is made when missing). A symbolic link is followed: the
        folder it names is the one replaced.

    Attributes
    ----------
    final : Path
        ``path`` as given.
    path : Path or None
        Where the files go now (None once committed for good, or discarded).
    commits : int
        How many times the staged folder was swapped in.

    Raises
    ------
    OSError
        When the parent or the staging folder cannot be made.
    InputError
        When the folder is the process's working directory or holds it (``--out .``): the
        swap would remove the folder the process, and the shell it runs in, stand in.
    """

    def __init__(self, path) -> None:
        self.final = Path(path)
        self.target = Path(os.path.realpath(self.final))
        _refuse_working_folder(self.final, self.target)
        self.commits = 0
        self.path: Path | None = None
        self.target.parent.mkdir(parents=True, exist_ok=True)
        clear_stale_folders(self.target)
        self._begin(seed=False)

    def _sibling(self, kind: str) -> Path:
        return self.target.parent / (f".{_folder_stem(self.target)}.{kind}-{os.getpid()}@"
                                     f"{_process_space()}.{secrets.token_hex(4)}")

    def _begin(self, seed: bool) -> None:
        path = self._sibling("partial")
        self.path = path
        _ours.add(str(path))
        if seed and self.target.is_dir():
            shutil.copytree(self.target, path, symlinks=True, copy_function=_link_or_copy)
        else:
            path.mkdir()
        try:
            os.chmod(path, self.target.stat().st_mode & 0o7777)
        except OSError:
            pass

    def commit(self, keep_going: bool = False) -> None:
        """Swap the staged folder in. With ``keep_going``, the writing goes on in a new
        staging folder that starts as a copy of the folder just committed (hard links),
        for a run that adds to a report it has already made whole.

        Raises
        ------
        KeyboardInterrupt
            Without swapping anything, when a Ctrl-C was seen (`ctrl_c_remembered`).
        FileError
            When the swap fails; the old folder is then in place.
        """
        if self.path is None:
            raise MachineSimError("the staged folder was already committed or discarded")
        if _interrupts._ctrl_c_seen:
            raise KeyboardInterrupt
        staging = self.path
        with _ctrl_c_deferred():
            aside = None
            try:
                if os.path.lexists(self.target):
                    aside = self._sibling("old")
                    os.rename(self.target, aside)
                try:
                    os.rename(staging, self.target)
                except BaseException:
                    if aside is not None:
                        os.rename(aside, self.target)
                    raise
            except OSError as exc:
                raise FileError(f"cannot put the new folder in place: {_reason(exc)}",
                                source=str(self.final)) from None
            _ours.discard(str(staging))
            self.commits += 1
            self.path = None
            if aside is not None:
                shutil.rmtree(aside, ignore_errors=True)
        if keep_going:
            self._begin(seed=True)

    def discard(self) -> None:
        """Remove the staging folder (the folder itself stays as it was); idempotent."""
        if self.path is not None:
            shutil.rmtree(self.path, ignore_errors=True)
            _ours.discard(str(self.path))
            self.path = None


def json_text(data, what: str = "report") -> str:
    """``data`` as indented JSON text, refusing NaN and infinity (JSON has neither).

    Raises
    ------
    MachineSimError
        Naming the key whose value is not a finite number; nothing should then be written.
    """
    try:
        return json.dumps(data, indent=2, allow_nan=False) + "\n"
    except ValueError:
        bad = ", ".join(f"{key} = {value!r}" for key, value in _non_finite(data))
        if not bad:
            raise
        raise MachineSimError(f"the {what} has values that are not finite numbers ({bad}); "
                              "JSON has no NaN or infinity, so nothing was written") from None


def _non_finite(value, key: str = ""):
    if isinstance(value, float) and not math.isfinite(value):
        yield key or "<value>", value
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _non_finite(v, f"{key}.{k}" if key else str(k))
    elif isinstance(value, list | tuple):
        for i, v in enumerate(value):
            yield from _non_finite(v, f"{key}[{i}]")


def read_json(path, what: str = "JSON file"):
    """The JSON value in the file ``path`` (UTF-8), with errors naming the path and position.

    NaN and Infinity, which Python's json would accept, are refused: they are not JSON.

    Raises
    ------
    InputError
        When the file cannot be read, is not UTF-8 text, or is not valid JSON.
    """
    path = check_readable_file(path, what)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise FileError(f"cannot read the {what}: {_reason(exc)}", source=str(path)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); "
                         f"expected the {what} as JSON", source=str(path)) from None

    def refuse(constant: str):
        raise InputError(f"{constant} is not a finite number, which JSON requires; expected "
                         f"the {what} as JSON", source=str(path))

    def number(literal: str) -> float:
        value = float(literal)
        if not math.isfinite(value):
            refuse(literal)
        return value

    try:
        return json.loads(text, parse_constant=refuse, parse_float=number)
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON ({exc.msg}); expected the {what}", source=str(path),
                         line=exc.lineno, column=exc.colno) from None
    except RecursionError:
        raise InputError(f"nested too deeply to be the {what}", source=str(path)) from None


__all__ = ["FileError", "StagedFolder", "stdout_to_null", "check_readable_file",
           "check_writable", "clear_stale_folders", "json_text", "not_a_regular_file",
           "read_json", "write_atomic", "write_together"]
