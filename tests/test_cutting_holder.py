"""The holder check's material step (`machinesim.cutting.holder.holder_in_material`): the
same sweeps as a straightforward reference, on programs whose earlier passes open the way
for the holder or leave material in its room, with each sweep's solid read a bounded number
of times (not once per candidate, as the reference does)."""

from __future__ import annotations

import numpy as np
import pytest
from cutting_helpers import _slot_in_steps  # the slot of test_cutting.py's holder tests

import machinesim.cutting.holder as holder
from machinesim.cutting import cut
from machinesim.cutting.holder import HOLDER_MATERIAL_M3, holder_in_material, holder_room
from machinesim.cutting.sweeps import Solids
from machinesim.cutting.sweepset import SweepSet
from machinesim.exceptions import HolderContactError
from machinesim.nc import ProgramBuilder, parse_program

MM = 1e-3


def reference(sweeps, candidates, solid, reach, keep, tolerance=0.0, lent=None):
    """Every candidate's room against the solid less every earlier sweep in the stock's
    box, one candidate at a time (candidates x earlier sweeps booleans); less its own sweep
    too where it takes the tool straight down its axis (a plunge: its body has cut its
    hole before the holder follows). ``tolerance``: one value, or one per sweep; ``lent``: a
    borrowed one only inside the lenders' boxes, the sweep's own outside them."""
    hulls, *_, owners = SweepSet.hulls(sweeps, keep)
    owners = np.asarray(owners)
    found = []
    for i in candidates:
        inset = float(tolerance if np.ndim(tolerance) == 0 else tolerance[i])
        room = holder_room(sweeps, i, reach, inset)
        if lent and i in lent:
            room = room + (holder_room(sweeps, i, reach, lent[i][0]) - lent[i][1])
        met = solid ^ room
        start, end = sweeps.poses[sweeps.pairs[i]], sweeps.poses[sweeps.pairs[i] + 1]
        down = (np.array_equal(start[:3, :3], end[:3, :3])
                and float(start[:3, 2] @ (end[:3, 3] - start[:3, 3])) < 0.0)
        for j in np.flatnonzero((owners < i) | ((owners == i) & down)):
            met = met - hulls[j]
            met.num_tri()
        if met.volume() > HOLDER_MATERIAL_M3:
            found.append(int(i))
    return found


class _Counted(Solids):
    """Solids that count how often each one is read."""

    def __init__(self, solids):
        super().__init__(list.__iter__(solids))
        self.reads = np.zeros(len(self), dtype=np.int64)

    def __getitem__(self, index):
        self.reads[index] += 1
        return super().__getitem__(index)


@pytest.fixture
def checked(monkeypatch):
    """Each call of the engine's material step, checked against `reference`: a list of
    (candidates, found, largest reads of one sweep's solid, sweeps built) per call."""
    calls = []
    built = []
    original = SweepSet.hulls

    def counted(self, keep, progress=None):
        result = original(self, keep, progress)
        built.append(_Counted(result[0]))
        return (built[-1], *result[1:])

    def both(sweeps, candidates, solid, reach, keep=None, tolerance=0.0, lent=None):
        built.clear()
        monkeypatch.setattr(SweepSet, "hulls", counted)
        try:
            found = holder_in_material(sweeps, candidates, solid, reach, keep, tolerance,
                                       lent)
        finally:
            monkeypatch.setattr(SweepSet, "hulls", original)
        reads = int(max((b.reads.max(initial=0) for b in built), default=0))
        count = sum(len(b) for b in built)
        assert found == reference(sweeps, candidates, solid, reach, keep, tolerance, lent)
        calls.append((list(candidates), found, reads, count))
        return found

    monkeypatch.setattr(holder, "holder_in_material", both)
    return calls


