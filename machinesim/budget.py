"""Error budget: the share of each error source in a procedure's "after" figures.

Each source (an instrument's noise, the artefacts' errors, the machine's background errors,
an approximation of the procedure) is switched off in turn and the procedure run again; the
share of a source in a figure is how much of the figure's square it removes:

    share = (a**2 - b**2) / a**2,   a = |after with every source on|,
                                    b = |after with only this source off|

If the sources are independent and each adds its own error in quadrature (a**2 = sum of the
sources' squares plus what none of them explains), the shares of one figure sum to at most 1
and the rest, ``1 - sum``, is what the listed sources do not explain (the identification's
own residual, the evaluation's rounding). Sources that correlate (two errors that cancel in
one run) can give shares below 0 or above 1; a single seeded run is one draw of the noise,
so a share near 0 says "small", not "absent". Switching factors off one at a time follows
paper 004's Fig. 16 (form error with and without each compensation); the quadrature share is
this project's way of putting the comparisons in one table. See docs/budget.md.
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial

from machinesim._io import check_ending, write_atomic
from machinesim.exceptions import InputError, brief
from machinesim.summary_schema import _is_finite, _is_number

__all__ = ["BUDGET_KEYS", "BUDGET_OPTIONAL_KEYS", "Budget", "BudgetRow", "LabInputs",
           "clipped_shares", "error_budget", "notes_of_rerun", "quadrature_share", "realism_budget"]

#: Keys of each row of ``budget`` in summary.json (`Budget.to_dict`).
BUDGET_KEYS = ("source", "figure", "unit", "after_all", "after_without", "share")
#: Keys a row of ``budget`` in summary.json holds only where it has something to say.
BUDGET_OPTIONAL_KEYS = ("notes",)


def quadrature_share(after_all: float, after_without: float) -> float:
    """The share of a source in a figure: ``(a^2 - b^2) / a^2``; NaN when ``a == 0`` (a
    share of nothing is undefined: written n/a in the table, null in summary.json).

    Parameters
    ----------
    after_all : float
        The figure's "after" with every source on (``a``; its sign is ignored).
    after_without : float
        The same with only this source off (``b``; its sign is ignored).
    """
    a, b = abs(float(after_all)), abs(float(after_without))
    if not (math.isfinite(a) and math.isfinite(b)):
        raise InputError(f"budget: expected finite figures, got after_all={after_all!r}, "
                         f"after_without={after_without!r}")
    return math.nan if a == 0.0 else (a * a - b * b) / (a * a)


@dataclass(frozen=True)
class BudgetRow:
    """One source's share in one figure.

    Attributes
    ----------
    source : str
        The source switched off (``"instrument_noise"``, ``"artefact_errors"``,
        ``"background"``, ``"tip_vs_nose"``, ...).
    figure : str
        A `machinesim.experiment.Figure` name of the result.
    unit : str
        The figure's unit.
    after_all : float
        The figure's "after" with every source on.
    after_without : float
        The same with only this source off.
    share : float
        ``(a^2 - b^2) / a^2`` with ``a = |after_all|``, ``b = |after_without|``; NaN (a
        share of nothing, undefined) if a == 0.
    notes : tuple of str
        What the identification of the run with this source off noted
        (`machinesim.experiment.Identified.notes`: readings that do not fit the model, ...)
        that the run with every source on did not, numbers aside (`notes_of_rerun`): read
        ``after_without`` with them. The same for every row of the source.
    """

    source: str
    figure: str
    unit: str
    after_all: float
    after_without: float
    share: float
    notes: tuple[str, ...] = ()

    def as_dict(self) -> dict:
        """The row as summary.json holds it (keys `BUDGET_KEYS`, and ``notes`` when it has
        any); a NaN share (of a figure of 0) as None, JSON's null."""
        out = {key: getattr(self, key) for key in BUDGET_KEYS}
        if math.isnan(self.share):
            out["share"] = None
        if self.notes:
            out["notes"] = list(self.notes)
        return out


