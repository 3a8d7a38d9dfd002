"""Hostile error files (TOML), as a user writes them: each is read as written, or refused
naming the file, the line, the key, the value and what was expected."""

from __future__ import annotations

import warnings

import pytest

from machinesim.errors import ErrorModel
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


def test_a_polynomial_reaching_beyond_any_machine_within_the_travel_is_noted(tmp_path, capsys):
    # c_2 = 1 um/mm**2 (perhaps meant per m**2) reaches 1 * 250**2 um = 62.5 mm at the ends
    # of grooving_4axis's X (-250 .. 250 mm), by hand; below check_travel's 1 m, so it was cut
    # with exit 0 and no note, while a table value of 62.5 mm is noted (beyond_any_machine)
    from machinesim.cli import main
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
    program = tmp_path / "p.nc"
    program.write_text("G90 G21\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\nG00 Z1.\nM30\n")
    code = main(["cut", str(program), "--machine", "grooving_4axis", "--tool", "v:90",
                 "--stock", "block:10x10x2", "--out", str(tmp_path / "a.ply"), "--errors",
                 str(path), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0 and f"note: {note}" in err, err
    # an angle's: EAX_poly_urad_mm = [0, 700] urad/mm turns 175 mrad (10.03 deg) at 250 mm
    path.write_text("[component.X]\nEAX_poly_urad_mm = [0.0, 700.0]\n")
    [line] = far_polynomials(ErrorModel.from_toml(path), machine)
    assert "EAX_poly_urad_mm = [0.0, 700.0] reaches -10.03 deg at X = -250 mm" in line, line
    path.write_text("[component.X]\nEAX_poly_urad_mm = [0.0, 690.0]\n")  # 9.88 deg: none
    assert far_polynomials(ErrorModel.from_toml(path), machine) == []
