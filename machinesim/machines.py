"""Machines: load a URDF model, and ask where the tool edge is on a machine with errors.

>>> import machinesim
>>> machine = machinesim.load_machine("robonano_a0ib")
>>> machine.axes
('X', 'Y', 'Z', 'B', 'C')
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

import numpy as np

from machinesim._io import broken_link, not_a_regular_file
from machinesim.exceptions import ModelError
from machinesim.inverse import AxisSolution
from machinesim.kinematics import DOFS
from machinesim.machine import (  # re-exported: Machine's home was this module
    NOSE_RADIUS_PARAM,  # noqa: F401
    Machine,
)
from machinesim.urdf import AXIS_ORDER, check_tree


def models_dir() -> Path:
    """The folder of the shipped URDF models (in the wheel, or the source tree's models/)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "models", here.parent / "models"):
        if candidate.is_dir() and any(candidate.glob("*.urdf")):
            return candidate
    raise ModelError(f"no URDF models found beside {here}")


def list_machines() -> tuple[str, ...]:
    """Names of the shipped machines, sorted."""
    return tuple(sorted(p.stem for p in models_dir().glob("*.urdf")))


def load_machine(name_or_path: str | Path) -> Machine:
    """Load a shipped machine by name, or any machinesim URDF by path.

    The file is checked whole before anything is built from it (`Machine`): every problem
    is a `ModelError` naming the file, the joint or link, and the value.

    Parameters
    ----------
    name_or_path : str or Path
        A name from `list_machines()`, or the path of a ``.urdf`` file.

    Raises
    ------
    ModelError
        For an unknown name, a path that is not a readable file, or a malformed model.
    """
    if isinstance(name_or_path, Machine):  # str() of it was an 'unknown machine' name
        raise ModelError(f"got a Machine ({name_or_path.name}), loaded already: use it as it "
                         "is; expected a machine's name or the path of a .urdf file")
    if not isinstance(name_or_path, (str, os.PathLike)) or isinstance(name_or_path, bytes):
        raise ModelError(f"expected a machine's name ({', '.join(list_machines())}) or the "
                         f"path of a .urdf file, got {type(name_or_path).__name__} "
                         f"{name_or_path!r:.60}")
    text = str(name_or_path)
    path = Path(text)
    if text.lower().endswith(".xacro"):  # taken for a machine's name, "unknown machine"
        urdf = path.stem if path.stem.lower().endswith(".urdf") else f"{path.stem}.urdf"
        raise ModelError(f"{path}: a xacro file; expand it first (xacro {path.name} > {urdf}) "
                         "and load the .urdf")
    if not text.lower().endswith(".urdf"):
        path = models_dir() / f"{text}.urdf"
        if not path.is_file():
            shipped = ", ".join(list_machines())
            given = Path(text)
            # a path that is there was called an 'unknown machine', as if a name were misspelt
            if given.is_dir():
                raise ModelError(f"{given}: is a folder; expected a machine's name ({shipped}) "
                                 "or the path of a .urdf file")
            if given.is_file():
                raise ModelError(f"{given}: a file whose name does not end in .urdf; expected "
                                 f"a machine's name ({shipped}) or the path of a .urdf file "
                                 "(a URDF saved under another ending: rename it to .urdf)")
            if given.exists():  # /dev/null, a FIFO: a path, no misspelt machine's name
                raise ModelError(f"{given}: {not_a_regular_file(given)}; expected a machine's "
                                 f"name ({shipped}) or the path of a .urdf file")
            raise ModelError(
                f"unknown machine {text!r}; expected one of {shipped} or the path of a .urdf "
                "file")
    elif path.is_dir():
        raise ModelError(f"{path}: is a folder; expected a .urdf file")
    elif path.exists() and not path.is_file():  # reading a FIFO blocks, /dev/zero never ends
        raise ModelError(f"{path}: {not_a_regular_file(path)}; expected a .urdf file")
    elif not path.is_file():
        raise ModelError(f"{path}: {broken_link(path) or 'no such URDF file'}")
    path = path.resolve()
    try:
        stat = path.stat()
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the URDF file ({exc.strerror})") from None
    return _load(path, stat.st_mtime_ns, stat.st_size)


def travel_text(m) -> str:
    """A machine's travel, axis by axis: mm, deg, or 'spindle' (`machinesim machines`, the
    viewer's overlay)."""
    return ", ".join(
        (f"{a} spindle" if m.axis(a).spindle
         else f"{a} {np.degrees(lo):g}..{np.degrees(hi):g} deg")
        if m.axis(a).rotary else f"{a} {lo * 1e3:g}..{hi * 1e3:g} mm"
        for a, lo, hi in zip(m.axes, m.lower, m.upper, strict=True))


def machines_summary() -> list[str]:
    """One line per shipped machine: name, axes and travel (mm, deg)."""
    lines = []
    for name in list_machines():
        m = load_machine(name)
        lines.append(f"{name:16s} {''.join(m.axes):8s} {travel_text(m)}")
    return lines


@functools.lru_cache(maxsize=16)
def _load(path: Path, mtime_ns: int, size: int) -> Machine:
    """The machine of ``path`` as it is now (a file edited since loads again)."""
    return Machine(path)


__all__ = ["AXIS_ORDER", "AxisSolution", "DOFS", "Machine", "check_tree", "list_machines",
           "load_machine", "machines_summary", "models_dir", "travel_text"]

