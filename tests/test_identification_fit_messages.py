"""What generic identification (machinesim.identification.fit) refuses and tells: observations
as objects or batches, readings and sigma by name, bad input named with its value, the
documented example, near symmetries and unit slips in the notes, progress, and estimates
and plan qualities that say what they are with units."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from identification_fit_helpers import DEG, MACHINE, SIGMA, UM, read, xy_plan

from machinesim.errors import ErrorModel
from machinesim.exceptions import ErrorModelError, InputError
from machinesim.identification.fit import (
    Combination,
    NotConvergedError,
    Observation,
    Observations,
    fit,
    observations,
    plan_quality,
)
from machinesim.machines import load_machine


def test_observations_as_objects_or_batches_agree():
    truth = ErrorModel().with_parameters({"workpiece.x": 3 * UM, "location.C.EX0C": 2 * UM})
    q, u = xy_plan()
    values = read(truth, q, u, np.zeros(3))
    batch = observations(q, directions=2 * u, values=values, sigma=SIGMA)
    np.testing.assert_array_equal(batch.directions, u)  # normalised
    singles = [Observation(q[i], value=values[i], direction=u[i], sigma=SIGMA)
               for i in range(len(values))]
    assert singles[3].frame == "tool_tip" and singles[3].point.tolist() == [0.0, 0.0, 0.0]
    names = ["workpiece.x", "location.C.EX0C"]
    a, b = fit(MACHINE, batch, names), fit(MACHINE, singles, names)
    np.testing.assert_array_equal(a.values, b.values)
    assert Observations.of([batch[0], batch]).q.shape == (21, 6)
    assert len(batch) == 20 and batch[5].value == values[5]
    with pytest.raises(ValueError, match="read-only"):
        batch.values[0] = 1.0
    assert str(Combination(("a", "b", "c"), [1.0, -0.5, 1e-5])) == "a - 0.5*b + 1e-05*c"
    assert str(Combination(("a", "b"), [-0.25, 1.0])) == "-0.25*a + b"


def test_readings_and_sigma_go_by_name_so_a_swap_cannot_pass():
    # Readings and sigma are both metres: observations(q, u, SIGMA, values), the two swapped
    # by position, passed when every reading was positive (here 2 and 3 um) and fitted
    # workpiece.x and .y at -50 nm each (the truth -3 and -2 um), std 0.6-0.9 um, residual
    # 1.5e-12, no note. No check on the numbers parts the two (readings steadier than
    # their sigma, or all equal, are real), so each takes them by name after q.
    q, u = xy_plan()
    truth = ErrorModel().with_parameters({"workpiece.x": -3 * UM, "workpiece.y": -2 * UM})
    values = read(truth, q, u, np.zeros(3))
    assert values.min() > 0.0
    names = ["workpiece.x", "workpiece.y"]
    estimate = fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA), names)
    assert estimate.values == pytest.approx([-3 * UM, -2 * UM], abs=1e-15)
    with pytest.raises(TypeError, match="positional argument"):
        observations(q, u, SIGMA, values)
    with pytest.raises(TypeError, match="positional argument"):
        Observations(q, SIGMA, u, values)
    with pytest.raises(TypeError, match="positional argument"):
        Observation(q[0], SIGMA, u[0], values[0])
    with pytest.raises(TypeError, match="positional argument"):
        plan_quality(MACHINE, q, "tool_tip", u, names, SIGMA)


def test_bad_input_is_refused_with_the_value_named():
    q, u = xy_plan()
    values = np.zeros(len(q))
    with pytest.raises(InputError, match=r"reading 2: direction \[0.0, 0.0, 0.0\] is zero"):
        observations(q, directions=np.where(np.arange(len(q))[:, None] == 2, 0.0, u),
                     values=values, sigma=SIGMA)
    with pytest.raises(InputError, match=r"reading 0: sigma -5e-08 m; expected a finite"):
        observations(q, directions=u, values=values, sigma=-SIGMA)
    with pytest.raises(InputError, match="disagree on the number of readings"):
        observations(q, directions=u, values=values[:5], sigma=SIGMA)
    with pytest.raises(ErrorModelError, match="unknown error parameter 'location.C.EZ0C'"):
        fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA),
            ["workpiece.x", "location.C.EZ0C"])
    with pytest.raises(InputError, match="'workpiece.x' is listed more than once"):
        fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA),
            ["workpiece.x", "workpiece.x"])
    with pytest.raises(InputError, match=r"expected axis values of shape \(N, 6\), got \(20, 5\)"):
        fit(MACHINE, observations(q[:, :5], directions=u, values=values, sigma=SIGMA),
            ["workpiece.x"])
    with pytest.raises(InputError, match="frame 'probe_tip' is not on robonano_ui"):
        plan_quality(MACHINE, q, ["workpiece.x"], directions=u, sigma=SIGMA, frame="probe_tip")
    with pytest.raises(InputError, match="expected a sequence of parameter names"):
        fit(MACHINE, observations(q, directions=u, values=values, sigma=SIGMA), "workpiece.x")
    truth = ErrorModel().with_parameters({"workpiece.gamma": 2 * DEG})
    with pytest.raises(NotConvergedError, match="did not converge in 1 Gauss-Newton steps"):
        fit(MACHINE, observations(q, directions=u, values=read(truth, q, u, np.zeros(3)),
                                  sigma=SIGMA), ["workpiece.gamma"], max_iterations=1)
    # readings in um given as m (12 um read as 12 m): the first step takes x past 1 m
    truth = ErrorModel().with_parameters({"workpiece.x": 12 * UM})
    with pytest.raises(NotConvergedError, match=r"diverged: after 1 Gauss-Newton steps "
                                                r"workpiece.x = 12 m, beyond any error \(1\)"):
        fit(MACHINE, observations(q, directions=u, values=1e6 * read(truth, q, u, np.zeros(3)),
                                  sigma=SIGMA), ["workpiece.x"])


def test_the_documented_example_runs(capsys):
    text = (Path(__file__).parents[1] / "docs" / "identification.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    exec(compile(code, "docs/identification.md", "exec"), {})
    out = capsys.readouterr().out
    assert "rank 6" in out and "unidentifiable: []" in out
    assert "tool.x        120.0000 um" in out


def _a0ib_r_test(injected, noise, seed=0):
    """An R-test of robonano_a0ib at B -30, 0, 30 deg and C every 90 deg, through a lab."""
    import machinesim
    from machinesim.identification import from_r_test

    q = np.array([[0.01, 0.005, 0.002, b * DEG, c * DEG]
                  for b in (-30, 0, 30) for c in range(0, 360, 90)])
    lab = machinesim.Lab("robonano_a0ib", injected, noise=noise, seed=seed)
    return lab.machine, from_r_test(lab.r_test().read(q))


def test_a_near_symmetry_and_a_missing_error_are_told_in_the_notes():
    # C's zero offset EC0C and the workpiece's rotation gamma turn the same way about the
    # C line: with the line off centre (EX0C, EY0C) they part only by the offset's lever, so
    # the fit has full rank, std in mrad and a correlation of ~1, which the notes name
    machine, obs = _a0ib_r_test({"location": {"C": {"EX0C_um": 3.0, "EY0C_um": -2.0}}}, True)
    estimate = fit(machine, obs, ["location.C.EC0C", "workpiece.gamma", "location.C.EX0C",
                                  "location.C.EY0C"])
    assert estimate.rank == 4 and estimate.std[0] > 1e-3
    assert abs(estimate.correlation[0, 1]) > 0.999
    assert any("location.C.EC0C and workpiece.gamma are correlated" in n
               for n in estimate.notes)
    assert not any("do not fit the model" in n for n in estimate.notes)
    assert not any(n.startswith("rank ") for n in estimate.notes)  # full rank
    # the plan at the nominal machine sees them as one: a combination, and a note of it
    from machinesim.identification.fit import plan_quality as quality
    nominal = quality(machine, obs.q, list(estimate.names), directions=obs.directions,
                      sigma=obs.sigma, frame=obs.frames)
    assert nominal.rank == 3
    assert sum("cannot see the combination" in n for n in nominal.notes) == 1
    # and the fit, which started there, says it sees that symmetry only through its own
    # estimate's errors (the line's offset): the same combination as the plan names
    (c,) = estimate.unseen_at_prior
    assert str(c) == str(nominal.combinations[0])
    assert set(c.names) == {"location.C.EC0C", "workpiece.gamma"}
    assert sum(n.startswith(f"at the prior the readings cannot see {c}; the fit, of rank 4")
               for n in estimate.notes) == 1
    # a tool offset the readings show and the parameters lack: the residual says so
    machine, obs = _a0ib_r_test({"location": {"C": {"EX0C_um": 3.0}},
                                 "tool": {"offset_um": [1.0, 0.5, 0.0]}}, False)
    estimate = fit(machine, obs, ["location.C.EC0C", "location.C.EX0C"])
    assert estimate.normalised_residual_rms > 10.0
    assert any("do not fit the model" in n for n in estimate.notes)


def test_readings_outside_the_travel_none_and_zero_iterations_are_refused():
    from machinesim.exceptions import AxisLimitError

    q = np.zeros((3, 5))
    q[:, 3] = [0.0, 30.0, -30.0]  # B given in degrees: 30 rad is past its travel
    with pytest.raises(AxisLimitError, match="axis B = .* outside its travel.*m and rad"):
        plan_quality(load_machine("robonano_a0ib"), q, ["tool.x"], directions=np.eye(3),
                     sigma=50e-9)
    with pytest.raises(InputError, match="at least one reading"):
        observations(np.zeros((0, 5)), directions=np.zeros((0, 3)), values=np.zeros(0), sigma=50e-9)
    machine, obs = _a0ib_r_test(None, False)
    with pytest.raises(InputError, match="max_iterations"):
        fit(machine, obs, ["tool.x"], max_iterations=0)


@pytest.mark.parametrize("key, bad", [
    ("values", "abc"), ("values", ["1e-6"] * 20), ("values", None), ("sigma", "50nm"),
    ("sigma", True), ("q", [[0.0] * 6, [0.0] * 2]), ("q", "zeros"),
    ("directions", np.eye(3)[[0] * 20] + 0j), ("point", ["0", "0", "0"]),
    ("zero_at", [[0.0] * 6, [0.0]]),
])
def test_readings_that_are_not_numbers_are_refused_naming_the_argument(key, bad):
    # Text, None, booleans, complex numbers and ragged lists had gone to numpy as they were:
    # "abc" and a ragged q raised numpy's ValueError (a traceback naming no argument), and
    # ["1e-6"] * 20 or True were read as numbers
    q, u = xy_plan()
    given = {"q": q, "directions": u, "values": np.zeros(len(q)), "sigma": SIGMA,
             "point": None, "zero_at": None, key: bad}
    name = {"point": "points"}.get(key, key)
    with pytest.raises(InputError, match=rf"Expected {name} as .*, got "):
        observations(**given)


@pytest.mark.parametrize("frame", [3, None, b"tool_tip"])
def test_a_frame_that_is_no_name_is_refused_naming_it(frame):
    # frame=3 had ended in a TypeError, "object of type 'int' has no len()" from
    # inside Observations, naming no argument
    q, u = xy_plan()
    with pytest.raises(InputError, match=rf"key 'frames': expected the frame as a name "
                                         rf"\(str\).*got {re.escape(repr(frame))} "
                                         rf"\({type(frame).__name__}\)"):
        observations(q, directions=u, values=np.zeros(len(q)), sigma=SIGMA, frame=frame)


def test_a_point_given_in_mm_as_m_is_refused_before_its_lever_is_fitted():
    # point=[0, 0, 40] (a ball 40 mm up the tool, in mm) had been fitted as 40 m: every
    # angle's effect 1000 times too large, with no note. robonano_ui's linear travel is
    # 280 x 100 x 130 mm (docs/machines.md): its diagonal, 324.5 mm, is the reach
    q, u = xy_plan()
    far = r"324\.5 mm from tool_tip's origin .*in m, not mm\), got \[0\.0, 0\.0, 40\.0\], " \
          r"40000 mm \(40 m\) from it"
    with pytest.raises(InputError, match=r"key 'points': reading 0: expected the point at most "
                                         + far):
        plan_quality(MACHINE, q, ["tool.rx"], directions=u, sigma=SIGMA, point=[0, 0, 40.0])
    points = np.zeros((len(q), 3))
    points[3] = [0.0, 0.0, 40.0]
    with pytest.raises(InputError, match="reading 3: expected the point at most " + far):
        fit(MACHINE, observations(q, directions=u, values=np.zeros(len(q)), sigma=SIGMA,
                                  point=points), ["tool.rx"])
    # 324 mm is a long stylus, not a unit slip: the plan is judged as given
    assert plan_quality(MACHINE, q, ["tool.x"], directions=u, sigma=SIGMA,
                        point=[0, 0, 0.324]).rank == 1


def test_a_prior_in_the_toml_layout_or_a_toml_file_is_the_model_it_writes(tmp_path):
    # Lab, cut and tool_pose take errors as a TOML layout dict or a TOML path; fit's prior
    # read the dict's sections as parameter names ("key 'tool': unknown parameter name")
    # and refused the path ("got str")
    q, u = xy_plan()
    layout = {"tool": {"offset_um": [0.0, 0.0, 2.0]}, "workpiece": {"gamma_deg": 0.5}}
    path = tmp_path / "prior.toml"
    ErrorModel.from_dict(layout).to_toml(path)
    by_name = plan_quality(MACHINE, q, ["tool.x"], directions=u, sigma=SIGMA,
                           prior={"tool.z": 2 * UM, "workpiece.gamma": 0.5 * DEG})
    for prior in (layout, path, str(path)):
        quality = plan_quality(MACHINE, q, ["tool.x"], directions=u, sigma=SIGMA, prior=prior)
        np.testing.assert_array_equal(quality.std, by_name.std)
    with pytest.raises(InputError, match=r"key 'prior': expected the prior as an ErrorModel, "
                                         r"a mapping name -> value \(SI\), a dict in the TOML "
                                         r"layout or a TOML path, got int"):
        plan_quality(MACHINE, q, ["tool.x"], directions=u, sigma=SIGMA, prior=3)
    with pytest.raises(ErrorModelError, match=r"key 'tol': unknown section"):
        plan_quality(MACHINE, q, ["tool.x"], directions=u, sigma=SIGMA, prior={"tol": {}})


def test_the_machine_may_be_named_as_everywhere_else_and_anything_else_is_refused():
    # fit("robonano_ui", ...) had raised AttributeError: 'str' object has no attribute
    # 'check_errors', while Lab, cut and the compensation take a shipped machine's name
    obs = observations(np.zeros((3, 6)), directions=np.eye(3), values=[1e-6, -2e-6, 0.0],
                       sigma=1e-8)
    named = fit("robonano_ui", obs, ["workpiece.x", "workpiece.y"])
    np.testing.assert_allclose(named.values, [-1e-6, 2e-6], rtol=1e-12)
    quality = plan_quality("robonano_ui", np.zeros((3, 6)), ["workpiece.x"],
                           directions=np.eye(3), sigma=1e-8)
    assert quality.std[0] == pytest.approx(1e-8, rel=1e-12)  # read once along X, sigma 10 nm
    with pytest.raises(InputError, match="Expected machine as a Machine or the name of a "
                                         "shipped one .*got 3"):
        fit(3, obs, ["workpiece.x"])


@pytest.mark.parametrize("name, hint", [
    # C on robonano_a0ib has no EZ0C (a shift of the C line along itself): its five listed
    ("location.C.EZ0C", "the location errors of its axis C are location.C.EX0C, "
                        "location.C.EY0C, location.C.EA0C, location.C.EB0C, location.C.EC0C;"),
    ("location.c.EX0C", "the location errors of its axis C are location.C.EX0C,"),
    ("EX0C", r"\(did you mean location.C.EX0C\?\)"),
    ("EZ0B", r"\(did you mean location.B.EZ0B\?\)"),
    ("workpiece.gama", r"\(did you mean workpiece.gamma\?\)"),
    ("component.X.EXX[1]", r"a component error is a parameter only when the prior holds its "
                           r"table or polynomial"),
])
def test_an_unknown_parameter_name_is_told_the_names_it_may_mean(name, hint):
    # the message had given only the patterns of every name (location.<axis>.<symbol>, ...)
    a0ib = load_machine("robonano_a0ib")
    obs = observations(np.zeros((3, 5)), directions=np.eye(3), values=np.zeros(3), sigma=SIGMA)
    with pytest.raises(ErrorModelError, match=rf"unknown error parameter '{re.escape(name)}' "
                                              rf"for robonano_a0ib; {hint}"):
        fit(a0ib, obs, ["tool.x", name])


def test_readings_in_micrometres_given_as_metres_are_named_in_the_notes():
    # An R-test of C's line offsets (0.3 and -0.2 um) read in um and handed over as m: the
    # fit, linear in the readings, returned EX0C = 0.3 m and EY0C = -0.2 m with no note (the
    # readings fit the model exactly, so no misfit), on a machine whose X travels 280 mm
    a0ib = load_machine("robonano_a0ib")
    q = np.zeros((8, 5))
    q[:, 4] = np.arange(8) * 45 * DEG
    q[:, :3] = np.random.default_rng(5).uniform(-0.01, 0.01, (8, 3))
    qs, u = np.repeat(q, 3, axis=0), np.tile(np.eye(3), (8, 1))
    names = ["location.C.EX0C", "location.C.EY0C"]
    truth = ErrorModel().with_parameters(dict(zip(names, [0.3 * UM, -0.2 * UM], strict=True)))
    readings = np.einsum("ni,ni->n", u, a0ib.tool_pose(qs, truth)[:, :3, 3]
                         - a0ib.tool_pose(qs)[:, :3, 3])
    right = fit(a0ib, observations(qs, directions=u, values=readings, sigma=SIGMA), names)
    np.testing.assert_allclose(right.values, [0.3 * UM, -0.2 * UM], rtol=1e-9)
    assert right.notes == ()
    as_um = fit(a0ib, observations(qs, directions=u, values=readings / UM, sigma=SIGMA), names)
    np.testing.assert_allclose(as_um.values, [0.3, -0.2], rtol=1e-3)  # a factor 1e6 off
    worst = int(np.argmax(np.abs(readings)))
    assert as_um.notes[0] == (
        f"reading {worst} is {readings[worst] / UM:.3g} m; location.C.EX0C = 0.3 m; "
        "location.C.EY0C = -0.2 m: beyond 0.01 m, more than a displacement sensor reads of a "
        "machine's errors. Readings and sigma are in metres: were they given in um or mm? "
        "The values are then off by that factor")
    # a sigma of 50 nm given in um (0.05) is named before anything is measured
    quality = plan_quality(a0ib, qs, names, directions=u, sigma=0.05)
    assert quality.notes == ("sigma 0 is 0.05 m: beyond 0.01 m, more than a displacement "
                             "sensor reads of a machine's errors. Readings and sigma are in "
                             "metres: were they given in um or mm? The values are then off "
                             "by that factor",)
    assert plan_quality(a0ib, qs, names, directions=u, sigma=SIGMA).notes == ()


@pytest.mark.parametrize("sigma", [1e-30, 1e-200, 5e-324, 50.0, 1e200, 1e308])
def test_a_sigma_no_sensor_has_is_refused_before_its_weight_leaves_float64(sigma):
    # 1e-200, 5e-324 and 1e200 and beyond had ended in numpy's LinAlgError "SVD did not
    # converge" (the weights 1/sigma, squared, overflowed or underflowed), 1e-200 in fit as
    # "location.C.EX0C: expected a finite number, got nan"; 50 (50 nm given as metres) had
    # passed
    q, u = xy_plan()
    with pytest.raises(InputError, match=rf"reading 0: sigma {re.escape(repr(sigma))} m; "
                                         r"expected a finite "
                                         r"standard uncertainty from 1e-18 m to 1 m"):
        fit(MACHINE, observations(q, directions=u, values=np.zeros(len(q)), sigma=sigma),
            ["workpiece.x"])
    with pytest.raises(InputError, match=r"from 1e-18 m to 1 m"):
        plan_quality(MACHINE, q, ["workpiece.x"], directions=u, sigma=sigma)


@pytest.mark.parametrize("scale", [1e300, 1e-320])
def test_a_direction_of_any_length_is_normalised(scale):
    # Directions are normalised; one of length 1e300 had a norm of inf (its square overflows)
    # and came out zero, so every reading was ignored and workpiece.x stayed 0 with a note
    # that nothing saw it; one of 1e-320 was refused as zero
    q, u = xy_plan()
    truth = ErrorModel().with_parameters({"workpiece.x": 3 * UM, "workpiece.y": -2 * UM})
    readings = read(truth, q, u, np.zeros(3))
    estimate = fit(MACHINE, observations(q, directions=u * scale, values=readings, sigma=SIGMA),
                   ["workpiece.x", "workpiece.y"])
    np.testing.assert_allclose(estimate.values, [3 * UM, -2 * UM], rtol=1e-9)


def test_progress_is_told_each_gauss_newton_step():
    # A fit of 100,000 readings took ~40 s with nothing said; progress tells each step.
    # Readings 1 and -2 um along X and Y of workpiece.x, .y (sigma 10 nm): before the first
    # step (reading - model) / sigma is (100, -200, 0), RMS sqrt(50000 / 3) = 129.1; the
    # step is the whole answer, workpiece.y -(-2 um)
    told = []
    obs = observations(np.zeros((3, 6)), directions=np.eye(3), values=[1e-6, -2e-6, 0.0],
                       sigma=1e-8)
    estimate = fit(MACHINE, obs, ["workpiece.x", "workpiece.y"], progress=told.append)
    assert len(told) == estimate.iterations == 2
    assert told[0] == ("Gauss-Newton step 1 on 3 readings: RMS of (reading - model) / sigma "
                       "before it 129.1, largest step workpiece.y 2e-06 m (2e+06 x the "
                       "stopping rule)")
    assert re.fullmatch(r"Gauss-Newton step 2 on 3 readings: RMS of \(reading - model\) / "
                        r"sigma before it (0|\S+e-\d\d), .*", told[1])


def test_an_r_test_reading_given_where_observations_go_is_told_the_way_in():
    # fit(machine, lab.r_test().read(q), ...) had raised TypeError "'RTestReading' object is
    # not iterable", and from_r_test of anything else AttributeError "... has no attribute
    # 'q'": tracebacks
    from machinesim import Lab
    from machinesim.identification import from_r_test

    lab = Lab("robonano_a0ib", noise=False)
    reading = lab.r_test().read(np.zeros((2, 5)))
    for given in (reading, [reading]):
        with pytest.raises(InputError, match=r"key 'observations': expected Observation or "
                                             r"Observations.*got an RTestReading: an R-test's "
                                             r"readings go in as from_r_test\(reading\)"):
            fit(lab.machine, given, ["location.C.EX0C"])
    with pytest.raises(InputError, match="expected Observation or Observations, or a sequence "
                                         "of them, got int"):
        fit(lab.machine, 3, ["location.C.EX0C"])
    with pytest.raises(InputError, match=r"key 'reading': expected the RTestReading that "
                                         r"lab.r_test\(\).read\(q\) returns, got ndarray"):
        from_r_test(np.zeros((2, 3)))
    assert len(from_r_test(reading)) == 6  # the way in: 2 poses x X, Y, Z


def test_estimate_and_plan_quality_say_what_they_are_with_units():
    """Their repr had been the dataclass dump: every std, the k x k covariance and
    correlation as bare SI arrays (some 4,000 characters for 6 parameters), the values
    themselves after them, no unit anywhere. Now the counts, then each value and std with
    its unit. Hand values: X, Y, Z read at 8 poses, sigma 50 nm: std 50 nm / sqrt(8) for
    the X offsets, and 2 x 50 nm / sqrt(8) for tool.z + workpiece.z told apart by B."""
    machine = load_machine("robonano_ui")
    deg = np.pi / 180
    abc = [(a, b, c) for a in (0, 180) for b in (-30, 30) for c in (0, 120)]
    q = np.repeat([[0.01 * i, 0.0, 0.02, a * deg, b * deg, c * deg]
                   for i, (a, b, c) in enumerate(abc)], 3, axis=0)
    u = np.tile(np.eye(3), (len(abc), 1))
    names = ["tool.x", "workpiece.x", "workpiece.gamma"]
    quality = plan_quality(machine, q, names, directions=u, sigma=50e-9)
    assert repr(quality).startswith("PlanQuality(3 parameters, 24 readings, rank 3, ")
    assert f"tool.x std {50e-9 / np.sqrt(8):.3g} m" in repr(quality)
    assert "workpiece.gamma std " in repr(quality) and repr(quality).endswith(" rad)")
    truth = ErrorModel().with_parameters({"tool.x": 120e-6, "workpiece.x": 15e-6,
                                          "workpiece.gamma": 1e-3})
    readings = np.einsum("ni,ni->n", u, machine.tool_pose(q, truth)[:, :3, 3]
                         - machine.tool_pose(q)[:, :3, 3])
    estimate = fit(machine, observations(q, directions=u, values=readings, sigma=50e-9),
                   names)
    text = repr(estimate)
    assert text.startswith("Estimate(3 parameters, 24 readings, rank 3, ")
    assert "tool.x = 0.00012 m +- " in text and "workpiece.gamma = 0.001 rad +- " in text
    assert "covariance" not in text and len(text) < 600
    many = plan_quality(machine, q, list(machine.parameter_names())[:12], directions=u,
                        sigma=50e-9)
    assert repr(many).endswith("... 4 more)") and " unidentifiable" in repr(many)


def test_an_estimate_names_a_polynomial_coefficient_s_unit():
    """A polynomial's coefficient k is m per m^k (ErrorModel.parameter_unit): the repr
    gives it so, where the plan, without a model, says SI."""
    machine = load_machine("grooving_4axis")
    prior = ErrorModel.from_dict({"component": {"X": {"EYX_poly_um_mm": [0.0, 0.0]}}})
    q = np.zeros((5, 4))
    q[:, 0] = np.linspace(-0.1, 0.1, 5)
    u = np.tile([0.0, 1.0, 0.0], (5, 1))
    names = ["component.X.EYX[0]", "component.X.EYX[1]"]
    estimate = fit(machine, observations(q, directions=u, values=1e-6 * q[:, 0] + 2e-7,
                                         sigma=1e-8), names, prior=prior)
    assert np.allclose(estimate.values, [2e-7, 1e-6], rtol=1e-6, atol=1e-15)
    assert "component.X.EYX[1] = 1e-06 m/m +- " in repr(estimate)
    assert "component.X.EYX[0] std " in repr(plan_quality(machine, q, names, directions=u,
                                                         sigma=1e-8, prior=prior))


def test_readings_taken_on_one_machine_are_refused_on_another():
    # an R-test read on planer_4axis (X Y Z A) had been fitted on grooving_4axis (X Y Z C),
    # its A column read as C, with no complaint: the arrays have the same width
    import pickle

    from machinesim import Lab
    from machinesim.identification import from_r_test
    from machinesim.metrology import RTestReading

    lab = Lab("planer_4axis", noise=False)
    q = np.zeros((3, 4))
    q[:, 3] = [-0.5, 0.0, 0.5]
    reading = lab.r_test().read(q)
    assert (reading.machine, reading.axes) == ("planer_4axis", ("X", "Y", "Z", "A"))
    obs = from_r_test(reading)
    assert (obs.machine, obs.axes, obs[4].machine) == ("planer_4axis", ("X", "Y", "Z", "A"),
                                                       "planer_4axis")
    refused = (r"key 'observations': the readings were taken on planer_4axis \(axes XYZA\), "
               r"not on grooving_4axis \(axes XYZC\)")
    for given in (obs, [obs[0], obs[1]], Observations.of([obs, obs])):
        with pytest.raises(InputError, match=refused):
            fit("grooving_4axis", given, ["tool.x"])
    assert fit(lab.machine, obs, ["tool.x"]).rank == 1  # on its own machine
    other = observations(np.zeros(4), directions=[1, 0, 0], values=0.0, sigma=SIGMA,
                         axes="XYZC")
    with pytest.raises(InputError, match=r"observations taken on a machine not named \(axes "
                                         r"XYZC\) and on planer_4axis \(axes XYZA\)"):
        Observations.of([obs, other])
    with pytest.raises(InputError, match="key 'axes': expected 4 axis letters, one per column "
                                         "of q, got 'XYZ'"):
        observations(np.zeros(4), directions=[1, 0, 0], values=0.0, sigma=SIGMA, axes="XYZ")
    # a reading pickled before it carried its machine: not known, so not checked
    old = RTestReading.__new__(RTestReading)
    old.__dict__.update({k: v for k, v in reading.__dict__.items()
                         if k not in ("machine", "axes")})
    old = pickle.loads(pickle.dumps(old))
    assert (old.machine, old.axes) == (None, None)
    assert fit("grooving_4axis", from_r_test(old), ["tool.x"]).rank == 1