def test_a_stepped_slot_opens_the_way_as_the_reference_finds(checked):
    # flat end mill, 2 mm of body, a slot 3 mm deep in 1 mm steps: the last pass's holder
    # is in the slot the earlier passes cut (nothing found); moved 0.5 mm sideways, it
    # meets the wall: its feed and lift (its plunge's holder, no wider than the body,
    # follows the body down the hole the plunge itself drilled)
    stock = "block:10x6x5@-5,-3,0"
    cut(_slot_in_steps(3), "grooving_4axis", tool="flat:1.0:h=2", stock=stock)
    candidates, found, _, _ = checked[-1]
    assert candidates and found == []
    with pytest.raises(HolderContactError):
        cut(_slot_in_steps(3, last_y=0.5 * MM), "grooving_4axis", tool="flat:1.0:h=2",
            stock=stock)
    candidates, found, _, _ = checked[-1]
    assert len(candidates) >= 3 and found == candidates[-2:]


def _bore(depth_mm, radius_mm=0.4, pitch_mm=0.25):
    """A helical bore: G02 half turns of ``radius_mm`` about the origin, ``pitch_mm`` down
    each, to ``depth_mm``, then a full circle there."""
    lines = ["G21 G90 G94", f"G00 X{radius_mm} Y0. Z0.1", "G01 Z0. F100."]
    z, k = 0.0, 0
    while z > -depth_mm + 1e-9:
        z = max(z - pitch_mm, -depth_mm)
        x = -radius_mm if k % 2 == 0 else radius_mm
        lines.append(f"G02 X{x:.4f} Y0. Z{z:.4f} I{x:.4f} J0.")
        k += 1
    lines += [f"G02 X{x:.4f} Y0. I{-x:.4f} J0.", "G00 Z1."]
    # chords of 10 um: a few per half turn, and the circle's do not line up with them
    return parse_program("\n".join(lines) + "\n", chord_tolerance=1e-5)


def test_a_bore_deeper_than_the_body_is_cut_its_holder_within_one_chord(checked, monkeypatch):
    # 1.5 mm deep with 1 mm of body, the holder as wide: the helix's holder is in the bore
    # the turns above it cut; the bottom circle's chords (15, 8.74 um inside the circle at
    # their middles) do not line up with the half turns' (8 each, 7.69 um), so the holder
    # at a chord's end, on the circle, meets the wall where a half turn's chord left it
    # 7.69 um short: slivers within one chord (10 um, the tolerance the arcs were read
    # within), no crash, and the bore was refused. Judged within one chord it is cut, as
    # with allow_holder_contact (the body's cut, nothing refused or listed).
    import machinesim.cutting.program as program

    kwargs = {"tool": "flat:1.0:h=1", "stock": "block:5x5x3@-2.5,-2.5,0"}
    part, report = cut(_bore(1.5), "grooving_4axis", **kwargs)
    candidates, found, reads, count = checked[-1]
    assert candidates and found == [] and report.holder_contact == ()
    # each sweep's solid is read a few times at most (containment, clipping, subtraction),
    # not once for every candidate after it
    assert count > 2 * 4 and reads <= 4
    allowed, by_body = cut(_bore(1.5), "grooving_4axis", allow_holder_contact=True, **kwargs)
    assert report.removed_volume_m3 == pytest.approx(by_body.removed_volume_m3, rel=1e-12)
    assert part.volume == pytest.approx(allowed.volume, rel=1e-12)
    # the holder enters the wall by the half turns' chords' sag, R (1 - cos(pi / 16)) =
    # 7.686 um by hand: a tolerance just under it refuses the bottom circle, just over cuts
    sag = 0.4 * MM * (1.0 - np.cos(np.pi / 16))
    monkeypatch.setattr(program, "holder_tolerance", lambda *_: 0.98 * sag)
    with pytest.raises(HolderContactError, match=r"line 10 takes the top"):
        cut(_bore(1.5), "grooving_4axis", **kwargs)
    monkeypatch.setattr(program, "holder_tolerance", lambda *_: 1.02 * sag)
    cut(_bore(1.5), "grooving_4axis", **kwargs)


