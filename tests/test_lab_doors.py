"""The honesty rule walked as an adversary would walk it: from inside each shipped procedure's
``identify`` and ``compensate`` (the procedure itself, its measurements, its `Identified`),
nothing the lab handed out (the lab, a part or report of its cuts, a workpiece it made, an
instrument) and none of the lab's truth is reachable by any attribute, public or private,
item or closure cell; a Machine's private caches apart, the door docs/lab.md names. And the
identification runs as well with the lab's truth poisoned.

Each procedure is measured once (the slow part), then walked, then identified and
compensated with the truth poisoned: one test per procedure, so that xdist measures it once.
"""

from __future__ import annotations

import numpy as np
import pytest
from honesty_walk import HandingLab, doors, truth_of

from machinesim import Lab
from machinesim.exceptions import InputError
from machinesim.realism import Realism


def _arm():
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    return ToolRotationArm(), "planer_4axis", {"tool": {"offset_um": [0.0, 3.0, 2.0]}}


def _six():
    from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis

    return ToolSetting6Axis(), "robonano_ui", {"tool": {"offset_um": [3.0, 1.0, 2.0]}}


def _grooves():
    from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece

    return (RobotLoadedWorkpiece("grooves", quick=True), "robonano_a0ib",
            {"workpiece": {"delta_um": [5.0, -3.0, 2.0]}})


def _xy():
    from machinesim.machines import models_dir
    from machinesim.procedures.xy_plane_errors import XYPlaneErrors

    model = models_dir() / "errors" / "xy_plane_grooving_4axis.toml"
    return XYPlaneErrors(), "grooving_4axis", model


def _sts():
    from machinesim.procedures.sts_turning import STSTurning

    return STSTurning(), "sts_lathe", {"tool": {"offset_um": [1.0, 0.0, 0.0]}}


#: name -> (procedure, machine, injected errors), and the realism each runs with (the lathe's
#: turned parts are read without spot and registration: noise alone).
PROCEDURES = {"tool_rotation_arm": (_arm, Realism.lab()),
              "tool_setting_6axis": (_six, Realism.lab()),
              "workpiece_setting_grooves": (_grooves, Realism.lab()),
              "xy_plane_errors": (_xy, Realism.lab()),
              "sts_turning": (_sts, Realism.noise_only())}


@pytest.mark.parametrize("name", sorted(PROCEDURES))
def test_identification_reaches_nothing_of_the_lab_and_runs_with_its_truth_poisoned(name):
    make, realism = PROCEDURES[name]
    procedure, machine, errors = make()
    lab = Lab(machine, errors, seed=5, realism=realism)
    handing = HandingLab(lab)
    measurements = procedure.measure(handing)
    identified = procedure.identify(measurements)
    # no door: nothing identify and compensate hold leads to the lab, to what it handed out
    # (parts, reports, workpieces, instruments) or to its truth
    forbidden = {**handing.handed, id(handing): "the lab", **truth_of(lab)}
    found = doors({"procedure": procedure, "measurements": measurements,
                   "identified": identified}, forbidden)
    assert not found, f"{name}:\n" + "\n".join(found)
    # and no read: with the truth poisoned the identification finds the same values
    restore = _poisoned(lab)
    try:
        poisoned = procedure.identify(measurements)
        programs = procedure.compensate(poisoned)
    finally:
        restore()
    assert dict(poisoned.parameters) == dict(identified.parameters)
    assert set(programs) == set(procedure.compensate(identified))


class Poison:
    """Stands in for the lab's truth: any use of it (an attribute, an item, a comparison, a
    truth value, an isinstance through ``__class__``) fails the test."""

    def __getattribute__(self, name):
        raise AssertionError(f"the identification read the lab's truth (.{name})")

    def _read(self, *args):
        raise AssertionError("the identification read the lab's truth")

    __getitem__ = __iter__ = __len__ = __bool__ = __eq__ = __hash__ = __array__ = _read
    __float__ = __index__ = __add__ = __sub__ = __mul__ = __call__ = _read

    def __repr__(self) -> str:
        return "Poison()"


