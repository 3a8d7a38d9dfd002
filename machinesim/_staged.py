"""Folders written whole or not at all: a report folder staged beside its name and swapped in.

`StagedFolder` writes into a staging folder beside the folder it replaces and swaps it in
at `StagedFolder.commit` (a Ctrl-C or SIGTERM held until the swap is done,
`machinesim._interrupts`); `clear_stale_folders` removes the staging folders of killed runs.
Single files written whole are `machinesim._io`'s.
"""

from __future__ import annotations

import hashlib
import os
import secrets
import shutil
from pathlib import Path

from machinesim import _interrupts
from machinesim._interrupts import ctrl_c_deferred
from machinesim._io import TEMP_STEM, os_reason, pid_alive, process_space
from machinesim.exceptions import FileError, InputError, MachineSimError

#: Staging folders of this process that are still being written (not stale).
_ours: set[str] = set()


def _folder_stem(target: Path) -> str:
    """The part of a staging folder's name that names ``target`` (shortened with a hash when
    its name is long, so that the sibling's name stays within the file system's limit)."""
    name = target.name
    if len(os.fsencode(name)) <= 160:
        return name
    digest = hashlib.sha1(os.fsencode(name)).hexdigest()[:12]
    return f"{name[:TEMP_STEM]}~{digest}"


def _sibling_kind(entry: str, stem: str) -> tuple[str, int] | None:
    """(``"partial"`` or ``"old"``, pid) when ``entry`` is a staging or swapped-out folder
    of ``stem`` made in this process's PID space (``.STEM.partial-PID@HOST.TOKEN``,
    ``.STEM.old-PID@HOST.TOKEN``, HOST `process_space`), else None: another host's or
    container's PID is no process here, and its live run's folder was removed as stale."""
    for kind in ("partial", "old"):
        head = f".{stem}.{kind}-"
        if entry.startswith(head):
            marked, _, _ = entry[len(head):].partition(".")
            pid, at, host = marked.partition("@")
            if pid.isdigit() and at and host == process_space():
                return kind, int(pid)
    return None


def _alive(pid: int, path: Path) -> bool:
    """Whether the run that named a folder with ``pid`` may still be writing it."""
    if pid == os.getpid():
        return str(path) in _ours
    return pid_alive(pid)


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
        The folder (its parent is made when missing, and removed again when nothing was
        swapped in). A symbolic link is followed: the folder it names is the one replaced.

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
        # the parents made here, deepest first: a run that ends before its first swap takes
        # them away again (an --out a/b/c that failed left a/b behind, empty)
        self._made = [p for p in (self.target.parent, *self.target.parent.parents)
                      if not os.path.lexists(p)]
        self.target.parent.mkdir(parents=True, exist_ok=True)
        clear_stale_folders(self.target)
        self._begin(seed=False)

    def _sibling(self, kind: str) -> Path:
        return self.target.parent / (f".{_folder_stem(self.target)}.{kind}-{os.getpid()}@"
                                     f"{process_space()}.{secrets.token_hex(4)}")

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
            Without swapping anything, when a Ctrl-C was seen (`ctrl_c_remembered`); a
            SIGTERM or SIGHUP as what it was (`Terminated`, `HungUp`).
        FileError
            When the swap fails; the old folder is then in place.
        """
        if self.path is None:
            raise MachineSimError("the staged folder was already committed or discarded")
        if _interrupts._ctrl_c_seen:  # as what it was: SIGTERM is `Terminated` (143)
            raise _interrupts._stop_kind
        staging = self.path
        with ctrl_c_deferred():
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
                raise FileError(f"cannot put the new folder in place: {os_reason(exc)}",
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
            if self.commits == 0:
                for parent in self._made:  # only if still empty: another run may use it
                    try:
                        os.rmdir(parent)
                    except OSError:
                        break


__all__ = ["StagedFolder", "clear_stale_folders"]
