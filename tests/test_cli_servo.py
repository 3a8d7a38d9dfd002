"""``machinesim cut --servo``: the axes' servo loops from a TOML file, and the lag they leave."""

import json

import pytest
from cli_helpers import CUT, assert_clean_failure, run

PD_X = """# a PD loop on X: a 12 kg slide on a guide of 1600 N s/m
[X]
kp_N_per_m = 1.2e6
ki_N_per_m_s = 0.0
kd_N_s_per_m = 3700.0
mass_kg = 12.0
damping_N_s_per_m = 1600.0
"""
LINE = "G90 G21 G17\nG00 X1. Y5. Z0.1\nG01 Z-0.001 F60.\nG01 X9. F600.\nG00 Z1.\nM30\n"



def _cut_line(tmp_path, capsys, servo_text: str):
    """`machinesim cut` of LINE with a --servo file holding ``servo_text`` and a --report:
    the servo file's path, the report's, and the command's (status, stdout, stderr)."""
    servo, program = tmp_path / "servo.toml", tmp_path / "line.nc"
    servo.write_text(servo_text)
    program.write_text(LINE)
    report = tmp_path / "r.json"
    return servo, report, run(["cut", program, *CUT, "--servo", servo, "--out",
                               tmp_path / "p.ply", "--report", report], capsys)

def test_a_servo_file_lags_the_cut_by_v_c_over_kp(tmp_path, capsys):
    # a PD loop's steady ramp error is v c / Kp: 10 mm/s x 1600 / 1.2e6 = 13.333 um
    servo, report, (code, out, err) = _cut_line(tmp_path, capsys, PD_X)
    assert code == 0, err
    lag = json.loads(report.read_text())["peak_following_error_um_or_urad"]
    assert lag["X"] == pytest.approx(10e-3 * 1600.0 / 1.2e6 * 1e6, rel=1e-4)
    assert lag["Y"] == 0.0 and lag["C"] == 0.0  # no loop: they follow exactly
    assert "largest following error: X 13.3333 um" in out


@pytest.mark.parametrize("text, line, words", [
    ("kp_N_per_m = 1e6\n", 1, ["stands outside any table", "[X], [Y], [Z], [C]"]),
    ("[Q]\nkp_N_per_m = 1.0\n", 1, ["table [Q] is not an axis of grooving_4axis"]),
    (PD_X.replace("mass_kg", "mass"), 6, ["unknown key 'mass' in [X]", "mass_kg"]),
    # a key that is missing: the line of its table
    (PD_X.replace("damping_N_s_per_m = 1600.0\n", ""), 2, ["[X] lacks damping_N_s_per_m"]),
    (PD_X.replace("1.2e6", '"1.2e6"'), 3, ["kp_N_per_m", "must be a number"]),
    (PD_X.replace("[X]", "[C]"), 3, ["unknown key 'kp_N_per_m' in [C], a rotary axis",
                                      "kp_N_m_per_rad"]),
    (PD_X.replace("damping_N_s_per_m = 1600.0", "damping_N_s_per_m = -1600.0"), 7,
     ["damping_N_s_per_m", "must be finite and >= 0, got -1600.0"]),
    ("[X\n", 1, ["not valid TOML"]),
    # unstable gains named the file and the table, not its line
    (PD_X.replace("kd_N_s_per_m = 3700.0", "kd_N_s_per_m = 1e200"), 2,
     ["[X]: servo loop of axis X is unstable", "Kd = 1e+200"]),
    # the loop's coefficients overflowed: an internal LinAlgError (exit 1); then named at
    # the mass_kg key whatever value it was: the loop as a whole, at its table's line
    (PD_X.replace("damping_N_s_per_m = 1600.0", "damping_N_s_per_m = 1e300"), 2,
     ["key 'X': [X]: servo loop of axis X cannot be formed in float64", "damping = 1e+300"]),
    # 10**400 (1329 bits) is read exactly by TOML; it was an internal error (exit 1)
    (PD_X.replace("1.2e6", "1" + "0" * 400), 3, ["kp_N_per_m", "integer of 1329 bits",
                                                 "beyond float64"]),
])
def test_a_bad_servo_file_is_named(tmp_path, capsys, text, line, words):
    # with the line of the key (of its table when it is missing), as an --errors file's
    # refusals give it: the servo file's named the file and key alone
    servo, program = tmp_path / "servo.toml", tmp_path / "line.nc"
    servo.write_text(text)
    program.write_text(LINE)
    code, _, err = run(["cut", program, *CUT, "--servo", servo, "--out", tmp_path / "p.ply"],
                       capsys)
    assert_clean_failure(code, err, f"servo.toml, line {line}, ", *words)
    assert not (tmp_path / "p.ply").exists()


@pytest.mark.parametrize("text", ["", "# [X]\n# kp_N_per_m = 1.2e6\n"])
def test_a_servo_file_without_a_table_is_noted(tmp_path, capsys, text):
    # an empty file, or one whose tables are commented out, printed 'largest following
    # error: X 0.0000 um, ...' with exit 0 and no word that no loop had been read, where an
    # --errors file that sets nothing is noted
    servo, report, (code, out, err) = _cut_line(tmp_path, capsys, text)
    assert code == 0, err
    said = (f"{servo} sets no servo loop (no axis table): every axis followed its command "
            "exactly, a following error of 0")
    assert err == f"note: {said}\n"
    assert said in json.loads(report.read_text())["notes"]
    lags = json.loads(report.read_text())["peak_following_error_um_or_urad"].values()
    assert max(lags) < 1e-9  # um: float round-off where one move's end meets the next's start
