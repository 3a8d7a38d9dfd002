"""A campaign's files: one small file per finished trial, then the whole as an xarray Dataset.

``DIR/campaign.json`` holds the spec (what the campaign runs); ``DIR/trials/trial_NNNNNN.json``
one trial's record (`machinesim.campaign.trials.run_trial`), each written atomically as the
trial completes (`machinesim._io.write_atomic`). Run again on the same DIR, a campaign reads
the trials already there and computes only the missing ones; a DIR holding another campaign
(another procedure, seed or distribution) is refused, never mixed; a distribution spelt
otherwise (``10nm``, ``0.01um``) is the same one (`same_campaign`).

``DIR/campaign.nc`` (netCDF 3, xarray's scipy engine) is the Dataset `assemble` builds, written
whole or not at all:

============================  ======================  ==========================================
variable                      dims                    what
============================  ======================  ==========================================
``drawn``                     (trial, varied)         the varied parameters' values, SI
``injected``                  (trial, parameter)      the lab's truth (``lab.reveal()``), SI
``identified``                (trial, parameter)      identified value, SI
``identified_std``            (trial, parameter)      the std the identification reported
``before``, ``after``         (trial, figure)         each figure before / after compensation
``after_std``                 (trial, figure)         the after's stated spread over labs
                                                      (`Figure.after_std`; NaN: none stated)
``elapsed_s``                 (trial)                 wall time of the trial, s
``failed``                    (trial)                 1 where the trial ended in an error
``figure_unit``               (figure)                unit of ``before``/``after`` (coordinate)
============================  ======================  ==========================================

Attributes: the campaign's ``seed`` (an integer; one of 2**31 or more, beyond netCDF 3's
integers, as its decimal digits), ``procedure``, ``trials``, ``vary`` (JSON), ``noise``,
``identify_only``, ``versions`` (JSON: machinesim, numpy, scipy, xarray, dask, distributed,
python), ``errors`` (JSON: trial -> message of each failed trial).
"""

from __future__ import annotations

import json
import math
import os
import platform
from importlib import metadata
from pathlib import Path

import numpy as np

from machinesim._io import check_writable, json_text, read_json, write_atomic
from machinesim.exceptions import FileError, InputError, brief

__all__ = ["CampaignFolder", "assemble", "finished_trials", "same_campaign",
           "versions"]


