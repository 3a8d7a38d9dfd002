"""Motion: what the planner refuses, naming what is wrong (a start, a program, an axis, a
missing feed, with the line and N word), and move and segment indices read as a tuple's."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim import load_machine
from machinesim.exceptions import InputError, NCProgramError
from machinesim.motion import plan
from machinesim.nc import Move, ProgramBuilder, parse_program


def test_an_arc_without_a_feed_is_not_called_a_g01():
    # 'G02 X1. Y0. R0.5' with no F so far was refused as 'a feed move (G01) with no feed
    # rate F given so far', naming a G01 the program does not hold; the reader now refuses
    # it at its line, naming the G02 (test_nc_feed.py), before the planner sees it
    with pytest.raises(NCProgramError) as caught:
        parse_program("G90 G21 G17\nG00 X0. Y0. Z1.\nG02 X1. Y0. R0.5\nM30\n")
    assert (caught.value.line, caught.value.key) == (3, "G02")
    assert caught.value.message.startswith("G02 feeds with no F in force")


def test_plan_takes_a_machine_by_name_and_refuses_a_path_for_the_program(tmp_path):
    # plan(program, "grooving_4axis"), as cut() takes a machine, and plan("grooves.nc", ...)
    # had ended in AttributeError ('str' object has no attribute 'axes' / 'moves')
    program = parse_program("G90 G21\nG00 X1.\nG01 X11. F600.\nM30\n")
    by_name = plan(program, "grooving_4axis")
    assert by_name.duration == plan(program, load_machine("grooving_4axis")).duration
    assert by_name.segments[-1].t[-1] - by_name.segments[-1].t[0] == pytest.approx(1.0)
    path = tmp_path / "p.nc"
    path.write_text("G00 X1.\nM30\n")
    for wrong in (path, str(path), [1, 2]):
        with pytest.raises(InputError) as info:
            plan(wrong, "grooving_4axis")
        assert info.value.key == "program"
        assert str(info.value).startswith("key 'program': Expected program as a "
                                          "machinesim.nc.Program, got ")
        assert "read an NC file with machinesim.nc.read_program(path)" in str(info.value)


def test_a_start_or_program_of_the_wrong_kind_is_refused_naming_it():
    # a new user's start="home" (or ["0", ...]) ended in numpy's ValueError inside plan, from
    # Lab.cut, machinesim.cut and the encoders alike; encoders.record(None) or record of a
    # path in AttributeError: 'NoneType' object has no attribute 'moves'
    import machinesim
    from machinesim.exceptions import InputError

    machine = load_machine("robonano_a0ib")
    program = ProgramBuilder(1).rapid(X=1e-3, Z=1e-3).build()
    for start in ("home", ["0"] * 5, [True, 0, 0, 0, 0], [None] * 5, {"X": 0.0}):
        with pytest.raises(InputError, match=r"start as axis values \(m, rad\), one per axis "
                                             r"of XYZBC") as info:
            plan(program, machine, start=start)
        assert info.value.key == "start"
    lab = machinesim.Lab(machine, noise=False)
    with pytest.raises(InputError, match="start as axis values"):
        lab.cut(program, "v:90", "block:10x10x2", start="home")
    for wrong, shown in ((None, "NoneType"), ("part.nc", "str 'part.nc'")):
        with pytest.raises(InputError, match=rf"program as a machinesim.nc.Program, got "
                                             rf"{shown}; read an NC file with "
                                             r"machinesim.nc.read_program\(path\)") as info:
            lab.encoders().record(wrong)
        assert info.value.key == "program"
    # numbers of any kind pass, as before: ints, numpy floats, a tuple
    start = (1, np.float64(2e-3), 0, 0, 0)
    assert plan(program, machine, start=start).segments[0].q[0].tolist() == [1, 2e-3, 0, 0, 0]


def test_a_planner_refusal_names_the_blocks_n_word_beside_its_line():
    # as the reader's refusals: 'line 2 (N40)' where the block has an N word, the line
    # alone where it has none; from a Program's arrays and from a plain list of Moves
    machine = load_machine("grooving_4axis")
    for text, where in (("G21 G90\nN40 G00 A1.\nM30\n", "p.nc, line 2 (N40), key 'A'"),
                        ("G21 G90\nG00 A1.\nM30\n", "p.nc, line 2, key 'A'")):
        program = parse_program(text, "p.nc")
        with pytest.raises(NCProgramError) as info:
            plan(program, machine)
        assert str(info.value) == f"{where}: axis A is not on grooving_4axis (axes XYZC)"

    class Moves:  # any object with moves (planner._program_arrays)
        source = "m.nc"
        moves = (Move("rapid", {"X": 0.0}, line=1, block_number=7),
                 Move("rapid", {"B": 0.1}, line=2, block_number=8))

    with pytest.raises(NCProgramError, match=r"^m.nc, line 2 \(N8\), key 'B': axis B is not"):
        plan(Moves(), machine)


def test_a_planner_refusal_of_a_program_without_n_words_names_its_line():
    # _program_arrays reads any object with the arrays; one without block_numbers or moves
    # keeps no N words: its refusal names the line alone (it had raised AttributeError:
    # no attribute 'moves', looking for a Move's block_number)
    targets = np.full((2, 6), np.nan)
    targets[0, :2] = 0.0
    targets[1, :2] = (1e-3, 0.0)

    class Arrays:
        source = "a.nc"
        kinds = np.array([0, 1], dtype=np.int8)  # a rapid, then a feed move with no F
        feeds = np.array([np.nan, np.nan])
        dwells = np.zeros(2)
        lines = np.array([2, 3], dtype=np.int64)

    Arrays.targets = targets
    with pytest.raises(NCProgramError, match=r"^a.nc, line 3, key 'F': a feed move \(G01"):
        plan(Arrays(), load_machine("robonano_a0ib"))


def test_move_and_segment_indices_are_read_as_a_tuple_reads_them():
    # a float index ended in "AttributeError: 'float' object has no attribute '__index__'"
    # (program.moves, trajectory.segments) or numpy's IndexError (trajectory.segment); a
    # tuple of the same moves refuses it with TypeError and takes a NumPy integer or a bool
    program = parse_program("G90 G21\nG01 X1. F100.\nG01 X2.\nM30\n")
    tr = plan(program, "robonano_ui")
    as_tuple = tuple(program.moves)
    for index in (1.0, "1", None):
        with pytest.raises(TypeError, match="move indices must be integers or slices, not"):
            program.moves[index]
        with pytest.raises(TypeError, match="move indices must be integers or slices, not"):
            tr.segments[index]
        with pytest.raises(TypeError, match="move indices must be integers or slices, not"):
            tr.segment(index)
        with pytest.raises(TypeError):
            as_tuple[index]
    assert program.moves[np.int64(1)] == program.moves[True] == as_tuple[1]
    assert program.moves[-1] == as_tuple[-1]
    assert tr.segments[np.int64(-1)].line == tr.segments[len(tr) - 1].line
    with pytest.raises(IndexError, match="move index 2 out of range for 2 moves"):
        program.moves[2]
    with pytest.raises(IndexError, match=f"move index {len(tr)} out of range"):
        tr.segment(len(tr))
