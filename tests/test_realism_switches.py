"""Realism's switches: the presets, their variants and reprs, a Lab's realism= and
noise= arguments; all off reads as the instruments built directly, bit for bit, and each
imperfection draws from its own stream."""

from __future__ import annotations

import numpy as np
import pytest
import realism_helpers
from lab_helpers import TRUTH
from realism_helpers import MM, ROUND_OFF_M

from machinesim import ErrorModel, Lab
from machinesim.exceptions import InputError
from machinesim.metrology import (
    LaserInterferometer,
    Microscope,
    TouchProbe,
    WhiteLightInterferometer,
)
from machinesim.metrology.imperfections import Lobing, Registration, ZonalForm
from machinesim.realism import Realism
from machinesim.streams import stream

#: The groove cut under the lab's truth (a fixture: imported by name, pytest's argument
#: of that name would read as its redefinition)
cut_part = realism_helpers.cut_part


# ------------------------------------------------------------------------------- switches


def test_presets_and_variants():
    assert Realism.ideal().on == () and Realism() == Realism.ideal()
    assert Realism.noise_only().on == ("instrument_noise",)
    assert Realism.lab().on == Realism.names() and len(Realism.names()) == 10
    budget = [Realism.lab().without(name) for name in Realism.names()]
    assert all(len(r.on) == 9 for r in budget)
    assert Realism.with_only("registration", "lateral_noise").on == ("lateral_noise",
                                                                      "registration")
    assert str(Realism.lab()) == "lab" and str(Realism.noise_only()) == "noise_only"
    assert str(Realism.with_only("registration")) == "registration"
    with pytest.raises(InputError, match="realism switch"):
        Realism.lab().without("thermal")
    with pytest.raises(InputError, match="registration"):
        Realism(registration="yes")


def test_a_realism_says_which_switches_are_on():
    """Its repr had been the dataclass dump of all ten flags ('Realism(instrument_noise=
    True, lateral_resolution=False, ...)'): the preset, or the switches on (in their order)
    and how many are off, or the lab's without the few that are off."""
    assert repr(Realism.ideal()) == "Realism(ideal: all 10 off)"
    assert repr(Realism.lab()) == "Realism(lab: all 10 on)"
    assert repr(Realism.noise_only()) == "Realism(noise_only: instrument_noise on; 9 off)"
    assert repr(Realism.with_only("registration", "lateral_noise")) == (
        "Realism(lateral_noise, registration on; 8 off)")
    assert repr(Realism.lab().without("air_refraction", "registration")) == (
        "Realism(lab without registration, air_refraction)")


def test_lab_arguments():
    assert repr(Lab("robonano_a0ib", seed=2)) == "Lab(robonano_a0ib, noise=on, seed=2)"
    assert repr(Lab("robonano_a0ib", seed=2, realism=Realism.lab().without("registration"))
                ).endswith("realism=instrument_noise+lateral_resolution+lateral_noise+"
                           "probe_pretravel+probe_ball_form+artefact_errors+background_errors+"
                           "stage_positioning+air_refraction)")
    assert Lab("robonano_a0ib", noise=False).realism == Realism.ideal()
    assert Lab("robonano_a0ib", realism=Realism.ideal()).noise is False
    with pytest.raises(InputError, match="not both"):
        Lab("robonano_a0ib", noise=False, realism=Realism.lab())
    with pytest.raises(InputError, match="Realism"):
        Lab("robonano_a0ib", realism="lab")


# ------------------------------------------------------- off gives today's readings exactly


def test_the_default_lab_reads_as_instruments_built_directly_and_as_noise_only(a0ib,
                                                                                cut_part):
    """Lab(...) and Lab(..., realism=Realism.noise_only()) read bit for bit what the
    instruments built as before (the lab's stream, no imperfection) read."""
    seed = 5
    labs = [Lab("robonano_a0ib", TRUTH, seed=seed),
            Lab("robonano_a0ib", TRUTH, seed=seed, realism=Realism.noise_only())]
    truth = ErrorModel.from_dict(TRUTH)
    direct = {
        "microscope": Microscope(rng=stream(seed, "microscope", "0")),
        "white": WhiteLightInterferometer(rng=stream(seed, "white_light_interferometer", "0")),
        "probe": TouchProbe(a0ib, truth, cut_part, rng=stream(seed, "touch_probe", "0")),
        "laser": LaserInterferometer(a0ib, truth, rng=stream(seed, "laser_interferometer",
                                                             "0")),
    }

    def read(instruments):
        q = np.zeros(5)
        q[:3] = 5 * MM, 1 * MM - 40 * MM, 1 * MM
        return [instruments["microscope"].profile(cut_part, (5e-3, 0.5e-3), (5e-3, 1.5e-3)).z,
                instruments["microscope"].height_map(cut_part, 4e-3, 4.01e-3, 1e-3, 1.01e-3).z,
                instruments["white"].profile(cut_part, (2e-3, 0.0), (2e-3, 2e-3)).z,
                instruments["probe"].touch(q, "-Z", 2 * MM),
                instruments["laser"].positioning("X", np.linspace(-0.1, 0.1, 5)).deviation]

    expected = read(direct)
    for lab in labs:
        got = read({"microscope": lab.microscope(), "white": lab.white_light_interferometer(),
                    "probe": lab.touch_probe(cut_part), "laser": lab.laser_interferometer()})
        for a, b in zip(got, expected, strict=True):
            assert np.array_equal(a, b, equal_nan=True)
    assert labs[0].reveal() is labs[0].reveal(background=False)
    assert labs[0].reveal_background().is_zero and labs[0].reveal_artefacts() == {}


def test_each_imperfection_draws_from_its_own_stream(cut_part):
    """Turning one switch off changes nothing another draws: the registrations, the probe's
    lobing and ball form, and the height noise are the same in every variant."""
    def drawn(realism):
        lab = Lab("robonano_a0ib", TRUTH, seed=9, realism=realism)
        lab.microscope(label="m")
        lab.white_light_interferometer(label="w")
        lab.touch_probe(cut_part, label="p")
        lab.laser_interferometer(label="l")
        return lab.reveal_instruments()

    full = drawn(Realism.lab())
    for name in Realism.names():
        variant = drawn(Realism.lab().without(name))
        for instrument, imperfections in variant.items():
            for key, value in imperfections.items():
                reference = full[instrument][key]
                if isinstance(value, Registration):
                    assert np.array_equal(value.offset, reference.offset)
                    assert value.rotation == reference.rotation
                elif isinstance(value, Lobing):
                    assert value.harmonics == reference.harmonics
                elif isinstance(value, ZonalForm):
                    assert np.array_equal(value.amplitudes, reference.amplitudes)
                else:
                    assert np.array_equal(value, reference)
    assert set(full["microscope/m"]) == {"registration"}
    assert set(full["touch_probe/p"]) == {"pretravel", "ball_form"}
    assert set(drawn(Realism.lab().without("registration"))["microscope/m"]) == set()

    # the height noise: (noise + registration) - registration == noise - exact, exactly
    def z(realism):
        lab = Lab("robonano_a0ib", TRUTH, seed=9, realism=realism)
        scope = lab.microscope(label="m", resolution=0.0)
        return scope.profile(cut_part, (5e-3, 0.5e-3), (5e-3, 1.5e-3)).z

    with_registration = z(Realism.with_only("instrument_noise", "registration")) - z(
        Realism.with_only("registration"))
    alone = z(Realism.noise_only()) - z(Realism.ideal())
    np.testing.assert_allclose(with_registration, alone, rtol=0, atol=ROUND_OFF_M)

