"""A campaign's files: one small file per finished trial, then the whole as an xarray Dataset.

``DIR/campaign.json`` holds the spec (what the campaign runs); ``DIR/trials/trial_NNNNNN.json``
one trial's record (`machinesim.campaign.trials.run_trial`) with the campaign's identity
(`campaign_id`), each written atomically as the trial completes
(`machinesim._io.write_atomic`). Run again on the same DIR, a campaign reads
the trials already there and computes only the missing ones; a DIR holding another campaign
(another procedure, seed or distribution) is refused, never mixed; a distribution spelt
otherwise (``10nm``, ``0.01um``) is the same one (`same_campaign`). While a campaign runs it
holds ``DIR/campaign.lock`` (`locked`, a kernel file lock, `machinesim.campaign.lock`): a
second one on DIR meanwhile is refused.

``DIR/campaign.nc`` (netCDF 3, xarray's scipy engine) is the Dataset `assemble`
(`machinesim.campaign.assembly`) builds, written whole or not at all.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import sys
from pathlib import Path

from machinesim._io import check_writable, write_atomic
from machinesim._json import json_text, read_json
from machinesim.campaign.assembly import Assembly, assemble, versions  # re-exported
from machinesim.campaign.lock import HOLDER_WAIT_S as HOLDER_WAIT_S  # re-exported
from machinesim.campaign.lock import (  # re-exported, but the folder's making
    LOCK_NAME,
    _make_folder,
    _unmade,
    locked,
    refuse_busy,
)
from machinesim.errors.model import _PARAMETER_RE
from machinesim.exceptions import InputError, brief
from machinesim.experiment import FIGURE_UNITS, note_kind  # note_kind re-exported

__all__ = ["LOCK_NAME", "TRIAL_SCHEMA_VERSION", "Assembly", "CampaignFolder", "assemble",
           "campaign_id", "finished_trials", "legacy_campaign_id", "locked", "note_kind",
           "refuse_busy", "refuse_foreign", "same_campaign", "versions"]


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
            raise _unmade(self.trials_path, exc) from None
        check_writable(self.trials_path / "trial_000000.json", "campaign trial")
        if stored.exists():
            old = read_json(stored, "campaign spec")
            if not isinstance(old, dict):
                raise InputError(f"{brief(repr(old))}; expected the campaign spec, an object "
                                 "(procedure, seed, noise, vary, ...)", source=str(stored))
            if not same_campaign(old, spec):
                kept = _identity_kept(old, spec)
                keys = sorted(k for k in set(old) | set(kept) if old.get(k) != kept.get(k))
                diff = ", ".join(_state_difference(old, kept) if k == "state" else
                                 _difference(k, old.get(k), kept.get(k)) for k in keys
                                 if k != "state_attributes" or "state" not in keys)
                back = (" (or put the procedure's code back as it was, to resume)"
                        if "code" in keys and "procedure" not in keys else "")
                raise InputError(f"holds another campaign ({diff}); give another --out or "
                                 f"empty it{back}", source=str(self.path))
            spec = old  # the texts the campaign was begun with, when spelt otherwise now
        else:
            write_atomic(stored, json_text(spec, "campaign spec"))
        self.spec = spec
        self.id = campaign_id(spec)
        self._ids = {self.id, legacy_campaign_id(spec)}  # the files written before too

    def trial_file(self, i: int) -> Path:
        return self.trials_path / f"trial_{i:06d}.json"

    def done(self, trials: int) -> list[int]:
        """The trials below ``trials`` whose file is there (one listing of trials/, not a
        look-up per trial)."""
        return [i for i in finished_trials(self.path) if i < trials]

    def write_trial(self, record: dict) -> dict:
        """Write ``record`` (`TRIAL_SCHEMA_VERSION` first); return it as `read_trial` reads
        it back (NaN for what JSON holds as null), so that the run need not read it again."""
        stored = _clean({"schema_version": TRIAL_SCHEMA_VERSION, **record,
                         "campaign": self.id})
        write_atomic(self.trial_file(record["trial"]), json_text(stored, "trial"))
        return {**_nan(stored), "error": stored.get("error")}

    def read_trial(self, i: int) -> dict:
        raw = read_json(self.trial_file(i), "campaign trial")
        # the number itself: true and 1.0 equal 1, and a true was taken for trial 1 (an
        # array index, "The truth value of an array ... is ambiguous"), a 1.0 refused
        # naming no file
        if not isinstance(raw, dict) or type(raw.get("trial")) is not int \
                or raw["trial"] != i:
            # it said "expected the record of trial 3" alone, of a copy of trial 4's file as
            # of a '{}' or a list: what the file holds, and what to do, are told too
            found = (f"a JSON {type(raw).__name__}" if not isinstance(raw, dict) else
                     "no trial number ('trial')" if "trial" not in raw else
                     f"the record of trial {brief(repr(raw['trial']))}")
            raise InputError(f"holds {found}; expected the record of trial {i}: delete it and "
                             "run again to compute the trial anew",
                             source=str(self.trial_file(i)), key="trial")
        _check_version(raw, self.trial_file(i))
        _check_record(raw, self.trial_file(i), tuple(self.spec["vary"]))
        self._check_campaign(raw.get("campaign"), self.trial_file(i))
        try:
            return {**_nan(raw), "error": raw.get("error")}
        except RecursionError:  # a key added by hand, lists in lists 500 deep: JSON takes
            # them (read_json's bound is the parser's), _nan's recursion did not
            raise InputError("nested too deeply to be a trial's record (a key added by hand?); "
                             "expected the record as machinesim campaign writes it: delete the "
                             "file and run again to compute the trial anew",
                             source=str(self.trial_file(i))) from None

    def _check_campaign(self, found, path: Path) -> None:
        """Refuse a trial file written by another campaign (`campaign_id`): one copied from
        another campaign's folder under the same name was taken as this one's trial. A file
        without the key, written before trial files held it, is taken as the folder's, and
        so is one holding the identity of its campaign.json's DIST texts as spelt
        (`legacy_campaign_id`, written before the identity took their meaning)."""
        if found is None or found in self._ids:
            return
        raise InputError(f"{brief(repr(found))}: the trial file of another campaign (this "
                         f"folder's campaign.json is campaign {self.id}); copied from "
                         "another campaign's folder? delete it and run again to compute the "
                         "trial anew", source=str(path), key="campaign")

    def write_dataset(self, dataset, name: str = "campaign.nc") -> Path:
        path = self.path / name
        write_atomic(path, bytes(dataset.to_netcdf()))
        return path


#: campaign.json's keys that name the code a campaign runs and its procedure's state
#: (`CampaignSpec.describe`, `machinesim.campaign.identity`), added 2026-12-01: a
#: campaign.json written before has none, and is resumed as it was (nothing then told
#: what code its trials ran).
IDENTITY_KEYS = ("machinesim", "code", "state", "state_attributes")


def _identity_kept(old: dict, new: dict) -> dict:
    """``new`` without the `IDENTITY_KEYS` that campaign.json ``old`` was written without,
    and without its code's ``imports`` when ``old``'s code has none (written before they
    were kept, 2026-12-01)."""
    kept = {k: v for k, v in new.items() if k in old or k not in IDENTITY_KEYS}
    code, was = kept.get("code"), old.get("code")
    if isinstance(code, dict) and isinstance(was, dict) and "imports" not in was:
        kept["code"] = {k: v for k, v in code.items() if k != "imports"}
    return kept


def _difference(key: str, old, new) -> str:
    """How campaign.json's ``key`` differs, for the refusal of another campaign: a user's
    procedure's ``errors`` (its whole error model, tables and all) by the entries that
    differ, each value `brief` (the model was shown whole: 96,016 characters for a table of
    2,001 positions, the one offset that differed lost in it)."""
    if key == "code" and isinstance(old, dict) and isinstance(new, dict):
        return _code_difference(old, new)
    if key == "state":
        return ("state: the procedure object's state (its attributes: the arguments it was "
                f"made with) is digest {new} now, {old} there: other arguments, or another "
                "object, than the campaign began with")
    if key == "machinesim":
        return (f"machinesim: version {old} there, {new} now (its trials ran the other "
                "version's code)")
    if key != "errors" or not isinstance(old, dict) or not isinstance(new, dict):
        return f"{key}: {old!r} there, {new!r} now"
    found = []

    def walk(a, b, path):
        for k in sorted(set(a) | set(b)):
            x, y = a.get(k), b.get(k)
            if isinstance(x, dict) and isinstance(y, dict):
                walk(x, y, f"{path}{k}.")
            elif x != y:
                found.append(f"{path}{k} {brief(repr(x))} there, {brief(repr(y))} now")

    walk(old, new, "")
    more = f"; and {len(found) - 4} more" if len(found) > 4 else ""
    return f"errors: {'; '.join(found[:4])}{more}"


def _state_difference(old: dict, new: dict) -> str:
    """How a user's procedure object's state differs from the campaign's (campaign.json's
    ``state``): by the attributes whose digests differ (``state_attributes``,
    `machinesim.campaign.identity.attributes_of`), each with its values where they are plain
    ("gain 1.0 there, 2.0 now"); by the two digests where either campaign lacks them (one
    begun before they were kept, a state not made of attributes)."""
    before, now = _attributes(old), _attributes(new)
    said = []
    if before is not None and now is not None:
        for name in sorted(set(before) | set(now)):
            was, is_ = before.get(name), now.get(name)
            if was is None:
                said.append(f"{name} is new")
            elif is_ is None:
                said.append(f"{name} is gone")
            elif was[0] != is_[0]:
                said.append(f"{name} {was[1]} there, {is_[1]} now" if was[1] is not None and
                            is_[1] is not None else f"{name} changed")
    if not said:
        return _difference("state", old.get("state"), new.get("state"))
    more = f"; and {len(said) - 4} more" if len(said) > 4 else ""
    return (f"state: the procedure object's attributes (the arguments it was made with) "
            f"differ: {'; '.join(said[:4])}{more}")


def _attributes(spec: dict) -> dict | None:
    """``spec``'s ``state_attributes`` where it is as `attributes_of` writes it (each name
    -> [digest text, shown text or None]), else None: a campaign.json edited by hand (an
    entry 5, [] or a digest alone) was read into a TypeError or an IndexError where the
    refusal was to be told; it is refused by the two digests instead."""
    found = spec.get("state_attributes")
    if not isinstance(found, dict) or not all(
            isinstance(entry, list) and len(entry) == 2 and isinstance(entry[0], str)
            and isinstance(entry[1], str | None) for entry in found.values()):
        return None
    return found


def _code_difference(old: dict, new: dict) -> str:
    """How a user's procedure's code (`machinesim.campaign.identity.code_of`) differs from the
    code its campaign began with: the classes whose source and the modules whose file
    changed, or came or went."""
    said = []
    for part, what in (("classes", "the source of class"), ("modules", "the file of module"),
                       ("imports", "the file of imported module")):
        before, now = old.get(part), new.get(part)
        if not isinstance(before, dict) or not isinstance(now, dict):
            continue
        for name in sorted(set(before) | set(now)):
            if name not in before:
                said.append(f"{what} {name} is new")
            elif name not in now:
                said.append(f"{what} {name} is no longer run")
            elif before[name] != now[name]:
                said.append(f"{what} {name} changed")
    shown = "; ".join(said) if said else f"{brief(repr(old))} there, {brief(repr(new))} now"
    return (f"code: {shown}, since the campaign began: its trials ran the code as it was, "
            "and a resume would mix them with the new code's in one summary")


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
                         if not _TRIAL_FILE.fullmatch(name))
    if not found and not others:
        return
    held = ([f"{len(found)} trial file{'s' * (len(found) > 1)} in trials/"] if found
            else []) + others[:5] + (["..."] if len(others) > 5 else [])
    raise InputError(f"holds {', '.join(held)} but no campaign.json: not a campaign "
                     "folder (a scenario's report, or a campaign whose campaign.json is "
                     "gone); expected a new or empty folder, or a campaign folder: give "
                     "another --out or empty it", source=str(path))


def campaign_id(spec: dict) -> str:
    """The identity of the campaign ``spec`` (campaign.json's): the first 16 hex digits of
    the SHA-256 of its JSON with sorted keys, which each trial file holds as ``campaign``
    (procedure, seed, noise, options, and each ``vary`` distribution by its meaning,
    `_meaning`: ``10nm`` and ``0.01um`` are one campaign, as `same_campaign` takes them).

    The DIST texts went in as spelt, so the trial file of a campaign begun with ``0.01um``,
    copied into the folder of one begun with ``10nm``, was refused as another campaign's.
    A spec whose ``vary`` is empty has the identity it had then; a file written with the
    identity of the texts is still its folder's (`legacy_campaign_id`)."""
    vary = spec.get("vary")
    if isinstance(vary, dict):
        spec = {**spec, "vary": {name: _meaning(name, text) for name, text in vary.items()}}
    return legacy_campaign_id(spec)


def legacy_campaign_id(spec: dict) -> str:
    """`campaign_id` as it was before 2026-11-30, of campaign.json's DIST texts as spelt:
    the identity the trial files written then hold."""
    text = json.dumps(spec, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


#: Significant digits of a distribution's SI numbers in a campaign's meaning (`_parsed`),
#: which both `campaign_id` and `same_campaign` go by: the units' factors leave 60nm and
#: 0.06um a last bit apart (6.000000000000001e-08 and 6e-08), which these digits do not see.
IDENTITY_DIGITS = 12


def _parsed(name: str, text) -> str | None:
    """The meaning of the distribution ``text`` of ``name``: its kind and SI numbers to
    `IDENTITY_DIGITS` significant digits, ``uniform:1e-08,2e-08`` for ``uniform:10nm,0.02um``;
    None for a text that does not parse (a campaign.json edited by hand)."""
    from machinesim.campaign.distributions import KINDS, parse_distribution

    try:
        dist = parse_distribution(text, name)
    except (InputError, TypeError):
        return None
    numbers = (dist.a, dist.b)[:KINDS[dist.kind]]
    # + 0.0: -0 is 0 ("uniform:-0um,1um")
    return f"{dist.kind}:" + ",".join(f"{x + 0.0:.{IDENTITY_DIGITS}g}" for x in numbers)


def _meaning(name: str, text):
    """The distribution ``text`` of ``name`` in `campaign_id`: its meaning (`_parsed`), or a
    text that does not parse as it is, which only its own spelling matches."""
    meaning = _parsed(name, text)
    return text if meaning is None else meaning


def same_campaign(old: dict, new: dict) -> bool:
    """True when the campaign specs ``old`` (campaign.json) and ``new``
    (`CampaignSpec.describe`) run the same trials: equal but for how each ``vary``
    distribution is spelt, which is compared by its meaning (`_parsed`: the kind and its
    numbers in SI to `IDENTITY_DIGITS` significant digits, which the units' rounding does
    not reach: ``uniform:10nm,20nm``, ``uniform:10 nm,0.02um``), the same meaning
    `campaign_id` hashes, so that a folder resumes exactly the campaigns whose trial files
    it takes for its own. A stored text that no longer parses is not the same.

    They had compared within 1e-12 relative while the identity rounds to 12 digits: 1um
    and 1.000000000004um were refused as two campaigns, yet each took the other's trial
    files (one identity); 1.0000000000049um and 1.0000000000051um the other way round."""
    new = _identity_kept(old, new)  # a campaign.json written before they were kept
    if old == new:
        return True
    if {k: v for k, v in old.items() if k != "vary"} != \
            {k: v for k, v in new.items() if k != "vary"}:
        return False
    before, now = old.get("vary"), new.get("vary")
    if not isinstance(before, dict) or not isinstance(now, dict) or set(before) != set(now):
        return False
    for name, text in now.items():
        meaning = _parsed(name, text)
        if meaning is None or meaning != _parsed(name, before[name]):
            return False
    return True


#: The version of a trial file's record (`trials.run_trial`, `CampaignFolder.write_trial`),
#: under ``schema_version``. A file without one was written before the field was added, when
#: the record was this version's (the field is its only change since): it is read as this
#: version. A change a reader of the old record would misread takes the next number.
TRIAL_SCHEMA_VERSION = 1


def _check_version(raw: dict, path: Path) -> None:
    """Refuse a trial file of another record version than `TRIAL_SCHEMA_VERSION`, naming
    the file and both versions; none is that version (written before the field)."""
    version = raw.get("schema_version", TRIAL_SCHEMA_VERSION)
    if type(version) is int and version == TRIAL_SCHEMA_VERSION:
        return
    newer = (" (written by a newer machinesim? update this one, or run the campaign into "
             "another --out)" if type(version) is int and version > TRIAL_SCHEMA_VERSION
             else "")
    raise InputError(f"schema_version {brief(repr(version))}; this machinesim reads trial "
                     f"files of schema version {TRIAL_SCHEMA_VERSION}{newer}",
                     source=str(path), key="schema_version")


def _number(value) -> bool:
    """A number or null (NaN as JSON writes it): an int a float holds (an edited 1 followed
    by 400 zeros, beyond float64, ended the campaign in an OverflowError as it was read)."""
    if value is None or isinstance(value, float):
        return True
    return isinstance(value, int) and not isinstance(value, bool) and abs(value) <= _MOST_INT


def _spread(value) -> bool:
    """A std or spread: null (none stated) or a number >= 0 (`_number`)."""
    return value is None or value >= 0


#: A figure's name in a trial file (`_check_record`): a procedure's, as a file name takes it.
_FIGURE_NAME = re.compile(r"[A-Za-z0-9_]+")

#: The largest int a float64 holds (`_number`).
_MOST_INT = int(sys.float_info.max)


def _check_record(raw: dict, path: Path, varied: tuple[str, ...]) -> None:
    """Refuse a trial file that is JSON but not a trial's record (`trials.run_trial`), naming
    the key: ``drawn`` each of the campaign's ``varied`` parameters -> a number (no other,
    none null: a trial draws each before it runs, failed or not), ``injected`` name ->
    number, ``identified`` name -> [value, std >= 0 or null], ``figures`` name -> [unit
    (`FIGURE_UNITS`), before, after(, after_std >= 0 or null)], ``notes`` (when there) a
    list of texts, ``elapsed_s`` a number, ``error`` null or a message (not blank);
    assembling it would otherwise fail on the first key it lacks."""
    def refuse(key: str, what: str) -> None:
        raise InputError(f"{brief(repr(raw.get(key)))}; expected {what} (a trial record as "
                         "machinesim campaign writes it): delete the file and run again to "
                         "compute the trial anew", source=str(path), key=key)

    entry_checks = {
        "drawn": (lambda v: _number(v), "an object of numbers"),
        "injected": (lambda v: _number(v), "an object of numbers"),
        # a std is a spread, >= 0 (or null): an edited -1 flipped that trial's z-score
        "identified": (lambda v: isinstance(v, list) and len(v) == 2
                       and all(_number(x) for x in v) and _spread(v[1]),
                       "an object of [value, std], the std >= 0 or null"),
        "figures": (lambda v: isinstance(v, list) and len(v) in (3, 4)
                    and v[0] in FIGURE_UNITS and all(_number(x) for x in v[1:])
                    and (len(v) == 3 or _spread(v[3])),
                    "an object of [unit, before, after, after_std], the unit one of "
                    + " ".join(FIGURE_UNITS) + ", the after_std >= 0 or null"),
    }
    for key, (good, what) in entry_checks.items():
        entries = raw.get(key)
        if not isinstance(entries, dict) or not all(good(v) for v in entries.values()):
            refuse(key, what)
    # a figure's name becomes a file's (hist_NAME.png): 'a/b' was refused only once every
    # trial had run ('the folder .../hist_a does not exist'), a NUL ended the campaign in
    # 'ValueError: embedded null byte'; procedures name figures in letters, digits and _
    odd = next((n for n in raw["figures"] if not _FIGURE_NAME.fullmatch(n)), None)
    if odd is not None:
        raise InputError(f"figure name {brief(repr(odd))}; expected letters, digits and _ (a "
                         "procedure's figure, as machinesim campaign writes it): delete the "
                         "file and run again to compute the trial anew", source=str(path),
                         key="figures")
    for key in ("injected", "identified"):  # error parameters' names (netCDF coordinates)
        odd = next((n for n in raw[key] if not _PARAMETER_RE.fullmatch(n)), None)
        if odd is not None:
            raise InputError(f"parameter name {brief(repr(odd))}; expected an error "
                             "parameter's (tool.y, location.C.EX0C, component.X.EXX[2]), as "
                             "machinesim campaign writes it: delete the file and run again to "
                             "compute the trial anew", source=str(path), key=key)
    notes = raw.get("notes", [])  # none in a file written before notes were kept
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        refuse("notes", "a list of the identification's notes (texts)")
    if not _number(raw.get("elapsed_s")):
        refuse("elapsed_s", "a number of seconds")
    # an empty message was taken as a failure naming nothing (summary.md's "Failed trials"
    # listed it as a blank line): a failure says what failed
    error = raw.get("error")
    if not (error is None or isinstance(error, str) and error.strip()):
        refuse("error", "null or the failed trial's message, which names what failed")
    # drawn: what the trial ran with, each varied parameter's value. A file edited to lack
    # one (or hold null) gave that trial a NaN in campaign.nc's drawn, silently, and one
    # naming another parameter was taken, the name dropped
    drawn = raw["drawn"]
    if set(drawn) != set(varied) or any(drawn[name] is None for name in varied):
        lacking = sorted(name for name in varied if drawn.get(name) is None)
        extra = sorted(set(drawn) - set(varied))
        said = "; ".join(
            ([f"no value of {', '.join(map(repr, lacking))}"] if lacking else [])
            + ([f"values of {', '.join(map(repr, extra))}, which the campaign does not vary"]
               if extra else []))
        raise InputError(f"drawn has {brief(said)}; expected a number for each parameter the "
                         f"campaign varies ({brief(', '.join(varied)) or 'none'}), as "
                         "machinesim campaign writes it: delete the file and run again to "
                         "compute the trial anew", source=str(path), key="drawn")


def finished_trials(path) -> list[int]:
    """The trials of the campaign folder ``path`` whose file is in its trials/ (sorted;
    none when there is no such folder). A trial's file is named as `CampaignFolder` writes
    it, ``trial_NNNNNN.json``: a ``trial_1.json`` (a copy renamed by hand) is no trial's, where
    it once counted trial 1 as done while trial_000001.json, the file read, was not there."""
    try:
        names = os.listdir(Path(path) / "trials")
    except OSError:
        return []
    found = []
    for name in names:
        match = _TRIAL_FILE.fullmatch(name)
        if match:
            found.append(int(match[1]))
    return sorted(found)


#: The name of a trial's file (`CampaignFolder.trial_file`): six digits, ASCII.
_TRIAL_FILE = re.compile(r"trial_([0-9]{6})\.json")