def _pocket(levels, last_wider=0.0):
    """A pocket in 0.5 mm levels: each a plunge and three passes along X, 0.5 mm apart in
    Y; the last level's passes reach ``last_wider`` (m) further in Y."""
    b = ProgramBuilder(1).rapid(X=0.0, Y=0.0, Z=1 * MM)
    for k in range(1, levels + 1):
        b.linear(Z=-0.5 * MM * k, feed_mm_per_min=300.0)
        wider = last_wider if k == levels else 0.0
        for n, y in enumerate((0.0, 0.5 * MM, 1 * MM + wider)):
            b.linear(Y=y).linear(X=0.0 if n % 2 else 2 * MM)
        b.rapid(Z=1 * MM).rapid(X=0.0, Y=0.0)
    return b.build()


def test_a_pocket_in_levels_meets_its_wall_only_when_a_level_reaches_past_it(checked):
    # 2.5 mm deep with 1 mm of body: the levels below 1 mm find the pocket the levels above
    # opened; the last level 0.3 mm wider puts the holder into the wall
    kwargs = {"tool": "flat:0.5:h=1", "stock": "block:4x3x3@-1,-1,0"}
    _, report = cut(_pocket(5), "grooving_4axis", **kwargs)
    candidates, found, _, _ = checked[-1]
    assert report.holder_contact == () and candidates and found == []
    with pytest.raises(HolderContactError):
        cut(_pocket(5, last_wider=0.3 * MM), "grooving_4axis", **kwargs)
    candidates, found, _, _ = checked[-1]
    assert found and len(found) < len(candidates)


def test_a_segment_top_along_x_gives_the_holder_a_room_not_an_empty_one():
    # a top that is a segment along X (2a long, at z = h), moved d along X: face, lifted and
    # moved all lie in the XZ plane, Qhull found no hull and the room came out empty (no
    # holder crash could be found). Widened across to its own length, the room is the box
    # (2a + d) x 2a x reach, by hand; a V's top (along Y) keeps its room as before.
    from types import SimpleNamespace

    from machinesim.exceptions import InputError

    a, h, d, reach = 0.5 * MM, 3 * MM, 2 * MM, 10 * MM
    poses = np.stack([np.eye(4), np.eye(4)])
    poses[1, 0, 3] = d
    along_x = SimpleNamespace(holder_face=np.array([[-a, 0.0, h], [a, 0.0, h]]),
                              pairs=np.array([0]), poses=poses)
    room = holder_room(along_x, 0, reach)
    assert room.volume() == pytest.approx((2 * a + d) * 2 * a * reach, rel=1e-12)
    # the same segment turned 30 deg about Z, moved along it: widened across it
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    turned = SimpleNamespace(holder_face=np.array([[-a * c, -a * s, h], [a * c, a * s, h]]),
                             pairs=np.array([0]), poses=poses.copy())
    turned.poses[1, :2, 3] = [d * c, d * s]
    assert holder_room(turned, 0, reach).volume() == pytest.approx(
        (2 * a + d) * 2 * a * reach, rel=1e-9)
    along_y = SimpleNamespace(holder_face=np.array([[0.0, -a, h], [0.0, a, h]]),
                              pairs=np.array([0]), poses=poses)
    assert holder_room(along_y, 0, reach).volume() == pytest.approx(
        (2 * a + d) * 2 * a * reach, rel=1e-12)
    point = SimpleNamespace(holder_face=np.array([[0.0, 0.0, h]]), pairs=np.array([0]),
                            poses=poses)
    with pytest.raises(InputError, match="holder's room over sweep 0 is flat"):
        holder_room(point, 0, reach)


