"""A parameter no reading moves at the prior is held there for the whole fit.

On robonano_a0ib the tool edge lies on the B axis line, so a tilt of that line (EA0B, EC0B)
moves no reading of a ball on the edge at the nominal machine. Once the fit has moved the
tool offset it sees such a tilt through that offset's lever (some um): a direction seen only
through the fit's own values, which took fits of it to mrad and past pi rad.
"""

import numpy as np
from identification_fit_helpers import random_truth

import machinesim
from machinesim.identification import fit, from_r_test, plan_quality

DEG = np.pi / 180.0
MACHINE = machinesim.load_machine("robonano_a0ib")
# an R-test plan: B -30, 0, 30 deg and C every 90 deg, the ball on the tool tip
Q = np.array([[0.01, 0.005, 0.002, b * DEG, c * DEG]
              for b in (-30, 0, 30) for c in range(0, 360, 90)])
EC0B = "location.B.EC0B"
#: Fifteen parameters the R-test below fits (rank 10, six Gauss-Newton steps); with EC0B
#: as well the fit ended in NotConvergedError (50 steps, the last of EB0C 0.07 rad).
FIFTEEN = ["workpiece.y", "location.B.EZ0B", "tool.x", "tool.z", "workpiece.alpha",
           "workpiece.beta", "location.C.EB0C", "location.C.EY0C", "tool.y", "workpiece.x",
           "workpiece.z", "workpiece.gamma", "tool.rz", "tool.rx", "location.B.EB0B"]


def test_the_b_line_tilt_moves_no_tool_edge_reading_at_the_nominal_machine():
    # second method: the machine's poses, not the fit's Jacobian
    tilted = machinesim.ErrorModel().with_parameters({EC0B: 1e-3})
    moved = (MACHINE.frame_pose("tool_tip", Q, tilted)[:, :3, 3]
             - MACHINE.frame_pose("tool_tip", Q)[:, :3, 3])
    assert np.max(np.abs(moved)) < 1e-18
    quality = plan_quality(MACHINE, np.repeat(Q, 3, axis=0), FIFTEEN + [EC0B],
                           directions=np.tile(np.eye(3), (len(Q), 1)), sigma=50e-9)
    assert EC0B in quality.unidentifiable


def test_a_parameter_unseen_at_the_prior_stays_there_and_leaves_the_others_as_without_it():
    seed = 706
    truth = random_truth(np.random.default_rng(seed), FIFTEEN + [EC0B])
    lab = machinesim.Lab("robonano_a0ib", truth, noise=True, seed=seed)
    obs = from_r_test(lab.r_test().read(Q))
    without = fit(lab.machine, obs, FIFTEEN)
    assert without.rank == 10 and without.normalised_residual_rms < 3.0
    estimate = fit(lab.machine, obs, FIFTEEN + [EC0B])
    # EC0B keeps the prior's value exactly and is named; the rest is the fit without it
    # (measured bit-identical)
    assert estimate.values[-1] == 0.0 and np.isnan(estimate.std[-1])
    assert EC0B in estimate.unidentifiable
    np.testing.assert_allclose(estimate.values[:-1], without.values, rtol=0, atol=1e-15)
    assert estimate.rank == without.rank
    assert sum(n.startswith(f"rank 10 of 16: the readings cannot see {EC0B}: its value is the "
                            "prior's") for n in estimate.notes) == 1
    # from a prior that holds a value of it, that value
    held = fit(lab.machine, obs, FIFTEEN + [EC0B], prior={EC0B: -8e-6})
    assert held.values[-1] == -8e-6


def test_a_zeroed_r_test_holds_the_b_line_tilts_and_finds_the_tool_offset():
    # the tilts are seen at the estimate only through a 5 um tool offset: in the readings'
    # 1 nm resolution they wandered by ~1e-11 rad a step against a stopping rule of 1e-12
    # rad, and the fit ended in NotConvergedError (noise-free and unrounded, it had found
    # them through that lever with a std of 10 mrad)
    injected = {"location": {"B": {"EA0B_urad": 12.0, "EC0B_urad": -8.0}},
                "tool": {"offset_um": [5.0, -3.0, 4.0]}}
    lab = machinesim.Lab("robonano_a0ib", injected, noise=False)
    obs = from_r_test(lab.r_test(zero="first").read(Q))
    names = ["tool.x", "tool.y", "tool.z", "location.B.EA0B", EC0B]
    estimate = fit(lab.machine, obs, names)
    assert estimate.values[3:].tolist() == [0.0, 0.0]
    assert estimate.unidentifiable[:2] == ("location.B.EA0B", EC0B)
    assert estimate.unseen_at_prior == ()
    # the offset within the readings' rounding to 1 nm (a std of 0.29 nm each; measured 0.08
    # nm off): the tilts' 12 urad through the 5 um lever move no reading by more than 0.1 nm
    np.testing.assert_allclose(estimate.values[:3], [5e-6, -3e-6, 4e-6], rtol=0, atol=3e-10)
