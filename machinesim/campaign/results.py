"""A campaign's files: one small file per finished trial, then the whole as an xarray Dataset.

``DIR/campaign.json`` holds the spec (what the campaign runs); ``DIR/trials/trial_NNNNNN.json``
one trial's record (`machinesim.campaign.trials.run_trial`), each written atomically as the
trial completes (`machinesim._io.write_atomic`). Run again on the same DIR, a campaign reads
the trials already there and computes only the missing ones; a DIR holding another campaign
(another procedure, seed or distribution) is refused, never mixed; a distribution spelt
otherwise (``10nm``, ``0.01um``) is the same one (`same_campaign`). While a campaign runs it
holds ``DIR/campaign.lock`` (`locked`, a kernel file lock): a second one on DIR meanwhile is
refused.

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
``notes_count``               (trial)                 how many notes the identification gave
                                                      (`Identified.notes`: readings that do not
                                                      fit the model, ...); NaN for a failed
                                                      trial and one written before they were kept
``elapsed_s``                 (trial)                 wall time of the trial, s
``failed``                    (trial)                 1 where the trial ended in an error
``figure_unit``               (figure)                unit of ``before``/``after`` (coordinate)
============================  ======================  ==========================================

Attributes: the campaign's ``seed`` (an integer; one of 2**31 or more, beyond netCDF 3's
integers, as its decimal digits), ``procedure``, ``trials``, ``vary`` (JSON), ``noise``,
``identify_only``, ``versions`` (JSON: machinesim, numpy, scipy, xarray, dask, distributed,
python), ``errors`` (JSON: trial -> message of each failed trial), ``notes`` (JSON: the
trials' notes as `Assembly.notes` groups them, each ``{"note": ..., "trials": [...]}``, most
trials first; a trial's own notes are in its file).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import platform
import re
import socket
import time
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path

import numpy as np

from machinesim._io import check_writable, json_text, pid_alive, read_json, write_atomic
from machinesim.exceptions import FileError, InputError, brief

__all__ = ["LOCK_NAME", "Assembly", "CampaignFolder", "assemble", "finished_trials", "locked",
           "note_kind", "refuse_foreign", "same_campaign", "versions"]


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
        _make_folder(self.path)
        stored = self.path / "campaign.json"
        refuse_foreign(self.path)  # before trials/ is made in it
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

    def trial_file(self, i: int) -> Path:
        return self.trials_path / f"trial_{i:06d}.json"

    def done(self, trials: int) -> list[int]:
        """The trials below ``trials`` whose file is there (one listing of trials/, not a
        look-up per trial)."""
        return [i for i in finished_trials(self.path) if i < trials]

    def write_trial(self, record: dict) -> dict:
        """Write ``record``; return it as `read_trial` reads it back (NaN for what JSON
        holds as null), so that the run need not read it again."""
        stored = _clean(record)
        write_atomic(self.trial_file(record["trial"]), json_text(stored, "trial"))
        return {**_nan(stored), "error": stored.get("error")}

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


def refuse_foreign(path) -> None:
    """Refuse a folder ``path`` without campaign.json that holds anything but an empty
    trials/ (and a campaign.lock); nothing when there is no such folder.

    campaign.json is written before any trial, so trial files without it are of a
    campaign nobody can tell (copied, or its campaign.json deleted): they were taken
    for this campaign's. Other files are not a campaign's at all (a scenario's report
    folder): the campaign wrote its summary.json and summary.md over them.
    Called before the lock is taken as well, so that a folder refused is left as it was
    (the lock's file stays, `locked`).
    """
    path = Path(path)
    trials = path / "trials"
    if not path.is_dir() or (path / "campaign.json").exists():
        return
    found = finished_trials(path)
    others = sorted(name for name in os.listdir(path) if name != LOCK_NAME  # ours
                    and (name != "trials" or not trials.is_dir()))
    if trials.is_dir():
        others += sorted(f"trials/{name}" for name in os.listdir(trials)
                         if not name.startswith("trial_") or not name.endswith(".json"))
    if not found and not others:
        return
    held = ([f"{len(found)} trial file{'s' * (len(found) > 1)} in trials/"] if found
            else []) + others[:5] + (["..."] if len(others) > 5 else [])
    raise InputError(f"holds {', '.join(held)} but no campaign.json: not a campaign "
                     "folder (a scenario's report, or a campaign whose campaign.json is "
                     "gone); expected a new or empty folder, or a campaign folder: give "
                     "another --out or empty it", source=str(path))


def _make_folder(path: Path) -> None:
    """Make the campaign folder ``path`` (not its trials/), refusing a file there."""
    if path.exists() and not path.is_dir():
        raise FileError("is a file; expected the campaign folder", source=str(path))
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FileError(f"cannot make the campaign folder: {exc.strerror or exc}",
                        source=str(path)) from None


@contextlib.contextmanager
def locked(folder) -> Iterator[None]:
    """Hold ``folder/campaign.lock`` within the block, the folder made when missing; taken
    before campaign.json is read or written.

    Two campaigns run on one folder at the same time ran the same missing trials, each
    writing every one of their files. The lock is the kernel's: an exclusive `fcntl.flock`
    on the open file, held for the block and released when its process ends, however it
    ends (SIGKILL, a power loss), so a killed campaign's lock is free to the next run, and
    of two runs that find it at the same instant one takes it (both did when each removed
    the stale file, or the other's fresh one, and made its own). The file is never removed
    (it stays after the run, held by nobody); it names the pid and host of the run that
    took it last, for the message refusing a second run.
    """
    folder = Path(folder)
    try:
        import fcntl
    except ImportError:  # Windows
        raise FileError("cannot lock the campaign folder: campaigns need POSIX file locks "
                        "(fcntl.flock), which this Python lacks; run the campaign on Linux "
                        "or macOS", source=str(folder)) from None
    _make_folder(folder)
    path = folder / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise FileError(f"cannot make the campaign's lock {LOCK_NAME}: "
                        f"{exc.strerror or exc}", source=str(folder)) from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _busy(folder, _named_holder(path)) from None
        except OSError as exc:  # ENOLCK: a file system that takes no locks (NFS without)
            raise FileError(f"cannot lock the campaign's lock {LOCK_NAME}: "
                            f"{exc.strerror or exc}; expected a folder on a file system "
                            "that takes file locks (flock)", source=str(folder)) from None
        os.ftruncate(fd, 0)
        os.write(fd, (json.dumps({"pid": os.getpid(), "host": socket.gethostname()})
                      + "\n").encode())
        yield
    finally:
        os.close(fd)  # the kernel releases the lock


#: Seconds a run refused the lock gives its file to name the run that has just taken it.
HOLDER_WAIT_S = 0.5


def _named_holder(path: Path) -> tuple[int, str] | None:
    """The holder the held lock ``path`` names (`_lock_holder`), given `HOLDER_WAIT_S` to
    name the run that has just taken it: until that run writes it, the file names nobody or
    the run before, which has ended."""
    deadline = time.monotonic() + HOLDER_WAIT_S
    while True:
        holder = _lock_holder(path)
        if (holder is not None and (holder[1] != socket.gethostname()
                                    or pid_alive(holder[0]))) or time.monotonic() > deadline:
            return holder
        time.sleep(0.02)


def _busy(folder: Path, holder: tuple[int, str] | None) -> InputError:
    lock = folder / LOCK_NAME
    if holder is None:
        who = f"its lock {lock} does not say which process (being taken just now, or damaged)"
    else:
        pid, host = holder
        where = "" if host == socket.gethostname() else f" on host {host}"
        who = f"pid {pid}{where}, holding {lock}"
    return InputError(f"another campaign is running in this folder ({who}): both would run "
                      "the same trials; wait for it to end, or give another --out",
                      source=str(folder))


#: The file a running campaign holds in its folder (`locked`).
LOCK_NAME = "campaign.lock"


def _lock_holder(path: Path) -> tuple[int, str] | None:
    """(pid, host) of the lock ``path``; None when it cannot be read as such."""
    try:
        held = json.loads(path.read_text(encoding="utf-8"))
        pid, host = held["pid"], held["host"]
    except (OSError, ValueError, TypeError, KeyError):
        return None
    if isinstance(pid, bool) or not isinstance(pid, int) or not 0 < pid < 2**31 \
            or not isinstance(host, str):
        return None
    return pid, host


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
    ``figures`` name -> [unit, before, after(, after_std)], ``notes`` (when there) a list of
    texts, ``elapsed_s`` a number, ``error`` null or a message; assembling it would
    otherwise fail on the first key it lacks."""
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
    notes = raw.get("notes", [])  # none in a file written before notes were kept
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        refuse("notes", "a list of the identification's notes (texts)")
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


#: A number in a note (a residual, a correlation, a std), not part of a name (``EX0C``,
#: ``EAC[3]``): `note_kind` leaves it out.
_NUMBER = re.compile(r"(?<![\w.\[])[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?(?![\w\]])")


def note_kind(note: str) -> str:
    """``note`` with its numbers as ``#``: the same note of two trials (``the readings do not
    fit the model: normalised residual 25.7 ...`` and ``... 31.2 ...``) is one kind."""
    return _NUMBER.sub("#", note)


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
        """Take trial ``record["trial"]``'s record (`trials.run_trial`, NaN for null)."""
        t = record["trial"]
        if not isinstance(t, int) or not 0 <= t < self.trials or self.added[t]:
            raise InputError(f"trial {t!r}; expected each of the records of trials 0 .. "
                             f"{self.trials - 1} once", key="records")
        self.added[t] = True
        for key, tables in self._TABLES.items():
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
        if record["error"] is not None:
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
        attrs = {"procedure": spec["procedure"],
                 "seed": seed if seed < _NC3_INT_END else str(seed), "trials": n,
                 "noise": int(bool(spec["noise"])),
                 "identify_only": int(bool(spec["identify_only"])),
                 "vary": json.dumps(spec["vary"]), "versions": json.dumps(versions()),
                 "errors": json.dumps(errors), "notes": json.dumps(self.notes()),
                 "seeding": "trial i: numpy SeedSequence(seed).spawn(trials)[i]"}
        return xr.Dataset(data, coords=coords, attrs=attrs)


def assemble(records, spec: dict, trials: int):
    """The records of trials 0 .. trials-1 (any iterable, in any order) as one
    `xarray.Dataset` (module docstring), through `Assembly`."""
    assembly = Assembly(spec, trials)
    for record in records:
        assembly.add(record)
    return assembly.dataset()
