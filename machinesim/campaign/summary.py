"""A campaign's report: summary.json, summary.md and the plots, from its Dataset.

summary.json (docs/campaigns.md). Its numbers are not all keyed by their unit, as a
scenario's report.json's ``details`` are (docs/reports.md): a `statistics.describe`'s
``mean``, ``std``, ``min``, ``max`` and intervals are in the unit named beside them (a
figure's ``unit``) or by the key holding them (``error_si``: the parameter's ``unit``, SI);
z-scores and rank correlations are ratios; ``count`` and the ``_count`` keys count trials.

- ``schema_version`` (`SCHEMA_VERSION`), ``procedure``, ``seed``, ``trials_count``,
  ``failed_count``, ``vary`` (name -> DIST text), ``versions``;
- ``figures``: per figure, its ``unit`` and ``before``/``after``: `statistics.describe`
  (count, mean, std, min, max, ``shortest_95`` and ``symmetric_95`` coverage intervals) in
  the figure's unit, over the trials that measured it (``count``); ``not_measured``:
  ``before``/``after`` -> the trials that ran without failing but read no value there (a
  procedure's None: the grooves not cut, say); ``sensitivity``: varied parameter ->
  Spearman rank correlation with the after value; where the procedure states the after's
  spread over labs (`Figure.after_std`), ``after_z``: the z-scores after / after_std
  (`statistics.z_summary`; a faithful spread gives std 1, 95 % within +-1.96);
- ``parameters``: per identified parameter, its SI ``unit`` (the Dataset's ``parameter_unit``:
  m, rad, or a polynomial coefficient's m/m^k ...), the identification error (identified -
  injected) described in that unit (``error_si``), its z-scores (`statistics.z_summary`)
  and ``sensitivity``: varied parameter -> Spearman rank correlation with the error's
  magnitude;
- ``coverage_interval``: which intervals are given (JCGM 101 7.7.1 and 7.7.2);
- ``failures``: each distinct message of a failed trial with the trials that ended in it
  (``{"message": ..., "trials": [...]}``, most trials first), messages that differ only in
  their numbers taken as one and the first trial's shown;
- ``noted_count``: the trials whose identification gave notes (`Identified.notes`: readings
  that do not fit the model, parameters the readings barely tell apart, ...), and ``notes``:
  each note with the trials that gave it, notes that differ only in their numbers taken as
  one (`machinesim.experiment.note_kind`) and the first trial's shown
  (``{"note": ..., "trials": [...]}``, most trials first).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from machinesim._io import write_together
from machinesim._json import json_text
from machinesim.campaign.distributions import parameter_kind
from machinesim.campaign.statistics import describe, spearman, z_scores, z_summary

__all__ = ["failures", "message_kind", "notes", "remove_report", "summarise",
           "write_report"]


#: The version of a campaign's summary.json (docs/campaigns.md), written first under
#: ``schema_version``; a change a reader of the old one would misread takes the next number.
SCHEMA_VERSION = 1


def _finite(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def _names(dataset, dim: str) -> list[str]:
    """The coordinate ``dim`` as strings; empty when the dataset has no such dimension (an
    identification-only campaign has no figures)."""
    return [str(v) for v in dataset[dim].values] if dim in dataset.dims else []


def _unit(dataset, k: int, name: str) -> str:
    """Parameter ``k``'s SI unit: the Dataset's ``parameter_unit``; for a campaign.nc
    written before it was kept, the name's kind (`parameter_kind`: m or rad; ``SI`` for
    neither)."""
    if "parameter_unit" in dataset.coords:
        return str(dataset["parameter_unit"].values[k])
    return _SI.get(parameter_kind(name), "SI")


def summarise(dataset) -> dict:
    """summary.json of a campaign Dataset (module docstring)."""
    failed = dataset["failed"].values.astype(bool)
    trials = dataset["trial"].values
    varied = _names(dataset, "varied")
    figures = {}
    for k, name in enumerate(_names(dataset, "figure")):
        after = dataset["after"].values[:, k]
        figures[str(name)] = {
            "unit": str(dataset["figure_unit"].values[k]),
            "before": describe(dataset["before"].values[:, k]),
            "after": describe(after),
            "not_measured": {which: [int(t) for t in trials[~failed & ~np.isfinite(
                dataset[which].values[:, k])]] for which in ("before", "after")},
            "sensitivity": {v: spearman(dataset["drawn"].values[:, j], after)
                            for j, v in enumerate(varied)},
        }
        if "after_std" in dataset:
            z = z_scores(after, 0.0, dataset["after_std"].values[:, k])
            if np.isfinite(z).any():
                figures[str(name)]["after_z"] = z_summary(z)
    parameters = {}
    for k, name in enumerate(_names(dataset, "parameter")):
        found, truth = dataset["identified"].values[:, k], dataset["injected"].values[:, k]
        with np.errstate(over="ignore"):  # beyond float64: inf, left out as NaN is
            error = found - truth
        z = z_scores(found, truth, dataset["identified_std"].values[:, k])
        parameters[str(name)] = {
            "unit": _unit(dataset, k, name),
            "error_si": describe(error), "z": z_summary(z),
            "sensitivity": {v: spearman(dataset["drawn"].values[:, j], np.abs(error))
                            for j, v in enumerate(varied)}}
    return _finite({
        "schema_version": SCHEMA_VERSION,
        "procedure": dataset.attrs["procedure"], "seed": int(dataset.attrs["seed"]),
        "trials_count": int(dataset.sizes["trial"]), "failed_count": int(failed.sum()),
        "vary": json.loads(dataset.attrs["vary"]),
        "versions": json.loads(dataset.attrs["versions"]),
        "coverage_interval": "95 %, JCGM 101:2008 7.7 from the sorted trials: shortest_95 "
        "(7.7.2) and symmetric_95 (probabilistically symmetric, 7.7.1)",
        "sensitivity": "Spearman rank correlation of each varied parameter with the figure "
        "after compensation (figures) and with |identified - injected| (parameters)",
        "figures": figures, "parameters": parameters,
        "failures": failures(dataset),
        "noted_count": int((dataset["notes_count"].values > 0).sum())
        if "notes_count" in dataset else 0,
        "notes": notes(dataset),
    })


def failures(dataset) -> list[dict]:
    """The failed trials' messages (the Dataset's ``errors``), each with its trials, most
    trials first; messages that differ only in their numbers are one (`message_kind`: a
    probe that missed its sphere at another height in each trial), shown with the first
    trial's numbers."""
    by_kind: dict[str, tuple[str, list[int]]] = {}
    errors = json.loads(dataset.attrs.get("errors", "{}"))
    for trial, message in sorted(((int(t), str(m)) for t, m in errors.items())):
        by_kind.setdefault(message_kind(message), (message, []))[1].append(trial)
    return [{"message": m, "trials": t}
            for m, t in sorted(by_kind.values(), key=lambda item: (-len(item[1]), item[1]))]


