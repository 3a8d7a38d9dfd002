"""Files: read with errors that name the user's path, written whole (or together) or not at all.

Every file-system problem (missing file, a folder given as a file, a folder that is not
there or cannot be written, a full disk) becomes a `FileError` (an `InputError`, and an
`OSError`) whose ``source`` is the path the user gave: the command line prints it as one
line, the Python API raises it. Nothing is renamed into place after a Ctrl-C or SIGTERM,
and a rename under way finishes first (`machinesim._interrupts`). A folder written whole
is `machinesim._staged`'s; JSON text, written and read, is `machinesim._json`'s.
"""

from __future__ import annotations

import argparse
import errno
import hashlib
import json
import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path

from machinesim import _interrupts
from machinesim._interrupts import ctrl_c_deferred
from machinesim.exceptions import FileError, InputError

#: Longest file name component (bytes) where the file system does not say (POSIX NAME_MAX).
_NAME_MAX = 255
#: Characters of the final name kept in a temporary file's name, so that it stays short.
TEMP_STEM = 64


def os_reason(exc: OSError) -> str:
    """What an OSError says went wrong, for a message ("No space left on device")."""
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
            raise FileError(f"{broken_link(path) or 'no such file'}; expected the {what}",
                            source=str(path))
        if not path.is_file():
            # a FIFO or device would block or never end: refuse it before opening
            raise FileError(f"{not_a_regular_file(path)}; expected the {what}",
                            source=str(path))
        with open(path, "rb"):
            pass
    except FileError:  # an OSError too: not wrapped in "cannot read" a second time
        raise
    except OSError as exc:
        raise FileError(f"cannot read the {what}: {os_reason(exc)}", source=str(path)) from None
    return path


def broken_link(path) -> str | None:
    """What ``path``, which does not exist as far as ``stat`` sees, is when a symbolic link
    is why, for a message in place of "no such file" (which ``ls``, showing the link,
    belies): "is a symbolic link to 'b.urdf', which does not exist", or, for links that lead
    round in a loop (or a folder of its path that is one), "cannot be reached: too many
    levels of symbolic links (a loop)". None for a path that is simply not there."""
    try:
        os.stat(path)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "cannot be reached: too many levels of symbolic links (a loop)"
        if os.path.islink(path):
            return f"is a symbolic link to {os.readlink(path)!r}, which does not exist"
    return None


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
                         f"{os_reason(exc)}", source=str(path)) from None
    return path


def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError):
        return _NAME_MAX


def _temp_head(path: Path) -> str:
    return f".{path.name[:TEMP_STEM]}."


def _temp_prefix(path: Path) -> str:
    """The start of a temporary file's name beside ``path``: ``.NAME.PID@HOST-`` (the name
    cut to `TEMP_STEM` characters, HOST `process_space`), so that a later write can tell
    those of a killed run."""
    return f"{_temp_head(path)}{os.getpid()}@{process_space()}-"


#: The host's id, stable across reboots (systemd's machine-id(5); the D-Bus copy is the same).
MACHINE_ID_FILE = "/etc/machine-id"


def process_space() -> str:
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


def _clear_stale_temps(path: Path, names: list[str]) -> None:
    """Remove the temporary files a killed run (SIGKILL, a power loss: nothing could run)
    left beside ``path``: ``.NAME.PID@HOST-XXXXXXXX.tmp`` of a process that is gone
    (`pid_alive`). They were never renamed into place, so no reader took them for ``path``,
    but they stayed for good, one per killed write. Those of live runs are left alone, and
    those of another host or PID namespace (HOST not this process's `process_space`),
    whose process this one cannot ask about. ``names``: the folder's entries."""
    head = _temp_head(path)
    names = [name for name in names if name.startswith(head)]
    space = f"@{process_space()}"
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
    try:  # one listing for both: a campaign's trials folder holds one file per trial
        names = [entry.name for entry in os.scandir(path.parent)]
    except OSError:
        names = []
    _undo_killed_sets(path.parent, names)
    _clear_stale_temps(path, names)
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
    return FileError(f"cannot write: {os_reason(exc)}", source=str(path))


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
        if _interrupts._ctrl_c_seen:  # as what it was: SIGTERM is `Terminated` (143)
            raise _interrupts._stop_kind
        # a Ctrl-C or SIGTERM during the renames is held until they and the removal of the
        # old files' second names are done: one landing between a rename and its record
        # left the new file without its old one and the first put back (a report beside
        # another run's part), and one in the removals left .NAME.old files behind
        with ctrl_c_deferred():
            _rename_all(staged)
            if _interrupts._written is not None:  # within: a stop held till now is told so
                _interrupts._written.extend(str(path) for path, _ in staged)
    finally:
        for _, temp in staged:
            Path(temp).unlink(missing_ok=True)


