"""Hostile error files (TOML), as a user writes them: each is read as written, or refused
naming the file, the line, the key, the value and what was expected."""

from __future__ import annotations

import math
import time
import warnings
from fractions import Fraction

import numpy as np
import pytest

from machinesim.errors import ComponentError, ErrorModel
from machinesim.errors.toml import _exact_si
from machinesim.exceptions import ErrorModelError


def test_positions_apart_as_written_but_equal_in_si_are_refused_naming_the_key(tmp_path):
    # 5e-324 mm is 5e-327 m, below float64's least: 0.0. The positions increase as written,
    # so the file's check passed them, and the table's own check then said "key 'positions':
    # ... got 0.0 then 0.0 m or rad", naming neither the file, its line nor its key
    path = tmp_path / "F.toml"
    path.write_text("[component.X]\nposition_mm = [0.0, 5e-324, 100.0]\nEXX_um = [0.0, 1.0, 2.0]\n")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (
        f"{path}, line 2, key 'component.X.position_mm': positions 0.0 and 5e-324 mm (indices "
        "0, 1) are both 0.0 m once in m (float64); expected positions strictly increasing in "
        "m too")
    # positions that stay apart in SI, however close, are read as written
    path.write_text("[component.X]\nposition_mm = [0.0, 1e-300, 100.0]\nEXX_um = [0.0, 1.0, 2.0]\n")
    positions = ErrorModel.from_toml(path).component["X"]["EXX"].positions
    assert positions.tolist() == [0.0, 1e-300 * 1e-3, 0.1]


