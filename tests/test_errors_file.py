"""An error model's file as written: a byte order mark dropped, the source and keys kept as
written, a refused key's line (counted by hand), a value below any machine noted in its
key's unit, and a misfit on a machine named at its key's line."""

from __future__ import annotations

import pickle
import re
import tomllib
from pathlib import Path

import pytest
from errors_helpers import assert_same_si, example_dict
from numpy.testing import assert_array_equal

from machinesim.errors import ErrorModel
from machinesim.exceptions import ErrorModelError, InputError

EXAMPLE = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"


BOM = "\ufeff"


def test_a_byte_order_mark_is_dropped(tmp_path):
    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    text = EXAMPLE.read_text(encoding="utf-8")
    plain.write_text(text, encoding="utf-8")
    marked.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    assert marked.read_bytes()[:3] == b"\xef\xbb\xbf"
    model = ErrorModel.from_toml(marked)
    assert model == ErrorModel.from_toml(plain) == ErrorModel.from_dict(example_dict())
    back = tmp_path / "back.toml"
    model.to_toml(back)
    assert_same_si(ErrorModel.from_toml(back), model, rtol=1e-15)


def test_after_a_byte_order_mark_lines_and_columns_count_as_without(tmp_path):
    for name, prefix in (("plain.toml", ""), ("marked.toml", BOM)):
        path = tmp_path / name
        path.write_text(prefix + "[tool]\noffset_um = [0.0, 0.0 0.0]\n", encoding="utf-8")
        with pytest.raises(ErrorModelError) as info:
            ErrorModel.from_toml(path)
        assert (info.value.line, info.value.column) == (2, 23)  # the 0 after "0.0 "
        assert "not valid TOML" in info.value.message and "Invalid statement" not in str(
            info.value)


def test_a_model_read_from_a_file_keeps_its_name_and_keys_as_written(tmp_path):
    path = tmp_path / "nose.toml"
    path.write_text("[tool_geometry]\nnose_radius_mm = -0.6\n[location.C]\nEX0C_nm = 20\n"
                    "[component.X]\nposition_mm = [-10, 10]\nEXX_um = [1, 2]\n"
                    "EBX_poly_urad_mm = [0.5, 0.25]\n")
    model = ErrorModel.from_toml(path)
    assert model.source == str(path)
    assert model.tool_geometry.nose_radius == -0.6 * 1e-3
    key, value = model.written["tool_geometry.nose_radius"]
    assert (key, value) == ("tool_geometry.nose_radius_mm", -0.6)
    assert model.written["location.C.EX0C"] == ("location.C.EX0C_nm", 20.0)
    assert model.written["component.X.position"][0] == "component.X.position_mm"
    assert_array_equal(model.written["component.X.EXX"][1], [1.0, 2.0])
    assert model.written["component.X.EBX"][0] == "component.X.EBX_poly_urad_mm"
    assert model.key_as_written("component.X.EBX") == "component.X.EBX_poly_urad_mm"
    assert model.key_as_written("location.C") == "location.C"  # a section: as it is
    assert ErrorModel().source is None and dict(ErrorModel().written) == {}
    # equal values are equal models, wherever they came from, and pickle alike (the cut
    # memo keys on pickles): a pickle holds the values, not the origin
    same = ErrorModel.from_dict(model.to_dict())
    assert same == model and same.source == "<dict>"
    assert pickle.dumps(same) == pickle.dumps(model)
    back = pickle.loads(pickle.dumps(model))
    assert back == model and back.source is None and dict(back.written) == {}
    with pytest.raises(TypeError):
        model.written["tool.offset"] = ("tool.offset_m", [0.0, 0.0, 0.0])
    # values set in Python are no longer the file's
    changed = model.with_parameters({"location.C.EX0C": 1e-6})
    assert changed.source is None and dict(changed.written) == {}


