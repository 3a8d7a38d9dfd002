"""What a cut's and a turn's reports say of themselves: what they are, with units.

Their reprs were the dataclass dumps: a CutReport of the README's cut ran to 666 characters
of bare floats and the program's reading ('removed_volume_m3=2.6208017637895062e-11, ...
nc={'integer_input': 'calculator', ...'), a TurningReport's following error a unitless
dict ('peak_following_error={'X': 0.0, 'Z': 0.0, 'C': 0.0}').
"""

from machinesim import load_machine
from machinesim.cutting.lathe import TurningReport, turn
from machinesim.cutting.report import CutReport
from machinesim.nc import parse_program

# ten turns of C facing in from X 1 mm to 0.5 mm: 3600 deg at 36000 deg/min is 6 s
FACING = ("G90 G21\nG00 X1.0 Z0.01 C0\nG01 Z-0.001 F10\nG01 X0.5 C3600. F36000\n"
          "G00 Z0.01\n")


def _report(**changes) -> CutReport:
    fields = dict(removed_volume_m3=2.5e-11, machining_time_s=30.0, cutting_time_s=28.5,
                  sweeps=36, substeps=48, rapids_that_cut=(), limit_violations=(),
                  sideways_sweeps=0, empty_cut=False, engine="boolean", elapsed_s=0.25,
                  tools=({"tool": None, "line": None, "length_m": 0.0,
                          "removed_volume_m3": 2.5e-11, "engine": "boolean"},),
                  thin_sheets=4, nc={"integer_input": "calculator"})
    return CutReport(**(fields | changes))


def test_a_cut_report_says_what_was_cut_with_units():
    assert repr(_report()) == (
        "CutReport(boolean engine: removed 0.025 mm^3 in 36 of 48 sub-steps, machining 30 s "
        "(cutting 28.5 s), 1 tool run, 4 thin sheets cut away; 0 notes; took 0.25 s)")


def test_a_cut_report_names_what_went_wrong_and_its_servo_lag():
    text = repr(_report(rapids_that_cut=(7,), holder_contact=tuple(range(10, 17)),
                        limit_violations=("X = 300 mm at line 9",), empty_cut=True,
                        notes=("a", "b"), peak_following_error={"X": 1.2e-6, "C": 4e-7}))
    assert ", peak following error X 1.2, C 0.4 um or urad; rapids that cut at line 7; " \
           "holder contact at lines 10, 11, 12, 13, 14 and 2 more; 1 limit violation; " \
           "empty cut; 2 notes; took 0.25 s)" in text


def test_a_turning_report_says_what_was_turned_with_units():
    _, report = turn(parse_program(FACING), load_machine("sts_lathe"))
    # 40 quarter-turn steps: 41 points; no servo loops: no following error to tell
    assert repr(report) == ("TurningReport(1 run, 41 path points over 10 revolutions, "
                            "machining 6 s; 0 notes)")
    lagging = TurningReport(points=5, runs=2, machining_time_s=1.5, revolutions=0.5,
                            peak_following_error={"X": 2e-7, "Z": 0.0, "C": 3e-6},
                            limit_violations=("X = 200 mm at line 4",), notes=("n",))
    assert repr(lagging) == ("TurningReport(2 runs, 5 path points over 0.5 revolutions, "
                             "machining 1.5 s, peak following error X 0.2, Z 0, C 3 um or "
                             "urad; 1 limit violation; 1 note)")
