"""Report folders of the scenarios: tables, summary.json, parts, NC programs, plots.

Every file goes through `machinesim._io.write_atomic` (whole or not at all). Keys of JSON
files carry their unit (``depth_error_um``, ``r_mm``): `check_units` refuses a number whose
key does not end in a unit, so a report never leaves a reader guessing.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

from machinesim._io import write_atomic
from machinesim.exceptions import InputError

#: Suffixes that name a unit (or say that a number has none).
UNIT_SUFFIXES = ("_m", "_mm", "_um", "_nm", "_rad", "_mrad", "_urad", "_deg", "_arcsec",
                 "_s", "_h", "_min", "_mm3", "_m3", "_percent", "_count", "_ratio", "_index",
                 "_per_s")
#: Keys that are not quantities.
PLAIN_KEYS = {"seed", "noise", "machine", "paper", "program", "scenario", "note", "notes",
              "name", "files", "version", "units"}


def check_units(data, path: str = "") -> None:
    """Raise InputError when a number in ``data`` sits under a key without a unit suffix."""
    if isinstance(data, Mapping):
        for key, value in data.items():
            where = f"{path}.{key}" if path else str(key)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                if key not in PLAIN_KEYS and not str(key).endswith(UNIT_SUFFIXES):
                    raise InputError(f"report key {where!r} holds a number but names no unit "
                                     f"(end it in one of {', '.join(UNIT_SUFFIXES)})")
            else:
                check_units(value, where)
    elif isinstance(data, (list, tuple)):
        for i, value in enumerate(data):
            if isinstance(value, (Mapping, list, tuple)):
                check_units(value, f"{path}[{i}]")


def _clean(data):
    """JSON-ready copy: numpy scalars and arrays become Python numbers and lists; NaN -> None."""
    if isinstance(data, Mapping):
        return {str(k): _clean(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [_clean(v) for v in data]
    if hasattr(data, "tolist"):
        return _clean(data.tolist())
    if isinstance(data, float) and not math.isfinite(data):
        return None
    return data


class ReportFolder:
    """A scenario's output folder.

    Parameters
    ----------
    path : str or Path
        Created when missing.
    """

    def __init__(self, path) -> None:
        self.path = Path(path)
        self.path.mkdir(parents=True, exist_ok=True)
        self.files: list[str] = []

    def _target(self, name: str) -> Path:
        self.files.append(name)
        return self.path / name

    def write_json(self, name: str, data: Mapping) -> Path:
        """JSON with units in every key (checked)."""
        data = _clean(data)
        check_units(data)
        target = self._target(name)
        write_atomic(target, json.dumps(data, indent=2) + "\n")
        return target

    def write_summary(self, injected: Mapping, identified: Mapping, before: Mapping,
                      after: Mapping, **extra) -> Path:
        """``summary.json`` with the four objects every scenario reports, plus ``extra``."""
        return self.write_json("summary.json", {"injected": injected, "identified": identified,
                                                "before": before, "after": after, **extra,
                                                "files": sorted(set(self.files))})

    def write_table(self, name: str, columns: Sequence[str], rows: Sequence[Sequence],
                    title: str = "", digits: int = 3) -> str:
        """A table as ``name.md`` and ``name.json``; returns the Markdown (for printing)."""
        def cell(v):
            if isinstance(v, float):
                return "n/a" if not math.isfinite(v) else f"{v:.{digits}f}"
            return str(v)

        lines = ([f"### {title}", ""] if title else []) + [
            "| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
        lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
        text = "\n".join(lines) + "\n"
        write_atomic(self._target(f"{name}.md"), text)
        self.write_json(f"{name}.json", {"columns": list(columns),
                                         "rows": [list(r) for r in rows]})
        return text

    def write_part(self, name: str, part) -> Path:
        """A machined part as float64 PLY."""
        target = self._target(name)
        part.export_ply(target)
        return target

    def write_program(self, name: str, program) -> Path:
        """An NC program (FANUC style)."""
        from machinesim.nc import write_program

        target = self._target(name)
        write_program(program, target)
        return target

    def write_text(self, name: str, text: str) -> Path:
        target = self._target(name)
        write_atomic(target, text)
        return target

    def plot(self, name: str, series: Sequence[tuple[str, Sequence, Sequence]], *, xlabel: str,
             ylabel: str, title: str = "", hlines: Sequence[tuple[float, str]] = ()) -> Path:
        """A line plot (PNG): ``series`` of (label, x, y) in the units the labels state."""
        import io

        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        figure, axes = plt.subplots(figsize=(8, 5), dpi=120)
        for label, x, y in series:
            axes.plot(x, y, marker="o", label=label)
        for value, label in hlines:
            axes.axhline(value, linestyle="--", color="grey", label=label)
        axes.set_xlabel(xlabel)
        axes.set_ylabel(ylabel)
        if title:
            axes.set_title(title)
        axes.grid(True, alpha=0.3)
        axes.legend()
        buffer = io.BytesIO()
        figure.tight_layout()
        figure.savefig(buffer, format="png")
        plt.close(figure)
        target = self._target(name)
        write_atomic(target, buffer.getvalue())
        return target


def scenario_arguments(description: str, default_out: str) -> argparse.ArgumentParser:
    """The options every scenario takes: --noise on|off, --seed N, --out DIR."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--noise", choices=("on", "off"), default="on",
                        help="instrument noise (default on, the instruments' stated models)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise (default 0)")
    parser.add_argument("--out", type=Path, default=Path(default_out),
                        help=f"report folder (default {default_out})")
    return parser


def parse_floats(text: str, count: int, option: str) -> list[float]:
    """``"a,b,c"`` -> floats, with a clear error naming the option."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(f"{option} {text!r}: expected {count} comma-separated numbers")
    return values