def _poisoned(lab):
    """Put `Poison` where the lab keeps its truth, and where the machine's caches bind it
    (by id() of the lab's models, which no other object has while the lab lives); returns
    how to put everything back (the machine is shared by every test of the process)."""
    truth = {id(model) for model in (lab.reveal(), lab.reveal(background=False),
                                     lab.reveal_background())}
    undo = []
    for name in ("truth", "set_up", "injected", "background", "servo", "artefacts",
                 "instruments", "adjusted"):
        attribute = f"_Lab__{name}"
        undo.append((lab, attribute, getattr(lab, attribute)))
        setattr(lab, attribute, Poison())
    machine = lab.machine
    for owner, name in ((machine, "_bindings"), (machine.kin, "_plans")):
        cache = getattr(owner, name)
        undo.append((owner, name, cache))
        setattr(owner, name, {key: Poison() if _binds(value, truth) else value
                              for key, value in cache.items()})

    def restore():
        for owner, name, value in undo:
            setattr(owner, name, value)
    return restore


def _binds(value, truth) -> bool:
    """Whether a cache entry (a Binding, or a plan led by one) binds one of ``truth``."""
    from machinesim.kinematics import Binding

    if isinstance(value, tuple) and value:
        value = value[0]
    return isinstance(value, Binding) and id(value.errors) in truth



def _probed():
    from machinesim.nc import ProgramBuilder

    return ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3).build(), "v:90", "block:10x10x2"


#: The cut the cheats measure: (program, tool, stock).
PROBED = _probed()


class _Cheat:
    """A procedure that keeps its lab (``keep``) or reads the machine's binding cache
    (``peek``): what the walk and the poison must catch."""

    def __init__(self, how: str) -> None:
        self.how = how

    def measure(self, lab):
        program = PROBED[0]
        lab.encoders().record(program)  # the machine binds nothing yet: the probe does
        lab.touch_probe(lab.cut(*PROBED)[0])
        if self.how == "keep":
            self.lab = lab
        return {"machine": lab.machine}

    def identify(self, measurements):
        from machinesim.experiment import Identified

        value = 0.0
        if self.how == "peek":
            value = max(float(b.errors.tool.offset[0]) for b in
                        measurements["machine"]._bindings.values() if b.errors is not None)
        return Identified({"tool.x": (value, 1e-9)})

    def compensate(self, identified):
        return {}


def test_the_walk_and_the_poison_catch_what_they_must():
    lab = Lab("robonano_a0ib", {"tool": {"offset_um": [5.0, 0.0, 0.0]}}, seed=1)
    keep, peek = _Cheat("keep"), _Cheat("peek")
    handing = HandingLab(lab)
    measurements = keep.measure(handing)
    found = doors({"procedure": keep, "measurements": measurements},
                  {**handing.handed, id(handing): "the lab", **truth_of(lab)})
    assert found == ["procedure.lab -> the lab"]
    # kept where an instance's attributes do not show: in its class, or in a partial
    import functools

    class Stash(_Cheat):
        parts: list = []

        def measure(self, lab):
            measured = super().measure(lab)
            self.later = functools.partial(print, lab.microscope())
            Stash.parts.append(lab.cut(*PROBED)[0])  # the cut measure made, handed back
            return measured

    stash = Stash("stash")
    measurements = stash.measure(handing)
    found = doors({"procedure": stash, "measurements": measurements},
                  {**handing.handed, id(handing): "the lab", **truth_of(lab)})
    assert sorted(found) == sorted([
        "procedure.later.args[0] -> lab.microscope(...)[0] (Microscope)",
        "procedure.__class__.parts[0] -> lab.cut(...)[0] (Part)"]), found
    peek.measure(lab)  # the door the poison covers: the machine's cache binds the truth
    assert any(b.errors is lab.reveal() for b in lab.machine._bindings.values())
    restore = _poisoned(lab)
    try:
        with pytest.raises(AssertionError, match="read the lab's truth"):
            peek.identify({"machine": lab.machine})
        with pytest.raises(AssertionError, match="read the lab's truth"):
            lab.reveal().parameters()
    finally:
        restore()
    assert lab.reveal().tool.offset[0] == pytest.approx(5e-6, rel=1e-12)  # put back


