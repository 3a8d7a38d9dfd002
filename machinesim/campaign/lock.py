"""A campaign folder's lock: one campaign at a time in a folder (`locked`, `refuse_busy`).

While a campaign runs it holds ``DIR/campaign.lock`` (`LOCK_NAME`), an exclusive kernel file
lock (`fcntl.flock`), so that a second run on DIR meanwhile is refused, naming the run that
holds it; the folder is made when missing (`_make_folder`), and a run stopped within the
block takes away what it made there that holds nothing. Moved from
`machinesim.campaign.results`, which re-exports its public names.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import stat
import time
from collections.abc import Iterator
from pathlib import Path

from machinesim._io import not_a_regular_file, pid_alive
from machinesim.exceptions import FileError, InputError

__all__ = ["HOLDER_WAIT_S", "LOCK_NAME", "locked", "refuse_busy"]


def _make_folder(path: Path) -> None:
    """Make the campaign folder ``path`` (not its trials/), refusing a file there."""
    if path.exists() and not path.is_dir():
        raise FileError("is a file; expected the campaign folder", source=str(path))
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _unmade(path, exc) from None


def _unmade(path: Path, exc: OSError) -> FileError:
    """The refusal of the folder ``path`` that mkdir could not make (``exc``), naming what
    is in its way: the file ``--out tmp/file.txt/campaign`` meets was told as 'Not a
    directory' of the folder asked for, and /proc's refusal of a new folder as 'No such file
    or directory' of a path whose folder is there."""
    above = path
    while above != above.parent and not _asks(above.parent.exists):
        above = above.parent
    above = above.parent
    # a symbolic link to nothing (its target moved or not yet made): mkdir meets the link
    # ('File exists'), which had been told as "'.' takes no new folder"
    dangling = next((p for p in (path, *path.parents)
                     if _asks(p.is_symlink) and not _asks(p.exists)), None)
    if dangling is not None:
        why = (f"{str(dangling)!r} is a symbolic link to {os.readlink(dangling)!r}, which "
               "does not exist")
    elif _asks(above.exists) and not _asks(above.is_dir):
        why = f"{str(above)!r} is a file, not a folder"
    elif path.exists() and not _asks(path.is_dir):  # trials/ made a file by hand, say
        why = f"{str(path)!r} is a file, not a folder"
    else:
        why = f"{str(above)!r} takes no new folder ({exc.strerror or exc})"
    return FileError(f"cannot make the campaign folder: {why}; expected a folder that can be "
                     "made and written, or one there", source=str(path))


def _asks(question) -> bool:
    """``question()``, False when the file system cannot answer it (no permission)."""
    try:
        return question()
    except OSError:
        return False


@contextlib.contextmanager
def locked(folder) -> Iterator[None]:
    """Hold ``folder/campaign.lock`` within the block, the folder made when missing; taken
    before campaign.json is read or written.

    Two campaigns run on one folder at the same time ran the same missing trials, each
    writing every one of their files. The lock is the kernel's: an exclusive `fcntl.flock`
    on the open file, held for the block and released when its process ends, however it
    ends (SIGKILL, a power loss), so a killed campaign's lock is free to the next run, and
    of two runs that find it at the same instant one takes it (both did when each removed
    the stale file, or the other's fresh one, and made its own). The file stays after the
    run, held by nobody; it names the pid and host of the run that took it last, for the
    message refusing a second run.

    A run stopped within the block (KeyboardInterrupt: Ctrl-C, or SIGTERM turned into one)
    takes away what it made here that holds nothing (`_unmade_when_stopped`): a Ctrl-C
    before campaign.json was written had left campaign.lock and an empty trials/ behind
    the command's 'interrupted; nothing was written'.
    """
    folder = Path(folder)
    try:
        import fcntl
    except ImportError:  # Windows
        raise FileError("cannot lock the campaign folder: campaigns need POSIX file locks "
                        "(fcntl.flock), which this Python lacks; run the campaign on Linux "
                        "or macOS", source=str(folder)) from None
    new_folders = _missing_folders(folder)
    _make_folder(folder)
    path = folder / LOCK_NAME
    had_trials = os.path.lexists(folder / "trials")
    # not through a symbolic link: the run writes its pid into the file, and a
    # campaign.lock linked to another file overwrote that file (it is no lock of ours)
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0)
    try:
        try:
            fd, made = os.open(path, flags | os.O_EXCL, 0o644), True
        except FileExistsError:
            fd, made = os.open(path, flags, 0o644), False
    except OSError as exc:
        raise _lock_refused(folder, exc) from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):  # a FIFO: its truncation failed as a bare
        os.close(fd)                            # 'Invalid argument', naming no file
        raise FileError(f"{LOCK_NAME} {not_a_regular_file(path)}; expected the campaign's "
                        "own lock file: remove it", source=str(folder))
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _busy(folder, _named_holder(path)) from None
        except OSError as exc:  # ENOLCK: a file system that takes no locks (NFS without)
            raise FileError(f"cannot lock the campaign's lock {LOCK_NAME}: "
                            f"{exc.strerror or exc}; expected a folder on a file system "
                            "that takes file locks (flock)", source=str(folder)) from None
        if not _same_file(fd, path):  # removed by the run that held it (stopped): it
            os.close(fd)              # is no longer the folder's lock; take the one there
            fd = -1
            with locked(folder):
                yield
            return
        os.ftruncate(fd, 0)
        os.write(fd, (json.dumps({"pid": os.getpid(), "host": socket.gethostname()})
                      + "\n").encode())
        try:
            yield
        except KeyboardInterrupt:
            _unmade_when_stopped(folder, made, had_trials)  # the lock still held
            os.close(fd)
            fd = -1
            for made_folder in new_folders:  # deepest first; another run's lock stays
                with contextlib.suppress(OSError):
                    made_folder.rmdir()
            raise
    finally:
        if fd >= 0:
            os.close(fd)  # the kernel releases the lock