@pytest.mark.parametrize("method", ["auto", "boolean"])
def test_a_body_taken_wholly_below_the_stock_has_its_holder_through_it(method):
    """A ball 0.5 mm in radius, its body 10 mm high, drawn across a 10 x 10 x 2 mm block with
    its edge 15 mm down: the body's top is at z = -5 mm, 3 mm below the block's bottom, and
    its holder rises from there through the whole block (by hand: its room holds the block's
    2 mm over the bar's width along all 10 mm). The holder check tested the top face's own
    box against the stock's z range, found it clear, and the cut said only that it removed
    nothing. A tool 12 mm longer than the program's, without its G43, does this."""
    from machinesim.cutting import remove
    from machinesim.tools import BallEndMill
    from machinesim.workpiece import block

    stock, tool = block(10 * MM, 10 * MM, 2 * MM), BallEndMill(0.5 * MM)
    path = np.tile(np.eye(4), (2, 1, 1))
    path[:, :3, 3] = [[-2 * MM, 5 * MM, -15 * MM], [12 * MM, 5 * MM, -15 * MM]]
    met = []
    _, report = remove(stock, tool, [path], method=method, on_holder_contact=met.append)
    assert met == [(0,)]
    assert report.holder_contact == (0,)
    assert report.removed_volume == 0.0  # the body itself never meets the block
    beside = path.copy()
    beside[:, 1, 3] = 20 * MM  # the same pass beside the block: no holder in it
    _, report = remove(stock, tool, [beside], method=method, on_holder_contact=met.append)
    assert met == [(0,)] and report.holder_contact == ()
    with pytest.raises(HolderContactError, match=r"line 4 takes the top of the tool's body"):
        cut(parse_program("G90 G21\nG00 X-2. Y5. Z1.\nG01 Z-15. F200.\nX12.\nM30\n"),
            "grooving_4axis", tool, "block:10x10x2")


def test_a_plunge_deeper_than_the_body_is_cut_and_a_move_at_that_depth_refused(checked):
    """A ball 0.5 mm in radius, its body 10 mm high and its holder no wider, plunged 12 mm
    into a 20 mm block: its holder follows the body down the hole the body drilled (any
    point of the holder's room that the body sweeps, the body swept first), so no holder
    meets the part, and the cut is the one --allow-holder-contact makes, a hole of the
    ball's section (the body alone leaves nothing standing). It was refused as a crash:
    the plunge's own sweep was not counted as cut. Moved sideways at that depth, or with
    a holder 2 mm wide, the holder meets the part and the line is refused."""
    stock = "block:10x10x20"
    plunge = "G90 G21\nG00 X5. Y5. Z1.\nG01 Z-12. F100.\n"
    part, report = cut(parse_program(plunge + "G00 Z15.\nM30\n"), "grooving_4axis",
                       tool="ball:0.5", stock=stock)
    allowed, by_body = cut(parse_program(plunge + "G00 Z15.\nM30\n"), "grooving_4axis",
                           tool="ball:0.5", stock=stock, allow_holder_contact=True)
    assert report.holder_contact == ()  # (allowed, the box test's lines are listed)
    assert checked[0][0] and checked[0][1] == []  # candidates, none meets material
    assert report.removed_volume_m3 == pytest.approx(by_body.removed_volume_m3, rel=1e-12)
    # a cylinder 0.5 mm in radius 11.5 mm deep and a half ball, to the facets' 1 um
    hand = np.pi * (0.5 * MM) ** 2 * 11.5 * MM + 2 / 3 * np.pi * (0.5 * MM) ** 3
    assert report.removed_volume_m3 == pytest.approx(hand, rel=5e-3)
    assert part.volume == pytest.approx(allowed.volume, rel=1e-12)
    with pytest.raises(HolderContactError, match=r": line 4 \(lines 4, 5\) takes the top"):
        cut(parse_program(plunge + "X6.\nG00 Z15.\nM30\n"), "grooving_4axis",
            tool="ball:0.5", stock=stock)
    with pytest.raises(HolderContactError, match=r": line 3 \(lines 3, 4\) takes the top"):
        cut(parse_program(plunge + "G00 Z15.\nM30\n"), "grooving_4axis",
            tool="ball:0.5:d=2", stock=stock)



#: robonano_a0ib at B = 30 deg: a plunge from X0 Z5 along the tool axis (0.5, 0, cos 30)
#: to X-8.5 ends at Z = 5 - 8.5 / tan 30 deg, 17 mm along it (mm).
TILTED_END_Z = 5.0 - 8.5 / np.tan(np.radians(30.0))


