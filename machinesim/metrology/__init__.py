"""Virtual instruments reading a machined part (never the injected errors).

The exact, noise-free core: top-surface height maps and profiles (`surface`), and the
contact of a touch-probe ball swept against the part's triangles (`probe`), found through
a tree over them (`meshindex`).
Feature fits on what they read: V grooves (`grooves`), lines, crossings and edges (`lines`),
spheres, planes, form error and Sa (`fits`); x3p files and PNG pictures (`export`).
"""

from __future__ import annotations

from machinesim._submodules import submodule
from machinesim.metrology.export import export_x3p, length_unit, plot_height_map, plot_profile
from machinesim.metrology.fits import (
    FormError,
    PlaneFit,
    SphereFit,
    fit_plane,
    fit_sphere,
    form_error,
    height_map_points,
    plane_angle,
    roughness_sa,
    sphere_centre_from_touch,
)
from machinesim.metrology.grooves import Pitch, VGroove, fit_v_groove, fit_v_grooves, groove_pitch
from machinesim.metrology.instruments import Readout
from machinesim.metrology.interferometer import (
    InterferometerReading,
    LaserInterferometer,
    squareness_from_diagonal,
)
from machinesim.metrology.iso230 import (
    PositioningEvaluation,
    evaluate_positioning,
    iso230_2_targets,
    positioning_test,
    squareness_from_diagonals,
)
from machinesim.metrology.lines import (
    GrooveCrossing,
    Line2D,
    ParallelEdges,
    edge_distance,
    fit_line,
    fit_parallel_edges,
    fit_parallel_lines,
    groove_crossing,
    intersect_lines,
    profile_points,
    step_positions,
)
from machinesim.metrology.meshindex import MeshIndex
from machinesim.metrology.optical import HeightMap, Microscope, Profile, WhiteLightInterferometer
from machinesim.metrology.part_features import (
    CrownFeatures,
    GrooveDepths,
    crown_features,
    groove_depths,
)
from machinesim.metrology.planes import Line3D, line_distance, plane_intersection
from machinesim.metrology.prisms import fit_apexes
from machinesim.metrology.probe import Contact, Contacts, touch, touch_many
from machinesim.metrology.probe_instrument import ScanReading, TouchProbe
from machinesim.metrology.rtest import RTest, RTestReading
from machinesim.metrology.surface import height_map, profile

__all__ = ["Contact", "Contacts", "MeshIndex", "height_map", "profile", "touch", "touch_many"]
__all__ += [
    "HeightMap", "InterferometerReading", "LaserInterferometer", "Microscope", "Profile",
    "Readout", "ScanReading", "TouchProbe", "WhiteLightInterferometer", "squareness_from_diagonal",
]
__all__ += [
    "FormError", "GrooveCrossing", "Line2D", "ParallelEdges", "Pitch", "PlaneFit", "SphereFit",
    "VGroove", "edge_distance", "export_x3p", "fit_line", "fit_parallel_edges",
    "fit_parallel_lines", "fit_plane",
    "fit_sphere", "fit_v_groove", "fit_v_grooves", "form_error", "groove_crossing", "groove_pitch",
    "height_map_points", "intersect_lines", "length_unit", "plane_angle", "plot_height_map",
    "plot_profile", "profile_points", "roughness_sa", "sphere_centre_from_touch", "step_positions",
]
__all__ += ["RTest", "RTestReading", "fit_apexes"]
__all__ += ["PositioningEvaluation", "evaluate_positioning", "iso230_2_targets",
            "positioning_test", "squareness_from_diagonals"]
__all__ += ["CrownFeatures", "GrooveDepths", "Line3D", "crown_features", "groove_depths",
            "line_distance", "plane_intersection"]


def __getattr__(name: str):
    # machinesim.metrology.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
