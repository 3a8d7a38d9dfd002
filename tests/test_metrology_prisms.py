"""Apexes of grooves that meet in ridges (`fit_apexes`) against profiles built analytically:
tilted as a microscope's stage holds a part, with and without noise, and its input checks."""

import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.metrology import fit_apexes

UM = 1e-6
CENTRES = np.array([150.0, 200.0, 250.0]) * UM
DEPTH = 25 * UM


def prisms(tilt=0.0, noise=0.0):
    """Three 90-deg V grooves 25 um deep, 50 um apart (sharing their ridges), between land at
    both ends of a 0.4 mm section, sheared by ``tilt`` and with normal noise of ``noise`` m."""
    s = np.arange(0.0, 400 * UM, 0.25 * UM)
    z = np.zeros_like(s)
    for centre in CENTRES:
        z = np.minimum(z, -DEPTH + np.abs(s - centre))
    return s, z + tilt * s + noise * np.random.default_rng(1).standard_normal(s.size)


@pytest.mark.parametrize("tilt", [2e-4, -2e-4, 1e-3, -1e-3])
def test_apexes_of_a_tilted_exact_profile(tilt):
    # A shear moves neither the crossing of two flank lines in s nor the apex's depth along z
    # below the land line: the analytic apexes and depths stand. The old land search (within
    # the noise of the 90th percentile of the heights) read the tilted ends as cut.
    centre, depth, _, _ = fit_apexes(*prisms(tilt), 3, prominence=5 * UM)
    # exact lines: float64 round-off of ~1e-20 m, amplified by the fits (as in
    # tests/test_tool_rotation_arm_equations.py's exact prism profile)
    np.testing.assert_allclose(centre, CENTRES, rtol=0, atol=1e-15)
    np.testing.assert_allclose(depth, DEPTH, rtol=0, atol=1e-17)


@pytest.mark.parametrize("tilt", [2e-4, -2e-4, 1e-3, -1e-3])
def test_apexes_of_a_tilted_noisy_profile_within_their_sigma(tilt):
    # 12 nm noise: the old search kept part of the left land as groove and put the first
    # apex 22.6 um off, 2.4 um deep, at tilt 2e-4
    centre, depth, centre_sigma, depth_sigma = fit_apexes(*prisms(tilt, 12e-9), 3,
                                                          prominence=5 * UM)
    # 5 sigma: a miss by chance in ~1e-6 per value (the sigmas are ~2.2 nm and ~3 nm)
    assert np.all(np.abs(centre - CENTRES) < 5 * centre_sigma)
    assert np.all(np.abs(depth - DEPTH) < 5 * depth_sigma)
    assert np.all(centre_sigma < 5e-9) and np.all(depth_sigma < 5e-9)


def test_a_profile_cut_at_an_end_is_refused_whatever_its_tilt():
    s, z = prisms()
    z = np.minimum(z, -DEPTH + np.abs(s - 5 * UM))
    for tilt in (0.0, 1e-3):
        with pytest.raises(InputError, match="uncut land at both ends"):
            fit_apexes(s, z + tilt * s, 4, prominence=5 * UM)


@pytest.mark.parametrize("tilt", [0.0, 2e-4])
def test_grooves_with_land_between_them_read_from_the_land_beside_each(tilt):
    # two grooves that share a ridge and a third 0.36 mm away across uncut land: a flank
    # starts where the land ends, not at the highest land sample between, which took land
    # into the second groove's right flank (untilted: its apex read 15 um off and 0 deep,
    # the first's 1.45 um off and 13.55 um deep; tilted: refused as no V)
    s = np.arange(0.0, 1e-3, 0.25 * UM)
    centres = np.array([300.0, 340.0, 700.0]) * UM
    z = np.zeros_like(s)
    for centre in centres:
        z = np.minimum(z, -15 * UM + np.abs(s - centre))
    centre, depth, _, _ = fit_apexes(s, z + tilt * s, 3, prominence=5 * UM)
    np.testing.assert_allclose(centre, centres, rtol=0, atol=1e-15)
    np.testing.assert_allclose(depth, 15 * UM, rtol=0, atol=1e-17)


@pytest.mark.parametrize("options, message", [
    ({"flank_band": (0.5,)}, r"Expected flank_band as two fractions, got \(0.5,\)"),
    ({"flank_band": (0.9, 0.1)}, r"Expected 0 <= lo < hi <= 1 in flank_band"),
    # text and bools were converted: "01" read as (0, 1), ("0.1", "0.9") and (False, True)
    ({"flank_band": "01"}, r"Expected flank_band as two fractions, got '01'"),
    ({"flank_band": ("0.1", "0.9")}, r"flank_band as a number \(fraction of the flank\), got '0.1"),
    ({"flank_band": (False, True)}, r"flank_band as a number \(fraction of the flank\), got False"),
    ({"flank_band": 0.5}, r"Expected flank_band as two fractions, got 0.5"),
    ({"prominence": "5e-6"}, r"Expected prominence as a number \(m\), got '5e-6'"),
    ({"prominence": -1.0}, r"Expected prominence > 0 \(m\), got -1.0"),
    ({"prominence": 0.0}, r"Expected prominence > 0 \(m\), got 0.0"),
    ({"count": "3"}, r"Expected count as a whole number >= 1 of grooves, got '3'"),
    ({"count": 3.0}, r"Expected count as a whole number >= 1 of grooves, got 3.0"),
    ({"count": True}, r"Expected count as a whole number >= 1 of grooves, got True"),
    ({"count": 0}, r"Expected count as a whole number >= 1 of grooves, got 0"),
])
def test_apex_input_errors_name_the_argument(options, message):
    # each once a raw ValueError or TypeError, a "found 3 of 3" refusal, a misleading "fewer
    # than two samples on a flank", or accepted
    arguments = {"count": 3, "prominence": 5 * UM} | options
    key = next(iter(options))
    with pytest.raises(InputError, match=message) as caught:
        fit_apexes(*prisms(), arguments.pop("count"), **arguments)
    assert caught.value.key == key


def test_stated_sigmas_match_the_scatter_with_lateral_noise():
    """Lateral noise (the lab microscope's 20 nm) shows on a 45-deg flank as 20 nm of height
    noise, not on the land; with 2 nm of height noise the old pooled residual, mostly the
    long land's, stated 1.56-1.60 nm for centres and depths scattering 3.7-4.5 nm over 200
    draws (0.36-0.43 of it). Each line's own residual states 4.13-4.17 nm."""
    s = np.arange(0.0, 400 * UM, 0.3 * UM)
    centres, sigmas = [], []
    for seed in range(200):
        rng = np.random.default_rng(seed)
        jittered = s + 20e-9 * rng.standard_normal(s.size)
        z = np.zeros_like(s)
        for centre in CENTRES:
            z = np.minimum(z, -DEPTH + np.abs(jittered - centre))
        centre, depth, centre_sigma, depth_sigma = fit_apexes(
            s, z + 2e-9 * rng.standard_normal(s.size), 3, prominence=5 * UM)
        centres.append(np.r_[centre, depth])
        sigmas.append(np.r_[centre_sigma, depth_sigma])
    ratio = np.mean(sigmas, axis=0) / np.std(centres, axis=0)
    # the std of 200 draws is known to 5 % (1 / sqrt(2 x 199))
    np.testing.assert_allclose(ratio, 1.0, rtol=0, atol=0.15)
