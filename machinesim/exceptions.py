"""The exception hierarchy: every error machinesim raises on purpose is a `MachineSimError`.

Messages name where the problem is (file, line, column, key), the value that arrived and
what was expected, so that a user can fix the input without reading the source.
"""

from __future__ import annotations

import contextlib
import sys
import warnings
from collections.abc import Iterator

#: A key or value longer than this is shown by its ends and its length (`brief`).
SHOWN_CHARACTERS = 60


def brief(text: str) -> str:
    """``text`` as a message shows it: whole when short, else its first and last characters
    and its length, so that a 10-million-digit word makes a line, not 20 MB of stderr."""
    text = str(text)
    if len(text) <= SHOWN_CHARACTERS:
        return text
    return f"{text[:40]}...{text[-12:]} ({len(text)} characters)"


def printable(text: str, keep: str = "") -> str:
    """``text`` with each character that is not printable (a control byte such as the ESC
    that starts a terminal's colour or title sequence, a newline or a tab in a file's name)
    written as its escape (``\\x1b``, ``\\n``), but those in ``keep``: a message names a
    file as given, on one line, and never writes raw control bytes to the terminal. Letters
    of any script (``ü``) and spaces stay as they are."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() or c in keep
                   else c.encode("unicode_escape").decode("ascii") for c in text)


def line_of(line: int, block: int | None = None) -> str:
    """``line 12``, or ``line 12 (N120)`` when the block there has an N word: the one way a
    message names a line of an NC program, by the file's line a text editor shows and the
    block number a machinist reads on the control."""
    return f"line {line}" if block is None else f"line {line} (N{block})"


def say(program: str, message: str) -> None:
    """Write ``program: message`` to stderr as one of machinesim's commands ends (an error,
    an interruption): what the message quotes of a file's name or a key goes through
    `printable`, the lines the message itself breaks kept. Every command line prints its
    last line here (``machinesim``, ``python -m machinesim.campaign.cli``, scenarios). A
    stderr that cannot be written (its terminal closed: EIO, the usual SIGHUP) is left
    unsaid: the error had replaced the command's exit status (1 for 129) and printed a
    traceback nobody could read."""
    try:
        print(f"{program}: {printable(message, keep=chr(10))}", file=sys.stderr)
    except OSError:
        pass


class MachineSimError(Exception):
    """Root of every error machinesim raises on purpose."""


class InputError(MachineSimError, ValueError):
    """An input (file, spec, array, key) is malformed or out of range.

    Parameters
    ----------
    message : str
        What is wrong and what was expected.
    source : str, optional
        The file (or other origin) the input came from.
    line, column : int, optional
        1-based position in ``source``.
    key : str, optional
        The key, word or field the problem is in.
    block : int, optional
        An NC program's N word of the block at ``line``: the message then names
        ``line 12 (N120)`` (`line_of`).
    """

    def __init__(
        self,
        message: str,
        *,
        source: str | None = None,
        line: int | None = None,
        column: int | None = None,
        key: str | None = None,
        block: int | None = None,
    ) -> None:
        self.message = message
        self.block = block
        self.source = source
        self.line = line
        self.column = column
        self.key = key
        where = []
        if source is not None:
            where.append(printable(source))  # a file's name may hold any byte but '/
        if line is not None:
            where.append(line_of(line, block))
        if column is not None:
            where.append(f"column {column}")
        if key is not None:
            key = self.key = str(key)  # a dict's key may be any hashable (an int)
            # a key read from a file may hold control bytes: shown escaped, never raw
            shown = key if key.isprintable() else key.encode("unicode_escape").decode("ascii")
            shown = brief(shown)
            where.append(f"key '{shown}'")
        prefix = ", ".join(where)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class ArgumentError(InputError, TypeError):
    """A public function was called with arguments it does not take (a misspelt keyword, one
    positional too many): Python's own message, with the close name and the arguments it
    takes. A `TypeError` too, as the call's own error was."""


class FileError(InputError, OSError):
    """A file-system problem with a file the user named (``source``): an `InputError`, so a
    `MachineSimError`, and also an `OSError`, so that code written for the plain library
    call it replaces (``except OSError``) still catches it."""


class ModelError(MachineSimError):
    """A machine model (URDF) is missing, malformed or breaks a machinesim convention."""