#: A number of a message, within a list ("[-0.006, 2.4e-05]") too; not an entry's index
#: ("component.X.EXX[2]") nor a digit of a word ("trial_000002").
_NUMBER = re.compile(r"(?<![\w.])(?<!\w\[)[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?(?![\w.])")


def message_kind(message: str) -> str:
    """``message`` with its numbers as ``#``: the same failure in two trials (``Expected the
    scans through [-0.006, -0.006, 2.9e-04] m ...`` and ``... 2.4e-05] m ...``) is one kind."""
    return _NUMBER.sub("#", message)


def notes(dataset) -> list[dict]:
    """The trials' notes (the Dataset's ``notes``), each with its trials, most trials
    first."""
    return json.loads(dataset.attrs.get("notes", "[]"))


def _g(value, digits: int = 4) -> str:
    return "n/a" if value is None else f"{value:.{digits}g}"


def _interval(pair) -> str:
    low, high = pair
    return "n/a (too few trials)" if low is None else f"[{_g(low)}, {_g(high)}]"


#: The SI unit of a parameter's kind (`machinesim.campaign.distributions.parameter_kind`), for a
#: campaign.nc without ``parameter_unit`` (`_unit`).
_SI = {"length": "m", "angle": "rad"}


def _markdown(summary: dict) -> str:
    total = summary["trials_count"]
    lines = [f"# Campaign: {summary['procedure']}, {total} trial{'s' * (total != 1)} "
             f"(seed {summary['seed']}, {summary['failed_count']} failed)", ""]
    if summary["vary"]:
        lines += ["Varied: " + ", ".join(f"`{n}={d}`" for n, d in summary["vary"].items()), ""]
    varied = list(summary["vary"])
    rho = [f"rho {v}" for v in varied]
    if summary["figures"]:
        lines += ["## Figures before and after compensation", "",
                  "trials: how many trials measured the figure, those the statistics beside "
                  "are computed from; 95 % coverage intervals from the sorted trials (JCGM "
                  "101 7.7.2, the shortest); sensitivity: Spearman rank correlation with the "
                  "after value.",
                  "", *_header(["figure", "unit", "before trials", "before mean",
                                "before std", "after trials", "after mean", "after std",
                                "after 95 % (shortest)", *rho])]
        for name, f in summary["figures"].items():
            b, a = f["before"], f["after"]
            lines.append(_row([name, f["unit"], str(b["count"]), _g(b["mean"]), _g(b["std"]),
                               str(a["count"]), _g(a["mean"]), _g(a["std"]),
                               _interval(a["shortest_95"]),
                               *(_g(f["sensitivity"][v], 3) for v in varied)]))
        lines.append("")
        lines += _not_measured(summary["figures"])
    stated = {name: f["after_z"] for name, f in summary["figures"].items() if "after_z" in f}
    if stated:
        lines += ["## The after against its stated spread over labs", "",
                  "z = after / after_std (the procedure's stated spread, docs/reports.md): a "
                  "faithful spread gives mean 0, std 1, 95 % within +-1.96.", "",
                  *_header(["figure", "trials", "z mean", "z std", "within +-1.96"])]
        lines += [_row([name, str(z["count"]), _g(z["mean"], 3), _g(z["std"], 3),
                        _g(z["within_1_96_ratio"], 3)]) for name, z in stated.items()]
        lines.append("")
    if summary["parameters"]:
        lines += ["## Identification: error and z-scores", "",
                  "error = identified - injected (SI: the unit beside it); z = error / reported "
                  "std: honest uncertainty gives mean 0, std 1, 95 % within +-1.96; rho: "
                  "Spearman rank correlation with |error|.", "",
                  *_header(["parameter", "unit", "trials", "error mean", "error std",
                            "error 95 % (symmetric)", "z trials", "z mean", "z std",
                            "within +-1.96", *rho])]
        for name, p in summary["parameters"].items():
            e, z = p["error_si"], p["z"]
            lines.append(_row([name, p["unit"], str(e["count"]),
                               _g(e["mean"]), _g(e["std"]),
                               _interval(e["symmetric_95"]), str(z["count"]),
                               _g(z["mean"], 3), _g(z["std"], 3),
                               _g(z["within_1_96_ratio"], 3),
                               *(_g(p["sensitivity"][v], 3) for v in varied)]))
        lines.append("")
    if summary["failures"]:
        lines += ["## Failed trials", "",
                  "Each message with its trials, most trials first; a message's numbers may "
                  "differ from trial to trial, the first trial's are shown.", ""]
        for failure in summary["failures"]:
            trials = failure["trials"]
            shown = ", ".join(str(t) for t in trials[:10]) + (" ..." if len(trials) > 10 else "")
            lines.append(f"- {len(trials)} trial{'s' * (len(trials) > 1)} ({shown}): "
                         f"{failure['message']}")
        lines.append("")
    lines += _notes(summary)
    lines += ["Versions: " + ", ".join(f"{k} {v}" for k, v in summary["versions"].items()), ""]
    return "\n".join(lines)


