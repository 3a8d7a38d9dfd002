"""What the compensation test files (tests/test_compensation_mapping.py, _refusals.py)
share (not collected: no test_ prefix): the grooves program on grooving_4axis and the
tilted one on robonano_a0ib, as NC text and as programs."""

from __future__ import annotations

from machinesim.nc import Program, parse_program

# X Y Z C; Y and C are not programmed at first (they start at the start position), a dwell
# and M codes sit between the moves.
GROOVES_NC = """%
O0012
G90 G21 G94 G54
N5 M03 S1000
N10 G00 X0. Z1.
N20 C30.
N30 G01 Z-0.002 F100.
N40 X5.123456 Y2.5 F50.
N50 G04 P500
N60 X6. C45.5 M08
N70 G00 Z1.
M30
%
"""


# X Y Z B C, the tool tilted and the workpiece turned.
TILTED_NC = """%
O0021
G90 G21 G94 G54
N10 G00 X-3. Y2. Z1. B0. C0.
N20 G01 Z-0.001 F20.
N30 X3. B10. C15.
N40 Y-2.5 C-20.25
N50 G04 X0.25
N60 B-5. C90.
N70 G00 Z1.
%
"""


def grooves() -> Program:
    return parse_program(GROOVES_NC, "grooves.nc")


def tilted() -> Program:
    return parse_program(TILTED_NC, "tilted.nc")
