"""The injected errors of a machine, as immutable values, read from and written to TOML.

Five families, machine-independent (the kinematics decides which symbols an axis can carry):

- tool setting error (`ToolSetting`), in the ``tool_mount`` frame;
- tool geometry error (`ToolGeometry`): the nose radius error dR (paper 004), applied by the
  cutting engines to the tool's shape;
- workpiece setting error (`WorkpieceSetting`, paper 002);
- location errors of an axis, position independent, ISO 230-1/-7 symbols ``E<d>0<axis>``
  (``EX0C``, ``EB0C``, squareness ``EC0Y``);
- component errors of an axis, position dependent, symbols ``E<d><axis>`` (``EXX``, ``EYX``,
  ``ECC``), each a table or a polynomial of the axis position (`ComponentError`).

In a symbol, ``d`` in X Y Z is a translation along that machine direction (a length), ``d`` in
A B C a rotation about X Y Z (an angle). SI inside (m, rad); units appear only in TOML keys.

TOML layout (every key carries its unit: m mm um nm, rad mrad urad deg arcsec)::

    [tool]           # offset_<length unit> = [x, y, z], rotation_<angle unit> = [a, b, c]
    [tool_geometry]  # nose_radius_<length unit> = dR
    [workpiece]      # delta_<length unit> = [x, y, z], alpha_/beta_/gamma_<angle unit> = v
    [location.C]     # <SYM>_<unit> = value, e.g. EX0C_um = 2.0
    [component.X]    # position_<unit> = [...], shared by the tables of the axis;
                     # <SYM>_<unit> = [...] a table, values at those positions;
                     # <SYM>_poly_<valueunit>_<positionunit> = [c0, c1, ...] a polynomial,
                     # value = sum c_k (x / positionunit)**k in valueunit

`ErrorModel.to_toml` writes lengths in um, angles in urad, positions of linear axes in mm and
of rotary axes in deg (polynomials in um or urad per mm**k or deg**k).
`ErrorModel.to_dict` gives the same structure in m and rad, so that it round trips exactly.
Every value read must be finite, an angle at most 180 deg and a length at most 1 m either way
(`LARGEST_ERROR`: beyond that it is another setting, not an error of one); a table's
positions must lie within the machine's travel of its axis, and a polynomial (of at most
`MAX_POLY_COEFFICIENTS`, 1000, coefficients) must stay within the same bound over that
travel (`ErrorModel.check_travel`, when the model meets a machine). A model read from a
file keeps the file's name, its keys as written and the line of each (`ErrorModel.source`,
`ErrorModel.written`, `ErrorModel.lines`), so a refusal of a key names the file, the key's
line and the key (``F.toml, line 3, key 'tool.offset_um': ...``; an array spanning lines
is the line of its key), whether found as the file is read or when the model meets a
machine (`ErrorModel.misfit`), from Python as from the command line; a TOML file may start
with a UTF-8 byte order mark.
"""

from machinesim._submodules import submodule
from machinesim.errors._checks import AXES, LARGEST_ERROR, LINEAR_AXES
from machinesim.errors.families import (
    MAX_POLY_COEFFICIENTS,
    ComponentError,
    ToolGeometry,
    ToolSetting,
    WorkpieceSetting,
)
from machinesim.errors.model import ErrorModel, as_error_model

__all__ = [
    "AXES",
    "LARGEST_ERROR",
    "LINEAR_AXES",
    "MAX_POLY_COEFFICIENTS",
    "ComponentError",
    "ErrorModel",
    "ToolGeometry",
    "ToolSetting",
    "WorkpieceSetting",
    "as_error_model",
]


def __getattr__(name: str):
    # machinesim.errors.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