#: summary.md lists this many of the notes (summary.json every one).
NOTES_SHOWN = 10


def _notes(summary: dict) -> list[str]:
    """summary.md's lines on the identification's notes: how many trials gave any, and each
    note with its trials; none when no trial did."""
    if not summary["notes"]:
        return []
    noted, total = summary["noted_count"], summary["trials_count"]
    lines = ["## Notes of the identification", "",
             f"{noted} of {total} trial{'s' * (total > 1)} gave notes: what the "
             "identification's fits say a reader should know before trusting the values "
             "(docs/reports.md, `notes`). Each note with its trials, most trials first; a "
             "note's numbers differ from trial to trial, the first trial's are shown.", ""]
    for note in summary["notes"][:NOTES_SHOWN]:
        trials = note["trials"]
        shown = ", ".join(str(t) for t in trials[:10]) + (" ..." if len(trials) > 10 else "")
        lines.append(f"- {len(trials)} trial{'s' * (len(trials) > 1)} ({shown}): "
                     f"{note['note']}")
    if len(summary["notes"]) > NOTES_SHOWN:
        lines.append(f"- and {len(summary['notes']) - NOTES_SHOWN} other notes (summary.json "
                     "lists every one)")
    return [*lines, ""]


def _not_measured(figures: dict) -> list[str]:
    """summary.md's lines naming the trials that ran but measured a figure not (left out of
    its statistics), figures with the same trials on one line; none when every trial that
    ran measured every figure."""
    by_trials: dict[tuple, list[str]] = {}
    for name, f in figures.items():
        for which in ("before", "after"):
            if f["not_measured"][which]:
                by_trials.setdefault((which, *f["not_measured"][which]), []).append(name)
    if not by_trials:
        return []
    lines = ["Not measured (the trial ran, but the procedure read no value there; left out "
             "of the statistics above):", ""]
    for (which, *trials), names in by_trials.items():
        shown = ", ".join(str(t) for t in trials[:10]) + (" ..." if len(trials) > 10 else "")
        lines.append(f"- {which} compensation, {len(trials)} trial{'s' * (len(trials) > 1)} "
                     f"({shown}): {', '.join(names)}")
    return [*lines, ""]