def _rename_all(staged: list[tuple[Path, str]]) -> None:
    """Rename every staged file into place; on any failure put the old files back. Several
    files are renamed under a journal (`_journal`), so that a run killed between two
    renames (SIGKILL, a power loss: nothing of it can run) is undone by the next write
    beside the first of them (`_undo_killed_sets`). The journal is written before the old
    files' second names are made and removed after they are: a run killed at any step
    leaves none of them but under its journal."""
    done: list[tuple[Path, str | None]] = []
    backups: list[str | None] = []
    failing = staged[0][0]
    journal = None
    try:
        if len(staged) > 1:
            backups = [_backup_name(path) for path, _ in staged]
            journal = _journal(staged, backups)
            for (failing, _), backup in zip(staged, backups, strict=True):
                if backup is not None:
                    _backup(failing, backup)
        else:
            backups = [None]
        for (failing, temp), backup in zip(staged, backups, strict=True):
            os.replace(temp, failing)
            done.append((failing, backup))
    except BaseException as exc:
        for path, backup in reversed(done):
            if backup is not None:
                os.replace(backup, path)
            else:
                path.unlink(missing_ok=True)
        for backup in backups[len(done):]:
            if backup is not None:
                Path(backup).unlink(missing_ok=True)
        if journal is not None:
            Path(journal).unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise _write_error(failing, exc) from None
        raise
    for _, backup in done:  # killed among these, the journal finds every file new: kept
        if backup is not None:
            Path(backup).unlink(missing_ok=True)
    if journal is not None:
        Path(journal).unlink(missing_ok=True)


def _journal(staged: list[tuple[Path, str]], backups: list[str | None]) -> str:
    """Write, beside the first file, ``.NAME.PID@HOST-XXXXXXXX.set``: each file with its old
    version's second name (`_backup_name`; None: there was none) and the new version's
    identity (`_identity`), flushed to disk before the second names are made. Removed once
    every file is renamed in and the second names are removed."""
    entries = [[os.path.abspath(path), backup, _identity(temp)]
               for (path, temp), backup in zip(staged, backups, strict=True)]
    first = staged[0][0]
    handle, name = tempfile.mkstemp(dir=first.parent, prefix=_temp_prefix(first), suffix=".set")
    try:  # a journal not written whole (a full disk) is not left behind
        with os.fdopen(handle, "w", encoding="utf-8") as file:
            json.dump(entries, file)
            file.flush()
            os.fsync(file.fileno())
    except BaseException:
        Path(name).unlink(missing_ok=True)
        raise
    return name


def _identity(path) -> list[int]:
    """A file's inode, size and modification time (ns): a rename keeps them, and a file
    written since differs in one of them (an inode alone is reused once freed)."""
    status = os.lstat(path)  # the new version is a file; a link put there since is not it
    return [status.st_ino, status.st_size, status.st_mtime_ns]


