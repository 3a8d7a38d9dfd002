"""A run saved and read back (`machinesim.result_file`): a loaded result passes the checks a
made one does, and a damaged file is refused naming the file and the field."""

from __future__ import annotations

import io
import math
import pickle

import pytest

from machinesim.exceptions import InputError
from machinesim.experiment import Figure, Result
from machinesim.result_file import load_result, save_result


@pytest.fixture(scope="module")
def result():
    """A toy procedure's result on a noise-free lab: one figure ``x`` (um), 1.0 then 0.5."""
    from toy_procedure import WorkpieceX

    from machinesim import Lab
    from machinesim.experiment import run

    return run(WorkpieceX(0.5), Lab("robonano_a0ib", noise=False))


def _tampered(result, **changes) -> bytes:
    """``result`` pickled as a hand-edited file or another version would hold it: each field
    in ``changes`` set to its value, or left out where the value is `_LEFT_OUT`; a key of the
    form ``figure.<field>`` changes the first figure's field."""

    class Editing(pickle.Pickler):
        def reducer_override(self, obj):
            if isinstance(obj, Result | Figure):
                rebuild, (cls, values, proxies) = obj.__reduce__()
                prefix = "" if isinstance(obj, Result) else "figure."
                values = dict(values)
                for key, value in changes.items():
                    if key.startswith(prefix) and (prefix or "." not in key):
                        field = key.removeprefix(prefix)
                        if value is _LEFT_OUT:
                            values.pop(field)
                        else:
                            values[field] = value
                return rebuild, (cls, values, proxies)
            return NotImplemented

    buffer = io.BytesIO()
    Editing(buffer, protocol=pickle.HIGHEST_PROTOCOL).dump(result)
    return buffer.getvalue()


_LEFT_OUT = object()


def test_a_saved_result_loads_back_the_same(result, tmp_path):
    path = save_result(result, tmp_path / "run.pkl")
    back = load_result(path)
    assert back.summary() == result.summary()
    assert back.figure("x") == Figure("x", "um", 1.0, 0.5)


@pytest.mark.parametrize(("changes", "key", "says"), [
    ({"figure.unit": "furlong"}, "unit", "figure 'x': unit 'furlong'; expected one of m, mm"),
    ({"seed": math.nan}, "seed", "Result.seed: expected a non-negative int or a numpy "
                                 "SeedSequence, got float nan"),
    ({"seed": "0"}, "seed", "Result.seed: expected a non-negative int"),
    ({"noise": "no"}, "noise", "Result.noise: expected True or False, got str 'no'"),
    ({"injected": {"workpiece.x": math.nan}}, "injected",
     "Result.injected: expected a mapping of parameter names to finite numbers (SI)"),
    ({"identified": {"workpiece.x": ("0", 1e-9)}}, "identified",
     "Result.identified: expected a mapping of parameter names to (value, std)"),
    ({"figures": [1.0]}, "figures", "Result.figures: expected a tuple of Figure, got list"),
    ({"evaluation": None}, "evaluation", "Result.evaluation: expected an Evaluation"),
    ({"figures": _LEFT_OUT}, "figures", "a pickled Result without its field 'figures': cut "
                                        "short, or written by another version"),
    ({"machine": _LEFT_OUT}, "machine", "a pickled Result without its field 'machine'"),
    ({"figure.name": _LEFT_OUT}, "name", "a pickled Figure without its field 'name'"),
    ({"colour": "red"}, "colour", "a pickled Result with fields it does not have (colour; "
                                  "it has paper, procedure, machine"),
    # 10**400 (1329 bits) is a real number float() refuses: math.isfinite and float raised
    # OverflowError ('int too large to convert to float'), naming no field, and a std of
    # 10**400 was taken
    ({"injected": {"workpiece.x": 10**400}}, "injected",
     "Result.injected: expected a mapping of parameter names to finite numbers (SI)"),
    ({"identified": {"workpiece.x": (0.0, 10**400)}}, "identified",
     "Result.identified: expected a mapping of parameter names to (value, std)"),
    ({"elapsed_s": {"run": 10**400}}, "elapsed_s",
     "Result.elapsed_s: expected a mapping of step names to times >= 0 (s)"),
    ({"figure.after": 10**400}, "x.after", "Expected x.after as a number or None, got 1000"),
])
def test_a_hand_edited_or_other_versions_result_is_refused_naming_the_file_and_field(
        result, tmp_path, changes, key, says):
    # Before, each loaded (pickle rebuilt the fields with no check): a figure in furlongs
    # printed in the table, a NaN seed or a missing field failed later in write_result.
    path = tmp_path / "run.pkl"
    path.write_bytes(_tampered(result, **changes))
    with pytest.raises(InputError) as refused:
        load_result(path)
    assert refused.value.source == str(path) and refused.value.key == key
    assert says in str(refused.value)
    assert str(refused.value).startswith(f"{path}, key '{key}': the saved result: ")


def test_plain_pickle_checks_a_loaded_figure_and_result_too(result):
    # the checks are the classes' own (a Dask worker's result comes back through them)
    with pytest.raises(InputError, match="unit 'furlong'"):
        pickle.loads(_tampered(result, **{"figure.unit": "furlong"}))
    with pytest.raises(InputError, match="without its field 'figures'"):
        pickle.loads(_tampered(result, figures=_LEFT_OUT))