def _plots(dataset) -> dict[str, bytes]:
    """The plots as PNG bytes by file name (written with the rest of the report)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    written: dict[str, bytes] = {}

    def save(fig, name):
        import io

        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=100)
        plt.close(fig)
        written[name] = buffer.getvalue()

    for k, name in enumerate(_names(dataset, "figure")):
        unit = str(dataset["figure_unit"].values[k])
        # side by side, each on its own scale: after is often 1000 x smaller than before
        fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
        for ax, which, colour in zip(axes, ("before", "after"), ("C0", "C1"), strict=True):
            y = dataset[which].values[:, k]
            y = y[np.isfinite(y)]
            scale = _scale(y)
            if y.size:
                _hist(ax, y, max(5, min(40, y.size // 3)), scale, color=colour)
                # counts of trials: whole numbers (4 trials had ticks every 0.25)
                ax.yaxis.set_major_locator(MaxNLocator(integer=True))
                # a few values as they are: the default's 8 ticks of a spread of nanometres
                # ran into each other (-0.00150-0.00125...), and its offset (+5e2 at the
                # axis' end) was read past
                ax.xaxis.set_major_locator(MaxNLocator(nbins=4))
                ax.ticklabel_format(axis="x", useOffset=False)
            else:
                ax.text(0.5, 0.5, "not measured", ha="center", transform=ax.transAxes)
            ax.set_xlabel(f"{name} {which} ({unit}" + (f", x {scale:g})" if scale != 1.0
                                                       else ")"))
            ax.set_ylabel("trials")
            ax.set_title(f"{which} compensation ({y.size} trials)")
        fig.tight_layout()
        save(fig, f"hist_{name}.png")
    z_all = []
    for k, name in enumerate(_names(dataset, "parameter")):
        z = z_scores(dataset["identified"].values[:, k], dataset["injected"].values[:, k],
                     dataset["identified_std"].values[:, k])
        z_all.append((str(name), z[np.isfinite(z)]))
    if any(z.size for _, z in z_all):
        fig, ax = plt.subplots(figsize=(6, 4))
        grid = np.linspace(-4, 4, 200)
        ax.plot(grid, np.exp(-grid**2 / 2) / math.sqrt(2 * math.pi), "k-", label="N(0, 1)")
        for name, z in z_all:
            if z.size:
                scale = _scale(z)
                _hist(ax, z, max(5, min(30, z.size // 3)), scale, density=True, alpha=0.4,
                      label=name if scale == 1.0 else f"{name} (x {scale:g})",
                      histtype="stepfilled")
        ax.set_xlabel("z = (identified - injected) / reported std")
        ax.set_ylabel("density")
        ax.set_title("Identification error against the reported std")
        ax.legend(fontsize=7)
        fig.tight_layout()
        save(fig, "z_scores.png")
    return written


#: The largest magnitude a histogram shows as it is (`_scale`): near float64's end (1e308)
#: numpy's bins and matplotlib's axis overflowed ('Too many bins for data range', a
#: traceback out of the campaign once every trial had run).
_PLOT_LARGEST = 1e300


def _scale(y: np.ndarray) -> float:
    """1, or for values beyond `_PLOT_LARGEST` the power of ten they are shown in units of."""
    largest = float(np.max(np.abs(y))) if y.size else 0.0
    return 10.0 ** math.floor(math.log10(largest)) if largest > _PLOT_LARGEST else 1.0


def _hist(ax, y: np.ndarray, bins: int, scale: float, **options) -> None:
    """``ax.hist`` of the finite values ``y`` / ``scale`` (`_scale`) in ``bins`` bins. Values
    all equal beyond 2**50 get bins over +-1e-6 of their size: numpy's own, +-0.5, is no bin
    at all there (an equal after of 1e17 in every trial was 'Too many bins for data
    range'); below, numpy's are kept."""
    y = y / scale
    low, high = float(y.min()), float(y.max())
    if low == high and abs(low) >= 2.0**50:
        half = abs(low) * 1e-6
        options["range"] = (low - half, low + half)
    ax.hist(y, bins=bins, **options)


def write_report(dataset, folder, with_files=None) -> dict:
    """Write summary.json, summary.md and the plots into ``folder``; return the summary.

    ``with_files`` (file name -> bytes or text; the campaign.nc these are the report of) is
    written together with them (`machinesim._io.write_together`): every file is made first,
    then all are renamed into place, so that a Ctrl-C or a full disk leaves the folder's
    campaign.nc and its summary of the same trials, the old ones or the new ones, never one
    of each. The plots of the earlier report (those its summary.json lists) that this one
    has none of are then removed: its z-scores when every trial of a shorter ``--trials``
    failed."""
    folder = Path(folder)
    summary = summarise(dataset)
    plots = _plots(dataset)
    summary["files"] = sorted(["campaign.nc", "summary.json", "summary.md", *plots])
    files = {**(with_files or {}), **plots, "summary.md": _markdown(summary),
             "summary.json": json_text(summary, "campaign summary")}
    earlier = _listed_plots(folder)
    write_together([(folder / name, data) for name, data in files.items()])
    # a plot of the earlier report this one has none of (its z-scores, when every trial of
    # a shorter --trials failed) would show other trials beside this summary, unlisted
    for name in sorted(earlier - set(plots)):
        (folder / name).unlink(missing_ok=True)
    return summary


def remove_report(folder) -> None:
    """Remove the report in ``folder``: summary.md, the plots its summary.json lists, then
    summary.json; for a campaign.nc written without a report (``run(report=False)``), which
    an earlier report, of other trials, would otherwise sit beside."""
    folder = Path(folder)
    for name in [*sorted(_listed_plots(folder)), "summary.md", "summary.json"]:
        (folder / name).unlink(missing_ok=True)


#: The names of the plots a campaign's report writes (`_plots`).
_PLOT = re.compile(r"hist_[^/\\]+\.png|z_scores\.png")


def _listed_plots(folder: Path) -> set[str]:
    """The plots the summary.json in ``folder`` lists (an earlier report's files); none when
    there is none or it cannot be read."""
    try:
        listed = json.loads((folder / "summary.json").read_text(encoding="utf-8"))["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return set()
    if not isinstance(listed, list):
        return set()
    return {name for name in listed if isinstance(name, str) and _PLOT.fullmatch(name)}


def _row(cells) -> str:
    """One Markdown table row of ``cells``."""
    return "| " + " | ".join(cells) + " |"


def _header(names) -> list[str]:
    """A Markdown table's header and separator rows, one cell each per name."""
    return [_row(names), "|" + "---|" * len(names)]