def _undo_killed_sets(folder: Path, names: list[str]) -> None:
    """Undo the renames of files written together by a run killed among them (its journal,
    `_journal`, left in ``folder``): each file that is still that run's new version gets its
    old version back (or is removed when there was none), so that a part is not left beside
    another run's report. A file written since (`_identity`) is left alone, and so is a
    journal that is not one this user's run could have written (`_journal_entries`).
    ``names``: the folder's entries."""
    for name in (name for name in names if name.endswith(".set")):
        pid, at, host = name[:-len(".set")].rpartition("-")[0].rpartition(".")[2].partition("@")
        if not (pid.isdigit() and at and host == process_space() and int(pid) != os.getpid()
                and not pid_alive(int(pid))):
            continue
        try:
            entries = _journal_entries(folder, name, f"{pid}@{host}")
            if entries is None:
                continue
            new = [os.path.lexists(target) and _identity(target) == identity
                   for target, _, identity in entries]
            for (target, backup, _), is_new in zip(entries, new, strict=True):
                # every file new: killed after its renames, the set is whole and stays
                if is_new and not all(new):
                    if backup is None:
                        os.unlink(target)
                    elif os.path.exists(backup):
                        os.replace(backup, target)
                if backup is not None:
                    Path(backup).unlink(missing_ok=True)
            os.unlink(folder / name)
        except OSError:
            pass


def _journal_entries(folder: Path, name: str, run: str) -> list | None:
    """The entries of the journal ``name`` in ``folder`` left by the run ``run``
    (``PID@HOST``), or None when it is not one that run wrote: a journal is a list of
    files to put back and second names to remove, and one from elsewhere (another user's, in
    a shared folder; a corrupt one) had the next write remove or replace whatever it named
    (``/etc/...``, ``../x``). A journal is this user's regular file; its first file is the
    one beside it whose name it starts with; every file is an absolute, normal path, and
    each second name is that run's ``.NAME.PID@HOST-XXXXXXXX.old`` beside its file; each
    identity three integers. A journal cut short as it was written (killed before it was
    flushed, so before any rename) has no entries."""
    journal = folder / name
    status = os.lstat(journal)
    if not stat.S_ISREG(status.st_mode) or (hasattr(os, "getuid")
                                            and status.st_uid != os.getuid()):
        return None
    try:
        entries = json.loads(journal.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError):
        return []
    if not isinstance(entries, list) or not entries:
        return None
    for entry in entries:
        if not (isinstance(entry, list) and len(entry) == 3):
            return None
        target, backup, identity = entry
        if not (isinstance(target, str) and os.path.isabs(target)
                and os.path.normpath(target) == target
                and isinstance(identity, list) and len(identity) == 3
                and all(type(number) is int for number in identity)):
            return None
        if backup is not None:
            head = f"{_temp_head(Path(target))}{run}-"
            base = os.path.basename(backup) if isinstance(backup, str) else ""
            if not (isinstance(backup, str) and os.path.dirname(backup) == os.path.dirname(target)
                    and base.startswith(head) and base.endswith(".old")
                    and len(base) == len(head) + _TEMP_RANDOM + len(".old")):
                return None
    first = Path(entries[0][0])
    if not (name.startswith(f"{_temp_head(first)}{run}-")
            and os.path.samefile(first.parent, folder)):
        return None
    return entries


def _backup_name(path: Path) -> str | None:
    """The name `_backup` gives the current ``path``'s second name, or None if there is no
    file (absolute: a later run, in another working folder, reads it from the journal)."""
    if not path.is_file():
        return None
    return os.path.abspath(path.parent / f"{_temp_prefix(path)}{secrets.token_hex(4)}.old")


def _backup(path: Path, name: str) -> None:
    """Give the current ``path`` the second name ``name`` (a hard link, else a copy)."""
    try:
        os.link(path, name)
    except OSError:
        shutil.copy2(path, name)


def stdout_to_null(stream) -> None:
    """Send ``stream``'s file descriptor (stdout) to the null device: its reader went away
    (``... | head -1``), and what is still written, or flushed at exit, must not raise
    BrokenPipeError again (the signal module's notes on SIGPIPE)."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, stream.fileno())
    os.close(null)


__all__ = ["FileError", "stdout_to_null", "check_readable_file", "check_writable",
           "not_a_regular_file", "write_atomic", "write_together"]
