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

from machinesim._io import write_atomic, write_together
from machinesim._json import json_text
from machinesim._staged import StagedFolder, _link_or_copy
from machinesim.exceptions import FileError, InputError
from machinesim.summary_schema import (  # noqa: F401  (re-exported: the names report had)
    FIGURE_KEYS,
    PLAIN_KEYS,
    SCHEMA_VERSION,
    SUMMARY_KEYS,
    UNIT_SUFFIXES,
    _check_budget,
    check_summary,
    check_units,
    read_summary,
)


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


def listed_files(folder) -> tuple[set[str], str | None]:
    """The names a report folder's summary.json lists under ``files``, and None; or an empty
    set and why it is no report's summary (it cannot be read, is not JSON, or lists no
    files): a folder holding it is not a report folder, and replacing it whole would lose
    the user's file. Without a summary.json: an empty set and None."""
    path = Path(folder) / "summary.json"
    if not path.exists():
        return set(), None
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        return set(), f"it cannot be read: {exc.strerror or exc}"
    except ValueError as exc:  # a UnicodeDecodeError too
        return set(), f"it is not JSON: {exc}"
    listed = summary.get("files") if isinstance(summary, dict) else None
    if not isinstance(listed, list):
        return set(), "it lists no files under 'files', as a report's does"
    return {str(n) for n in listed}, None


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


def _markdown_cell(text: str) -> str:
    """``text`` as one cell of a Markdown table: each ``|`` escaped (``\\|``), a line break
    a space (a table's row is one line)."""
    return text.replace("|", "\\|").replace("\r\n", " ").replace("\n", " ").replace("\r", " ")


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
        listed, unlike = listed_files(self.final)
        if unlike is not None:
            raise InputError(f"report folder {str(self.final)!r}: holds a summary.json that "
                             f"is no report's ({unlike}), so it is not a report folder; the "
                             "new report replaces the folder whole, so it would be lost: "
                             "move it, or give another folder", key="out")
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
        """A `machinesim.budget.Budget` as ``name.md`` (table) and ``name.png`` (bar plot),
        both or neither (`write_together`); returns the Markdown."""
        notes = budget.notes_text()
        text = ("### Error budget: share of each source in the 'after' figures\n\n"
                + budget.table() + (f"\n{notes}" if notes else ""))
        # together, as a table's two files (`write_table`): one after the other, a full disk
        # at the plot left the new table beside the old plot
        write_together([(self._target(f"{name}.md"), text),
                        (self._target(f"{name}.png"), budget.png())])
        return text

    def write_table(self, name: str, columns: Sequence[str], rows: Sequence[Sequence],
                    title: str = "", digits: int = 3, *, significant: bool = False,
                    note: str = "") -> str:
        """A table as ``name.md`` and ``name.json``, both or neither (`write_together`);
        returns the Markdown (for printing).
        Numbers are shown with ``digits`` decimals, or with ``significant`` as ``digits + 1``
        significant digits in scientific notation (SI values from 1e-12 to 1e-3 alike);
        ``note``, a paragraph under the Markdown table. A ``|`` within a cell or column
        name is written ``\\|`` (GitHub's Markdown reads it as the character): bare, it ended
        the cell, and a note with ``|angle - 90 deg|`` split its row into more cells than
        the header has (the JSON keeps the text as given)."""
        def cell(v):
            if isinstance(v, float):
                if not math.isfinite(v):
                    return "n/a"
                return f"{v:.{digits}e}" if significant else f"{v:.{digits}f}"
            return _markdown_cell(str(v))

        table = _clean({"columns": list(columns), "rows": [list(r) for r in rows]})
        check_units(table)
        data = json_text(table, f"{name}.json")  # before the Markdown: both or neither
        lines = ([f"### {title}", ""] if title else []) + [
            "| " + " | ".join(_markdown_cell(str(c)) for c in columns) + " |",
            "|" + "---|" * len(columns)]
        lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
        text = "\n".join(lines) + "\n" + (f"\n{note}\n" if note else "")
        # together: written one after the other, a full disk (or a Ctrl-C) between them left
        # the new name.md beside the old name.json, two tables of one name that disagree
        write_together([(self._target(f"{name}.md"), text),
                        (self._target(f"{name}.json"), data)])
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
