"""`machinesim view` from the command line as a new user meets it: hostile inputs in each
view mode (a part, a report folder, a machine with a program) end in a clear refusal or
note, never a traceback or a silently wrong page (docs/viewer.md)."""

from __future__ import annotations

import argparse

import pytest

from machinesim.viewer.cli import add_view_parser, run_view
from machinesim.viewer.scene import Scene

#: A 10 um deep V groove 2 mm along X, as test_errors_hostile cuts it.
GROOVE = "G90 G21\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X2.\nG00 Z1.\nM30\n"


def run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="machinesim")
    add_view_parser(parser.add_subparsers(dest="command", required=True))
    return run_view(parser.parse_args(["view", *argv]))


@pytest.fixture
def captured(monkeypatch):
    """machine_scene replaced by one that records its arguments and draws nothing."""
    import machinesim.viewer.machine as viewer_machine

    seen = {}

    def capture(machine, program, **kwargs):
        seen.update(program=program, **kwargs)
        return Scene("captured")

    monkeypatch.setattr(viewer_machine, "machine_scene", capture)
    return seen


def test_an_error_file_gets_the_unit_slip_notes_cut_gives(tmp_path, captured, capsys):
    # c_2 = 1 um/mm**2 reaches 1 * 250**2 um = 62.5 mm at the ends of grooving_4axis's X
    # (-250 .. 250 mm), by hand: machinesim cut notes it (test_errors_hostile); view printed
    # no note and drew the page
    program = tmp_path / "p.nc"
    program.write_text(GROOVE)
    errors = tmp_path / "poly.toml"
    errors.write_text("[component.X]\nEXX_poly_um_mm = [0.0, 0.0, 1.0]\n")
    assert run(["grooving_4axis", "--program", str(program), "--tool", "v:90", "--errors",
                str(errors), "--html", str(tmp_path / "p.html")]) == 0
    err = capsys.readouterr().err
    assert (f"note: {errors}, line 2: component.X.EXX_poly_um_mm = [0.0, 0.0, 1.0] reaches "
            "62.5 mm at X = -250 mm within X's travel, beyond the errors of any machine: were "
            "its coefficients written for other units than its key asks?") in err, err
    assert captured["errors"].written