def test_positions_a_float64_range_apart_are_read_without_numpys_overflow_warning(tmp_path):
    # np.diff of -1e308 and 1e308 overflowed: "RuntimeWarning: overflow encountered in
    # subtract" with a line of numpy's source reached the command line's stderr before its
    # refusal (the table lies outside any travel, which the machine then refuses)
    path = tmp_path / "F.toml"
    path.write_text("[component.X]\nposition_mm = [-1e308, 1e308]\nEXX_um = [0.0, 1.0]\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        positions = ErrorModel.from_toml(path).component["X"]["EXX"].positions
        assert positions.tolist() == [-1e305, 1e305]
        path.write_text("[component.X]\nposition_mm = [1e308, -1e308]\nEXX_um = [0.0, 1.0]\n")
        with pytest.raises(ErrorModelError, match=r"line 2, key 'component\.X\.position_mm': "
                                                  r"positions must be strictly increasing, got "
                                                  r"1e\+308 then -1e\+308 mm \(indices 0, 1\)"):
            ErrorModel.from_toml(path)


def _cut_with(errors, tmp_path, capsys) -> str:
    """The stderr of ``machinesim cut`` of a 10 um deep V groove 2 mm along X on
    grooving_4axis with ``errors`` as its --errors file, which exits 0."""
    from machinesim.cli import main

    program = tmp_path / "p.nc"
    program.write_text("G90 G21\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\nG00 Z1.\nM30\n")
    code = main(["cut", str(program), "--machine", "grooving_4axis", "--tool", "v:90",
                 "--stock", "block:10x10x2", "--out", str(tmp_path / "a.ply"), "--errors",
                 str(errors), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0, err
    return err


def test_a_polynomial_reaching_beyond_any_machine_within_the_travel_is_noted(tmp_path, capsys):
    # c_2 = 1 um/mm**2 (perhaps meant per m**2) reaches 1 * 250**2 um = 62.5 mm at the ends
    # of grooving_4axis's X (-250 .. 250 mm), by hand; below check_travel's 1 m, so it was cut
    # with exit 0 and no note, while a table value of 62.5 mm is noted (beyond_any_machine)
    from machinesim.errors.unit_slips import far_polynomials
    from machinesim.machines import load_machine

    machine = load_machine("grooving_4axis")
    path = tmp_path / "poly.toml"
    path.write_text("[component.X]\nEXX_poly_um_mm = [0.0, 0.0, 1.0]\n"
                    "[component.C]\nEXC_poly_um_deg = [0.0, 0.01]\n")
    errors = ErrorModel.from_toml(path)
    note = (f"{path}, line 2: component.X.EXX_poly_um_mm = [0.0, 0.0, 1.0] reaches 62.5 mm "
            "at X = -250 mm within X's travel, beyond the errors of any machine: were its "
            "coefficients written for other units than its key asks?")
    assert far_polynomials(errors, machine) == [note]  # C's reaches 3.6 um at 360 deg: none
    err = _cut_with(path, tmp_path, capsys)
    assert f"note: {note}" in err, err
    # an angle's: EAX_poly_urad_mm = [0, 700] urad/mm turns 175 mrad (10.03 deg) at 250 mm
    path.write_text("[component.X]\nEAX_poly_urad_mm = [0.0, 700.0]\n")
    [line] = far_polynomials(ErrorModel.from_toml(path), machine)
    assert "EAX_poly_urad_mm = [0.0, 700.0] reaches -10.03 deg at X = -250 mm" in line, line
    path.write_text("[component.X]\nEAX_poly_urad_mm = [0.0, 690.0]\n")  # 9.88 deg: none
    assert far_polynomials(ErrorModel.from_toml(path), machine) == []


def test_a_turn_table_whose_values_a_turn_apart_differ_is_noted(tmp_path, capsys):
    # the table spans -180 .. 180 deg, a whole turn, and repeats each turn beyond it on
    # grooving_4axis's C (-360 .. 360 deg): ECC steps from 2 to 1 arcsec as C passes 180 deg,
    # which turns the tool about C by 1 arcsec at once, 10 mm * 4.848e-6 rad = 0.0485 um at
    # X = 10 mm by hand, with exit 0 and no note before
    import numpy as np

    from machinesim.errors.unit_slips import turn_steps
    from machinesim.machines import load_machine

    machine = load_machine("grooving_4axis")
    path = tmp_path / "turn.toml"
    path.write_text("[component.C]\nposition_deg = [-180.0, 0.0, 180.0]\n"
                    "ECC_arcsec = [1.0, 0.0, 2.0]\n")
    errors = ErrorModel.from_toml(path)
    moved = [machine.tool_pose(np.array([0.01, 0.0, 0.0, np.radians(c)]), errors)[:3, 3]
             - machine.tool_pose(np.array([0.01, 0.0, 0.0, np.radians(c)]))[:3, 3]
             for c in (180.0 - 1e-9, 180.0 + 1e-9)]
    assert abs(np.linalg.norm(moved[0] - moved[1]) - 0.01 * np.radians(1 / 3600)) < 1e-12
    note = (f"{path}, line 3: component.C.ECC_arcsec is 1 arcsec at C = -180 deg and 2 arcsec "
            "at 180 deg, a turn apart: the table repeats each turn beyond -180 .. 180 deg, "
            "within C's travel, so the error steps by 1 arcsec there, which no chord follows: "
            "give the same value a turn apart")
    assert turn_steps(errors, machine) == [note]
    err = _cut_with(path, tmp_path, capsys)
    assert f"note: {note}" in err, err
    # the same value a turn apart, and a table of less than a turn (which holds its end
    # values beyond it, as on a linear axis), are not noted
    for text in ("ECC_arcsec = [1.0, 0.0, 1.0]", "ECC_arcsec = [1.0, 0.0, 2.0]"):
        positions = ("[-180.0, 0.0, 180.0]" if text.endswith("1.0]")
                     else "[-180.0, 0.0, 179.0]")
        path.write_text(f"[component.C]\nposition_deg = {positions}\n{text}\n")
        assert turn_steps(ErrorModel.from_toml(path), machine) == []


def test_a_long_polynomial_whose_unit_factor_leaves_float64_reads_its_coefficients(tmp_path):
    # um/nm**k is 1e-6 / 1e-9**k m/m**k: from k = 35 (1e309) the factor alone overflowed, so
    # a zero coefficient there read 0 * inf = nan and the file was refused, "coefficient c_35
    # = 0 um/nm**35 is inf times as large in m/m**35, beyond float64", with numpy's
    # RuntimeWarnings (divide by zero, overflow, invalid value) on stderr before it
    path = tmp_path / "F.toml"
    zeros = ", ".join(["0.0"] * 38)
    path.write_text(f"[component.X]\nEXX_poly_um_nm = [0.0, 0.001, {zeros}]\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        values = ErrorModel.from_toml(path).component["X"]["EXX"].values
        assert values.size == 40 and values[1] == 0.001 * (1e-6 / 1e-9)  # 1 um/um, by hand
        assert not values[2:].any()
        # a coefficient there that is finite in SI reads as the product, rounded once:
        # 1e-300 um/nm**40 = 1e-306 m / 1e-360 m**40 = 1e54 m/m**40 (within the float 1e-9's
        # own 1e-17 relative, to the 40th power: 2.5e-15 off)
        path.write_text(f"[component.X]\nEXX_poly_um_nm = [0.0, 0.0, {zeros}, 1e-300]\n")
        values = ErrorModel.from_toml(path).component["X"]["EXX"].values
        assert values[40] == pytest.approx(1e54, rel=1e-14)
        # beyond float64 in SI, refused naming the factor as :g writes it
        path.write_text(f"[component.X]\nEXX_poly_um_nm = [0.0, 0.0, {zeros}, 1.0]\n")
        with pytest.raises(ErrorModelError) as info:
            ErrorModel.from_toml(path)
        assert str(info.value) == (
            f"{path}, line 2, key 'component.X.EXX_poly_um_nm': coefficient c_40 = 1 um/nm**40 "
            "is 1e+354 times as large in m/m**40, beyond float64; expected a length error of "
            "at most 1e+06 um (1 m) over the travel")


def test_a_coefficient_far_beyond_float64_is_told_from_its_exponents_at_once():
    # each coefficient past c_105 in um/mm**k (whose factor 1e-6 / 1e-3**k leaves float64)
    # was taken exactly, with powers of 1e-3 growing to millions of digits: 10,000 zero
    # coefficients (a 20 kB file) took a minute to read, 300,000 never ended
    start = time.perf_counter()
    assert _exact_si(0.0, 1e-6, 1e-3, 300_000) == 0.0
    assert _exact_si(-1e-300, 1e-6, 1e-3, 300_000) == -math.inf  # refused: beyond float64
    assert time.perf_counter() - start < 1.0
    # near float64's range the product is still taken exactly, rounded once: 1e-300 um/nm**40
    # = 1e-306 m / 1e-360 m**40 (as the file test above)
    assert _exact_si(1e-300, 1e-6, 1e-9, 40) == float(
        Fraction(1e-300) * Fraction(1e-6) / Fraction(1e-9) ** 40)


def test_a_polynomial_of_more_than_a_thousand_coefficients_is_refused(tmp_path):
    # each evaluation passes over every coefficient: 300,000 zeros (600 kB) cut in 15 s and
    # `view` of the program ran past 3 minutes; 1000 (degree 999) still read
    path = tmp_path / "F.toml"
    path.write_text("[component.X]\nEXX_poly_um_mm = [0.001" + ", 0.0" * 999 + "]\n")
    assert ErrorModel.from_toml(path).component["X"]["EXX"].values.size == 1000
    path.write_text("# polynomial\n[component.X]\nEXX_poly_um_mm = [0.001" + ", 0.0" * 1000
                    + "]\n")
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (
        f"{path}, line 3, key 'component.X.EXX_poly_um_mm': a polynomial of 1001 coefficients "
        "(degree 1000); expected at most 1000: an axis error's polynomial has a few, and finer "
        "detail is a table (position_<unit> beside the values)")
    with pytest.raises(ErrorModelError, match="a polynomial of 1001 coefficients"):
        ComponentError("poly", None, np.zeros(1001))


def test_a_tool_table_or_a_servo_file_given_for_the_errors_says_which_it_is(tmp_path):
    # were "unknown key; expected offset_<length unit>, rotation_<angle unit>" and "unknown
    # section; expected one of tool, ...", neither saying the file is another option's
    path = tmp_path / "F.toml"
    path.write_text("[tool.1]\nlength_mm = 0.0\n")  # docs/nc.md's least tool table
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (
        f"{path}, line 1, key 'tool.1': unknown key; expected offset_<length unit>, "
        "rotation_<angle unit> ([tool.1] is a tool table's, given with --tools; an error "
        "file's [tool] is the tool setting error)")
    path.write_text("[X]\nkp_N_per_m = 1.2e6\nmass_kg = 12.0\n")  # docs/cli.md's servo table
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (
        f"{path}, line 1, key 'X': unknown section; expected one of tool, tool_geometry, "
        "workpiece, location, component; [X] alone is a servo loop's table (--servo); an "
        "axis's errors go in [location.X] and [component.X]")


@pytest.mark.parametrize("name, value, said", [
    ("tool.x", 2.0, "2000 mm (2 m) is no length error"),
    ("tool.rz", 4.0, "229.183118052 deg (4 rad) is no angle error"),
    ("tool_geometry.nose_radius", 5.0, "5000 mm (5 m) is no length error"),
    ("workpiece.z", -3.0, "3000 mm (3 m) is no length error"),
    ("workpiece.gamma", 4.0, "229.183118052 deg (4 rad) is no angle error"),
    ("component.X.EXX[1]", 2.0, "2000 mm (2 m) is no length error")])
def test_with_parameters_names_the_parameter_whose_value_is_no_error(name, value, said):
    # the settings' own checks named their field: "key 'offset'" for tool.x (or y or z),
    # "key 'gamma'", "key 'component.X.EXX'" for EXX[1]: which of many parameters was it?
    model = ErrorModel.from_dict({"component": {"X": {"position_mm": [-250.0, 0.0, 250.0],
                                                      "EXX_um": [0.0, 1.0, 2.0]}}}, "d")
    with pytest.raises(ErrorModelError) as info:
        model.with_parameters({"tool.y": 1e-6, name: value})
    assert info.value.key == name
    assert said in str(info.value)
    # a polynomial's coefficient has no bound of its own (its reach over a travel has)
    model = ErrorModel.from_dict({"component": {"X": {"EYX_poly_um_mm": [0.0, 1e-3]}}}, "d")
    assert model.with_parameters({"component.X.EYX[1]": 2.0}).component["X"]["EYX"].values[1] == 2.0


def test_a_toml_file_past_the_size_cap_is_refused_before_it_is_read_and_one_at_it_reads(
        tmp_path):
    # a 20 MB error file of one table (1,000,000 positions) took 25 s and 210 MB to read
    # before anything was checked
    from machinesim.errors.toml import MAX_TOML_BYTES

    path = tmp_path / "F.toml"
    head = "[tool]\noffset_um = [1.0, 0.0, 0.0]\n"
    path.write_text(head + "#" * (MAX_TOML_BYTES - len(head) - 1) + "\n")  # at the cap
    assert path.stat().st_size == MAX_TOML_BYTES
    assert ErrorModel.from_toml(path).tool.offset.tolist() == [1e-6, 0.0, 0.0]
    with path.open("a") as file:
        file.write("\n")  # one byte past it
    with pytest.raises(ErrorModelError) as info:
        ErrorModel.from_toml(path)
    assert str(info.value) == (
        f"{path}: larger than 4 MB; an error model, tool table or servo file is a few kB (an "
        "error table of 10,000 positions some 0.2 MB): expected at most 4 MB")


def test_a_polynomial_on_a_spindle_gets_its_refusal_and_no_note_before_it():
    # sts_lathe's C turns -1e5 .. 1e5 rad: a polynomial there is refused (each_turn), and
    # far_polynomials noted it first, "reaches -5730 mm at C = -5.73e+06 deg", which a
    # scenario's --errors printed before the refusal
    from machinesim.errors.unit_slips import far_polynomials
    from machinesim.machines import load_machine

    machine = load_machine("sts_lathe")
    errors = ErrorModel.from_dict({"component": {"C": {"EXC_poly_um_deg": [0.0, 1.0]}}}, "d")
    assert far_polynomials(errors, machine) == []
    with pytest.raises(ErrorModelError, match="a polynomial in the angle does not repeat"):
        machine.check_errors(errors)
