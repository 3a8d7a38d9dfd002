"""The check of each run's subtraction (machinesim.cutting.run_check): material manifold3d
leaves inside the sweeps it subtracted is cut again one sweep at a time, or refused."""

import json
import math
import types
from pathlib import Path

import manifold3d
import numpy as np
import pytest
from cutting_engine_helpers import pose
from manifold3d import OpType

import machinesim
from machinesim.cutting import engine, remove, run_check
from machinesim.exceptions import InputError, SubtractionError
from machinesim.tolerances import INSIDE_SWEEP_M
from machinesim.tools import BallEndMill
from machinesim.workpiece import block

#: Float64 meshes from a flat end mill's rotary turn 10.1 mm from the axis (flat:1.0, 1 deg,
#: the run of sweeps 58-65): the part before the run, cut down to a 60 x 220 um window about
#: where manifold3d 3.5.4 left material inside the run, and the run's 8 sweeps. Subtracted
#: united they leave 5.3e-18 m^3 of it 168 nm inside a sweep (the whole part: 5.0e-18 m^3).
WEDGE = Path(__file__).parent / "data" / "subtraction_wedge.npz"
#: Material the booleans' round-off may leave in a sweep's union (m^3): the correct runs of
#: that turn measured at most 6.4e-24 (intersection of the part and the run's union).
ROUND_OFF_M3 = 1e-22


def solid(vertices, triangles, tolerance=None):
    mesh = manifold3d.Mesh64(vert_properties=np.ascontiguousarray(vertices, dtype=np.float64),
                             tri_verts=np.ascontiguousarray(triangles, dtype=np.uint64),
                             **({} if tolerance is None else {"tolerance": float(tolerance)}))
    return manifold3d.Manifold(mesh)


def saved(name):
    data = np.load(WEDGE)
    return solid(data[f"{name}_vertices"], data[f"{name}_triangles"], data[f"{name}_tolerance"])


def tetrahedron(corner, size):
    """A right tetrahedron at ``corner`` with legs ``size`` (m): volume size^3 / 6."""
    points = np.asarray(corner, dtype=np.float64) + size * np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    return manifold3d.Manifold.hull_points(points)


@pytest.fixture
def union_short_of(monkeypatch):
    """Make `run_check`'s union of a run leave out ``piece`` (a manifold3d union that
    misses material inside its sweeps, as manifold3d's subtraction did): the run's
    subtraction then keeps the material of the part in ``piece``."""
    def patch(piece):
        def batch_boolean(solids, op):
            united = manifold3d.Manifold.batch_boolean(solids, op)
            return united - piece if op == OpType.Add else united
        fake = types.SimpleNamespace(Manifold=types.SimpleNamespace(batch_boolean=batch_boolean))
        monkeypatch.setattr(run_check, "manifold3d", fake)
    return patch


def test_material_left_inside_a_run_is_cut_one_sweep_at_a_time(union_short_of):
    # a 10 mm cube less two boxes over two of its edges, overlapping at the corner
    cube = manifold3d.Manifold.cube((10e-3, 10e-3, 10e-3))
    first = manifold3d.Manifold.cube((4e-3, 12e-3, 4e-3)).translate((7e-3, -1e-3, 7e-3))
    second = manifold3d.Manifold.cube((12e-3, 4e-3, 4e-3)).translate((-1e-3, 7e-3, 7e-3))
    # by hand: 3 x 10 x 3 mm under each, the 3 x 3 x 3 mm corner counted once
    cut = (2 * 3e-3 * 10e-3 * 3e-3 - 3e-3 ** 3)
    union_short_of(tetrahedron((8e-3, 2e-3, 8e-3), 1e-3))  # inside the first box and the cube
    kept = run_check.subtract_run(cube, [first, second], [4, 5], check=False)
    assert kept.volume() == pytest.approx(10e-3 ** 3 - cut + 1e-3 ** 3 / 6, rel=1e-12)
    # the tetrahedron's faces y = 2 mm and x + y + z = 19 mm have their centroids 4/3 mm
    # inside the first box (from its faces x = 7 mm and z = 7 mm)
    deepest = run_check.deepest_inside(cube, kept, [first, second])
    assert deepest == pytest.approx(4e-3 / 3, rel=1e-12, abs=0.0)
    part = run_check.subtract_run(cube, [first, second], [4, 5])
    assert part.volume() == pytest.approx(10e-3 ** 3 - cut, rel=1e-12)
    assert run_check.deepest_inside(cube, part, [first, second]) <= INSIDE_SWEEP_M


