"""What machinesim.errors refuses, naming the key and value (and the file, line and column):
bad dicts and TOML text, unreadable or non-UTF-8 files, a pipe, a folder or a missing
file, and constructor arguments."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from machinesim.errors import ComponentError, ErrorModel, ToolSetting, WorkpieceSetting
from machinesim.exceptions import ErrorModelError, InputError


def with_(section: str, content) -> dict:
    return {section: content}


REFUSALS = [
    (with_("tools", {}), r"key 'tools'.*unknown section"),
    (with_("tool", {"offsett_um": [0, 0, 0]}), r"'tool\.offsett_um'.*unknown key"),
    (with_("tool", {"offset": [0, 0, 0]}), r"'tool\.offset'.*no unit suffix"),
    (with_("tool", {"offset_inch": [0, 0, 0]}), r"'tool\.offset_inch'.*'inch' is not recog"),
    (with_("tool", {"rotation_um": [0, 0, 0]}), r"'tool\.rotation_um'.*angle unit.*'um'"),
    (with_("tool", {"offset_deg": [0, 0, 0]}), r"'tool\.offset_deg'.*length unit.*'deg'"),
    (with_("tool", {"offset_um": [1, 2, 3], "offset_mm": [1, 2, 3]}), r"offset_mm.*twice"),
    (with_("workpiece", {"alpha_mm": 1.0}), r"'workpiece\.alpha_mm'.*angle unit.*'mm'"),
    (with_("location", {"C": {"EB0C_um": 1.0}}), r"'location\.C\.EB0C_um'.*angle unit.*'um'"),
    (with_("location", {"C": {"EX0C_deg": 1.0}}), r"'location\.C\.EX0C_deg'.*length.*'deg'"),
    (with_("location", {"C": {"EX0C": 1.0}}), r"'location\.C\.EX0C'.*no unit suffix"),
    (with_("component", {"X": {"position_deg": [0, 1], "EXX_um": [0, 1]}}),
     r"'component\.X\.position_deg'.*length unit.*'deg'"),
    (with_("component", {"C": {"position_mm": [0, 1], "ECC_urad": [0, 1]}}),
     r"'component\.C\.position_mm'.*angle unit.*'mm'"),
    (with_("component", {"X": {"EYX_poly_urad_mm": [0.0, 1.0]}}),
     r"'component\.X\.EYX_poly_urad_mm'.*length unit.*'urad'"),
    (with_("component", {"X": {"EYX_poly_um_deg": [0.0, 1.0]}}),
     r"'component\.X\.EYX_poly_um_deg'.*length unit.*'deg'"),
    (with_("component", {"X": {"EYX_poly_um": [0.0, 1.0]}}), r"EYX_poly_um'.*polynomial key"),
    (with_("tool", {"offset_um": [float("nan"), 0, 0]}), r"'tool\.offset_um'.*finite.*nan"),
    (with_("location", {"C": {"EX0C_um": float("inf")}}), r"'location\.C\.EX0C_um'.*inf"),
    (with_("tool", {"offset_um": [0.0, 1.0]}), r"'tool\.offset_um'.*3 values.*\[0\.0, 1\.0\]"),
    (with_("tool", {"offset_um": [[0.0, 1.0, 2.0]]}), r"'tool\.offset_um'.*\[0\.0, 1\.0, 2\.0\]"),
    (with_("tool", {"offset_um": 1.0}), r"'tool\.offset_um'.*list of numbers.*1\.0"),
    (with_("workpiece", {"alpha_deg": [0.1]}), r"'workpiece\.alpha_deg'.*number.*\[0\.1\]"),
    (with_("component", {"X": {"position_mm": [0, 1, 2], "EXX_um": [0, 1]}}),
     r"'component\.X\.EXX_um'.*2 values, \[0, 1\].*position_mm has 3"),
    (with_("component", {"X": {"position_mm": [0, 250, 250], "EXX_um": [0, 1, 2]}}),
     r"'component\.X\.position_mm'.*strictly increasing.*250.*250"),
    (with_("component", {"X": {"position_mm": [0, 500, 250], "EXX_um": [0, 1, 2]}}),
     r"'component\.X\.position_mm'.*strictly increasing.*500.*250"),
    (with_("component", {"X": {"position_mm": [], "EXX_um": []}}), r"position_mm'.*empty"),
    (with_("component", {"X": {"EXX_um": [0, 1, 2]}}), r"'component\.X\.EXX_um'.*no position_"),
    (with_("tool", {"offset_um": [True, 0, 0]}), r"'tool\.offset_um'.*number.*True"),
    (with_("workpiece", {"alpha_deg": "0.1"}), r"'workpiece\.alpha_deg'.*number.*'0\.1'"),
    (with_("location", {"W": {"EX0W_um": 1.0}}), r"'location\.W'.*'W' is not one of X, Y, Z"),
    (with_("component", {"Q": {"EXQ_um": [1.0]}}), r"'component\.Q'.*'Q' is not one of"),
    (with_("component", {"X": {"position_mm": [0], "EXY_um": [1.0]}}),
     r"'component\.X\.EXY_um'.*'EXY' is of axis Y, not \[component\.X\]"),
    (with_("location", {"C": {"EX0A_um": 1.0}}), r"'EX0A' is of axis A, not \[location\.C\]"),
    (with_("location", {"C": {"EXC_um": 1.0}}), r"'EXC' is a component.*E<d>0C"),
    (with_("component", {"C": {"EX0C_poly_um_deg": [1.0]}}), r"'EX0C' is a location"),
    (with_("location", {"C": {"FOO_um": 1.0}}), r"'location\.C\.FOO_um'.*'FOO' is not an ISO"),
    (with_("component", {"X": {"EQX_um": [1.0]}}), r"'EQX' is not an ISO 230 component"),
    (with_("component", {"X": {"EXX_um": [1.0], "EXX_poly_um_mm": [1.0]}}), r"EXX is given tw"),
    (with_("location", {"C": 2.0}), r"'location\.C'.*expected a table, got 2\.0"),
    (with_("workpiece", {"gamma_deg": 1e308}), r"'workpiece\.gamma_deg'.*1e\+308 deg is no "
     r"angle error: expected at most 180 deg"),
    (with_("workpiece", {"gamma_deg": -180.5}), r"180\.5 deg is no angle error"),
    (with_("tool", {"offset_mm": [0, 1001, 0]}), r"'tool\.offset_mm'.*1001 mm is no length "
     r"error: expected at most 1000 mm"),
    (with_("location", {"C": {"EB0C_urad": 4e6}}), r"4e\+06 urad is no angle error"),
    (with_("component", {"X": {"position_mm": [0, 1], "EXX_m": [0, -2]}}),
     r"'component\.X\.EXX_m'.*2000 mm \(2 m\) is no length error: expected at most 1000 mm "
     r"\(1 m\) either way"),  # a key in SI told as the API's values are: mm first
]


@pytest.mark.parametrize(("data", "match"), REFUSALS)
def test_from_dict_refuses_naming_the_key_and_value(data, match):
    with pytest.raises(ErrorModelError, match=match) as info:
        ErrorModel.from_dict(data, source="my.toml")
    assert str(info.value).startswith("my.toml, key ")
    assert isinstance(info.value, InputError)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[tool]\noffset_um = [0.0, inf, 0.0]\n", r"'tool\.offset_um'.*finite.*inf"),
        ("[location.C]\nEX0C_um = nan\n", r"'location\.C\.EX0C_um'.*nan"),
        ("[tool]\noffset_um = [true, 0.0, 0.0]\n", r"'tool\.offset_um'.*True"),
        ("[workpiece]\nalpha_deg = '0.1'\n", r"'workpiece\.alpha_deg'.*'0\.1'"),
        # TOML reads an integer of any length exactly; 10**400 has 1329 bits, beyond float64
        # (it was an internal OverflowError, exit 1 on the command line)
        ("[tool]\noffset_um = [1" + "0" * 400 + ", 0, 0]\n",
         r"'tool\.offset_um'.*integer of 1329 bits, beyond float64"),
        ("[location.C]\nEX0C_um = -1" + "0" * 400 + "\n",
         r"'location\.C\.EX0C_um'.*integer of 1329 bits"),
    ],
)
def test_from_toml_refuses_naming_the_file(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ErrorModelError, match=re.escape(str(path)) + ".*" + match):
        ErrorModel.from_toml(path)


def test_unreadable_toml_gives_line_and_column(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[tool]\noffset_um = [0.0, 0.0 0.0]\n")
    with pytest.raises(ErrorModelError, match=re.escape(f"{path}, line 2, column ")) as info:
        ErrorModel.from_toml(path)
    assert info.value.line == 2 and info.value.column is not None
    assert "not valid TOML" in str(info.value)


def test_toml_left_open_at_its_end_gives_the_last_line(tmp_path):
    # "not valid TOML: Unclosed array (at end of document)" named no line
    path = tmp_path / "open.toml"
    path.write_text("[tool]\noffset_um = [0.0,\n  0.0,\n  0.0\n")
    with pytest.raises(ErrorModelError, match=re.escape(f"{path}, line 4, column 6")) as info:
        ErrorModel.from_toml(path)
    assert "Unclosed array (at end of document)" in str(info.value)


def test_a_file_not_in_utf8_gives_the_line_and_column_of_the_byte(tmp_path):
    # a micro sign saved as Latin-1 (0xB5) in a comment: the message gave only "at byte 38"
    # and no expectation; the byte order mark, allowed, does not count in the column
    path = tmp_path / "latin1.toml"
    path.write_bytes(b"\xef\xbb\xbf[tool]\n# \xc3\xa9 um\noffset_um = [1.0, 0.0, 0.0]  # 1 \xb5m\n")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    # 0xb5 follows the 33 characters before it on line 3
    assert (info.value.line, info.value.column) == (3, 34)
    assert "byte 0xb5" in str(info.value) and "expected UTF-8 TOML" in str(info.value)
    path.write_bytes("[tool]\noffset_um = [1.0, 0.0, 0.0]\n".encode("utf-16"))
    with pytest.raises(ErrorModelError, match=r"line 1, column 1: .*UTF-16"):
        ErrorModel.from_toml(path)
    # a PNG given for the TOML (zero bytes, not UTF-16 text) was called UTF-16 from Notepad
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x01\x00")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (f"{path}, line 1, column 1: not UTF-8 text (byte 0x89, invalid "
                               "start byte: binary data, not a text file); expected UTF-8 "
                               "TOML: save the file as UTF-8")


def test_a_pipe_or_a_device_is_refused_before_it_is_read(tmp_path):
    # a named pipe with no writer hung the reading for ever, /dev/zero filled the memory
    # (15 GB in 100 s: scenarios/sts_turning.py --errors /dev/zero) and /dev/null read as
    # a model without errors
    fifo = tmp_path / "errors.toml"
    os.mkfifo(fifo)
    for path, kind in ((Path(os.devnull), "a character device"),
                       (fifo, "a named pipe (FIFO)")):
        with pytest.raises(ErrorModelError) as info:
            ErrorModel.from_toml(path)
        assert str(info.value) == (f"{path}: is {kind}, not a regular file; "
                                   "expected a TOML file")


def test_a_folder_given_as_the_toml_file_is_named_a_folder(tmp_path):
    # 'scenarios/tool_rotation_arm.py --errors DIR' said 'DIR: cannot read the file: Is a
    # directory' (the reading's OSError); the command line's checks say 'is a folder'
    folder = tmp_path / "errors.toml"
    folder.mkdir()
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(folder)
    assert str(info.value) == f"{folder}: is a folder; expected a TOML file"


@pytest.mark.parametrize(("given", "got"), [
    ({"tool": {"offset_um": [0.0, 1.0, 0.0]}},
     "got dict; a dict of the TOML layout is read by ErrorModel.from_dict"),
    (None, "got NoneType"), (3, "got int")])
def test_from_toml_given_no_path_says_what_came(given, got):
    # a dict given to from_toml (for from_dict) ended in "TypeError: stat: path should be
    # string, bytes, os.PathLike or integer, not dict"; 3 was read as file descriptor 3
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(given)
    assert info.value.key == "path"
    assert str(info.value) == f"key 'path': expected the TOML file's path as a str or Path, {got}"


def test_missing_file_is_named(tmp_path):
    path = tmp_path / "absent.toml"
    with pytest.raises(ErrorModelError, match=re.escape(str(path)) + ".*cannot read"):
        ErrorModel.from_toml(path)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: ComponentError("spline", None, [1.0]), r"'kind'.*'spline'"),
        (lambda: ComponentError("table", None, [1.0]), r"'positions'.*needs positions"),
        (lambda: ComponentError("poly", [0.0], [1.0]), r"'positions'.*no positions"),
        (lambda: ComponentError("table", [0.0, 1.0], [1.0]), r"'values'.*1 values for 2"),
        (lambda: ComponentError("table", [1.0, 0.0], [1.0, 2.0]), r"strictly increasing"),
        (lambda: ComponentError("poly", None, []), r"'values'.*empty"),
        (lambda: ComponentError("poly", None, np.array([1.0, np.nan])), r"'values'.*nan"),
        (lambda: ToolSetting(offset=[0.0, 0.0]), r"'offset'.*3 values"),
        (lambda: WorkpieceSetting(alpha=float("inf")), r"'alpha'.*inf"),
        (lambda: ErrorModel(tool=None), r"'tool'.*ToolSetting"),
        (lambda: ErrorModel(location={"C": {"EX0C": "1"}}), r"'location\.C\.EX0C'.*'1'"),
        (lambda: ErrorModel(component={"X": {"EXX": 1.0}}), r"'component\.X\.EXX'.*Compon"),
        (
            lambda: ErrorModel(component={"X": {
                "EXX": ComponentError("table", [0.0, 1.0], [0.0, 1.0]),
                "EYX": ComponentError("table", [0.0, 2.0], [0.0, 1.0]),
            }}),
            r"'component\.X\.EYX'.*share their positions",
        ),
    ],
)
def test_constructors_refuse(build, match):
    with pytest.raises(ErrorModelError, match=match):
        build()


@pytest.mark.parametrize("text", [
    "[component.X]\nEXX_poly_ppm_mm = [0.0, 10.0]\n",
    "[component.X]\nposition_mm = [0.0, 10.0]\nEXX_ppm = [0.0, 10.0]\n",
    "[location.Y]\nEC0Y_ppm = 10.0\n",
])
def test_ppm_is_refused_saying_how_a_scale_error_and_a_slope_are_written(tmp_path, text):
    """No key takes a ratio: the refusal says what to write instead, and what it says reads
    as the ratio: 10 ppm of X is 100 nm over 10 mm, 10 ppm across Y is 10 urad."""
    path = tmp_path / "ppm.toml"
    path.write_text(text)
    with pytest.raises(ErrorModelError, match=r"unit 'ppm' is not recognised.*ppm is a ratio.*"
                       r"EXX_poly_um_m = \[0\.0, s\].*an angle of s urad"):
        ErrorModel.from_toml(path)
    path.write_text("[component.X]\nEXX_poly_um_m = [0.0, 10.0]\n[location.Y]\nEC0Y_urad = 10.0\n")
    model = ErrorModel.from_toml(path)
    assert model.component["X"]["EXX"].evaluate([10e-3])[0] == pytest.approx(100e-9, rel=1e-15)
    assert model.location["Y"]["EC0Y"] == pytest.approx(10e-6, rel=1e-15)