def _missing_folders(folder: Path) -> list[Path]:
    """``folder`` and the folders above it that are not there (deepest first)."""
    missing = []
    while not os.path.lexists(folder) and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    return missing


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` is still the file open as ``fd``."""
    try:
        there = os.stat(path, follow_symlinks=False)
    except OSError:
        return False
    here = os.fstat(fd)
    return (there.st_dev, there.st_ino) == (here.st_dev, here.st_ino)


def _unmade_when_stopped(folder: Path, made_lock: bool, had_trials: bool) -> None:
    """Take away, for a run stopped while it holds ``folder``'s lock, what it made there that
    holds nothing: trials/ when empty and not there before, and the lock file when it made
    it (removed while still held: a run that opened it meanwhile finds it gone, `locked`).
    What was there before stays, and so do campaign.json and any trial file."""
    if not had_trials:
        with contextlib.suppress(OSError):  # not empty, or not a folder: kept
            (folder / "trials").rmdir()
    if made_lock:
        with contextlib.suppress(OSError):
            (folder / LOCK_NAME).unlink()


def refuse_busy(folder) -> None:
    """Refuse ``folder`` as `locked` would while another run holds its lock (`_busy`),
    leaving it as it is (no lock file made, none kept): for a refusal found before the lock
    is taken (`refuse_foreign`), which a run making the folder its campaign's just then
    meets (its campaign.json's temporary file there, no campaign.json yet) and had told as
    no campaign folder."""
    try:
        import fcntl
    except ImportError:  # Windows: `locked` says so
        return
    path = Path(folder) / LOCK_NAME
    try:  # never through a link, and a FIFO opened without waiting for a writer
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | os.O_NONBLOCK)
    except OSError:  # no lock file (or none to open): nobody holds it
        return
    try:
        if stat.S_ISREG(os.fstat(fd).st_mode):
            try:
                fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)  # released as fd closes
            except BlockingIOError:
                raise _busy(Path(folder), _named_holder(path)) from None
            except OSError:  # a file system without locks: `locked` says so
                pass
    finally:
        os.close(fd)


def _lock_refused(folder: Path, exc: OSError) -> FileError:
    """The refusal of ``folder``'s lock file, which ``os.open`` could not open or make
    (``exc``), naming what is at its path: a folder there was told as 'cannot make the
    campaign's lock campaign.lock: Is a directory', naming no remedy."""
    path = folder / LOCK_NAME
    expected = "expected the campaign's own lock file, which each run writes its pid into"
    if _asks(path.is_symlink):
        return FileError(f"{LOCK_NAME} is a symbolic link (to {os.readlink(path)!r}); "
                         f"{expected}: remove the link", source=str(folder))
    if _asks(path.is_dir):
        return FileError(f"{LOCK_NAME} is a folder, not a regular file; {expected}: move "
                         "the folder away or remove it", source=str(folder))
    there = ("is a regular file" if _asks(path.is_file) else "exists"
             if _asks(path.exists) else "does not exist")
    return FileError(f"cannot open or make the campaign's lock {LOCK_NAME}, which {there}: "
                     f"{exc.strerror or exc}; {expected}, in a folder this run can write",
                     source=str(folder))


#: Seconds a run refused the lock gives its file to name the run that has just taken it.
HOLDER_WAIT_S = 0.5


def _named_holder(path: Path) -> tuple[int, str] | None:
    """The holder the held lock ``path`` names (`_lock_holder`), given `HOLDER_WAIT_S` to
    name the run that has just taken it: until that run writes it, the file names nobody or
    the run before, which has ended."""
    deadline = time.monotonic() + HOLDER_WAIT_S
    while True:
        holder = _lock_holder(path)
        if (holder is not None and (holder[1] != socket.gethostname()
                                    or pid_alive(holder[0]))) or time.monotonic() > deadline:
            return holder
        time.sleep(0.02)


def _busy(folder: Path, holder: tuple[int, str] | None) -> InputError:
    lock = folder / LOCK_NAME
    if holder is None:
        who = f"its lock {lock} does not say which process (being taken just now, or damaged)"
    else:
        pid, host = holder
        where = "" if host == socket.gethostname() else f" on host {host}"
        who = f"pid {pid}{where}, holding {lock}"
    return InputError(f"another campaign is running in this folder ({who}): both would run "
                      "the same trials; wait for it to end, or give another --out",
                      source=str(folder))


#: The file a running campaign holds in its folder (`locked`).
LOCK_NAME = "campaign.lock"


def _lock_holder(path: Path) -> tuple[int, str] | None:
    """(pid, host) of the lock ``path``; None when it cannot be read as such."""
    try:
        held = json.loads(path.read_text(encoding="utf-8"))
        pid, host = held["pid"], held["host"]
    except (OSError, ValueError, TypeError, KeyError):
        return None
    if isinstance(pid, bool) or not isinstance(pid, int) or not 0 < pid < 2**31 \
            or not isinstance(host, str):
        return None
    return pid, host