def test_saved_wedge_is_cut_one_sweep_at_a_time():
    before = saved("before")
    sweeps = [saved(f"sweep{i}") for i in range(8)]
    union = manifold3d.Manifold.batch_boolean(sweeps, OpType.Add)
    # the meshes still show manifold3d's error: subtracted united, the run leaves material
    # inside it, measured by intersection (a second method) and by the faces' depth
    united = run_check.subtract_run(before, sweeps, range(58, 66), check=False)
    assert (united ^ union).volume() == pytest.approx(5.3e-18, rel=1e-2, abs=0.0)
    deepest = run_check.deepest_inside(before, united, sweeps)
    assert deepest == pytest.approx(168e-9, rel=1e-2, abs=0.0)
    part = run_check.subtract_run(before, sweeps, range(58, 66))
    assert (part ^ union).volume() <= ROUND_OFF_M3
    assert run_check.deepest_inside(before, part, sweeps) <= INSIDE_SWEEP_M
    # what was removed is what the part had inside the run
    removed = before.volume() - part.volume()
    assert removed == pytest.approx((before ^ union).volume(), rel=0.0, abs=ROUND_OFF_M3)


def test_material_left_one_at_a_time_too_is_refused(union_short_of, monkeypatch):
    cube = manifold3d.Manifold.cube((10e-3, 10e-3, 10e-3))
    first = manifold3d.Manifold.cube((4e-3, 12e-3, 4e-3)).translate((7e-3, -1e-3, 7e-3))
    tetra = tetrahedron((8e-3, 2e-3, 8e-3), 1e-3)
    union_short_of(tetra)
    monkeypatch.setattr(run_check, "one_at_a_time",
                        lambda piece, solids: piece - (solids[0] - tetra))
    with pytest.raises(SubtractionError, match=r"sweeps 7 left material 1.33e\+06 nm inside "
                                               r"them \(1.33e\+06 nm united") as raised:
        run_check.subtract_run(cube, [first], [7])
    assert raised.value.sweeps == (7,)
    assert isinstance(raised.value, machinesim.MachineSimError)


def turning_paths():
    """A ball end mill 0.2 mm into a block, moved 1 mm along X while it turns 2 deg about
    Y in 4 steps."""
    angles = np.radians(np.linspace(0.0, 2.0, 5))
    rotations = [np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0],
                           [-math.sin(a), 0.0, math.cos(a)]]) for a in angles]
    return [np.array([pose((1e-3 + 0.25e-3 * k, 2e-3, -0.2e-3), r)
                      for k, r in enumerate(rotations)])]


def cut_exact_then_short(stock, tool, paths, union_short_of, corner, leg=20e-6):
    """The exact cut (part, report) of ``paths``, after checking that with the check off a
    run whose union misses the tetrahedron of legs ``leg`` at ``corner`` keeps its volume,
    leg^3 / 6 (`union_short_of` stays in force for the caller's cuts)."""
    exact, exact_report = remove(stock, tool, paths, method="boolean")
    union_short_of(tetrahedron(corner, leg))
    _, kept_report = remove(stock, tool, paths, method="boolean", check_runs="off")
    assert exact_report.removed_volume - kept_report.removed_volume == pytest.approx(
        leg ** 3 / 6, rel=1e-6, abs=0.0)
    return exact, exact_report


def test_remove_checks_the_runs_of_a_turning_tool(union_short_of):
    stock, tool, paths = block(4e-3, 4e-3, 1e-3), BallEndMill(0.5e-3), turning_paths()
    # 50 um above the tip at the first pose: inside its sweep and the block
    exact, exact_report = cut_exact_then_short(stock, tool, paths, union_short_of,
                                               (1e-3, 2e-3, -0.15e-3))
    for check in ("turning", "all"):
        part, report = remove(stock, tool, paths, method="boolean", check_runs=check)
        assert report.removed_volume == pytest.approx(exact_report.removed_volume, rel=1e-12)
        assert (part.manifold - exact.manifold).volume() <= ROUND_OFF_M3


def test_straight_moves_are_checked_only_when_asked(union_short_of):
    stock, tool = block(4e-3, 4e-3, 1e-3), BallEndMill(0.5e-3)
    paths = [np.array([pose((1e-3, 2e-3, -0.2e-3)), pose((3e-3, 2e-3, -0.1e-3))])]
    exact, exact_report = remove(stock, tool, paths, method="boolean")
    leg = 20e-6
    union_short_of(tetrahedron((1e-3, 2e-3, -0.15e-3), leg))
    _, default = remove(stock, tool, paths, method="boolean")
    assert exact_report.removed_volume - default.removed_volume == pytest.approx(
        leg ** 3 / 6, rel=1e-6, abs=0.0)
    checked, report = remove(stock, tool, paths, method="boolean", check_runs="all")
    assert report.removed_volume == pytest.approx(exact_report.removed_volume, rel=1e-12)
    assert (checked.manifold - exact.manifold).volume() <= ROUND_OFF_M3


@pytest.mark.parametrize("value", ["yes", True, None, "ALL"])
def test_bad_check_runs_is_refused(value):
    with pytest.raises(InputError, match="key 'check_runs': Expected check_runs as one of "
                                         "'turning', 'all', 'off', got"):
        remove(block(4e-3, 4e-3, 1e-3), BallEndMill(0.5e-3), turning_paths(), check_runs=value)


