"""Report folders of the scenarios: tables, summary.json, parts, NC programs, plots.

Every file goes through `machinesim._io.write_atomic` (whole or not at all), and a scenario
run through `machinesim.scenario_runs.scenario_status` writes its whole folder so: into a
staging folder beside it, swapped in once every file is written
(`machinesim._staged.StagedFolder`), so that the folder holds the previous report or the new
one, never a mix. Keys of JSON files carry their unit (``depth_error_um``, ``r_mm``):
`check_units` refuses a number whose key does not end in a unit, so a report never leaves
a reader guessing.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

from machinesim._io import write_atomic
from machinesim._json import json_text
from machinesim._staged import StagedFolder, _link_or_copy
from machinesim.exceptions import FileError, InputError

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


def _has_number(items) -> bool:
    """Whether a list (of lists ...) holds a number directly, not inside an object."""
    return any(_is_number(v) or (isinstance(v, (list, tuple)) and _has_number(v))
               for v in items)


def _clean(data):
    """JSON-ready copy: numpy scalars and arrays become Python numbers and lists; NaN -> None
    (not measured). An infinity stays, for the checks and `json_text` to refuse naming its
    key: it had become None too, and null reads as "not measured"."""
    if isinstance(data, Mapping):
        return {str(k): _clean(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [_clean(v) for v in data]
    if hasattr(data, "tolist"):
        return _clean(data.tolist())
    if isinstance(data, float) and math.isnan(data):
        return None
    return data


#: Staged report folders of the running scenarios (`machinesim.scenario_runs.scenario_status`),
#: by `folder_key`: a ReportFolder made for one writes into its staging folder.
STAGED: dict[str, StagedFolder] = {}


def folder_key(path) -> str:
    """The key of a report folder in `STAGED`: its real path."""
    return os.path.realpath(Path(path))


def identified_notes(result) -> str:
    """The notes under a result's table of identified parameters (identified.md; "" when
    there are none): what was injected and not identified, what the std leaves out when
    the lab's instruments had no noise, and a list of what the identification's fits noted
    (`machinesim.experiment.Identified.notes`)."""
    notes = []
    if result.not_identified:
        notes.append(
            "Injected and not among the identified parameters: "
            f"{_parameter_list(result.not_identified, result.polynomials)}. The procedure's "
            "model does not hold them as such (or it measures them without naming them, as "
            "a compensation table does): what they do shows in the errors above and in the "
            "figures after.")
    if not result.noise:
        notes.append(
            "The lab's instruments had no noise: each std holds what the readings' "
            "rounding leaves, and an error beyond it is the procedure's own approximation "
            "(its model of the machine and the part) or a bias of the lab, which no std "
            "holds.")
    paragraphs = [" ".join(notes)] if notes else []
    if result.notes:
        paragraphs.append("The identification's fits noted, from the readings alone:\n\n"
                          + "\n".join(f"- {note}" for note in result.notes))
    return "\n\n".join(paragraphs)


class ReportFolder:
    """A scenario's output folder.

    Inside `scenario_status`, the folder of ``args.out`` is staged: ``path`` is then the
    staging folder beside it, where the files are written, and ``final`` the folder the
    report becomes once it is whole (what to tell the user). Elsewhere both are ``path``:
    `write_result` and `add_budget` stage the folder themselves (`_whole`), the other
    methods write their file into it directly (each whole, `write_atomic`).

    Parameters
    ----------
    path : str or Path
        Created when missing.
    """

    def __init__(self, path) -> None:
        if not isinstance(path, str | os.PathLike):
            raise InputError(f"Expected the report folder as a path, got {path!r:.60}",
                             key="out")
        self.final = Path(path)
        self._staged = STAGED.get(folder_key(path))
        self.files: list[str] = []
        #: The names the last `write_result` (and `add_budget`) wrote: the report a next
        #: result replaces, while what was written besides stays.
        self._report: set[str] = set()
        if self._staged is not None:
            return
        try:
            self.final.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"report folder {str(path)!r}: cannot make the report folder there "
                             f"({exc.strerror or exc}); expected a folder, or a path where "
                             "one can be made", key="out") from None
        if not os.access(self.final, os.W_OK | os.X_OK):
            raise InputError(f"report folder {str(path)!r}: the report folder is not writable",
                             key="out")

    @property
    def path(self) -> Path:
        """Where the files are written now (the staging folder while one is in use)."""
        if self._staged is not None and self._staged.path is not None:
            return self._staged.path
        return self.final

    def publish(self, last: bool = False) -> None:
        """Make what is written so far the report folder, whole, now (inside
        `scenario_status`; nothing to do elsewhere). So a scenario says where its report is
        only once it is there. What the run writes after goes to a new staging folder (a
        copy) that replaces the folder again when the run ends: a run that adds to its
        report later (an error budget), stopped then, leaves the report as published. With
        ``last``, nothing more is written (no new staging folder)."""
        if self._staged is not None and self._staged.path is not None:
            self._staged.commit(keep_going=not last)

    def _target(self, name: str) -> Path:
        if (not isinstance(name, str) or name in ("", ".", "..")
                or any(sep and sep in name for sep in ("/", os.sep, os.altsep))):
            raise InputError(f"report file name {name!r}: expected a file name within the "
                             "report folder, without a folder part", key="name")
        self.files.append(name)
        return self.path / name

    @contextmanager
    def _whole(self, *, adding: bool = False):
        """What is written within reaches the folder whole or not at all. Inside
        `scenario_status` the folder is staged already. Elsewhere (the Python API) the
        writing goes to a staging folder beside it, swapped in at the end
        (`machinesim._staged.StagedFolder`), which begins with the files written through this
        `ReportFolder` before; anything else in the folder must be the previous report (the
        files its summary.json lists), which the new one replaces, and is refused otherwise,
        before anything is written. ``adding`` (a budget added to a report): the staging
        folder begins with every file of the folder, and the summary lists them."""
        if self._staged is not None:
            yield
            return
        from machinesim.scenario_runs import _debris

        kept = [n for n in dict.fromkeys(self.files) if (self.final / n).is_file()]
        listed = self._check_replaceable(set(kept) | {"summary.json"}, _debris)
        if adding:
            kept += [n for n in sorted(listed) if n not in kept and n != "summary.json"
                     and (self.final / n).is_file()]
            self.files += [n for n in kept if n not in self.files]
        try:
            staged = StagedFolder(self.final)
            for name in kept:
                _link_or_copy(str(self.final / name), str(staged.path / name))
        except OSError as exc:
            raise FileError(f"cannot write the report beside it: {exc.strerror or exc}",
                            source=str(self.final)) from None
        self._staged = staged
        try:
            yield
            staged.commit()
        finally:
            staged.discard()
            self._staged = None

    def _check_replaceable(self, ours: set[str], debris) -> set[str]:
        """Refuse a folder holding files besides ``ours`` and those its summary.json lists:
        replacing the folder whole would lose them. Returns the names it lists."""
        try:
            names = sorted(n for n in os.listdir(self.final) if not debris(n))
        except OSError as exc:
            raise FileError(f"cannot read the report folder ({exc.strerror or exc})",
                            source=str(self.final)) from None
        try:
            listed = json.loads((self.final / "summary.json").read_text(encoding="utf-8"))
            listed = listed.get("files") if isinstance(listed, dict) else None
        except (OSError, ValueError):
            listed = None
        listed = {str(n) for n in listed} if isinstance(listed, list) else set()
        foreign = [n for n in names if n not in ours and n not in listed]
        if not foreign:
            return listed
        shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more"
                                          if len(foreign) > 5 else "")
        found = (f"holds files its summary.json does not list ({shown})"
                 if "summary.json" in names else
                 f"holds files ({shown}) and no summary.json, so it is not a report folder")
        raise InputError(f"report folder {str(self.final)!r}: {found}; the new report "
                         "replaces the folder whole, so they would be lost: move them, or "
                         "give another folder", key="out")

    def write_json(self, name: str, data: Mapping) -> Path:
        """JSON with units in every key (checked)."""
        data = _clean(data)
        check_units(data)
        target = self._target(name)
        write_atomic(target, json_text(data, name))
        return target

    def write_summary(self, summary: Mapping) -> Path:
        """``summary.json`` in the one schema of docs/reports.md (checked, `check_summary`).

        Its version is added first, under ``schema_version`` (`SCHEMA_VERSION`), and the
        list of the folder's files under ``files``.
        """
        data = _clean({"schema_version": SCHEMA_VERSION, **summary,
                       "files": sorted(set(self.files) | {"summary.json"})})
        check_summary(data)
        target = self._target("summary.json")
        write_atomic(target, json_text(data, "summary"))
        return target

    def write_result(self, result, digits: int = 4, budget=None) -> str:
        """A `machinesim.experiment.Result`: its parts, programs, the figures table (Markdown
        and JSON), the identification table, and summary.json. Returns the Markdown.

        With ``budget`` (a `machinesim.budget.Budget`), also its table (``budget.md``), its
        bar plot (``budget.png``) and its rows under ``budget`` in summary.json (or later,
        `add_budget`). Without, a budget an earlier run left in the folder is removed: the
        folder never pairs this result with another run's budget.

        Outside a scenario the folder is written whole or not at all, as a scenario's is: it
        then holds this report (and what was written through this folder before), or, when
        stopped or failed, what it held before. A folder holding other files than an earlier
        report's is refused (`InputError`), before anything is written.

        A second result written through the same folder replaces the first's report whole:
        the files the earlier result (and its budget) wrote go; what was written through the
        folder besides (a table, notes), before the earlier result or since, stays."""
        from machinesim.experiment import Result

        if not isinstance(result, Result):
            raise InputError(f"Expected a machinesim.experiment.Result "
                             f"(experiment.run(procedure, lab)), got {type(result).__name__}",
                             key="result")
        earlier, self._report = self._report, set()
        self.files = [name for name in self.files if name not in earlier]
        if self._staged is not None:  # a staging folder is swapped in as it stands
            for name in earlier:
                (self.path / name).unlink(missing_ok=True)
        start = len(self.files)
        with self._whole():
            text = self._write_result(result, digits, budget)
        self._report = set(self.files[start:])
        return text

    def _write_result(self, result, digits: int, budget) -> str:
        for name, part in result.evaluation.parts.items():
            self.write_part(f"{name}.ply", part)
        for name, program in {**result.evaluation.programs, **result.programs}.items():
            self.write_program(f"{name}.nc", program)
        figures = self.write_table(
            "figures", ["figure", "unit", "paper before", "before", "paper after", "after",
                        "after std", "note"],
            [[f.name, f.unit, _cell(f.paper_before), _cell(f.before), _cell(f.paper_after),
              _cell(f.after), _cell(f.after_std), f.note] for f in result.figures],
            title=f"Paper {result.paper}, {result.procedure} on {result.machine}: before and "
                  "after compensation", digits=digits)
        identified = self.write_table(
            "identified", ["parameter", "injected (SI)", "identified (SI)", "std (SI)",
                           "error (SI)"],
            [[name, result.injected.get(name, math.nan), value, std,
              value - result.injected.get(name, math.nan)]
             for name, (value, std) in result.identified.items()],
            title="Identified error parameters (m, rad)", digits=6, significant=True,
            note=identified_notes(result))
        text = figures + "\n" + identified
        if budget is not None:
            return text + "\n" + self.add_budget(result, budget)
        for name in ("budget.md", "budget.png"):
            (self.path / name).unlink(missing_ok=True)
        self.files = [name for name in self.files if name not in ("budget.md", "budget.png")]
        self.write_summary(result.summary())
        return text

    def add_budget(self, result, budget) -> str:
        """The error budget of ``result`` (written by `write_result` before, or not): its
        table and plot (`write_budget`) and summary.json again with its rows under
        ``budget``. Returns the table's Markdown. Outside a scenario, the folder with the
        budget is swapped in whole, as `write_result`'s."""
        summary = {**result.summary(), "budget": budget.to_dict()}
        _check_budget(summary["budget"], {f["name"]: f["unit"] for f in summary["figures"]},
                      {f["name"]: f["after"] for f in summary["figures"]})  # before writing
        start = len(self.files)
        with self._whole(adding=True):
            text = self.write_budget(budget)
            self.write_summary(summary)
        self._report |= set(self.files[start:])  # the budget belongs to the result's report
        return text

    def write_budget(self, budget, name: str = "budget") -> str:
        """A `machinesim.budget.Budget` as ``name.md`` (table) and ``name.png`` (bar plot);
        returns the Markdown."""
        notes = budget.notes_text()
        text = ("### Error budget: share of each source in the 'after' figures\n\n"
                + budget.table() + (f"\n{notes}" if notes else ""))
        write_atomic(self._target(f"{name}.md"), text)
        budget.plot(self._target(f"{name}.png"))
        return text

    def write_table(self, name: str, columns: Sequence[str], rows: Sequence[Sequence],
                    title: str = "", digits: int = 3, *, significant: bool = False,
                    note: str = "") -> str:
        """A table as ``name.md`` and ``name.json``; returns the Markdown (for printing).
        Numbers are shown with ``digits`` decimals, or with ``significant`` as ``digits + 1``
        significant digits in scientific notation (SI values from 1e-12 to 1e-3 alike);
        ``note``, a paragraph under the Markdown table."""
        def cell(v):
            if isinstance(v, float):
                if not math.isfinite(v):
                    return "n/a"
                return f"{v:.{digits}e}" if significant else f"{v:.{digits}f}"
            return str(v)

        table = _clean({"columns": list(columns), "rows": [list(r) for r in rows]})
        check_units(table)
        data = json_text(table, f"{name}.json")  # before the Markdown: both or neither
        lines = ([f"### {title}", ""] if title else []) + [
            "| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
        lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
        text = "\n".join(lines) + "\n" + (f"\n{note}\n" if note else "")
        write_atomic(self._target(f"{name}.md"), text)
        write_atomic(self._target(f"{name}.json"), data)
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


def _parameter_list(values: Mapping[str, float], polynomials=()) -> str:
    """``name (value)`` for each parameter, SI; a component table's entries as one item,
    ``component.X.EXX (6 table entries)``, and so a polynomial's coefficients, those of
    the errors named in ``polynomials``: ``component.X.EYX (2 polynomial coefficients)``."""
    tables: dict[str, int] = {}
    items = []
    for name, value in values.items():
        if "[" in name:
            table = name.split("[")[0]
            if table not in tables:
                items.append(table)
            tables[table] = tables.get(table, 0) + 1
        else:
            items.append(f"{name} ({value:.6e})")
    def count(item: str) -> str:
        n = tables[item]
        if item in polynomials:
            return f"{n} polynomial coefficient{'s' if n > 1 else ''}"
        return f"{n} table entr{'ies' if n > 1 else 'y'}"

    return ", ".join(f"{item} ({count(item)})" if item in tables else item for item in items)


def _cell(value):
    return math.nan if value is None else value


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
        if not _is_number(value) or not math.isfinite(value):
            refuse(f"{where} must be a finite number{' or null' if null else ''}, got "
                   f"{value!r}", key)
        if least is not None and value < least:
            refuse(f"{where} must be >= {least}, got {value!r}", key)

    if not isinstance(data, Mapping):
        raise InputError(f"summary.json: expected an object, got {type(data).__name__}")
    version = data.get("schema_version", SCHEMA_VERSION)  # none: written before the field
    if version != SCHEMA_VERSION or not isinstance(version, int) or isinstance(version, bool):
        newer = (" (written by a newer machinesim? update this one to read it)"
                 if isinstance(version, int) and not isinstance(version, bool)
                 and version > SCHEMA_VERSION else "")
        refuse(f"schema_version {version!r}; this machinesim reads schema version "
               f"{SCHEMA_VERSION} (docs/reports.md){newer}", "schema_version")
    for key, kind in SUMMARY_KEYS.items():
        if key not in data or not isinstance(data[key], kind) or (
                kind is int and isinstance(data[key], bool)):
            refuse(f"expected {key!r} as {kind.__name__}, got {data.get(key)!r}", key)
    number(data["seed"], "seed", "seed", least=0)
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
    and the one this machinesim reads), damaged or edited. A file without
    ``schema_version`` is read as `SCHEMA_VERSION` (written before the field was added)."""
    from machinesim._json import read_json

    path = Path(path)
    if path.is_dir():
        path = path / "summary.json"
    data = read_json(path, "report summary (summary.json)")
    try:
        check_summary(data)
    except InputError as error:
        raise InputError(error.message.removeprefix("summary.json: "), source=str(path),
                         key=error.key) from None
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
            if (not isinstance(value, (int, float)) or isinstance(value, bool)
                    or not math.isfinite(value)):
                raise InputError(f"summary.json: budget[{i}].{key} must be a finite number, "
                                 f"got {value!r}", key="budget")
        after = afters[row["figure"]]
        if after is None or row["after_all"] != after:
            held = "none (not measured)" if after is None else repr(after)
            raise InputError(f"summary.json: budget[{i}] ({row['source']}) gives figure "
                             f"{row['figure']!r} an after of {row['after_all']!r} "
                             f"{row['unit']} with every source on, the summary's figure an "
                             f"after of {held}; expected the budget of this run (another "
                             "run's, of another seed or error model?)", key="budget")
