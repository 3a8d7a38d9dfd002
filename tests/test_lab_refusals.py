"""What the lab and `run` refuse with a MachineSimError: bad arguments, a background file,
what is fixed when a lab is made, cut options and realisms it does not take, a lab an
earlier run moved or tuned, a tool adjustment in mm; and every documented error kind
importable from the package."""

from __future__ import annotations

import numpy as np
import pytest
from lab_helpers import TRUTH, groove

import machinesim
from machinesim import ErrorModel, Lab
from machinesim.exceptions import InputError


def test_bad_lab_arguments_are_clear_errors():
    with pytest.raises(InputError, match="seed"):
        Lab("robonano_a0ib", seed=-1)
    with pytest.raises(InputError, match="noise"):
        Lab("robonano_a0ib", noise="yes")
    with pytest.raises(InputError, match="errors"):
        Lab("robonano_a0ib", errors=3.0)
    with pytest.raises(machinesim.MachineSimError, match="axis 'A' is not on this machine"):
        Lab("robonano_a0ib", {"location": {"A": {"EX0A_um": 1.0}}})


def test_an_errors_file_that_sets_nothing_or_slips_a_unit_is_told_to_whoever_sets_the_lab_up(
        tmp_path):
    # machinesim cut notes both; a Lab had taken them without a word, an empty file a
    # machine as built and 178 um written under offset_mm a tool 178 mm off
    import warnings

    from machinesim.exceptions import MachineSimWarning

    empty = tmp_path / "empty.toml"
    empty.write_text("[tool]\n")
    slip = tmp_path / "slip.toml"
    slip.write_text("[tool]\noffset_mm = [0.0, -178.0, 0.0]\n")
    with pytest.warns(MachineSimWarning) as told:
        lab = Lab("grooving_4axis", empty)
    assert [str(w.message) for w in told] == [
        f"{empty} sets no error (no key in any section): the lab is set up on the machine as "
        "built, every error zero"]
    assert told[0].filename == __file__  # the caller's line, not the lab's
    with pytest.warns(MachineSimWarning, match=r"slip.toml, line 2: tool.offset_mm = "
                      r"\[0.0, -178.0, 0.0\] reaches 178 mm.*written in um, where the key "
                      "asks mm"):
        Lab("grooving_4axis", slip)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Lab("grooving_4axis", "models/errors/example.toml")  # a file of errors: no word
        Lab("grooving_4axis", ErrorModel())  # a model made in Python: the maker's own
    # the lab's cut keeps quiet about its errors
    _, report = lab.cut(groove(), tool="v:90", stock="block:10x10x2")
    assert not any("sets no error" in note for note in report.notes)


def test_the_api_refuses_what_it_cannot_use_with_a_machinesim_error():
    from machinesim.campaign.runner import _vary
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    machine = machinesim.load_machine("robonano_a0ib")
    q = np.array([1e-3, 2e-3, 0.0, 0.3, 1.1])
    # errors as a dict, as Lab and cut take them, pose the tool as the ErrorModel does
    as_dict = machine.tool_pose(q, TRUTH)
    assert np.array_equal(as_dict, machine.tool_pose(q, ErrorModel.from_dict(TRUTH)))
    assert not np.array_equal(as_dict, machine.tool_pose(q))
    with pytest.raises(InputError, match="expected axis values as numbers"):
        machine.tool_pose("abc")
    with pytest.raises(InputError, match="expected a machinesim.Lab"):
        run(ToolRotationArm(), "planer_4axis")
    with pytest.raises(InputError, match="without measure, identify"):
        run("tool_rotation_arm", Lab("planer_4axis"))
    # a background the realism would not use is refused, naming it
    with pytest.raises(InputError, match="key 'background'.*no background_errors"):
        Lab("planer_4axis", background={})
    # one "PARAM=DIST" string is one variation, not one per character
    assert [name for name, _ in _vary("microscope.sigma=uniform:5nm,200nm")] == [
        "microscope.sigma"]