@pytest.mark.parametrize("cutter", ["cut", "cut_turned"])
def test_cut_names_the_lines_of_a_refused_run(monkeypatch, cutter):
    """Both cutters name the program's lines of the first refused run's sweeps: the plunge
    (line 3) and the retract (line 5) that cuts; cut_turned cuts no rapid, and its first
    run is the plunge's alone."""
    def refuse(piece, solids, sweeps, check, pieces=None):
        raise SubtractionError("manifold3d's subtraction left material", sweeps=tuple(sweeps))
    monkeypatch.setattr(engine, "subtract_run", refuse)
    program = ("G21 G90 G17\nG00 X1. Y2. Z1.\nG01 Z-0.2 F50.\nG01 X3. F100.\nG00 Z5.\nM30\n")
    lines = r"line 3 \(lines 3, 5\)" if cutter == "cut" else r"line 3"
    with pytest.raises(SubtractionError, match=rf"^<string>: {lines}: manifold3d's "):
        getattr(machinesim.cutting, cutter)(machinesim.nc.parse_program(program),
                                            "grooving_4axis", tool="ball:1.0",
                                            stock="block:4x4x1")


def test_a_turn_that_moves_no_vertex_past_the_twist_is_not_checked():
    # a tool's vertices 1 mm from its tip; turned about X by 5e-9 rad they move 5e-12 m, by
    # 2e-8 rad 2e-11 m: only the second is past TWIST_M (1e-11 m), a sweep cut turning
    vertices = np.array([[0.0, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]])

    def turned(angle):
        c, s = math.cos(angle), math.sin(angle)
        return pose((0.0, 0.0, 0.0), np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]))

    poses = np.array([pose((0.0, 0.0, 0.0)), turned(5e-9), turned(2.5e-8), turned(2.5e-8)])
    sweeps = types.SimpleNamespace(poses=poses, pairs=np.array([0, 1, 2]), vertices=vertices)
    assert run_check.checked_sweeps("turning", sweeps, [0, 1, 2]).tolist() == [False, True,
                                                                               False]
    assert run_check.checked_sweeps("all", sweeps, [0, 2]).tolist() == [True, True]
    assert run_check.checked_sweeps("off", sweeps, [0, 1]).tolist() == [False, False]


#: A straight groove 0.2 mm deep along X at y = 2 mm (lines 3 and 4), cut by a ball of 1 mm.
GROOVE = "G21 G90 G17\nG00 X1. Y2. Z1.\nG01 Z-0.2 F50.\nG01 X3. F100.\nG00 Z5.\nM30\n"


@pytest.mark.parametrize("how", ["cut", "cut_turned", "Lab.cut", "machinesim cut"])
def test_every_run_is_checked_when_a_user_asks(union_short_of, how, tmp_path, capsys):
    """``check_runs`` through each way a user cuts: a run of straight moves whose union
    misses a tetrahedron inside its sweeps (leg 20 um: 20e-6^3 / 6 m^3 of the block kept) is
    cut whole with "all", and keeps that tetrahedron with the default, which checks only
    the runs of a tool that turns."""
    from cli_helpers import run

    def cutting(check_runs=None):
        """The removed volume (m^3) of the groove cut ``how``."""
        options = {} if check_runs is None else {"check_runs": check_runs}
        program = machinesim.nc.parse_program(GROOVE)
        where = {"tool": "ball:1.0", "stock": "block:4x4x1"}
        if how == "cut":
            return machinesim.cut(program, "grooving_4axis", **where,
                                  **options)[1].removed_volume_m3
        if how == "cut_turned":
            return machinesim.cutting.cut_turned(program, "grooving_4axis", **where,
                                                 **options)[1].removed_volume_m3
        if how == "Lab.cut":
            lab = machinesim.Lab("grooving_4axis")
            lab.reuse_cuts = False
            return lab.cut(program, **where, **options)[1].removed_volume_m3
        nc, report = tmp_path / "groove.nc", tmp_path / f"r_{check_runs}.json"
        nc.write_text(GROOVE)
        flag = [] if check_runs is None else ["--check-runs", check_runs]
        code, _, err = run(["cut", nc, "--machine", "grooving_4axis", "--tool", "ball:1.0",
                            "--stock", "block:4x4x1", "--quiet", "--out",
                            tmp_path / "part.ply", "--report", report, *flag], capsys)
        assert code == 0, err
        return json.loads(report.read_text())["removed_volume_mm3"] * 1e-9

    exact = cutting("off")
    leg = 20e-6
    union_short_of(tetrahedron((2e-3, 2e-3, -0.15e-3), leg))
    assert exact - cutting() == pytest.approx(leg ** 3 / 6, rel=1e-6, abs=0.0)
    assert cutting("all") == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("cutter", ["cut", "cut_turned"])
def test_a_bad_check_runs_is_refused_before_any_cut(cutter):
    with pytest.raises(InputError, match="key 'check_runs': Expected check_runs as one of"):
        getattr(machinesim.cutting, cutter)(machinesim.nc.parse_program(GROOVE),
                                            "grooving_4axis", tool="ball:1.0",
                                            stock="block:4x4x1", check_runs="every")