class ErrorModelError(InputError):
    """An error model (TOML or dict) has an unknown key, a missing unit or a bad value."""


class NCProgramError(InputError):
    """An NC program has a word, block or modal state that cannot be run (its ``block``,
    the N word at ``line``, named beside the line: `InputError`)."""

    @property
    def problems(self) -> tuple[NCProgramError, ...]:
        """Every problem the reader found, the first first (docs/nc.md, "Everything
        refused, at once"); an error of one problem holds itself. It had been set on an
        error of several only, and ``error.problems`` of a program with one problem raised
        AttributeError."""
        return self.__dict__.get("_problems", (self,))

    @problems.setter
    def problems(self, value) -> None:
        self.__dict__["_problems"] = tuple(value)


class ProgramTimeError(NCProgramError):
    """An NC program's moves and dwells take longer in all than its float64 clock keeps
    (`machinesim.nc.words.MAX_PROGRAM_TIME_S`), or one of them no finite time."""


class NotConvergedError(MachineSimError):
    """An iteration (e.g. the Gauss-Newton of `machinesim.identification.fit`) did not reach
    its stopping rule within its cap."""


class KinematicsError(MachineSimError):
    """A pose cannot be reached, or an axis value lies outside its travel."""


class UnreachableError(KinematicsError):
    """No axis values put the tool edge at the requested pose."""


class AxisLimitError(KinematicsError):
    """An axis value lies outside the axis travel."""


class HolderContactError(MachineSimError):
    """A move takes the tool deeper than its body: its holder, which does not cut, would
    hit the part (a real machine crashes there; the body alone would leave a tunnel)."""


class SubtractionError(MachineSimError):
    """manifold3d's booleans left material inside sweeps that were subtracted, and
    subtracting them one at a time left it too: the part would be wrong, so none is returned
    (`machinesim.cutting.run_check`). ``sweeps`` holds the sweeps' indices over the paths
    given to `machinesim.cutting.engine.remove`."""

    def __init__(self, message: str, *, sweeps: tuple[int, ...] = ()) -> None:
        self.sweeps = tuple(sweeps)
        super().__init__(message)


class ReadOnlyError(MachineSimError, AttributeError):
    """An attribute fixed when its object was made was set or deleted (a `Lab`'s machine,
    seed, noise, realism): a `MachineSimError`, and an `AttributeError` as Python's own
    read-only attributes raise."""


class MachineSimWarning(UserWarning):
    """An input machinesim accepts that may not be what was meant (a URDF's rotary limits
    that read as degrees). The command line shows one as a ``machinesim: warning:`` line."""


@contextlib.contextmanager
def warnings_as_lines() -> Iterator[None]:
    """Within the block, show a `MachineSimWarning` as one line on stderr, ``machinesim:
    warning: ...`` (Python's own form names machinesim's source line and prints it), and
    any other warning as before; the command lines' display (``machinesim``, and
    ``python -m machinesim.campaign.cli`` alone)."""
    with warnings.catch_warnings():
        python_show = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None) -> None:
            if issubclass(category, MachineSimWarning):
                print(f"machinesim: warning: {printable(message)}", file=sys.stderr)
            else:
                python_show(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        yield


def check_length(value, name: str, *, positive: bool = False) -> float:
    """``value`` as a finite float length (m), >= 0 (or > 0 with ``positive``).

    Raises InputError naming ``name``, the value that arrived and what was expected. A bool
    or a str is refused, not converted (True is no 1 m, ``"5e-5"`` no number), as
    `machinesim.metrology._arrays.as_number` refuses them.
    """
    import math

    import numpy as np

    if isinstance(value, bool | np.bool_ | str | bytes):
        raise InputError(f"Expected {name} as a number (m), got {value!r}", key=name)
    try:
        number = float(value)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} as a number (m), got {value!r}", key=name) from error
    except OverflowError:  # an int beyond float64 (10**400), as as_number says it
        what = (f"an int of {value.bit_length()} bits" if isinstance(value, int)
                else brief(repr(value)))
        raise InputError(f"Expected a finite {name} (m), got {what}, beyond float64",
                         key=name) from None
    if not math.isfinite(number) or number < 0.0 or (positive and number == 0.0):
        want = "> 0" if positive else ">= 0"
        raise InputError(f"Expected {name} {want} (m), got {number!r}", key=name)
    return number