@pytest.mark.parametrize("call, key, said", [
    (lambda: machinesim.cut("models/examples/grooves.nc", "grooving_4axis",
                            allow_overtravle=True),
     "allow_overtravle", "cut() got an unexpected keyword argument 'allow_overtravle' (did you "
                         "mean allow_overtravel?); it takes program, machine, tool, stock"),
    (lambda: Lab("planer_4axis", nosie=False),
     "nosie", "Lab.__init__() got an unexpected keyword argument 'nosie' (did you mean noise?); "
              "it takes machine, errors, noise, seed, realism, background, servo"),
    (lambda: machinesim.load_machine("planer_4axis").tool_pose(np.zeros(4), error=None),
     "error", "Machine.tool_pose() got an unexpected keyword argument 'error' (did you mean "
              "errors?); it takes q, errors"),
    (lambda: Lab("planer_4axis").microscope().profile(None, (0, 0), (1e-3, 0), spaceing=1e-6),
     "spaceing", "_Profiler.profile() got an unexpected keyword argument 'spaceing' (did you "
                 "mean spacing?); it takes part, start, end, spacing"),
    (lambda: Lab(), None, "Lab.__init__() missing 1 required positional argument: 'machine'"),
    (lambda: machinesim.campaign.run("tool_rotation_arm", 1), None,
     "run() missing 1 required keyword-only argument: 'out'; it takes procedure, trials, vary, "
     "seed, out"),
    (lambda: machinesim.campaign.run("tool_rotation_arm", 1, out="x", wokers=2),
     "wokers", "run() got an unexpected keyword argument 'wokers' (did you mean workers?)"),
])
def test_an_argument_a_public_call_does_not_take_is_a_machinesim_error_naming_it(call, key,
                                                                                  said):
    # Python's own TypeError had ended these, outside machinesim's errors and with no hint
    # of the name meant; it is still a TypeError, as code catching that expects
    with pytest.raises(machinesim.ArgumentError) as info:
        call()
    assert isinstance(info.value, InputError) and isinstance(info.value, TypeError)
    assert info.value.key == key and said in str(info.value), str(info.value)


def test_a_type_error_inside_a_call_that_binds_is_left_as_it_is():
    from machinesim._keywords import keywords_checked

    @keywords_checked
    def raises(x, *, y=0):
        raise TypeError("from the body")

    with pytest.raises(TypeError, match="^from the body$") as info:
        raises(1, y=2)
    assert not isinstance(info.value, machinesim.MachineSimError)


def test_a_background_file_refused_names_its_line(tmp_path):
    # the refusal of a background file's key kept the file but dropped the key's line
    path = tmp_path / "own.toml"
    path.write_text("[location.C]\nEX0C_um = 1.0\n[tool]\noffset_um = [1.0, 2.0]\n")
    with pytest.raises(InputError) as info:
        Lab("planer_4axis", realism=machinesim.Realism.lab(), background=path)
    assert str(info.value) == (f"{path}, line 4, key 'background': expected 3 values, got 2: "
                               "[1.0, 2.0] (list)")


def test_every_error_kind_the_docs_name_is_importable_from_the_package():
    import machinesim.exceptions as exceptions

    kinds = {name for name, value in vars(exceptions).items()
             if isinstance(value, type) and issubclass(value, exceptions.MachineSimError)}
    assert kinds >= {"InputError", "ModelError", "UnreachableError", "AxisLimitError",
                     "HolderContactError", "NCProgramError"}
    for name in kinds:
        assert getattr(machinesim, name) is getattr(exceptions, name)
        assert name in machinesim.__all__
    # the refusals a user meets first are caught by the name the package gives
    with pytest.raises(machinesim.ModelError):
        machinesim.load_machine("no_such_machine")


def test_a_labs_machine_seed_noise_and_realism_are_fixed_when_it_is_made():
    # each was a plain attribute: lab.seed = 3 after an instrument had left the next one
    # numbered on from the old lab (neither the old lab's reading nor a fresh Lab(seed=3)'s),
    # lab.seed = -5 was refused only at the next instrument, lab.machine = "sts_lathe" failed
    # in repr with "'str' object has no attribute 'name'", and lab.noise = False on a realism
    # with instrument noise left the two saying otherwise
    from machinesim.exceptions import ReadOnlyError, brief
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, seed=1, realism=Realism.lab())
    machine = lab.machine
    lab.laser_interferometer()
    for name, value in (("seed", 3), ("seed", -5), ("machine", "sts_lathe"), ("noise", False),
                        ("realism", Realism.ideal())):
        with pytest.raises(ReadOnlyError) as info:
            setattr(lab, name, value)
        assert str(info.value).startswith(f"Lab.{name} cannot be set (to "
                                          f"{brief(repr(value))}): ")
        assert str(info.value).endswith(f"; make another Lab with the {name} wanted")
        assert isinstance(info.value, machinesim.MachineSimError | AttributeError)
        assert isinstance(info.value, AttributeError)
        with pytest.raises(ReadOnlyError, match=rf"^Lab\.{name} cannot be deleted: "):
            delattr(lab, name)
    assert (lab.machine, lab.seed, lab.noise, lab.realism) == (machine, 1, True, Realism.lab())
    assert repr(lab) == "Lab(robonano_a0ib, noise=on, seed=1, realism=lab)"
    # the lab reads on as made: its next instrument is the one a fresh lab hands out second
    fresh = Lab("robonano_a0ib", TRUTH, seed=1, realism=Realism.lab())
    fresh.laser_interferometer()
    assert lab.laser_interferometer()._rng.random() == fresh.laser_interferometer()._rng.random()
    # a pickle and a copy carry them; reuse_cuts stays the lab's switch to set
    import copy
    import pickle

    again = pickle.loads(pickle.dumps(Lab("robonano_a0ib", seed=7, noise=False)))
    assert (again.machine.name, again.seed, again.noise) == ("robonano_a0ib", 7, False)
    assert copy.copy(again).seed == 7
    again.reuse_cuts = False
    assert again.reuse_cuts is False