# Lines counted by hand in each text (line 1 is the first). tomllib gives no positions: a
# refusal of a key named the file and the key but not its line.
KEY_LINE_SHAPES = [
    # a plain key under its [section] header
    ("# an error model\n\n[tool]\noffset_um = [0.0, 1.0]\n", 4, "tool.offset_um",
     "expected 3 values"),
    # an unknown section: a plain key at the top, after a header of a known one
    ("[tool]\noffset_um = [0.0, 1.0, 0.0]\n\n[tools]\noffset_um = [0.0, 1.0, 0.0]\n", 4,
     "tools", "unknown section"),
    # dotted keys, under a header and at the top (a quoted part among them)
    ("[workpiece]\nalpha_deg = 0.1\n[location]\nC.EX0C_um = 2.0\nC.'EB0C_urad' = '15'\n", 5,
     "location.C.EB0C_urad", "expected a number, got '15'"),
    ("tool.offset_um = [0.0, 0.0, 0.0]\nlocation.C.EX0C_xx = 1.0\n", 2,
     "location.C.EX0C_xx", "unit 'xx' is not recognised"),
    # an array spanning lines: its key's line, not the line of the value refused
    ("[tool]\nrotation_deg = [0.0, 0.0, 0.0]\noffset_um = [  # x, y, z\n  0.0,\n  -178.0,\n"
     "  'z',\n]\n", 3, "tool.offset_um", "expected a number, got 'z'"),
    # after a multi-line string holding a header, a '#' and '=' (no key: not counted)
    ('[tool]\nnote = """\n[location.C]\n# x = 1\n"""\n', 2, "tool.note", "unknown key"),
    # a key in an inline table
    ("tool = { offset_um = [0.0,\n  1.0, 0.0], rotation_urad = [1.0, 2.0, 3.0] }\n"
     "workpiece = {delta_um = [1, 2, 3], gamma_um = 1}\n", 3, "workpiece.gamma_um",
     "expected an angle unit"),
    # Windows line ends; a table's header alone
    ("[component.X]\r\nposition_mm = [0.0, 1.0]\r\nEXX_um = [0, 1]\r\n\r\n[component.Y]\r\n"
     "position_mm = [0, 1]\r\nEYY_um = [1.0]\r\n", 7, "component.Y.EYY_um",
     "the table has 1 values"),
    ("\n[location.W]\nEX0W_um = 1.0\n", 2, "location.W", "'W' is not one of"),
]


@pytest.mark.parametrize(("text", "line", "key", "match"), KEY_LINE_SHAPES)
def test_a_refused_key_of_a_file_names_its_line(tmp_path, text, line, key, match):
    path = tmp_path / "errors.toml"
    path.write_bytes(text.encode())
    with pytest.raises(ErrorModelError, match=re.escape(match)) as info:
        ErrorModel.from_toml(path)
    assert (info.value.source, info.value.line, info.value.key) == (str(path), line, key)
    assert str(info.value).startswith(f"{path}, line {line}, key '{key}': ")
    # the same dict given to from_dict names no line (there is no text to count in)
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_dict(tomllib.loads(text), source="d")
    assert info.value.line is None and str(info.value).startswith(f"d, key '{key}': ")


def test_key_lines_of_every_shape_are_counted_as_by_hand():
    from machinesim.errors.toml import key_lines

    text = ("# head [tool]\n"                                    # 1
            "[tool]  # the tool\n"                               # 2
            "offset_um = [0.0,   # x = 1\n"                      # 3
            "   -178.0,\n   0.0]\n"                              # 4, 5
            "s = '''a\n[b]\n'''  # c\n"                          # 6, 7, 8
            't = "q\\" = ["\n'                                   # 9
            "[location]\n"                                       # 10
            "C.EX0C_um = 2.0\n"                                  # 11
            "\"C\" . 'EB0C_urad' = 1.5\n"                        # 12
            "[ component . X ]\n"                                # 13
            "position_mm = [\n  [1, 2], {a = 1},\n]\n"           # 14, 15, 16
            "[[w]]\n"                                            # 17
            "q = {a = 1, b.c = [1,\n 2], d = {e = 'x'}}\n")      # 18, 19
    tomllib.loads(text)  # valid TOML
    assert key_lines(text) == {
        "tool": 2, "tool.offset_um": 3, "tool.s": 6, "tool.t": 9, "location": 10,
        "location.C": 11, "location.C.EX0C_um": 11, "location.C.EB0C_urad": 12,
        "component": 13, "component.X": 13, "component.X.position_mm": 14, "w": 17,
        "w.q": 18, "w.q.a": 18, "w.q.b": 18, "w.q.b.c": 18, "w.q.d": 19, "w.q.d.e": 19}
    # a scan that loses its way (text tomllib would refuse) gives no lines, not a traceback
    assert key_lines("[tool]\noffset_um = " + "[" * 5000 + "]" * 5000) == {}
    assert key_lines("[tool]\noffset_um = '") == {}