# ------------------------------------------------------------- what a refusal tells of the lab


def test_a_refused_reading_names_the_place_asked_for_not_where_the_stage_put_it():
    # Two blocks, 4 mm and a 2 mm gap: a profile over the gap lies within the part's extent
    # and reads nothing. Its message gave the line where the stage had put it, to 6 digits:
    # the hidden stage offset (1 um sigma) to 10 nm.
    from machinesim.metrology import Microscope
    from machinesim.workpiece import Part, block

    left = block(4e-3, 3e-3, 1e-3)
    part = Part(left.manifold + left.manifold.translate((6e-3, 0.0, 0.0)))
    scope = Microscope(noise=False, stage_sigma=1e-6, stage_rng=1)
    with pytest.raises(InputError) as refused:
        scope.profile(part, (4.2e-3, 1.5e-3), (5.8e-3, 1.5e-3), spacing=1e-5)
    assert "the profile from (0.0042, 0.0015) to (0.0058, 0.0015) m reads no" in str(
        refused.value)
    with pytest.raises(InputError) as refused:
        scope.height_map(part, 4.2e-3, 5.8e-3, 1e-3, 2e-3, spacing=1e-4)
    assert "the height map over x 0.0042 .. 0.0058 m, y 0.001 .. 0.002 m reads no" in str(
        refused.value)


def test_a_reading_is_judged_where_the_part_really_lies_and_named_as_given():
    # The on-part check (ON_PART_SHARE) judges the block as the registration placed it, so a
    # line over the part as really placed reads, as on a real stage (judged on the block as
    # given, paper 003's profiles on ridges found in the instrument's frame were refused:
    # tests/test_xy_plane.py, the compensated corner). Its message gives the part's extent
    # as given: as registered it had told the hidden registration to 0.1 um.
    from machinesim.metrology import Microscope
    from machinesim.metrology.imperfections import Registration
    from machinesim.workpiece import block

    flat = block(5e-3, 3e-3, 1e-3)
    # wholly 20 um past the block's given x = 0 edge; the registration (the instrument's
    # point xi is the workpiece's xi + 30 um) puts that edge at xi = -30 um, under the line
    scope = Microscope(noise=False, registration=Registration([30e-6, 0.0, 0.0]))
    read = scope.profile(flat, (-30e-6, 1.5e-3), (-20e-6, 1.5e-3), spacing=1e-6)
    assert np.count_nonzero(~read.missing) == 11  # every sample over the placed block
    for dx in (-3e-6, 3e-6):
        scope = Microscope(noise=False, registration=Registration([dx, 0.0, 0.0]))
        with pytest.raises(InputError) as refused:
            scope.profile(flat, (6e-3, 1e-3), (7e-3, 1e-3))
        assert "the part spans x 0 .. 5 mm, y 0 .. 3 mm" in str(refused.value)


def test_a_stylus_over_travel_says_how_far_to_two_digits_not_the_exact_distance():
    # The message gave the surface's distance above the path exactly: with the workpiece
    # 3.21 um high, 0.000553209999999951 m, a reading with neither noise nor rounding.
    from machinesim.errors import ErrorModel
    from machinesim.machines import load_machine
    from machinesim.metrology import TouchProbe
    from machinesim.metrology.probe_instrument import StylusOverTravel
    from machinesim.workpiece import block

    a0ib = load_machine("robonano_a0ib")

    def above(x, y, z):  # the probe_tip 40 mm along +Y and 1 mm above the tool edge
        q = np.zeros(len(a0ib.axes))
        q[:3] = x, y - 40e-3, z - 1e-3
        return q

    errors = ErrorModel.from_dict({"workpiece": {"delta_um": [0.0, 0.0, 3.21]}})
    probe = TouchProbe(a0ib, errors, block(5e-3, 3e-3, 1e-3), noise=False)
    with pytest.raises(StylusOverTravel) as refused:
        probe.scan([above(1e-3, 1.5e-3, 1e-3), above(2.5e-3, 1.5e-3, -0.3e-3)], stroke=0.5e-3)
    assert "got it about 0.00055 m above at points [1]" in str(refused.value)