def test_a_realism_given_by_its_scenario_name_says_how_to_make_it():
    # the scenarios take --realism ideal; Lab(..., realism="ideal") said only "got str"
    from machinesim.realism import Realism

    with pytest.raises(InputError, match=r"got str 'ideal': make one with "
                                         r"machinesim\.realism\.Realism\.ideal\(\), "
                                         r"\.noise_only\(\) or \.lab\(\)"):
        Lab("sts_lathe", realism="ideal")
    assert Lab("sts_lathe", realism=Realism.ideal()).realism == Realism.ideal()


def test_a_cut_option_the_lab_does_not_take_is_refused_with_the_options_it_takes():
    # lab.cut(..., chord=1e-9) ended in TypeError: cut() got an unexpected keyword argument
    # 'chord' and progress=5 in TypeError: 'int' object is not callable from the engine,
    # after the planning; the instruments refuse an option they do not take with a list
    lab = Lab("robonano_a0ib", noise=False)
    with pytest.raises(InputError, match=r"Lab.cut has no option 'chord'; it takes start, "
                                         r"chord_tolerance, servo, progress, allow_overtravel, "
                                         r"allow_holder_contact, check_runs, turn_step") as info:
        lab.cut(groove(), "v:90", "block:10x10x2", chord=1e-9)
    assert info.value.key == "chord"
    with pytest.raises(InputError, match=r"Lab.cut with turn_step has no option 'chord'; it "
                                         r"takes floor, start, turn_step, turn_axis, "
                                         r"chord_tolerance, servo, allow_overtravel, "
                                         r"allow_holder_contact, progress, check_runs"):
        lab.cut(groove(), "v:90", "block:10x10x2", turn_step=0.5, chord=1e-9)
    for cutter in (lambda **o: lab.cut(groove(), "v:90", "block:10x10x2", **o),
                   lambda **o: machinesim.cut(groove(), "robonano_a0ib", **o)):
        with pytest.raises(InputError, match=r"Expected progress as a callable\(done, total\) "
                                             r"or None, got 5") as info:
            cutter(progress=5)
        assert info.value.key == "progress"
    told = []
    _, report = lab.cut(groove(), "v:90", "block:10x10x3", progress=lambda *a: told.append(a))
    assert told and told[-1] == (report.sweeps, report.sweeps)


def test_reveal_takes_true_or_false_for_the_background():
    # lab.reveal(background="no") (a string, so true) gave the injected errors plus the
    # background, the column a report puts beside the injected ones
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, realism=Realism.lab())
    assert lab.reveal(background=False) is not lab.reveal()
    with pytest.raises(InputError, match=r"Expected background as True or False, got 'no'"):
        lab.reveal(background="no")


def test_run_refuses_a_progress_it_cannot_call_before_measuring():
    # run(procedure, lab, progress=5) ended in TypeError: 'int' object is not callable
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    with pytest.raises(InputError, match=r"Expected progress as a callable\(text\) or None, "
                                         r"got 5") as info:
        run(ToolRotationArm(), Lab("planer_4axis", noise=False), progress=5)
    assert info.value.key == "progress"