def _tilted_plunge(z_text, tool="ball:0.5", **kwargs):
    program = (f"G90 G21\nG00 X0. Y0. Z5. B30.\nG01 X-8.5 Z{z_text} F100.\n"
               "G00 X0. Z5.\nM30\n")
    return cut(parse_program(program), "robonano_a0ib", tool=tool,
               stock="block:40x40x20@-20,-20,0", **kwargs)


@pytest.mark.parametrize("z_text", ["-9.72243186433", "-9.7224319", "-9.722432", "-9.7224"])
def test_a_tilted_plunge_written_to_4_to_11_decimals_is_cut(z_text):
    """The plunge at B30 with its end written to 11, 7, 6 and 4 decimals: only 0 and 45 deg
    are reached exactly at 4-6, and the end 36 pm (7 decimals) to 32 nm (4) off the axis in Z
    leaves its holder that much times sin 30 deg beside the hole the body drilled. Before the
    holder was judged within one chord (e438d6c) it was refused as a crash from 7 decimals
    down (a reviewer read 1.1e-18 m^3 in the holder's room at 7, 4.2e-18 at 6). Within one
    chord (100 nm, a tenth of the ball's 1 um facets) it is cut: no holder contact, the cut
    --allow-holder-contact makes, and by hand the ball's hole, a cylinder from the ball's
    centre to the top face along the axis (an oblique cut of a cylinder holds pi r^2 times
    its length on the axis) and a half ball, to the facets' 1 um. At 4 decimals or more an
    end computed from a written start lies at most 0.05 um (cos B + sin B) <= 71 nm beside
    the axis, and the holder enters the wall by less (see the next test): within 100 nm,
    the least allowance of a straight move (141 nm at 4 decimals: `written_rounding`)."""
    part, report = _tilted_plunge(z_text)
    allowed, by_body = _tilted_plunge(z_text, allow_holder_contact=True)
    assert report.holder_contact == ()
    assert report.removed_volume_m3 == pytest.approx(by_body.removed_volume_m3, rel=1e-12)
    assert part.volume == pytest.approx(allowed.volume, rel=1e-12)
    centre_z = float(z_text) * MM + 0.5 * MM * np.cos(np.radians(30.0))
    hand = (np.pi * (0.5 * MM) ** 2 * (-centre_z / np.cos(np.radians(30.0)))
            + 2 / 3 * np.pi * (0.5 * MM) ** 3)
    assert report.removed_volume_m3 == pytest.approx(hand, rel=5e-3)


def test_a_tilted_plunge_written_to_4_decimals_is_cut_at_any_chord_tolerance():
    """With a 2 mm body (its holder in the hole from 15 mm along the axis down, about 0.56
    of the plunge) the end written to 4 decimals, 32 nm off the axis in Z (16 nm beside it),
    puts the holder up to some 9 nm into the hole's wall: within the words' rounding
    (141 nm at 4 decimals, `written_rounding`), and cut at the default chord, but the
    allowance was capped by the chord tolerance, and with chord_tolerance=1e-9 (--chord-nm
    1) the same program was refused as a crash. The words' rounding is the text's: cut at both, as
    --allow-holder-contact cuts it."""
    z_text = f"{TILTED_END_Z:.4f}"
    parts = [_tilted_plunge(z_text, tool="ball:0.5:h=2", chord_tolerance=chord)
             for chord in (1e-7, 1e-9)]
    allowed, _ = _tilted_plunge(z_text, tool="ball:0.5:h=2", chord_tolerance=1e-9,
                                allow_holder_contact=True)
    assert all(report.holder_contact == () for _, report in parts)
    assert parts[1][0].volume == pytest.approx(allowed.volume, rel=1e-12)


