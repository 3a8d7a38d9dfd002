"""JSON text: written without NaN or infinity, read with errors naming the file and position.

JSON has neither NaN nor infinity, though Python's json writes and reads them: `json_text`
refuses them naming the key, `read_json` naming the file.
"""

from __future__ import annotations

import json
import math

from machinesim._io import check_readable_file, os_reason
from machinesim.exceptions import FileError, InputError, MachineSimError


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
        raise FileError(f"cannot read the {what}: {os_reason(exc)}", source=str(path)) from None
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


__all__ = ["json_text", "read_json"]