def test_run_refuses_a_lab_whose_tool_an_earlier_run_moved():
    # sts_turning's evaluate aligns the tool (lab.adjust_tool); a second run on that lab, or
    # any run on a lab so moved, identified what the machine then had (tool.y 0) and
    # reported it against the 3 um the lab was made with: a 3 um error nobody made
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    arm = ToolRotationArm()
    lab = Lab("planer_4axis", {"tool": {"offset_um": [0.0, 3.0, 2.0]}}, noise=False)
    first = run(arm, lab)
    assert first.identified["tool.y"][0] == pytest.approx(3e-6, abs=1e-9)
    again = run(arm, lab)  # a lab no run moved is run on again as made: the same readings
    assert again.identified == first.identified
    lab.adjust_tool((0.0, -3e-6, 0.0))  # as paper 004's alignment moves it
    with pytest.raises(InputError, match=r"this lab's tool has been moved by lab\.adjust_tool "
                                         r".*run each procedure on a new Lab") as info:
        run(arm, lab)
    assert info.value.key == "lab"


def test_run_refuses_a_procedures_class_for_a_procedure():
    # run(ToolRotationArm, lab), the class for its instance, passed the check (its methods
    # are callable) and ended in TypeError: measure() missing 1 required positional argument
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    with pytest.raises(InputError) as info:
        run(ToolRotationArm, Lab("planer_4axis", noise=False))
    assert str(info.value) == ("key 'procedure': expected a procedure, got the class "
                               "ToolRotationArm itself; make one: run(ToolRotationArm(), lab)")
    assert info.value.key == "procedure"


class _Names:
    """A procedure of one's own that identifies ``names`` (each 1 um, std 0) and cuts
    nothing: what run does with the names alone."""

    name, paper, lab_uses = "names", "tests", {"measure": (), "evaluate": ()}

    def __init__(self, names):
        self.names = names

    def measure(self, lab):
        return {}

    def identify(self, measurements):
        from machinesim.experiment import Identified

        return Identified({name: (1e-6, 0.0) for name in self.names})

    def compensate(self, identified):
        return {}

    def evaluate(self, lab, identified, programs):
        from machinesim.experiment import Evaluation

        return Evaluation(figures=())


@pytest.mark.parametrize("name, hint", [
    ("tool.xx", " (did you mean tool.x?)"), ("location.B.EX0B", " (did you mean "
                                                               "location.C.EX0C?)"),
    ("component.Q.EXX[0]", ""), ("workpiece.gama", " (did you mean workpiece.gamma?)"),
    # a quantity of the procedure's own ran to its report and was refused only when
    # summary.json was written ("identified key 'arm.r' is not an error parameter name")
    ("arm.r", ""),
])
def test_run_refuses_an_identified_error_parameter_the_machine_has_not(name, hint):
    # identify naming tool.xx (or an axis grooving_4axis lacks) ran on, and the result set
    # its identified 1 um beside an injected 0.0: the truth's get of a name it has not
    from machinesim.experiment import run
    from machinesim.summary_schema import check_summary

    lab = Lab("grooving_4axis", {"tool": {"offset_um": [1.0, 0.0, 0.0]}}, noise=False)
    with pytest.raises(InputError) as info:
        run(_Names(["tool.x", name]), lab)
    assert str(info.value).startswith(
        f"key 'identify': names.identify named {name!r}, no error parameter of grooving_4axis "
        f"(axes XYZC){hint}: its value would be reported against an injected 0")
    # the machine's own names pass, and a table entry of an axis it has; tool.x's truth is
    # the injected 1 um
    result = run(_Names(["tool.x", "location.C.EB0C", "component.X.EZX[2]"]),
                 Lab("grooving_4axis", {"tool": {"offset_um": [1.0, 0.0, 0.0]}}, noise=False))
    assert result.injected["tool.x"] == pytest.approx(1e-6, abs=1e-18)
    check_summary(result.summary())  # and its summary.json holds them


