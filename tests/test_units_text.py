"""How a refusal shows a length or an angle, also beyond float64 in the unit shown."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim.errors import ErrorModel
from machinesim.exceptions import ErrorModelError
from machinesim.machines import load_machine
from machinesim.units import angle_text, length_text


def test_a_value_beyond_float64_in_the_unit_shown_is_written_not_inf():
    # 1e306 m is 1e309 mm, past float64: it was shown "inf mm (1e+306 m)", and an angle of
    # 1e308 rad "inf deg (1e+308 rad)" (ErrorModel().with_parameters({"tool.rz": 1e308}))
    assert length_text(1e306) == "1e+309 mm (1e+306 m)"
    assert angle_text(1e308) == "5.72957795131e+309 deg (1e+308 rad)"  # 1e308 * 180 / pi
    assert angle_text(-1.7e308) == "-9.74028251722e+309 deg (-1.7e+308 rad)"
    assert length_text(2.5e307) == "2.5e+310 mm (2.5e+307 m)"
    # within float64, as before (:g of the quotient)
    assert length_text(0.009) == "9 mm (0.009 m)"
    assert angle_text(np.pi) == "180 deg (3.14159265359 rad)"
    assert length_text(float("inf")) == "inf mm (inf m)"
    with pytest.raises(ErrorModelError, match=r"5\.72957795131e\+309 deg \(1e\+308 rad\) is no "
                                              r"angle error"):
        ErrorModel().with_parameters({"tool.rz": 1e308})


def test_table_positions_beyond_float64_in_mm_are_written_not_inf():
    # "table positions -inf .. inf mm lie outside the travel of axis X" for position_m =
    # [-1e306, 1e306]
    machine = load_machine("grooving_4axis")
    errors = ErrorModel.from_dict({"component": {"X": {"position_m": [-1e306, 1e306],
                                                       "EXX_um": [0.0, 1.0]}}}, "d")
    with pytest.raises(ErrorModelError, match=r"table positions -1e\+309 \.\. 1e\+309 mm lie "
                                              r"outside the travel of axis X, -250 \.\. 250 mm"):
        machine.check_errors(errors)
