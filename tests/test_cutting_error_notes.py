"""The notes on an errors file (a value perhaps written in other units than its key asks,
location errors an axis kept at zero never shows) in the report of a cut made in Python,
where a user reads them, printed once by ``machinesim cut``; and none in a `Lab`'s cut,
whose errors are the truth a procedure must not read."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_helpers import run

import machinesim
from machinesim.cutting import cut_turned
from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError, MachineSimWarning
from machinesim.nc import parse_program

#: A slot along X at C = 0 throughout, as test_cli_notes cuts it on robonano_a0ib.
SLOT = "G90 G21\nG00 X0.5 Y5. Z0.1\nG01 Z-0.02 F50.\nX10.5 F100.\nG00 Z0.1\nM30\n"
#: EX0C_um = 4e-6 is 4 um written in metres (4 pm: a unit slip); with EB0C both move nothing
#: at C = 0 (E J E^-1 is the identity there).
ERRORS = "[location.C]\nEX0C_um = 4e-6\nEB0C_urad = 3.0\n"
KEYS = {"tool": "v:90", "stock": "block:12x10x2"}


@pytest.fixture(scope="module")
def errors_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("notes") / "mine.toml"
    path.write_text(ERRORS)
    return path


def _notes(path) -> tuple[str, str]:
    # the words test_cli_notes asserts for machinesim cut, the line counted by hand
    slip = (f"{path}, line 2: location.C.EX0C_um = 4e-06 is at most 4e-06 um (4e-12 m), below "
            "anything a machine shows: was it written in m, where the key asks um?")
    idle = (f"{path}, line 2: location.C EX0C, EB0C move nothing in this program: C stays at "
            "0 from its start to its end, and the offsets and tilts of its line show only as "
            "it turns; the part is the one the machine without them cuts")
    return slip, idle


def test_a_python_cut_reports_the_notes_machinesim_cut_prints(errors_file):
    # ErrorModel.from_toml and machinesim.cut: report.notes had been silent on both
    program = parse_program(SLOT)
    machine = machinesim.load_machine("robonano_a0ib")
    errors = ErrorModel.from_toml(errors_file)
    _, report = machinesim.cut(program, machine, errors=errors, **KEYS)
    assert report.notes[-2:] == _notes(errors_file), report.notes
    _, report = machinesim.cut(program, machine, errors=str(errors_file), **KEYS)
    assert report.notes[-2:] == _notes(errors_file), report.notes
    _, report = cut_turned(program, machine, errors=errors, **KEYS)
    assert report.notes[-2:] == _notes(errors_file), report.notes
    # as a path or a dict, as cut takes them (cut_turned ended with an AttributeError,
    # 'dict' object has no attribute 'written', after the whole cut)
    _, report = cut_turned(program, machine, errors=str(errors_file), **KEYS)
    assert report.notes[-2:] == _notes(errors_file), report.notes
    given = {"location": {"C": {"EX0C_um": 4e-6, "EB0C_urad": 3.0}}}
    _, public = machinesim.cut(program, machine, errors=given, **KEYS)
    _, report = cut_turned(program, machine, errors=given, **KEYS)
    assert "move nothing" in report.notes[-1]
    assert report.notes[-2:] == public.notes[-2:], report.notes
    # C at 180 deg from the start on: they move the slot, and only the slip is noted
    _, report = machinesim.cut(program, machine, errors=errors, start=np.where(
        np.array(machine.axes) == "C", np.pi, 0.0), **KEYS)
    assert report.notes[-1] == _notes(errors_file)[0], report.notes
    assert not any("move nothing" in note for note in report.notes), report.notes


def test_a_labs_cut_names_none_of_its_errors(errors_file):
    # the lab's errors are its truth: a procedure reading its cut's notes would learn which
    # location errors it has, and their values
    program = parse_program(SLOT)
    with pytest.warns(MachineSimWarning) as told:  # told to whoever sets the lab up
        lab = machinesim.Lab("robonano_a0ib", errors_file, noise=False)
    assert [str(w.message) for w in told] == [_notes(errors_file)[0]]
    lab.reuse_cuts = False
    for options in ({}, {"turn_step": np.pi / 4}):
        part, report = lab.cut(program, **KEYS, **options)
        assert not any("EX0C" in note or "mine.toml" in note for note in report.notes), (
            options, report.notes)
        # the same part as cut() with those errors makes, notes apart
        cutter = cut_turned if options else machinesim.cut
        made, public = cutter(program, lab.machine, errors=lab.reveal(), **KEYS, **options)
        assert np.array_equal(part.mesh()[0], made.mesh()[0])
        assert report.notes == public.notes[:len(report.notes)]
        assert len(public.notes) == len(report.notes) + 2
    with pytest.raises(InputError, match="has no option 'file_notes'"):
        lab.cut(program, file_notes=True, **KEYS)


def test_a_file_that_sets_no_error_is_noted_in_a_python_cut_as_on_the_command_line(tmp_path,
                                                                                  capsys):
    # machinesim cut noted such a file; cut(..., errors="empty.toml") cut on the machine as
    # built with no note. A Lab's cut still notes nothing of its errors
    program = parse_program(SLOT)
    empty, zeros = tmp_path / "empty.toml", tmp_path / "zeros.toml"
    empty.write_text("# to fill in\n[tool]\n")
    zeros.write_text("[tool]\noffset_um = [0.0, 0.0, 0.0]\n")
    said = (f"{empty} sets no error (no key in any section): cut on the machine as built, "
            "every error zero")
    for errors in (empty, str(empty)):
        _, report = machinesim.cut(program, "robonano_a0ib", errors=errors, **KEYS)
        assert report.notes.count(said) == 1, report.notes
    for errors in (zeros, {}, ErrorModel(), None):  # zeros written on purpose, or no file
        _, report = machinesim.cut(program, "robonano_a0ib", errors=errors, **KEYS)
        assert not any("sets no error" in note for note in report.notes), (errors, report.notes)
    with pytest.warns(MachineSimWarning, match="sets no error .*: the lab is set up on the "
                      "machine as built"):
        lab = machinesim.Lab("robonano_a0ib", empty, noise=False)
    assert not any("sets no error" in note for note in lab.cut(program, **KEYS)[1].notes)
    path = tmp_path / "slot.nc"  # the command line prints and writes it once
    path.write_text(SLOT)
    code, _, err = run(["cut", path, "--machine", "robonano_a0ib", "--tool", "v:90", "--stock",
                        "block:12x10x2", "--errors", empty, "--quiet", "--out",
                        tmp_path / "p.ply", "--report", tmp_path / "r.json"], capsys)
    assert code == 0 and err.count(f"note: {said}") == 1, err
    assert json.loads((tmp_path / "r.json").read_text())["notes"].count(said) == 1


def test_machinesim_cut_prints_and_writes_each_note_once(errors_file, tmp_path, capsys):
    # the cut's report holds them now: the command line had added its own, which would
    # print each twice
    program = tmp_path / "slot.nc"
    program.write_text(SLOT)
    code, _, err = run(["cut", program, "--machine", "robonano_a0ib", "--tool", "v:90",
                        "--stock", "block:12x10x2", "--errors", errors_file, "--quiet",
                        "--out", tmp_path / "p.ply", "--report", tmp_path / "r.json"], capsys)
    assert code == 0, err
    notes = json.loads((tmp_path / "r.json").read_text())["notes"]
    for note in _notes(errors_file):
        assert err.count(note) == 1 and err.count(f"note: {note}") == 1, err
        assert notes.count(note) == 1, notes


@pytest.mark.parametrize("radius_mm", [1.0, 2.0])
def test_a_tool_tables_radius_is_checked_against_the_tool_as_given(tmp_path, radius_mm):
    # nose:1.0 beside a table radius of 1 mm agrees: with a nose radius error of 3 um in a
    # Lab, its cut had noted "the cut's own tool (radius 1.003 mm ...)", the truth to 1 nm;
    # beside 2 mm the note names the tool as given (1 mm), as machinesim view does
    from machinesim.cutting.tool_runs import tool_notes
    from machinesim.nc import read_program
    from machinesim.tool_specs import tool_from_spec

    tools = tmp_path / "tools.toml"
    tools.write_text(f"[tool.1]\nlength_mm = 0.0\nradius_mm = {radius_mm}\n")
    path = tmp_path / "t1.nc"
    path.write_text(SLOT.replace("G21\n", "G21\nT1 M6\n"))
    program = read_program(path, tools=tools)
    given = tool_notes(program, tool_from_spec("nose:1.0:90"))
    assert len(given) == (radius_mm != 1.0)
    assert all("(radius 1 mm, RoundNoseTool)" in note for note in given), given
    errors = {"tool_geometry": {"nose_radius_um": 3.0}}
    lab = machinesim.Lab("robonano_a0ib", errors, noise=False)
    lab.reuse_cuts = False
    volumes = []
    for cutter in (lab.cut, lambda *a: machinesim.cut(a[0], lab.machine, *a[1:],
                                                      errors=errors)):
        part, report = cutter(program, "nose:1.0:90", "block:12x10x2")
        assert [note for note in report.notes if note.startswith("T1")] == list(given)
        volumes.append(part.volume)
    # the error still cuts: a nose 3 um larger, the groove otherwise (not the nominal's)
    nominal, _ = machinesim.cut(program, lab.machine, "nose:1.0:90", "block:12x10x2")
    assert volumes[0] == volumes[1] != nominal.volume