def test_run_refuses_a_lab_whose_servo_an_earlier_run_tuned():
    # sts_turning's evaluate tunes the servo to Table 6 "after" before Case 4; run again on
    # that lab (noise off, no tool error: no tool move to refuse), its Case 1, the control
    # "as found", was cut with the "after" loops. A lab set back to the loops it was made
    # with (the very ones, or equal ones) is as made: run stops here only at its first step
    from machinesim.experiment import run
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm
    from machinesim.servo import table6_servo

    class Started(Exception):
        pass

    def stop(text):
        raise Started(text)

    axes = ("x", "y", "z", "a")
    before = table6_servo("before", axis_order=axes)
    lab = Lab("planer_4axis", noise=False, servo=before)
    with pytest.raises(Started, match="measure"):
        run(ToolRotationArm(), lab, progress=stop)
    lab.tune_servo(table6_servo("after", axis_order=axes))
    assert lab.reveal_servo(as_made=True) is before
    with pytest.raises(InputError, match=r"this lab's servo loops have been tuned by "
                                         r"lab\.tune_servo since it was made .*'before' case "
                                         r".*run each procedure on a new Lab") as info:
        run(ToolRotationArm(), lab, progress=stop)
    assert info.value.key == "lab"
    lab.tune_servo(table6_servo("before", axis_order=axes))  # equal to those it was made with
    with pytest.raises(Started, match="measure"):
        run(ToolRotationArm(), lab, progress=stop)
    lab.tune_servo(before)
    with pytest.raises(Started, match="measure"):
        run(ToolRotationArm(), lab, progress=stop)
    lab.adjust_tool((1e-6, 0.0, 0.0))
    lab.tune_servo(table6_servo("after", axis_order=axes))
    with pytest.raises(InputError, match=r"this lab's tool has been moved by lab\.adjust_tool "
                                         r"and its servo loops tuned by lab\.tune_servo since"):
        run(ToolRotationArm(), lab, progress=stop)
    ideal = Lab("planer_4axis", noise=False)  # no loops as made: any set is a tuning
    ideal.tune_servo(table6_servo("before", axis_order=axes))
    with pytest.raises(InputError, match=r"servo loops have been tuned"):
        run(ToolRotationArm(), ideal, progress=stop)
    with pytest.raises(InputError, match=r"Expected as_made as True or False, got 'no'"):
        ideal.reveal_servo(as_made="no")


def test_a_tool_adjustment_given_in_mm_is_refused_naming_the_unit():
    # adjust_tool([10, 0, 0]), 10 mm meant, is a 10 m move: it was refused by the +-5 mm
    # stroke with no word of the unit; a move longer than the whole stroke (10 mm) asks
    lab = Lab("robonano_a0ib", seed=1)
    with pytest.raises(InputError, match=r"offset is in m, 10 m: given in mm or um\?"):
        lab.adjust_tool([10, 0, 0])
    # a move the adjuster could make from elsewhere in its stroke is no unit slip
    lab.adjust_tool([-4e-3, 0.0, 0.0])
    with pytest.raises(InputError, match="beyond its stroke") as info:
        lab.adjust_tool([9.5e-3, 0.0, 0.0])
    assert "given in mm" not in str(info.value)


class _Values(_Names):
    name = "values"

    def __init__(self, values):
        super().__init__(list(values))
        self.values = values

    def identify(self, measurements):
        from machinesim.experiment import Identified

        return Identified({name: (value, 0.0) for name, value in self.values.items()})


@pytest.mark.parametrize("name, value, shown", [
    ("tool.x", 4.0, "4000 mm"),                  # 4 um reported as 4 (m)
    ("workpiece.gamma", -200.0, "-11459.2 deg"),  # 200 urad reported as 200 (rad)
])
def test_run_refuses_an_identified_value_no_error_model_holds(name, value, shown):
    # an identify that gave its um as m ran to a report of 4 m identified against 4 um
    from machinesim.experiment import run

    lab = Lab("grooving_4axis", {"tool": {"offset_um": [4.0, 0.0, 0.0]}}, noise=False)
    with pytest.raises(InputError) as info:
        run(_Values({name: value}), lab)
    assert str(info.value).startswith(
        f"key 'identify': values.identify gave {name} = {value!r} "
        f"{'m' if name == 'tool.x' else 'rad'} ({shown}), beyond what an error model holds")


def test_run_warns_of_an_identified_value_beyond_any_machines_errors():
    # 20 mm: 20 um given in mm; an error model can hold it, no machine is set that far off
    from machinesim.exceptions import MachineSimWarning
    from machinesim.experiment import run

    lab = Lab("grooving_4axis", {"tool": {"offset_um": [4.0, 0.0, 0.0]}}, noise=False)
    with pytest.warns(MachineSimWarning, match=r"tool\.x = 0\.02 m \(20 mm\), beyond the "
                                               r"errors of any machine") as record:
        result = run(_Values({"tool.x": 0.02, "tool.y": 9e-3}), lab)
    assert len(record) == 1 and record[0].filename == __file__  # 9 mm is not noted
    assert result.identified["tool.x"][0] == 0.02