@dataclass(frozen=True)
class Budget:
    """The shares of every source in every "after" figure of a result.

    Attributes
    ----------
    rows : tuple of BudgetRow
        Grouped by figure (in the result's order), sources in the order given.
    """

    rows: tuple[BudgetRow, ...]

    @classmethod
    def from_dict(cls, rows: Sequence[Mapping]) -> Budget:
        """The inverse of `to_dict` (rows as summary.json holds them)."""
        from machinesim.experiment import FIGURE_UNITS

        if isinstance(rows, str | bytes | Mapping) or not isinstance(rows, Sequence):
            raise InputError(f"budget: expected a list of rows, got {type(rows).__name__}",
                             key="budget")
        out = []
        for i, row in enumerate(rows):
            missing = [key for key in BUDGET_KEYS if not isinstance(row, Mapping)
                       or key not in row]
            if missing:
                raise InputError(f"budget[{i}]: expected an object with "
                                 f"{', '.join(BUDGET_KEYS)}; lacks {', '.join(missing)}",
                                 key="budget")
            for key in ("source", "figure", "unit"):  # str() had made None a source "None"
                if not isinstance(row[key], str) or not row[key]:
                    raise InputError(f"budget[{i}].{key} must be a non-empty string, got "
                                     f"{row[key]!r}", key="budget")
            if row["unit"] not in FIGURE_UNITS:
                raise InputError(f"budget[{i}].unit {row['unit']!r}; expected one of "
                                 f"{', '.join(FIGURE_UNITS)} (a figure's unit)", key="budget")
            numbers = []
            for key in ("after_all", "after_without", "share"):
                value = row[key]
                if key == "share" and value is None and numbers[0] == 0.0:
                    numbers.append(math.nan)  # a share of a figure of 0: undefined (to_dict)
                    continue
                # an int beyond float64 (10**400) is no finite number: math.isfinite raised
                # OverflowError on it
                if not _is_number(value) or not _is_finite(value):
                    null = (" (null only where after_all is 0: a share of nothing)"
                            if key == "share" and value is None else "")
                    raise InputError(f"budget[{i}].{key} must be a finite number, got "
                                     f"{brief(repr(value))}{null}", key="budget")
                numbers.append(float(value))
            notes = row.get("notes", [])
            if not isinstance(notes, list) or not all(isinstance(n, str) and n.strip()
                                                      for n in notes):
                raise InputError(f"budget[{i}].notes must be a list of non-empty strings, "
                                 f"got {notes!r}", key="budget")
            out.append(BudgetRow(row["source"], row["figure"], row["unit"], *numbers,
                                 tuple(notes)))
        return cls(tuple(out))

    @property
    def sources(self) -> tuple[str, ...]:
        """The sources, in order."""
        return tuple(dict.fromkeys(row.source for row in self.rows))

    @property
    def figures(self) -> tuple[str, ...]:
        """The figures, in order."""
        return tuple(dict.fromkeys(row.figure for row in self.rows))

    @property
    def notes(self) -> dict[str, tuple[str, ...]]:
        """Source -> the notes of its rerun (`BudgetRow.notes`), for each source with any,
        in order."""
        out = {}
        for row in self.rows:
            if row.notes:
                out.setdefault(row.source, row.notes)
        return out

    def notes_text(self) -> str:
        """`notes` as Markdown for under the table: ``""`` when no rerun noted anything."""
        if not self.notes:
            return ""
        lines = ["The identification of a run with one source off noted what the run with "
                 "every source on did not (numbers aside): its rows' 'after, source off' "
                 "rest on that identification.", ""]
        lines += [f"- {source} off: {note}" for source, notes in self.notes.items()
                  for note in notes]
        return "\n".join(lines) + "\n"

    def share(self, source: str, figure: str) -> float:
        """The share of ``source`` in ``figure``."""
        for row in self.rows:
            if row.source == source and row.figure == figure:
                return row.share
        raise InputError(f"budget has no row for source {source!r} and figure {figure!r}; "
                         f"sources {', '.join(self.sources)}, figures "
                         f"{', '.join(self.figures)}", key="source")

    def unexplained(self, figure: str) -> float:
        """``1 - sum of the shares`` of ``figure``: what no listed source explains (under the
        independence assumption of the module docstring); NaN for a figure of 0, whose
        shares are."""
        shares = [row.share for row in self.rows if row.figure == figure]
        if not shares:
            raise InputError(f"budget has no figure {figure!r}; it has "
                             f"{', '.join(self.figures)}", key="figure")
        return 1.0 - sum(shares)

    def table(self) -> str:
        """The budget as a Markdown table: one row per figure and source, then per figure
        the part no listed source explains."""
        lines = ["| figure | unit | source | after, all on | after, source off | share |",
                 "|---|---|---|---|---|---|"]
        for figure in self.figures:
            rows = [row for row in self.rows if row.figure == figure]
            for row in rows:
                lines.append(f"| {row.figure} | {row.unit} | {row.source} | "
                             f"{row.after_all:.4g} | {row.after_without:.4g} | "
                             f"{_percent(row.share)} |")
            lines.append(f"| {figure} | {rows[0].unit} | (none of these) | | | "
                         f"{_percent(self.unexplained(figure))} |")
        return "\n".join(lines) + "\n"

    def to_dict(self) -> list[dict]:
        """The rows as summary.json holds them under ``budget``."""
        return [row.as_dict() for row in self.rows]

    def plot(self, path) -> None:
        """A bar plot (PNG) of the shares in percent: one group per figure, a bar per source,
        at most `FIGURES_PER_PANEL` figures to a panel, panels one under the other.

        The axis spans -100 .. 100 %: a share beyond (a figure near 0 with every source on,
        which switching one off moves far) is drawn to the edge, hatched, its value written
        beside it, and an undefined one (a figure of 0) as no bar, written n/a
        (`clipped_shares`). Written whole or not at all
        (`machinesim._io.write_atomic`); ``path`` ends in ``.png`` (any case: another
        ending is refused).
        """
        check_ending(path, "png", "Budget.plot", "a PNG picture")
        write_atomic(path, self.png())

    def png(self) -> bytes:
        """The bar plot of `plot` as PNG bytes (for a caller writing it with other files)."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        figures, sources = self.figures, self.sources
        panels = [figures[i:i + FIGURES_PER_PANEL]
                  for i in range(0, len(figures), FIGURES_PER_PANEL)] or [()]
        width = 0.8 / max(len(sources), 1)
        colours = plt.get_cmap("tab10" if len(sources) <= 10 else "tab20").colors
        figure, axes = plt.subplots(len(panels), 1, squeeze=False, dpi=120, figsize=(
            max(6.0, 1.5 * max(len(p) for p in panels) + 3.5), 0.5 + 3.4 * len(panels)))
        for axis, names in zip(axes[:, 0], panels, strict=True):
            for k, source in enumerate(sources):
                x = [i + (k - (len(sources) - 1) / 2) * width for i in range(len(names))]
                heights, labels = clipped_shares(
                    [100.0 * self.share(source, name) for name in names], PLOT_LIMIT_PERCENT)
                bars = axis.bar(x, heights, width=width, color=colours[k % len(colours)],
                                label=source)
                for bar, label in zip(bars, labels, strict=True):
                    if label:
                        bar.set_hatch("///")
                        axis.annotate(label, (bar.get_x() + bar.get_width() / 2,
                                              bar.get_height()),
                                      ha="center", va="bottom" if bar.get_height() > 0
                                      else "top", rotation=90, fontsize=6)
            axis.axhline(0.0, color="black", linewidth=0.8)
            axis.set_ylim(-1.35 * PLOT_LIMIT_PERCENT, 1.35 * PLOT_LIMIT_PERCENT)
            axis.set_xticks(range(len(names)))
            axis.set_xticklabels(names, rotation=15, fontsize=8, ha="right")
            axis.set_ylabel("share, % (quadrature)")
            axis.grid(True, axis="y", alpha=0.3)
        axes[0, 0].set_title("Error budget: each source switched off in turn\n(share of the "
                             "'after' figure; hatched: beyond the axis, value written)",
                             fontsize=10)
        axes[0, 0].legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.0, 1.0))
        buffer = io.BytesIO()
        figure.tight_layout()
        figure.savefig(buffer, format="png")
        plt.close(figure)
        return buffer.getvalue()


#: The budget plot's axis, percent either way: a share of 100 % is the whole figure.
PLOT_LIMIT_PERCENT = 100.0
#: Figures in one panel of the budget plot.
FIGURES_PER_PANEL = 8


def _percent(share: float) -> str:
    """A share as the table writes it: ``12.3 %``, or ``n/a`` where it is undefined (NaN)."""
    return "n/a" if math.isnan(share) else f"{100.0 * share:.1f} %"


def clipped_shares(percent: Sequence[float], limit: float) -> tuple[list[float], list[str]]:
    """Bar heights within ``-limit .. limit`` and, for each bar cut there, its value as a
    label (``""`` for the others); an undefined share (NaN) is no bar, labelled n/a."""
    heights, labels = [], []
    for value in percent:
        if math.isnan(value):
            heights.append(0.0)
            labels.append("n/a")
            continue
        clipped = min(max(float(value), -limit), limit)
        heights.append(clipped)
        labels.append("" if clipped == value else f"{value:.0f} %")
    return heights, labels


def _check_sources(sources) -> tuple[str, ...]:
    if isinstance(sources, str):
        raise InputError(f"error_budget: expected a sequence of source names, got the "
                         f"string {sources!r}", key="sources")
    out = tuple(sources)
    bad = [s for s in out if not isinstance(s, str) or not s]
    if bad or not out:
        raise InputError(f"error_budget: expected a non-empty sequence of source names, got "
                         f"{list(out)!r}", key="sources")
    doubled = sorted({s for s in out if out.count(s) > 1})
    if doubled:
        raise InputError(f"error_budget: source(s) {', '.join(doubled)} given twice",
                         key="sources")
    return out


def _figures(result, what: str) -> dict:
    figures = getattr(result, "figures", None)
    if figures is None:
        raise InputError(f"error_budget: run({what}) returned {type(result).__name__}; "
                         "expected a machinesim.experiment.Result", key="run")
    return {f.name: f for f in figures}


def realism_budget(procedure, result, realism, make_lab, enabled: bool = True, *,
                   progress=None, jobs: int = 1):
    """The error budget of a scenario's run over its lab's realism switches: each switch
    that is on and that ``procedure.realism_sources`` lists, turned off in turn on a lab of
    its own (``make_lab(realism)``); ``result`` is the run with every switch on. None when
    not ``enabled`` or no such switch is on (then, enabled, ``progress("budget")`` says so).
    ``progress``: a stage's printer for each rerun, ``progress("budget, <source> off")``
    (`machinesim.scenario_runs.progress_printer`).

    ``jobs`` above 1 (and more than one source) runs the reruns on that many worker
    processes, at most one per source (`error_budget`), each
    building its lab there: ``make_lab`` and ``procedure`` must then pickle (`LabInputs`
    does; a function defined inside another does not, and is refused by name), and
    ``progress`` is told how many at a time, then one line per rerun as it finishes,
    ``budget, <source> off: done in 12 s (1 of 3)``, rather than its steps."""
    from machinesim._processes import check_jobs
    from machinesim.experiment import run

    jobs = check_jobs(jobs, "budget rerun")  # before any rerun, as error_budget
    sources = [name for name in realism.on if name in procedure.realism_sources]
    if enabled and not sources and progress is not None:
        progress("budget")(f"none: no source it shares out is on (realism {realism}), so "
                           "budget.md and budget.png are not written")
    if not enabled or not sources:
        return None
    if getattr(result, "figures", None) is None:
        # jobs=2 had handed the missing result on to error_budget, whose worker's run(None)
        # was refused as a realism switch None
        raise InputError(f"realism_budget: expected result, the run with every switch on (a "
                         f"machinesim.experiment.Result), got {type(result).__name__}",
                         key="result")
    jobs = min(jobs, len(sources))  # one rerun: here, each step shown, no worker to start
    if jobs == 1:
        return error_budget(lambda off: result if off is None else _quietly(
            run, procedure, make_lab(realism.without(off)),
            progress=None if progress is None else progress(f"budget, {off} off")), sources)
    if progress is not None:
        progress("budget")(f"{len(sources)} sources switched off in turn, {jobs} at a time "
                           "on worker processes")
    finished = []

    def done(source, seconds):
        finished.append(source)
        if progress is not None:
            progress(f"budget, {source} off")(f"done in {seconds:.0f} s ({len(finished)} of "
                                              f"{len(sources)})")

    return error_budget(partial(_rerun_without, procedure=procedure, make_lab=make_lab,
                                realism=realism), sources, everything=result, jobs=jobs,
                        done=done)


def _rerun_without(off: str, *, procedure, make_lab, realism):
    """`realism_budget`'s rerun with ``off`` switched off, as a worker process runs it."""
    from machinesim.experiment import run

    return _quietly(run, procedure, make_lab(realism.without(off)))