def test_a_value_below_any_machine_is_noted_in_its_keys_unit_with_si_beside(tmp_path):
    """A key in um, urad, deg or nm: its note gave the size in mm or deg ('4e-09 mm (4e-12 m)'
    for EX0C_um = 4e-6), a unit the file never wrote. By hand: 4e-6 um = 4e-12 m, 2e-6 urad =
    2e-12 rad, 1e-10 deg = 1e-10 pi / 180 = 1.74533e-12 rad, 0.004 nm = 4e-12 m; a key in m
    keeps mm first, m beside, as every message does for SI."""
    from machinesim.errors.toml import below_any_machine

    path = tmp_path / "slip.toml"
    path.write_text("[tool]\noffset_m = [0.0, 3e-12, 0.0]\n[location.C]\nEX0C_um = 4e-6\n"
                    "EA0C_urad = 2e-6\nEB0C_deg = 1e-10\nEY0C_nm = 0.004\n")
    sizes = [line.split(" is at most ")[1].split(", below")[0]
             for line in below_any_machine(ErrorModel.from_toml(path))]
    assert sizes == ["3e-09 mm (3e-12 m)", "4e-06 um (4e-12 m)", "2e-06 urad (2e-12 rad)",
                     "1e-10 deg (1.74533e-12 rad)", "0.004 nm (4e-12 m)"]


def test_a_value_below_any_machine_in_an_si_key_asks_no_unit_question(tmp_path):
    """A key in m or rad cannot hold SI where a smaller unit was asked: its note asked 'was
    it written in m, where the key asks m?'. It now asks whether the value was converted to
    SI twice (3 um as 3e-6 m, then again: 3e-12 m), and a key in um still asks for m."""
    from machinesim.errors.toml import below_any_machine

    path = tmp_path / "slip.toml"
    path.write_text("[tool]\noffset_m = [0.0, 3e-12, 0.0]\n[workpiece]\ngamma_rad = 5e-12\n"
                    "[location.C]\nEX0C_um = 4e-6\n")
    lines = below_any_machine(ErrorModel.from_toml(path))
    assert [line.split(", below anything a machine shows")[1] for line in lines] == [
        ": was it converted to m twice? (the key takes 1 um as 1e-06)",
        ": was it converted to rad twice? (the key takes 1 urad as 1e-06)",
        ": was it written in m, where the key asks um?"]
    assert not any("where the key asks m?" in line or "asks rad?" in line for line in lines)


def test_a_misfit_on_a_machine_names_the_line_of_the_key(tmp_path):
    from machinesim.machines import load_machine
    from machinesim.tool_specs import tool_from_spec
    from machinesim.tools import with_nose_radius_error

    path = tmp_path / "misfit.toml"
    path.write_text("[tool]\noffset_um = [0.0, 0.0, 0.0]\n\n[location.B]\nEX0B_um = 2.0\n"
                    "[tool_geometry]\nnose_radius_um = 1.0\n")
    model = ErrorModel.from_toml(path)
    assert model.line_of("location.B") == 4 and model.line_of("tool_geometry.nose_radius") == 7
    with pytest.raises(ErrorModelError) as info:
        load_machine("grooving_4axis").check_errors(model)  # X Y Z C: no B
    assert (info.value.source, info.value.line, info.value.key) == (str(path), 4, "location.B")
    with pytest.raises(InputError) as info:  # a V tool has no nose radius
        with_nose_radius_error(tool_from_spec("v:90"), model)
    assert (info.value.source, info.value.line) == (str(path), 7)
    assert info.value.key == "tool_geometry.nose_radius_um"


def test_misfit_names_the_model_file_first_then_the_machine(tmp_path):
    path = tmp_path / "axis_missing.toml"
    path.write_text("[location.C]\nEX0C_um = 2.0\n[component.X]\nEYX_poly_um_mm = [0.0, 1.0]\n")
    model = ErrorModel.from_toml(path)
    found = ErrorModelError("axis 'C' is not on this machine; it has X, Y, Z",
                            source="m/mill3.urdf", key="location.C")
    told = model.misfit(found, "mill3")
    assert isinstance(told, ErrorModelError)
    assert str(told) == (f"{path}, line 1, key 'location.C': axis 'C' is not on this machine; "
                         "it has X, Y, Z (machine mill3, m/mill3.urdf)")
    assert (told.source, told.key) == (str(path), "location.C")
    # a key the file wrote is named as written, unit and all
    symbol = ErrorModelError("EYX is no good here", source="m/mill3.urdf", key="component.X.EYX")
    assert model.misfit(symbol, "mill3").key == "component.X.EYX_poly_um_mm"
    # a model built in Python has no file: the machine's message stands
    assert ErrorModel.from_dict(model.to_dict()).with_parameters({}).misfit(found, "m") is found
    assert ErrorModel().misfit(found, "mill3") is found
