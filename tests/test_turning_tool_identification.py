"""dx, |dy| and dR read back from the height map of a sphere turned with them (engine-cut;
the identification sees only the map and the design)."""

import numpy as np
import pytest

import machinesim.cam.spiral as sp
from machinesim.cutting.turning import EdgePath, turned_surface
from machinesim.exceptions import InputError
from machinesim.identification.turning_tool import identify_tool_errors

RS, FEED, RADIUS, R = 0.5e-3, 1e-6, 0.12e-3, 0.2e-3
DESIGN = sp.sphere(RS)


def test_tool_errors_from_a_turned_sphere():
    dx, dy, dr = 0.8e-6, -3e-6, 15e-6
    shift = (4e-6, -2.5e-6)  # where the spindle axis lies in the measurement's coordinates
    spiral = sp.Spiral(RADIUS, FEED)
    tp = sp.tool_path(sp.cutting_points(DESIGN, spiral, sp.constant_angle(spiral, 0.02)), R)
    x = np.linspace(-0.1e-3, 0.1e-3, 201) + 0.3e-6
    heights = turned_surface(EdgePath(tp.c, tp.x + dx, dy, tp.z), R + dr, x, x, top=1e-6)
    found = identify_tool_errors(DESIGN, x + shift[0], x + shift[1], heights,
                                 core_step=50e-9, aperture=0.1e-3)
    # bias from the scallops (<= f_c^2 / 8R ~ 1.2 nm) over the sensitivities rho / Rs (dx) and
    # rho^2 / 2 Rs^2 (dR) at rho ~ 0.1 mm: ~ 6 nm and ~ 0.1 um
    assert found.dx == pytest.approx(dx, abs=10e-9)
    assert found.d_radius == pytest.approx(dr, abs=0.1e-6)
    assert found.dy_abs == pytest.approx(abs(dy), abs=1e-6)  # the map's pixel
    assert found.centre == pytest.approx(shift, abs=20e-9)
    assert found.residual_rms < 1.5e-9


def test_bad_map_is_named():
    x = np.linspace(-1e-4, 1e-4, 5)
    with pytest.raises(InputError, match="heights"):
        identify_tool_errors(DESIGN, x, x, np.zeros((4, 5)), core_step=5e-8, aperture=1e-4)


def test_a_sphere_cut_deeper_than_programmed_reads_the_same_tool_errors():
    """Table 5's tool (dx = dy = -3.5 um, dR = 100 um) on paper 004's test sphere (Rs 2 mm,
    nose 0.5 mm), cut as programmed and 4 um deeper (a workpiece set 4 um high): the map is
    the same less 4 um but for the uncut core, and the fit reads the same dx and dR. Started
    from the programmed heights it settled on dR = -1815 um for the deeper one, with a
    residual (0.083 nm) as small as the right one's."""
    design = sp.sphere(2e-3)
    spiral = sp.Spiral(0.12e-3, FEED)
    tp = sp.tool_path(sp.cutting_points(design, spiral, sp.constant_angle(spiral, 0.02)),
                      0.5e-3)
    x = np.linspace(-0.1e-3, 0.1e-3, 401)
    found = [identify_tool_errors(design, x, x, turned_surface(
        EdgePath(tp.c, tp.x - 3.5e-6, -3.5e-6, tp.z - depth), 0.6e-3, x, x, top=1e-6),
        core_step=50e-9, aperture=0.1e-3) for depth in (0.0, 4e-6)]
    assert found[0].d_radius == pytest.approx(100e-6, rel=1e-3)
    assert found[1].d_radius == pytest.approx(found[0].d_radius, abs=1e-12)
    assert found[1].dx == pytest.approx(found[0].dx, abs=1e-12)


@pytest.mark.parametrize("key, value, message", [
    # each of these raised numpy's UFuncTypeError or a TypeError, or was taken: aperture True
    # as 1 m (dx -46.5 um for 0.8), -1e-4 and NaN (no point within it) as dx = dR = 0, core
    # step 0 (every point above the fit a core: dx -60.3 um), NaN as no core at all
    ("aperture", "1e-4", "Expected aperture as a number (m), got '1e-4'"),
    ("aperture", True, "Expected aperture as a number (m), got True"),
    ("aperture", None, "Expected aperture as a number (m), got None"),
    ("aperture", -1e-4, "Expected aperture > 0 (m), got -0.0001"),
    ("aperture", np.nan, "Expected aperture > 0 (m), got nan"),
    ("aperture", 1e-9, "Expected the map to hold at least 5 finite heights within aperture "
                       "1e-09 m of its origin (the fit's unknowns), got 1 of 1681"),
    ("core_step", "5e-8", "Expected core_step as a number (m), got '5e-8'"),
    ("core_step", True, "Expected core_step as a number (m), got True"),
    ("core_step", None, "Expected core_step as a number (m), got None"),
    ("core_step", np.nan, "Expected core_step > 0 (m), got nan"),
    ("core_step", 0.0, "Expected core_step > 0 (m), got 0.0"),
    ("core_step", -5e-8, "Expected core_step > 0 (m), got -5e-08"),
])
def test_an_aperture_or_core_step_that_is_no_length_is_refused_by_name(key, value, message):
    x = np.linspace(-0.1e-3, 0.1e-3, 41)
    spiral = sp.Spiral(RADIUS, FEED)
    tp = sp.tool_path(sp.cutting_points(DESIGN, spiral, sp.constant_angle(spiral, 0.02)), R)
    heights = turned_surface(EdgePath(tp.c, tp.x + 0.8e-6, -3e-6, tp.z), R + 15e-6, x, x,
                             top=1e-6)
    arguments = {"core_step": 50e-9, "aperture": 0.1e-3}
    arguments[key] = value
    with pytest.raises(InputError) as info:
        identify_tool_errors(DESIGN, x, x, heights, **arguments)
    assert info.value.key == key
    assert str(info.value) == f"key {key!r}: {message}"
