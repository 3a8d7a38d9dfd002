"""The one schema of a report's summary.json (docs/reports.md) and the rule every JSON file
of a report keeps: a number's key names its unit (`check_units`). `check_summary` checks a
summary as it is written (`machinesim.report.ReportFolder.write_summary`), `read_summary`
as it is read back, its version among it."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from pathlib import Path

from machinesim.exceptions import InputError, brief

#: Suffixes that name a unit (or say that a number has none).
UNIT_SUFFIXES = ("_m", "_mm", "_um", "_nm", "_rad", "_mrad", "_urad", "_deg", "_arcsec",
                 "_s", "_h", "_min", "_mm2", "_mm3", "_m3", "_percent", "_count", "_ratio",
                 "_index", "_per_s", "_lines")
#: Keys that are not quantities.
PLAIN_KEYS = {"seed", "spawn_key", "noise", "machine", "paper", "program", "scenario", "note",
              "notes", "name", "files", "version", "units", "procedure", "line", "tool",
              "rows"}  # a table's rows: its "columns" name the units


def check_units(data, path: str = "", named: bool = False) -> None:
    """Raise InputError when a number in ``data`` sits under a key without a unit suffix
    (a number itself, or numbers in a list under it, at any depth of lists), unless a key
    it sits within names the unit (``"yaw_urad": {"y_mm": [...], "value": [...]}``)."""
    if isinstance(data, Mapping):
        for key, value in data.items():
            where = f"{path}.{key}" if path else str(key)
            has_unit = named or key in PLAIN_KEYS or str(key).endswith(UNIT_SUFFIXES)
            if not has_unit and (_is_number(value) or (isinstance(value, (list, tuple))
                                                       and _has_number(value))):
                raise InputError(f"report key {where!r} holds a number but names no unit "
                                 f"(end it in one of {', '.join(UNIT_SUFFIXES)})")
            if isinstance(value, (Mapping, list, tuple)):
                check_units(value, where, has_unit and key not in PLAIN_KEYS or named)
    elif isinstance(data, (list, tuple)):
        for i, value in enumerate(data):
            if isinstance(value, (Mapping, list, tuple)):
                check_units(value, f"{path}[{i}]", named)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_finite(value) -> bool:
    """Whether the number ``value`` is finite as a float64: an int beyond the largest float
    is not (math.isfinite raised OverflowError on it: a traceback out of read_summary)."""
    if isinstance(value, int):
        return abs(value) <= _MOST_INT
    return math.isfinite(value)


#: The largest int a float64 holds.
_MOST_INT = int(sys.float_info.max)


def _has_number(items) -> bool:
    """Whether a list (of lists ...) holds a number directly, not inside an object."""
    return any(_is_number(v) or (isinstance(v, (list, tuple)) and _has_number(v))
               for v in items)


#: The version of summary.json's schema (docs/reports.md) this machinesim writes and reads,
#: under ``schema_version``. A summary.json without one was written before the field was
#: added, when the schema was this version's (the field is its only change since): it is
#: read as this version. A change that a reader of the old schema would misread (a key's
#: meaning or unit) takes the next number.
SCHEMA_VERSION = 1

#: Top-level keys of summary.json, with what each must hold (docs/reports.md).
SUMMARY_KEYS = {"paper": str, "procedure": str, "machine": str, "seed": int, "noise": bool,
                "injected": Mapping, "identified": Mapping, "figures": list}
#: Keys of each entry of ``figures``.
FIGURE_KEYS = ("name", "unit", "before", "after", "paper_before", "paper_after")


def _version_refusal(data: Mapping) -> str | None:
    """Why the summary ``data`` is of a schema version this machinesim does not read; None
    when it is `SCHEMA_VERSION` (or has none: written before the field)."""
    version = data.get("schema_version", SCHEMA_VERSION)  # none: written before the field
    if version == SCHEMA_VERSION and isinstance(version, int) and not isinstance(version, bool):
        return None
    newer = (" (written by a newer machinesim? update this one to read it)"
             if isinstance(version, int) and not isinstance(version, bool)
             and version > SCHEMA_VERSION else "")
    return (f"schema_version {brief(repr(version))}; this machinesim reads schema version "
            f"{SCHEMA_VERSION} (docs/reports.md){newer}")


def check_version(data, source: str | None = None) -> None:
    """Raise InputError (naming ``source`` and the key) when the summary ``data`` (an
    object) is of another schema version than `SCHEMA_VERSION` (`check_summary`'s check,
    for a reader that takes the rest of a summary as it finds it: the viewer)."""
    wrong_version = _version_refusal(data) if isinstance(data, Mapping) else None
    if wrong_version is not None:
        raise InputError(wrong_version, source=source, key="schema_version")


def check_summary(data: Mapping) -> None:
    """Raise InputError when ``data`` is not a summary.json of the documented schema.

    ``injected`` maps error parameter names (`machinesim.ErrorModel.parameters`) to finite
    SI values, ``identified`` maps them to ``{"value", "std"}`` (a number, and a number >= 0
    or null); ``figures`` is a list of objects with `FIGURE_KEYS` (numbers or null, the
    ``unit`` one of `machinesim.experiment.FIGURE_UNITS`, an optional ``note`` and an
    optional ``after_std`` >= 0); ``seed`` >= 0; ``files`` a list of names; the optional
    ``background`` ``{"file": name or null, "nonzero_count": n >= 1}``; the optional
    ``notes`` a list of non-empty strings; every other numeric key names its unit.
    """
    from machinesim.errors.model import _PARAMETER_RE
    from machinesim.experiment import FIGURE_UNITS

    def refuse(message: str, key: str):
        raise InputError(f"summary.json: {message}", key=key)

    def number(value, where: str, key: str, *, null: bool = False, least=None) -> None:
        if value is None and null:
            return
        if not _is_number(value) or not _is_finite(value):
            refuse(f"{where} must be a finite number{' or null' if null else ''}, got "
                   f"{brief(repr(value))}", key)
        if least is not None and value < least:
            refuse(f"{where} must be >= {least}, got {value!r}", key)

    if not isinstance(data, Mapping):
        raise InputError(f"summary.json: expected an object, got {type(data).__name__}")
    wrong_version = _version_refusal(data)
    if wrong_version is not None:
        refuse(wrong_version, "schema_version")
    for key, kind in SUMMARY_KEYS.items():
        if key not in data or not isinstance(data[key], kind) or (
                kind is int and isinstance(data[key], bool)):
            refuse(f"expected {key!r} as {kind.__name__}, got {data.get(key)!r}", key)
    if data["seed"] < 0:  # an int (above) of any size: a seed is no float (Lab's seed=2**1100)
        refuse(f"seed must be >= 0, got {brief(repr(data['seed']))}", "seed")
    spawn_key = data.get("spawn_key", [])
    if not isinstance(spawn_key, list) or not all(
            isinstance(k, int) and not isinstance(k, bool) and k >= 0 for k in spawn_key):
        refuse(f"expected 'spawn_key' as a list of ints >= 0, got {spawn_key!r}", "spawn_key")
    for section in ("injected", "identified"):
        for name, value in data[section].items():
            if not isinstance(name, str) or not _PARAMETER_RE.fullmatch(name):
                refuse(f"{section} key {name!r} is not an error parameter name (tool.x, "
                       "workpiece.alpha, location.C.EX0C, component.X.EXX[0])", section)
            if section == "injected":
                number(value, f"injected[{name!r}]", section)
            elif not isinstance(value, Mapping) or set(value) != {"value", "std"}:
                refuse(f'identified[{name!r}] must be {{"value": v, "std": s}}, got '
                       f"{value!r}", section)
            else:
                number(value["value"], f"identified[{name!r}].value", section)
                number(value["std"], f"identified[{name!r}].std", section, null=True,
                       least=0.0)
    names: dict[str, int] = {}
    for i, figure in enumerate(data["figures"]):
        if not isinstance(figure, Mapping):
            refuse(f"figures[{i}] must be an object, got {figure!r}", "figures")
        missing = [k for k in FIGURE_KEYS if k not in figure]
        if missing:
            refuse(f"figures[{i}] lacks {', '.join(missing)}", "figures")
        if not isinstance(figure["name"], str) or not figure["name"]:
            refuse(f"figures[{i}].name must be a non-empty string, got {figure['name']!r}",
                   "figures")
        if names.setdefault(figure["name"], i) != i:
            refuse(f"figures[{i}] is named {figure['name']!r}, as figures"
                   f"[{names[figure['name']]}] is; expected each figure once (a figure is "
                   "read by its name)", "figures")
        if figure["unit"] not in FIGURE_UNITS:
            refuse(f"figures[{i}] ({figure['name']}): unit {figure['unit']!r}; expected one "
                   f"of {', '.join(FIGURE_UNITS)}", "figures")
        for key in ("before", "after", "paper_before", "paper_after", "after_std"):
            if key in figure:
                number(figure[key], f"figures[{i}].{key}", "figures", null=True,
                       least=0.0 if key == "after_std" else None)
        if not isinstance(figure.get("note", ""), str):
            refuse(f"figures[{i}].note must be a string, got {figure['note']!r}", "figures")
    files = data.get("files", [])
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        refuse(f"expected 'files' as a list of file names, got {files!r}", "files")
    if "budget" in data:
        _check_budget(data["budget"], {f["name"]: f["unit"] for f in data["figures"]},
                      {f["name"]: f["after"] for f in data["figures"]})
    if "background" in data:
        background = data["background"]
        if (not isinstance(background, Mapping) or set(background) != {"file", "nonzero_count"}
                or not isinstance(background["file"], (str, type(None)))
                or not isinstance(background["nonzero_count"], int)
                or isinstance(background["nonzero_count"], bool)
                or background["nonzero_count"] < 1):
            refuse('expected \'background\' as {"file": name or null, "nonzero_count": n >= 1}'
                   f", got {background!r}", "background")
    if "notes" in data:
        notes = data["notes"]
        if not isinstance(notes, list) or not all(isinstance(n, str) and n.strip()
                                                  for n in notes):
            refuse(f"expected 'notes' as a list of non-empty strings, got {notes!r}", "notes")
    rest = {k: v for k, v in data.items()
            if k not in SUMMARY_KEYS and k not in ("budget", "schema_version")}
    check_units(rest)


def read_summary(path) -> dict:
    """The summary.json at ``path`` (a file, or a report folder holding one), read and
    checked against the schema (`check_summary`, its version among it): an `InputError`
    naming the file and the key, for a file of another schema version (the version found
    and the one this machinesim reads), damaged or edited, or a campaign's summary.json;
    key 'path' for a ``path`` that is no file name (None, a number). A file without
    ``schema_version`` is read as `SCHEMA_VERSION` (written before the field was added)."""
    from machinesim._io import check_path
    from machinesim._json import read_json

    # None or a number was 'TypeError: expected str, bytes or os.PathLike object'
    path = Path(check_path(path, "reading a report summary (summary.json)"))
    if path.is_dir():
        path = path / "summary.json"
    data = read_json(path, "report summary (summary.json)")
    if isinstance(data, Mapping) and "paper" not in data and "trials_count" in data:
        # a campaign folder's summary.json was refused as "expected 'paper' as str, got
        # None", as if a report's were damaged
        raise InputError("a campaign's summary.json (machinesim campaign, docs/campaigns.md: "
                         "its trials' statistics), not a scenario report's; expected the "
                         "summary.json of a report folder (docs/reports.md)", source=str(path))
    try:
        check_summary(data)
    except InputError as error:
        raise InputError(error.message.removeprefix("summary.json: "), source=str(path),
                         key=error.key) from None
    except RecursionError:  # lists in lists 500 deep under a key of its own: JSON takes
        # them (read_json's bound is the parser's), check_units's recursion did not
        raise InputError("nested too deeply to be a report summary (a key added by hand?); "
                         "expected the summary.json of docs/reports.md", source=str(path)) \
            from None
    return data


def _check_budget(rows, units: Mapping[str, str], afters: Mapping[str, float | None]) -> None:
    """``budget`` of summary.json: a list of rows with `machinesim.budget.BUDGET_KEYS` (and
    ``notes``, a list of non-empty strings, where a row has any), each of a figure of the
    summary's ``units`` (figure name -> unit), in its unit, whose ``after_all`` is the
    figure's ``after`` in ``afters`` (figure name -> after), exactly: a budget is made from
    the run's own figures (`machinesim.budget.error_budget` takes each row's after_all from
    the result), and JSON gives a float back to the bit, so any difference is another
    run's budget (of the same figures and units: a seed or an error model apart)."""
    from machinesim.budget import BUDGET_KEYS, BUDGET_OPTIONAL_KEYS

    if not isinstance(rows, list):
        raise InputError(f"summary.json: expected 'budget' as a list of rows, got "
                         f"{type(rows).__name__}", key="budget")
    for i, row in enumerate(rows):
        if (not isinstance(row, Mapping) or not set(BUDGET_KEYS) <= set(row)
                or not set(row) <= {*BUDGET_KEYS, *BUDGET_OPTIONAL_KEYS}):
            raise InputError(f"summary.json: budget[{i}] must have exactly the keys "
                             f"{', '.join(BUDGET_KEYS)} (and optionally "
                             f"{', '.join(BUDGET_OPTIONAL_KEYS)}), got {row!r}", key="budget")
        notes = row.get("notes", [])
        if "notes" in row and (not isinstance(notes, list) or not notes or not all(
                isinstance(n, str) and n.strip() for n in notes)):
            raise InputError(f"summary.json: budget[{i}].notes must be a non-empty list of "
                             f"non-empty strings, got {notes!r}", key="budget")
        for key in ("source", "figure", "unit"):
            if not isinstance(row[key], str) or not row[key]:
                raise InputError(f"summary.json: budget[{i}].{key} must be a non-empty "
                                 f"string, got {row[key]!r}", key="budget")
        if units.get(row["figure"]) != row["unit"]:
            held = (f"in {units[row['figure']]}" if row["figure"] in units else
                    f"none of that name (its figures: {', '.join(units) or 'none'})")
            raise InputError(f"summary.json: budget[{i}] gives figure {row['figure']!r} in "
                             f"{row['unit']}, the summary's figures {held}; expected the "
                             "budget of this run's figures (another run's?)", key="budget")
        for key in ("after_all", "after_without", "share"):
            value = row[key]
            if key == "share" and value is None and row["after_all"] == 0.0:
                continue  # a share of a figure of 0: undefined, null (docs/budget.md)
            if not _is_number(value) or not _is_finite(value):
                null = (" (null only where after_all is 0: a share of nothing)"
                        if key == "share" and value is None else "")
                raise InputError(f"summary.json: budget[{i}].{key} must be a finite number, "
                                 f"got {brief(repr(value))}{null}", key="budget")
        after = afters[row["figure"]]
        if after is None or row["after_all"] != after:
            held = "none (not measured)" if after is None else repr(after)
            raise InputError(f"summary.json: budget[{i}] ({row['source']}) gives figure "
                             f"{row['figure']!r} an after of {row['after_all']!r} "
                             f"{row['unit']} with every source on, the summary's figure an "
                             f"after of {held}; expected the budget of this run (another "
                             "run's, of another seed or error model?)", key="budget")
