"""A campaign's Dataset, assembled from its trials' records (`assemble`, `Assembly`).

``DIR/campaign.nc`` (netCDF 3, xarray's scipy engine) is the Dataset `assemble` builds, written
whole or not at all (`machinesim.campaign.results`):

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
``notes_count``               (trial)                 how many notes the identification gave
                                                      (`Identified.notes`: readings that do not
                                                      fit the model, ...); NaN for a failed
                                                      trial and one written before they were kept
``elapsed_s``                 (trial)                 wall time of the trial, s
``failed``                    (trial)                 1 where the trial ended in an error
``figure_unit``               (figure)                unit of ``before``/``after`` (coordinate)
``parameter_unit``            (parameter)             SI unit of ``injected``, ``identified``,
                                                      ``identified_std`` (coordinate): m or
                                                      rad, a polynomial's coefficient k >= 1
                                                      m/m^k, rad/m^k, m/rad^k or rad/rad^k
                                                      (`trials.parameter_unit`)
``varied_unit``               (varied)                SI unit of ``drawn`` (coordinate), alike
============================  ======================  ==========================================

Attributes: the campaign's ``seed`` (an integer; one of 2**31 or more, beyond netCDF 3's
integers, as its decimal digits), ``procedure``, ``trials``, ``vary`` (JSON), ``noise``,
``identify_only``, ``versions`` (JSON: machinesim, numpy, scipy, xarray, dask, distributed,
python), ``errors`` (JSON: trial -> message of each failed trial), ``notes`` (JSON: the
trials' notes as `Assembly.notes` groups them, each ``{"note": ..., "trials": [...]}``, most
trials first; a trial's own notes are in its file). A campaign of a user's own procedure
(`machinesim.campaign.own`) has its reference as ``procedure`` (``package.module:Class``)
and besides ``procedure_name`` (its ``name``), ``machine`` and ``base_errors`` (JSON: the
error model the trials are drawn on, SI, `ErrorModel.to_dict`).
"""

from __future__ import annotations

import json
import platform
from importlib import metadata

import numpy as np

from machinesim.exceptions import InputError
from machinesim.experiment import note_kind

__all__ = ["Assembly", "assemble", "versions"]