def _quietly(run, *args, **kwargs):
    """``run(*args, **kwargs)`` with its `MachineSimWarning`s kept to itself: a rerun's
    warning is of a variant of the run, whose own warning the user has already seen
    (paper 003's uncut pyramids were said six times over, once per rerun, each with the
    variant's figures)."""
    import warnings

    from machinesim.exceptions import MachineSimWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MachineSimWarning)
        return run(*args, **kwargs)


@dataclass(frozen=True)
class LabInputs:
    """A ``make_lab`` for `realism_budget` that pickles, so that its reruns can build their
    labs on worker processes: ``LabInputs(machine, errors, seed=3)(realism)`` is
    ``Lab(machine, errors, seed=3, realism=realism)`` (``servo`` too when given).

    Attributes
    ----------
    machine : Machine or str
    errors : ErrorModel, mapping, path or None
    seed : int
    servo : optional
        As `machinesim.Lab` takes them.
    """

    machine: object
    errors: object = None
    seed: int = 0
    servo: object = None

    def __call__(self, realism):
        from machinesim.lab import Lab

        return Lab(self.machine, self.errors, seed=self.seed, realism=realism,
                   servo=self.servo)


def error_budget(run: Callable, sources: Sequence[str], *, everything=None, jobs: int = 1,
                 done: Callable[[str, float], None] | None = None) -> Budget:
    """The error budget of a procedure: each source switched off in turn.

    Parameters
    ----------
    run : callable
        ``run(None)`` -> `machinesim.experiment.Result` with every source on;
        ``run(source)`` -> the same with that one source off.
    sources : sequence of str
        The sources, in the order of the table.
    everything : Result, optional
        The run with every source on, when it is already there: then ``run(None)`` is not
        called (and ``run`` need not take None).
    jobs : int
        Reruns at a time: 1 (default) runs them here, one after the other; more runs
        ``run(source)`` for each source on that many worker processes
        (`machinesim._processes.in_processes`; no more than there are sources), so ``run``
        must pickle (a module-level function or a `functools.partial` of one; see
        `crown_rerun` in `machinesim.workpiece_setting_budget`) and what it
        returns too. ``run(None)``, when called, runs here. Each worker starts with the cuts
        this process made (`machinesim.lab.CUTS`), so a rerun hands back the parts it would
        here; the budget is the same to the bit, the rows in the sources' order.
    done : callable(str, float), optional
        With ``jobs`` above 1: told here, as each rerun finishes, its source and seconds.

    Returns
    -------
    Budget
        A row per figure with an "after" value (in the result's order) and per source, each
        with the notes of its source's rerun that the all-on run has none of
        (`notes_of_rerun`).
    """
    from machinesim._processes import check_jobs

    sources = _check_sources(sources)
    # before the run with every source on (minutes): jobs=0 was refused only after it, and
    # jobs=True (== 1) taken as one job
    jobs = check_jobs(jobs, "budget rerun")
    if not callable(run):
        raise InputError(f"error_budget: expected run as a callable, run(source or None) -> "
                         f"Result, got {run!r:.60}", key="run")
    if everything is None:
        everything = run(None)
    every = _figures(everything, "None")
    names = [name for name, f in every.items() if f.after is not None]
    rows = {name: [] for name in names}
    if jobs == 1:
        reruns = (run(source) for source in sources)  # lazily: each checked as it comes
    else:
        from machinesim._processes import in_processes
        from machinesim.lab import CUTS

        reruns = in_processes(run, sources, jobs, what="budget rerun", done=None
                              if done is None else lambda i, s: done(sources[i], s),
                              setup=partial(_remember_cuts, CUTS))
    for source, rerun in zip(sources, reruns, strict=True):
        without = _figures(rerun, repr(source))
        notes = notes_of_rerun(rerun, everything)
        for name in names:
            if name not in without or without[name].after is None:
                raise InputError(f"error_budget: with {source!r} off the result has no "
                                 f"'after' for figure {name!r}", key=source)
            if without[name].unit != every[name].unit:  # 1 um against 500 nm: -2.5e7 %
                raise InputError(f"error_budget: with {source!r} off figure {name!r} is in "
                                 f"{without[name].unit!r}, with every source on in "
                                 f"{every[name].unit!r}; expected one unit for both runs",
                                 key=source)
            a, b = every[name].after, without[name].after
            rows[name].append(BudgetRow(source, name, every[name].unit, a, b,
                                        quadrature_share(a, b), notes))
    return Budget(tuple(row for name in names for row in rows[name]))


def _remember_cuts(cuts) -> None:
    """In a rerun's worker process: the cuts the budget's own process made
    (`machinesim.lab.CUTS`), so that a rerun whose source leaves a cut as it was (one that
    acts on an instrument alone) hands back the first run's part, as it does there, rather
    than cutting it again."""
    from machinesim.lab import CUTS

    CUTS.update(cuts)


def notes_of_rerun(rerun, everything) -> tuple[str, ...]:
    """The identification's notes of ``rerun`` (a `machinesim.experiment.Result` with one
    source off: ``notes``, none for a result without) that ``everything``, the run with every
    source on, has no note of the same kind: the same words, numbers aside
    (`machinesim.experiment.note_kind`; a misfit of normalised residual 3.1 in both
    runs is one kind whatever its number). The all-on run's own notes are in the report's
    identified.md."""
    from machinesim.experiment import note_kind

    kinds = {note_kind(note) for note in getattr(everything, "notes", ())}
    return tuple(note for note in getattr(rerun, "notes", ()) if note_kind(note) not in kinds)
