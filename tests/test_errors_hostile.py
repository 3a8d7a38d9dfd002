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