def test_a_tilted_ramp_whose_holder_enters_the_wall_past_one_chord_is_refused():
    """The same feed with its end dz off the axis in Z: the end lies dz sin 30 deg = dz / 2
    beside the axis, and the holder's room h above the body's top is where the body was
    h / L of the way back along the feed (L = 17 mm), dz / 2 * h / L beside it. So the
    holder enters the wall by dz / 2 * h_max / L, h_max the most of the room below the
    stock's top on the side the end moved away from; one chord (t = 100 nm) is allowed:
    refused beyond dz = 2 t L / h_max. The body's top at the end lies 10 mm up the axis,
    at z = Z_end + 10 cos 30 = -1.0622 mm, the room's side 0.5 mm out 0.25 mm lower (dz < 0)
    or higher (dz > 0): h_max = (1.0622 +- 0.25) / cos 30 = 1.5152 or 0.9378 mm, so 2.244 um
    below the axis and 3.625 um above (a scan: 2.2 cut, 2.3 refused; 3.6 cut, 3.7 refused).
    At 0.95 of it the ramp is cut, at 1.05 (1.2 and 1.9 um beside the axis, a dozen and
    more chords) refused, as is the exact plunge with a holder 2 mm wide."""
    top = TILTED_END_Z + 10.0 * np.cos(np.radians(30.0))
    for side in (-1.0, 1.0):
        h_max = -(top + side * 0.25) / np.cos(np.radians(30.0))
        limit = 2.0 * 100e-6 * 17.0 / h_max  # mm
        _, report = _tilted_plunge(f"{TILTED_END_Z + side * 0.95 * limit:.7f}")
        assert report.holder_contact == ()
        with pytest.raises(HolderContactError, match=r": line 3 \(lines 3, 4\) takes the top"):
            _tilted_plunge(f"{TILTED_END_Z + side * 1.05 * limit:.7f}")
    with pytest.raises(HolderContactError, match=r": line 3 \(lines 3, 4\) takes the top"):
        _tilted_plunge("-9.72243186433", tool="ball:0.5:d=2")


@pytest.mark.parametrize("bad", [-1e-9, float("nan"), "1e-6", None, [1e-9, 1e-9],
                                 [float("nan")], [-1e-9], ["1e-6"]])
def test_a_holder_tolerance_that_is_no_length_is_refused_naming_it(bad):
    # one value, or one per sweep (the path below is one sweep: two values are no fit)
    from machinesim.cutting import remove
    from machinesim.exceptions import InputError
    from machinesim.tools import FlatEndMill
    from machinesim.workpiece import block

    with pytest.raises(InputError, match="holder_tolerance"):
        remove(block(MM, MM, MM), FlatEndMill(0.1 * MM), [np.tile(np.eye(4), (2, 1, 1))],
               holder_tolerance=bad)


def test_an_empty_path_is_no_sweep_of_holder_tolerance():
    # a path of no pose makes no sweep (a path of one pose makes one): counted as one, two
    # values for the pass below and an empty path were refused, asking for 3, and three
    # were taken and failed in the holder check (ValueError: operands could not be broadcast)
    from machinesim.cutting import remove
    from machinesim.exceptions import InputError
    from machinesim.tool_specs import tool_from_spec
    from machinesim.workpiece import stock_from_spec

    tool = tool_from_spec("flat:1.0:h=1")
    stock = stock_from_spec("block:10x10x3")
    # a pass along Y 2 mm deep: the holder, from 1 mm down, in the block (sweep 1)
    path = np.array([np.eye(4)] * 3)
    path[:, :3, 3] = [[5 * MM, -MM, MM], [5 * MM, -MM, -2 * MM], [5 * MM, 11 * MM, -2 * MM]]
    empty = np.zeros((0, 4, 4))
    met = []
    alone, report = remove(stock, tool, [path], holder_tolerance=[1e-7, 1e-7],
                           on_holder_contact=met.append)
    for paths in ([path, empty], [empty, path]):
        part, with_empty = remove(stock, tool, paths, holder_tolerance=[1e-7, 1e-7],
                                  on_holder_contact=met.append)
        assert with_empty.holder_contact == report.holder_contact == (1,)
        assert part.volume == pytest.approx(alone.volume, rel=1e-12)
        with pytest.raises(InputError, match=r"holder_tolerance .* or 2 of them"):
            remove(stock, tool, paths, holder_tolerance=[1e-7] * 3)
    assert met == [(1,)] * 3
