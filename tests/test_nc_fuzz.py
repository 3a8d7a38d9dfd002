"""Hypothesis over programs in the whole dialect, valid and mangled: only `MachineSimError`
escapes, and every program that reads satisfies the `Program` invariants."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from machinesim.exceptions import MachineSimError, NCProgramError
from machinesim.nc import Program, format_program, parse_program

_number = st.one_of(
    st.integers(-50, 50).map(str),
    st.floats(-100, 100, allow_nan=False).map(lambda v: f"{v:.3f}"),
    st.sampled_from(["0", "1", "2", "5.", "-5.", "10.", ".5", "1e9", "9" * 30, "-", "1.2.3",
                     "1000000000.", "0.000001"]),
)
_g = st.sampled_from(["G00", "G01", "G02", "G03", "G04", "G17", "G18", "G19", "G20", "G21",
                      "G28", "G40", "G41", "G43", "G44", "G49", "G53", "G54", "G55", "G61",
                      "G64", "G80", "G81", "G82", "G83", "G90", "G91", "G94", "G95", "G98",
                      "G99", "G05.1", "G5.1", "G08", "G8", "G92", "G54.1"])
_m = st.sampled_from(["M03", "M05", "M06", "M08", "M30", "M02", "M98", "M99", "M3.5"])
_word = st.one_of(
    _g, _g, _m,
    st.tuples(st.sampled_from("XYZABCIJKRQFPLHTDSNOEU"), _number).map("".join),
    st.sampled_from(["P2", "P3", "P20002", "L2", "L0", "Q1", "Q0", "P1", "P0", "H1", "H2",
                     "T1", "D1", "R1.", "K3", "(note)", "#1", "%", "/"]),
)
_block = st.lists(_word, min_size=0, max_size=6).map(" ".join)
_subprogram = st.tuples(st.sampled_from(["O2", "O3", "O0002"]),
                        st.lists(_block, max_size=5),
                        st.sampled_from(["M99", "", "M99\nG00 X1"])).map(
    lambda t: "\n".join([t[0], *t[1], t[2]]))
_program = st.tuples(
    st.sampled_from(["", "O1\n", "%\nO1\n", "O1\nG90 G21 G17 G00 X0 Y0 Z5.\n"]),
    st.lists(_block, max_size=15),
    st.sampled_from(["", "\nM30", "\nM02"]),
    st.lists(_subprogram, max_size=2),
).map(lambda t: t[0] + "\n".join(t[1]) + t[2] + "".join("\n" + s for s in t[3]))


def _check_invariants(program: Program) -> None:
    t = program.targets
    assert t.shape == (len(program), 6)
    assert not np.isinf(t).any()
    unset = np.isnan(t)
    assert not (unset[1:] & ~unset[:-1]).any()  # modal: a set axis stays set
    assert set(np.unique(program.kinds)) <= {0, 1, 2}
    assert np.all(program.lines >= 1)
    assert all(98 not in c and 99 not in c for c in program.m_codes.values())


def _read(text: str, **kwargs) -> None:
    try:
        program = parse_program(text, "fuzz.nc", **kwargs)
    except NCProgramError as error:
        assert "fuzz.nc" in str(error)
        for problem in getattr(error, "problems", ()):
            assert isinstance(problem, NCProgramError) and problem.line is not None
        return
    _check_invariants(program)
    try:
        written = format_program(program)
    except NCProgramError:
        return
    parse_program(written)


@settings(max_examples=400, deadline=None)
@given(_program, st.sampled_from(["calculator", "increment"]),
       st.sampled_from([None, {"tool": {"1": {"length_mm": 10.0}, "2": {"radius_mm": 1.0}}}]),
       st.sampled_from([1e-9, 1e-6]))
def test_programs_raise_only_nc_errors(text, integer_input, tools, tolerance):
    _read(text, integer_input=integer_input, tools=tools, chord_tolerance=tolerance)


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8"), max_size=200))
def test_any_text_raises_only_nc_errors(text):
    _read(text)


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_any_bytes_in_a_file_raise_only_machinesim_errors(tmp_path_factory, data):
    from machinesim.nc import read_program

    path = tmp_path_factory.mktemp("fuzz") / "p.nc"
    path.write_bytes(data)
    try:
        _check_invariants(read_program(path))
    except MachineSimError:
        pass


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 6).flatmap(lambda n: st.tuples(
    st.lists(st.lists(st.one_of(st.just(np.nan), st.floats(-1, 1), st.just(np.inf)),
                      min_size=6, max_size=6), min_size=n, max_size=n),
    st.lists(st.integers(-1, 3), min_size=n, max_size=n),
    st.lists(st.one_of(st.just(np.nan), st.floats(-1, 1)), min_size=n, max_size=n),
    st.lists(st.one_of(st.just(0.0), st.floats(-1, 1)), min_size=n, max_size=n),
)))
def test_program_from_arrays_raises_only_nc_errors(arrays):
    targets, kinds, feeds, dwells = arrays
    try:
        program = Program.from_arrays(np.array(targets).reshape(-1, 6), kinds, feeds, dwells)
    except NCProgramError:
        return
    _check_invariants(program)
