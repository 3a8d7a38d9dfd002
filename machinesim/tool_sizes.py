"""What a tool may be: its default height and the bounds on its sizes, angles and polygons.

A tool smaller than the cutting engine resolves (`MIN_TOOL_SIZE_M`), larger than the
machines (`MAX_TOOL_SIZE_M`), with an included angle outside (0, 180) deg, or a polygon of
more than `MAX_TOOL_VERTICES` vertices is an input error: the tools of `machinesim.tools`
and `machinesim.end_mills` check themselves with these as they are made, and a refusal is
an `InputError` naming the parameter, the value, and the bound with why it is there.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from machinesim.exceptions import InputError, brief
from machinesim.units import M_PER_MM, angle_text, length_text

#: Default length of a tool's body from its edge point to the holder (m). Ten times the
#: deepest cut of the shipped examples and seed experiments (grooves and face passes of tens
#: of um, the 5 mm deep grooves of the tests stay below it) and of the order of a diamond
#: tool's overhang from its holder. The engine clips every sweep just above the stock, so a
#: tall body costs nothing where it does not reach the stock.
TOOL_HEIGHT_M = 10e-3
#: Largest tool dimension accepted (m): radius, height, or the width of the flanks' top.
#: The shipped machines travel at most 0.5 m (+-250 mm), so a larger tool is a unit mix-up
#: (``ball:1e9`` is a kilometre-wide ball); tessellating it within the nm chord tolerances
#: would need billions of vertices (that spec crashed manifold3d before this bound).
MAX_TOOL_SIZE_M = 1.0
#: Smallest tool dimension accepted (m): radius, height, shank radius. The engine's booleans
#: (manifold3d) merge what lies within 1e-12 of a solid's largest coordinate
#: (``Manifold.get_tolerance``: 1e-14 m on a 10 mm block), and a tool is cut right only from
#: about 100 times that. Measured with models/examples/grooves.nc on mill3 and a 10x10x2 mm
#: block: a ball of 1e-12 m radius removes its hand-derived 1.6e-18 m^3, one of 1e-13 m 3 %
#: less, one of 2e-14 m 50 times more, one of 1e-14 m nothing ("does it reach the
#: stock?"). 1e-9 m is 100 times that tolerance on a part 10 m across (the largest travel
#: a machine file may give, `machinesim.urdf_checks.MAX_TRAVEL_M`), and the machines' 1 nm axis
#: resolution (`CHORD_TOLERANCE_M`): no real tool is that small.
MIN_TOOL_SIZE_M = 1e-9
#: Most vertices of a tool polygon or polyhedron: about 10 MB of float64 points per pose
#: pair in the engine, far above the defaults (a R2 mm ball at 1 um has ~5,000, a R2 mm
#: nose at 1 nm ~900). A finer request is refused with advice to loosen ``chord_tol``.
MAX_TOOL_VERTICES = 200_000

#: Why the size bounds are what they are, as refusals say it.
_MAX_WHY = ("MAX_TOOL_SIZE_M: larger than any machine's travel, and too many polygon vertices "
            "at the nm chord tolerance")
_MIN_WHY = ("MIN_TOOL_SIZE_M: 100 times the tolerance of the cutting engine's booleans on a "
            "part as large as a machine's travel, below which a tool removes nothing or a "
            "wrong volume")
_MIN_SHORT = "MIN_TOOL_SIZE_M, below which a tool removes nothing or a wrong volume"


def _bound(value: float, why: str) -> str:
    """A size bound as messages show it, with its name and why: ``1e-06 mm (1e-09 m,
    MIN_TOOL_SIZE_M: ...)``."""
    return f"{value / M_PER_MM:g} mm ({value:g} m, {why})"


def _real(name: str, value, unit: str) -> float:
    """``value`` as a float if it is a number, else InputError naming it: a size given as
    text ("1") ended in a TypeError deep in the mesh, an array (even of one number) in
    "unhashable type", and True was read as 1 (1 m, 1 rad)."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        spec = ("; a tool written as text, in mm and deg, is read by tool_from_spec "
                "('flat:1.0', 'v:90')" if isinstance(value, str) else "")
        raise InputError(f"{name} must be a number in {unit}, got {brief(repr(value))} "
                         f"({type(value).__name__}){spec}", key=name)
    return float(value)


def _check_positive(name: str, value: float) -> float:
    value = _real(name, value, "m")
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"{name} must be a positive finite number, got {length_text(value)}",
                         key=name)
    return value


def _check_shank(value: float) -> None:
    """A shank radius: 0 (as wide as the tool) or a size (`_check_size`)."""
    if value != 0.0:
        _check_size("shank_radius", value)


def _check_size(name: str, value: float) -> float:
    """A length from `MIN_TOOL_SIZE_M` to `MAX_TOOL_SIZE_M`, else InputError naming it."""
    value = _check_positive(name, value)
    if value > MAX_TOOL_SIZE_M:
        raise InputError(
            f"{name} must be at most {_bound(MAX_TOOL_SIZE_M, _MAX_WHY)}, got "
            f"{length_text(value)}",
            key=name,
        )
    if value < MIN_TOOL_SIZE_M:
        raise InputError(
            f"{name} must be at least {_bound(MIN_TOOL_SIZE_M, _MIN_WHY)}, got "
            f"{length_text(value)}",
            key=name,
        )
    return value


def _check_angle(name: str, value: float) -> float:
    value = _real(name, value, "rad")
    if not math.isfinite(value) or not 0.0 < value < math.pi:
        raise InputError(
            f"{name} must lie between 0 and 180 deg (0 and pi rad), got {angle_text(value)}",
            key=name,
        )
    return value


def _check_count(what: str, count: int, chord_tol: float) -> None:
    if count > MAX_TOOL_VERTICES:
        raise InputError(
            f"the {what} would have {count:,} vertices at chord_tol {chord_tol!r} m, over "
            f"MAX_TOOL_VERTICES ({MAX_TOOL_VERTICES:,}); give a larger chord_tol",
            key="chord_tol",
        )