def test_a_field_added_since_takes_its_default_as_the_constructor_gives_it(result, tmp_path):
    # a result saved before `polynomials` and `background` were fields
    path = tmp_path / "old.pkl"
    path.write_bytes(_tampered(result, polynomials=_LEFT_OUT, background=_LEFT_OUT))
    back = load_result(path)
    assert back.polynomials == () and dict(back.background) == {}
    assert back.summary() == result.summary()


def test_a_truncated_or_foreign_file_is_refused_naming_it(result, tmp_path):
    whole = pickle.dumps(result)
    path = tmp_path / "cut.pkl"
    for size in (0, 1, len(whole) // 2, len(whole) - 1):
        path.write_bytes(whole[:size])
        with pytest.raises(InputError, match="not a whole saved result") as refused:
            load_result(path)
        assert refused.value.source == str(path), size
    path.write_bytes(pickle.dumps({"paper": "000"}))
    with pytest.raises(InputError, match="holds a dict, not a machinesim.experiment.Result"):
        load_result(path)
    path.write_text('{"paper": "000", "figures": []}')  # a summary.json is no saved result
    with pytest.raises(InputError, match="not a whole saved result"):
        load_result(path)
    with pytest.raises(InputError, match="saved result"):
        load_result(tmp_path / "missing.pkl")
    with pytest.raises(InputError, match="Expected a machinesim.experiment.Result"):
        save_result(result.summary(), tmp_path / "x.pkl")


def test_a_file_whose_frame_length_is_beyond_any_size_is_refused_naming_it(tmp_path):
    # a damaged length byte of pickle protocol 5's FRAME opcode (0x95, 8 bytes): pickle
    # raised OverflowError ('FRAME length exceeds system's maximum'), a traceback; random
    # byte damage to a saved result met it in 6 of 3000 files
    path = tmp_path / "damaged.pkl"
    path.write_bytes(b"\x80\x05\x95" + b"\xff" * 8 + b".")
    with pytest.raises(InputError, match="not a whole saved result \\(OverflowError") as refused:
        load_result(path)
    assert refused.value.source == str(path)



def test_an_int_beyond_float64_is_no_figure_nor_identified_value():
    from machinesim.experiment import Identified

    with pytest.raises(InputError, match="Expected x.before as a number or None") as refused:
        Figure("x", "um", 10**400, 0.5)
    assert refused.value.key == "x.before"
    with pytest.raises(InputError, match=r"as numbers \(value, std\)") as refused:
        Identified({"workpiece.x": (0.0, -10**400)})
    assert refused.value.key == "workpiece.x"


def test_an_identified_std_is_a_spread_refused_below_zero_when_identified():
    # Identified took (1e-6, -1e-9): the run ended, then its report's summary.json was
    # refused ('std must be >= 0') and a campaign wrote a trial file its resume refuses
    from machinesim.experiment import Identified

    with pytest.raises(InputError, match=r"Expected parameters\['tool.x'\]'s std >= 0 \(or "
                                         r"NaN: none stated\), got \(1e-06, -1e-09\)") as info:
        Identified({"tool.x": (1e-6, -1e-9)})
    assert info.value.key == "tool.x"
    kept = Identified({"tool.x": (1e-6, 0.0), "tool.y": (2e-6, math.nan), "tool.z": 3e-6})
    assert kept.parameters["tool.x"] == (1e-6, 0.0) and math.isnan(
        kept.parameters["tool.y"][1]) and math.isnan(kept.parameters["tool.z"][1])


@pytest.mark.parametrize("path", [None, b"run.pkl", 5])
def test_a_saved_result_named_by_no_file_name_is_refused_as_such(path):
    # save_result refused these (check_path); load_result's check_readable_file gave them
    # to Path(), a TypeError traceback ('expected str, bytes or os.PathLike object')
    with pytest.raises(InputError, match=r"reading the saved result: expected a file name "
                                         r"\(str or pathlib.Path\), got ") as refused:
        load_result(path)
    assert refused.value.key == "path"


def test_a_result_and_its_identified_say_what_they_are_with_units(result, tmp_path):
    """Their repr had been the dataclass dump: a Result's measurements, programs and
    evaluation in full, identified as bare SI tuples (`mappingproxy({'tool.x':
    (3.997833333334532e-06, 1.4433997290348152e-08), ...})`), no unit. Now the run, each
    identified value with its unit and std, each figure before -> after in its unit, the
    notes' count; the same after a save and load."""
    from machinesim.experiment import Identified

    text = repr(result)
    assert text.startswith("Result(workpiece_x (")
    assert " on robonano_a0ib, seed 0, noise off, realism ideal; " in text
    assert "figures before -> after: x 1 -> 0.5 um; 0 notes)" in text
    assert "identified workpiece.x = " in text and " m +- 1e-09 m;" in text
    assert repr(load_result(save_result(result, tmp_path / "r.pkl"))) == text
    identified = Identified({"workpiece.gamma": (1e-3, 2e-6), "component.X.EXX[1]": 3e-8,
                             "component.C.EAC[0]": (1e-6, 0.0), "squareness_xy": 1e-5},
                            detail=[1.0], notes=("fit: a note",))
    assert repr(identified) == (
        "Identified(4 parameters: workpiece.gamma = 0.001 rad +- 2e-06 rad, "
        "component.X.EXX[1] = 3e-08 m (no std), component.C.EAC[0] = 1e-06 rad "
        "+- 0 rad, squareness_xy = 1e-05 SI (no std); 1 note; detail list)")