def versions() -> dict:
    """Versions of the packages a campaign's numbers depend on."""
    out = {"python": platform.python_version()}
    for name in ("machinesim", "numpy", "scipy", "xarray", "dask", "distributed"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def _clean(value):
    """NaN -> None, recursively (JSON has no NaN)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    return value


def _nan(value):
    if value is None:
        return math.nan
    if isinstance(value, dict):
        return {k: _nan(v) for k, v in value.items()}
    if isinstance(value, list):
        return [v if isinstance(v, str) else _nan(v) for v in value]
    return value


class CampaignFolder:
    """The folder of one campaign (see the module docstring).

    Parameters
    ----------
    path : str or Path
        DIR; created when missing.
    spec : dict
        `CampaignSpec.describe`: written to campaign.json, or checked against it
        (`same_campaign`: a distribution spelt otherwise is the same); ``self.spec`` is then
        campaign.json's, with the texts the campaign was begun with.
    """

    def __init__(self, path, spec: dict) -> None:
        self.path = Path(path)
        self.trials_path = self.path / "trials"
        if self.path.exists() and not self.path.is_dir():
            raise FileError("is a file; expected the campaign folder", source=str(path))
        stored = self.path / "campaign.json"
        if self.path.is_dir() and not stored.exists():
            self._refuse_foreign()  # before trials/ is made in it
        try:
            self.trials_path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise FileError(f"cannot make the campaign folder: {exc.strerror or exc}",
                            source=str(path)) from None
        check_writable(self.trials_path / "trial_000000.json", "campaign trial")
        if stored.exists():
            old = read_json(stored, "campaign spec")
            if not isinstance(old, dict):
                raise InputError(f"{brief(repr(old))}; expected the campaign spec, an object "
                                 "(procedure, seed, noise, vary, ...)", source=str(stored))
            if not same_campaign(old, spec):
                diff = ", ".join(f"{k}: {old.get(k)!r} there, {spec.get(k)!r} now"
                                 for k in sorted(set(old) | set(spec))
                                 if old.get(k) != spec.get(k))
                raise InputError(f"holds another campaign ({diff}); give another --out or "
                                 "empty it", source=str(self.path))
            spec = old  # the texts the campaign was begun with, when spelt otherwise now
        else:
            write_atomic(stored, json_text(spec, "campaign spec"))
        self.spec = spec

    def _refuse_foreign(self) -> None:
        """Refuse a folder without campaign.json that holds anything but an empty trials/.

        campaign.json is written before any trial, so trial files without it are of a
        campaign nobody can tell (copied, or its campaign.json deleted): they were taken
        for this campaign's. Other files are not a campaign's at all (a scenario's report
        folder): the campaign wrote its summary.json and summary.md over them.
        """
        found = finished_trials(self.path)
        others = sorted(name for name in os.listdir(self.path)
                        if name != "trials" or not self.trials_path.is_dir())
        if self.trials_path.is_dir():
            others += sorted(f"trials/{name}" for name in os.listdir(self.trials_path)
                             if not name.startswith("trial_") or not name.endswith(".json"))
        if not found and not others:
            return
        held = ([f"{len(found)} trial file{'s' * (len(found) > 1)} in trials/"] if found
                else []) + others[:5] + (["..."] if len(others) > 5 else [])
        raise InputError(f"holds {', '.join(held)} but no campaign.json: not a campaign "
                         "folder (a scenario's report, or a campaign whose campaign.json is "
                         "gone); expected a new or empty folder, or a campaign folder: give "
                         "another --out or empty it", source=str(self.path))

    def trial_file(self, i: int) -> Path:
        return self.trials_path / f"trial_{i:06d}.json"

    def done(self, trials: int) -> list[int]:
        """The trials below ``trials`` whose file is there (one listing of trials/, not a
        look-up per trial)."""
        return [i for i in finished_trials(self.path) if i < trials]

    def write_trial(self, record: dict) -> None:
        write_atomic(self.trial_file(record["trial"]), json_text(_clean(record), "trial"))

    def read_trial(self, i: int) -> dict:
        raw = read_json(self.trial_file(i), "campaign trial")
        if not isinstance(raw, dict) or raw.get("trial") != i:
            raise InputError(f"expected the record of trial {i}", source=str(self.trial_file(i)))
        _check_record(raw, self.trial_file(i))
        return {**_nan(raw), "error": raw.get("error")}

    def write_dataset(self, dataset, name: str = "campaign.nc") -> Path:
        path = self.path / name
        write_atomic(path, bytes(dataset.to_netcdf()))
        return path


def same_campaign(old: dict, new: dict) -> bool:
    """True when the campaign specs ``old`` (campaign.json) and ``new``
    (`CampaignSpec.describe`) run the same trials: equal but for how each ``vary``
    distribution is spelt, which is compared by its meaning, the kind and its numbers in SI
    (``uniform:10nm,20nm``, ``uniform:10 nm,0.02um``; within 1e-12 relative, the rounding
    of the units' factors). A stored text that no longer parses is not the same."""
    from machinesim.campaign.distributions import parse_distribution

    if old == new:
        return True
    if {k: v for k, v in old.items() if k != "vary"} != \
            {k: v for k, v in new.items() if k != "vary"}:
        return False
    before, now = old.get("vary"), new.get("vary")
    if not isinstance(before, dict) or not isinstance(now, dict) or set(before) != set(now):
        return False
    for name, text in now.items():
        try:
            a, b = parse_distribution(before[name], name), parse_distribution(text, name)
        except (InputError, TypeError):
            return False
        if a.kind != b.kind or not all(math.isclose(x, y, rel_tol=1e-12, abs_tol=0.0)
                                       for x, y in ((a.a, b.a), (a.b, b.b))):
            return False
    return True


def _number(value) -> bool:
    """A number or null (NaN as JSON writes it)."""
    return value is None or (isinstance(value, int | float) and not isinstance(value, bool))


def _check_record(raw: dict, path: Path) -> None:
    """Refuse a trial file that is JSON but not a trial's record (`trials.run_trial`), naming
    the key: ``drawn`` and ``injected`` name -> number, ``identified`` name -> [value, std],
    ``figures`` name -> [unit, before, after(, after_std)], ``elapsed_s`` a number, ``error``
    null or a message; assembling it would otherwise fail on the first key it lacks."""
    def refuse(key: str, what: str) -> None:
        raise InputError(f"{brief(repr(raw.get(key)))}; expected {what} (a trial record as "
                         "machinesim campaign writes it): delete the file and run again to "
                         "compute the trial anew", source=str(path), key=key)

    entry_checks = {
        "drawn": (lambda v: _number(v), "an object of numbers"),
        "injected": (lambda v: _number(v), "an object of numbers"),
        "identified": (lambda v: isinstance(v, list) and len(v) == 2
                       and all(_number(x) for x in v), "an object of [value, std]"),
        "figures": (lambda v: isinstance(v, list) and len(v) in (3, 4)
                    and isinstance(v[0], str) and all(_number(x) for x in v[1:]),
                    "an object of [unit, before, after, after_std]"),
    }
    for key, (good, what) in entry_checks.items():
        entries = raw.get(key)
        if not isinstance(entries, dict) or not all(good(v) for v in entries.values()):
            refuse(key, what)
    if not _number(raw.get("elapsed_s")):
        refuse("elapsed_s", "a number of seconds")
    if not (raw.get("error") is None or isinstance(raw.get("error"), str)):
        refuse("error", "null or the failed trial's message")


def finished_trials(path) -> list[int]:
    """The trials of the campaign folder ``path`` whose file is in its trials/ (sorted;
    none when there is no such folder)."""
    try:
        names = os.listdir(Path(path) / "trials")
    except OSError:
        return []
    found = []
    for name in names:
        number = name.removeprefix("trial_").removesuffix(".json")
        if name.startswith("trial_") and name.endswith(".json") and number.isdigit():
            found.append(int(number))
    return sorted(found)


#: netCDF 3 holds 32-bit integers: a seed from here on is kept as its decimal digits (a
#: string attribute), where writing campaign.nc failed once every trial had run.
_NC3_INT_END = 2**31


def _names(records, key: str) -> list[str]:
    names: dict[str, None] = {}
    for record in records:
        names.update(dict.fromkeys(record[key]))
    return list(names)


def assemble(records: list[dict], spec: dict, trials: int):
    """The records of trials 0 .. trials-1 as one `xarray.Dataset` (module docstring)."""
    import xarray as xr

    records = sorted(records, key=lambda r: r["trial"])
    if [r["trial"] for r in records] != list(range(trials)):
        raise InputError(f"expected the records of trials 0 .. {trials - 1}, got "
                         f"{len(records)}", key="records")
    varied = list(spec["vary"])
    parameters = _names(records, "identified")
    figures = _names(records, "figures")
    units = {}
    for record in records:
        for name, values in record["figures"].items():
            units.setdefault(name, values[0])
    n = len(records)

    def table(names, value):
        out = np.full((n, len(names)), np.nan)
        for t, record in enumerate(records):
            for k, name in enumerate(names):
                out[t, k] = value(record, name)
        return out

    def get(mapping, name, index=None):
        # NaN for what a record lacks: trials written before figures carried after_std hold
        # three values
        v = mapping.get(name)
        if v is None or (index is not None and index >= len(v)):
            return math.nan
        return v if index is None else v[index]

    data = {
        "drawn": (("trial", "varied"), table(varied, lambda r, k: get(r["drawn"], k))),
        "injected": (("trial", "parameter"),
                     table(parameters, lambda r, k: get(r["injected"], k))),
        "identified": (("trial", "parameter"),
                       table(parameters, lambda r, k: get(r["identified"], k, 0))),
        "identified_std": (("trial", "parameter"),
                           table(parameters, lambda r, k: get(r["identified"], k, 1))),
        "before": (("trial", "figure"), table(figures, lambda r, k: get(r["figures"], k, 1))),
        "after": (("trial", "figure"), table(figures, lambda r, k: get(r["figures"], k, 2))),
        "after_std": (("trial", "figure"), table(figures, lambda r, k: get(r["figures"], k, 3))),
        "elapsed_s": (("trial",), np.array([r["elapsed_s"] for r in records], dtype=float)),
        "failed": (("trial",), np.array([r["error"] is not None for r in records],
                                        dtype=np.int8)),
    }
    errors = {str(r["trial"]): r["error"] for r in records if r["error"] is not None}
    coords = {"trial": np.arange(n), "varied": np.array(varied, dtype=object),
              "parameter": np.array(parameters, dtype=object),
              "figure": np.array(figures, dtype=object),
              "figure_unit": ("figure", np.array([units[f] for f in figures], dtype=object))}
    # netCDF 3 has no zero-length fixed dimension: a dimension with nothing on it (no
    # figures in an identification-only campaign, nothing varied) is left out
    for dim, names in (("varied", ("drawn",)), ("parameter", ("injected", "identified",
                                                              "identified_std")),
                       ("figure", ("before", "after", "after_std"))):
        if not len(coords[dim]):
            for name in names:
                del data[name]
            del coords[dim]
            if dim == "figure":
                del coords["figure_unit"]
    seed = int(spec["seed"])
    attrs = {"procedure": spec["procedure"], "seed": seed if seed < _NC3_INT_END else str(seed),
             "trials": int(trials),
             "noise": int(bool(spec["noise"])), "identify_only": int(bool(spec["identify_only"])),
             "vary": json.dumps(spec["vary"]), "versions": json.dumps(versions()),
             "errors": json.dumps(errors),
             "seeding": "trial i: numpy SeedSequence(seed).spawn(trials)[i]"}
    return xr.Dataset(data, coords=coords, attrs=attrs)