def versions() -> dict:
    """Versions of the packages a campaign's numbers depend on."""
    out = {"python": platform.python_version()}
    for name in ("machinesim", "numpy", "scipy", "xarray", "dask", "distributed"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


#: netCDF 3 holds 32-bit integers: a seed from here on is kept as its decimal digits (a
#: string attribute), where writing campaign.nc failed once every trial had run.
_NC3_INT_END = 2**31


class Assembly:
    """The Dataset of trials 0 .. trials-1 (`assemble`, module docstring) built as their
    records come, one at a time and in any order (`add`), holding their numbers, not the
    records: a resumed campaign of 20000 paper-003 trial files held every record read
    (~15 kB of dicts each: 460 MB), and would have 1.5 GB at 100000. Each name's values
    are one float64 column of ``trials``; the parameters and figures come out in the order
    the records of trials 0, 1, ... first name them, as when the records are read in order.
    """

    #: record key -> the tables filled from it: (table, index into the record's value or None)
    _TABLES = {"drawn": (("drawn", None),), "injected": (("injected", None),),
               "identified": (("identified", 0), ("identified_std", 1)),
               "figures": (("before", 1), ("after", 2), ("after_std", 3))}

    def __init__(self, spec: dict, trials: int) -> None:
        self.spec, self.trials = spec, int(trials)
        self.varied = list(spec["vary"])
        self.columns: dict[str, dict[str, np.ndarray]] = {
            table: {} for tables in self._TABLES.values() for table, _ in tables}
        self.first: dict[str, dict[str, tuple[int, int]]] = {"identified": {}, "figures": {}}
        self.units: dict[str, tuple[int, str]] = {}  # figure -> (trial, unit): the first's
        self.elapsed = np.full(self.trials, np.nan)
        self.failed = np.zeros(self.trials, dtype=np.int8)
        self.errors: dict[int, str] = {}
        self.notes_count = np.full(self.trials, np.nan)
        self._notes: dict[str, tuple[int, str, list[int]]] = {}  # `note_kind` -> (first
        # trial, its note, the trials)
        self.added = np.zeros(self.trials, dtype=bool)

    def add(self, record: dict) -> None:
        """Take trial ``record["trial"]``'s record (`trials.run_trial`, NaN for null).

        A failed trial's (``error`` not None) is its draws, time and message alone: what it
        holds besides (a trial file edited, or written by hand) is left out, as NaN, where
        its figures were taken into the statistics as a trial that ran."""
        t = record["trial"]
        if not isinstance(t, int) or not 0 <= t < self.trials or self.added[t]:
            raise InputError(f"trial {t!r}; expected each of the records of trials 0 .. "
                             f"{self.trials - 1} once", key="records")
        failed = record["error"] is not None
        for name, value in ({} if failed else record["figures"]).items():
            seen = self.units.get(name)
            if seen is not None and seen[1] != value[0]:
                first, then = sorted((t, seen[0]))
                raise InputError(
                    f"trial {t} gives figure {name!r} in {value[0]}, trial {seen[0]} in "
                    f"{seen[1]}: a campaign's figure holds one unit (trial files of another "
                    "version of machinesim, or edited?); delete the wrong one's file "
                    f"(trials/trial_{first:06d}.json, trials/trial_{then:06d}.json) and run "
                    "again to compute it anew", key="figures")
        self.added[t] = True
        for key, tables in self._TABLES.items():
            if failed and key != "drawn":  # a failed trial identified and measured nothing
                continue
            entries = record[key]
            if key == "drawn":
                entries = {name: entries[name] for name in self.varied if name in entries}
            for position, (name, value) in enumerate(entries.items()):
                if key in self.first:
                    seen = self.first[key].get(name)
                    if seen is None or t < seen[0]:
                        self.first[key][name] = (t, position)
                if key == "figures" and (name not in self.units or t < self.units[name][0]):
                    self.units[name] = (t, value[0])
                for table, index in tables:
                    column = self.columns[table].get(name)
                    if column is None:
                        column = self.columns[table][name] = np.full(self.trials, np.nan)
                    # NaN for what a record lacks: trials written before figures carried
                    # after_std hold three values
                    got = value if index is None else \
                        (value[index] if index < len(value) else None)
                    column[t] = np.nan if got is None else got
        self.elapsed[t] = record["elapsed_s"]
        if failed:
            self.failed[t] = 1
            self.errors[t] = record["error"]
        elif "notes" in record:
            self.notes_count[t] = len(record["notes"])
            for note in record["notes"]:
                kind = note_kind(note)
                first, text, trials = self._notes.get(kind, (t, note, []))
                if not trials or trials[-1] != t:  # a kind noted twice in a trial: once
                    trials.append(t)
                self._notes[kind] = (t, note, trials) if t < first else (first, text, trials)

    def notes(self) -> list[dict]:
        """The trials' notes, grouped by `note_kind` (the same note but for its numbers),
        each ``{"note": the first trial's, "trials": [...]}``, most trials first."""
        groups = sorted(self._notes.values(), key=lambda g: (-len(g[2]), g[0]))
        return [{"note": text, "trials": sorted(trials)} for _, text, trials in groups]

    def _names(self, key: str) -> list[str]:
        return sorted(self.first[key], key=self.first[key].__getitem__)

    def _table(self, table: str, names: list[str]) -> np.ndarray:
        out = np.full((self.trials, len(names)), np.nan)
        for k, name in enumerate(names):
            if name in self.columns[table]:
                out[:, k] = self.columns[table][name]
        return out

    def _units(self, names: list[str]) -> np.ndarray:
        """The SI unit of each parameter (`trials.parameter_unit`: m, rad, or a polynomial
        coefficient's m/m^2): the values are SI, and the name alone tells m from rad, not a
        polynomial's coefficient from a table's value."""
        from machinesim.campaign.shipped import spec_parameter_unit
        from machinesim.exceptions import MachineSimError

        out = []
        for name in names:
            try:
                out.append(spec_parameter_unit(self.spec, name))
            except MachineSimError as error:  # a trial file edited, or of another model
                first = self.first["identified"].get(name, (None,))[0]
                where = "" if first is None else \
                    f" (trials/trial_{first:06d}.json first names it)"
                raise InputError(f"parameter {name!r}{where} has no unit in "
                                 f"{self.spec['procedure']}'s error model: "
                                 f"{getattr(error, 'message', error)}; delete the trial "
                                 "files that name it and run again to compute them anew",
                                 key="records") from None
        return np.array(out, dtype=object)

    def dataset(self):
        """The Dataset, once every trial's record was added."""
        import xarray as xr

        got = int(self.added.sum())
        if got != self.trials:
            raise InputError(f"expected the records of trials 0 .. {self.trials - 1}, got "
                             f"{got}", key="records")
        spec, n, varied = self.spec, self.trials, self.varied
        parameters, figures = self._names("identified"), self._names("figures")
        data = {"drawn": (("trial", "varied"), self._table("drawn", varied))}
        for table in ("injected", "identified", "identified_std"):
            data[table] = (("trial", "parameter"), self._table(table, parameters))
        for table in ("before", "after", "after_std"):
            data[table] = (("trial", "figure"), self._table(table, figures))
        data["notes_count"] = (("trial",), self.notes_count)
        data["elapsed_s"] = (("trial",), self.elapsed)
        data["failed"] = (("trial",), self.failed)
        units = {name: unit for name, (_, unit) in self.units.items()}
        errors = {str(t): self.errors[t] for t in sorted(self.errors)}
        coords = {"trial": np.arange(n), "varied": np.array(varied, dtype=object),
                  "varied_unit": ("varied", self._units(varied)),
                  "parameter": np.array(parameters, dtype=object),
                  "parameter_unit": ("parameter", self._units(parameters)),
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
                del coords[dim], coords[f"{dim}_unit"]
        seed = int(spec["seed"])
        attrs = {"procedure": spec["procedure"],
                 "seed": seed if seed < _NC3_INT_END else str(seed), "trials": n,
                 "noise": int(bool(spec["noise"])),
                 "identify_only": int(bool(spec["identify_only"])),
                 "vary": json.dumps(spec["vary"]), "versions": json.dumps(versions()),
                 "errors": json.dumps(errors), "notes": json.dumps(self.notes()),
                 "seeding": "trial i: numpy SeedSequence(seed).spawn(trials)[i]"}
        if "machine" in spec:  # a user's procedure (`procedure` is its reference)
            attrs.update(procedure_name=spec["name"], machine=spec["machine"],
                         base_errors=json.dumps(spec["errors"]))
        return xr.Dataset(data, coords=coords, attrs=attrs)


def assemble(records, spec: dict, trials: int):
    """The records of trials 0 .. trials-1 (any iterable, in any order) as one
    `xarray.Dataset` (module docstring), through `Assembly`."""
    assembly = Assembly(spec, trials)
    for record in records:
        assembly.add(record)
    return assembly.dataset()
