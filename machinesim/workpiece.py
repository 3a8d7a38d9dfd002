"""Stock: the solids a cut starts from, made by size (m) or from a text spec (mm).

The solid itself, `Part` (an immutable float64 manifold3d solid in the workpiece frame),
its mesh volume and its files live in `machinesim.part`, re-exported here.

Stock conventions (workpiece frame, metres): a block L x W x H occupies x in [0, L],
y in [0, W], z in [-H, 0]; a cylinder has its axis on Z through the origin and its top face
at z = 0. A placement translates either. Specs are in mm: ``"block:10x10x2"``,
``"cylinder:5x2"`` (radius x height), ``"block:10x10x2@-5,-5,0"``,
``"spheres:30x30x5:2"`` (block with three reference spheres of radius 2 mm, seed 002 Fig. 4)
and ``"crown"`` (seed 002's roughly machined diamond crown, 10 um oversize).
"""

from __future__ import annotations

import math
import numbers

import manifold3d
import numpy as np

from machinesim.exceptions import InputError, brief
from machinesim.part import (  # re-exported; _unpickle_part so older pickles still load
    EXPORT_UNITS,
    VOLUME_CHUNK,  # noqa: F401
    Part,
    _unpickle_part,  # noqa: F401
    mesh_volume,  # noqa: F401
)
from machinesim.tolerances import CYLINDER_CHORD_M, SPHERE_CHORD_M
from machinesim.tools import arc_segments, sphere_polygon
from machinesim.units import M_PER_MM, M_PER_UM, length_text, typed_float


def _sizes(kind: str, form: str, **sizes) -> list[float]:
    """A solid's sizes (m) as floats, refusing what is no number, naming it: cylinder("5", 2)
    ended in "TypeError: must be real number, not str", and True read as 1 m. ``form`` is the
    stock spec of the solid, which takes its sizes in mm as text."""
    values = []
    for name, value in sizes.items():
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
            value = value.item()
        if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
            spec = (f"; a size written as text, in mm, is read by stock_from_spec('{form}')"
                    if isinstance(value, str) else "")
            raise InputError(f"{kind} {name} must be a number in m, got {brief(repr(value))} "
                             f"({type(value).__name__}){spec}", key=name)
        values.append(float(value))
    return values


def block(length: float, width: float, height: float, origin=(0.0, 0.0, 0.0)) -> Part:
    """Block occupying [0, L] x [0, W] x [-H, 0] (m), translated by ``origin`` (m)."""
    length, width, height = _sizes("block", "block:LxWxH", length=length, width=width,
                                   height=height)
    for name, value in (("length", length), ("width", width), ("height", height)):
        if not math.isfinite(value) or value <= 0.0:
            raise InputError(f"block {name} must be positive, got {length_text(value)}",
                             key=name)
    solid = manifold3d.Manifold.cube((length, width, height)).translate((0.0, 0.0, -height))
    return Part(solid.translate(tuple(float(v) for v in origin)))


def cylinder(radius: float, height: float, origin=(0.0, 0.0, 0.0),
             chord_tol: float = CYLINDER_CHORD_M) -> Part:
    """Cylinder about Z through ``origin``, top face at z = origin z, radius and height in m.

    The circle is an inscribed polygon whose sagitta is at most ``chord_tol`` (m).
    """
    radius, height = _sizes("cylinder", "cylinder:RxH", radius=radius, height=height)
    for name, value in (("radius", radius), ("height", height)):
        if not math.isfinite(value) or value <= 0.0:
            raise InputError(f"cylinder {name} must be positive, got {length_text(value)}",
                             key=name)
    segments = arc_segments(radius, 2.0 * math.pi, chord_tol)
    solid = manifold3d.Manifold.cylinder(height, radius, radius, segments)
    return Part(solid.translate((float(origin[0]), float(origin[1]), float(origin[2]) - height)))


def block_with_spheres(length: float, width: float, height: float, radius: float,
                       centres=None, dimples: bool = False,
                       chord_tol: float = SPHERE_CHORD_M) -> Part:
    """Block with three reference spheres on its top face (seed 002, Fig. 4), all in m.

    Parameters
    ----------
    length, width, height : float
        Block size; the block occupies [0, L] x [0, W] x [-H, 0].
    radius : float
        Sphere radius.
    centres : array-like, shape (3, 2), optional
        (x, y) of the sphere centres S1, S2, S3 on the plane z = 0. Default: three corners,
        2 R in from the edges, so that S1->S2 runs along +X and S1->S3 along +Y (the
        workpiece axes of seed 002, Fig. 5a).
    dimples : bool
        False: hemispherical bumps above the top face. True: hemispherical cavities (seed
        002 cuts its spheres with a ball end mill and finds the centre above the bottom point,
        which fits a cavity).
    chord_tol : float
        Largest facet depth of the sphere polygon.
    """
    radius, = _sizes("sphere", "spheres:LxWxH:R", radius=radius)
    stock = block(length, width, height).manifold
    if radius <= 0.0 or 4.0 * radius >= min(length, width):
        raise InputError(
            f"sphere radius must be positive and below a quarter of the block's smaller side, "
            f"{length_text(min(length, width) / 4)}, got {length_text(radius)}",
            key="radius",
        )
    if centres is None:
        inset = 2.0 * radius
        centres = [(inset, inset), (length - inset, inset), (inset, width - inset)]
    centres = np.asarray(centres, dtype=np.float64)
    if centres.shape != (3, 2):
        raise InputError(f"expected three (x, y) sphere centres, got shape {centres.shape}")
    sphere = sphere_polygon(radius, chord_tol)
    spheres = manifold3d.Manifold.batch_boolean(
        [sphere.translate((float(x), float(y), 0.0)) for x, y in centres], manifold3d.OpType.Add
    )
    return Part(stock - spheres if dimples else stock + spheres)


def diamond_crown(oversize: float = 10.0 * M_PER_UM, top_across_flats: float = 4.0 * M_PER_MM,
                  crown_height: float = 0.2 * M_PER_MM, base_size: float = 10.0 * M_PER_MM,
                  base_height: float = 3.0 * M_PER_MM,
                  slope: float = math.atan(0.2)) -> Part:
    """Seed 002's diamond crown (section 3.2), roughly machined ``oversize`` larger (m, rad).

    Fig. 9 of the paper is missing; these dimensions follow its text: one top face and
    eight side faces sloped at 11.31 deg (tan = 0.2, ``slope``) facing C = 0, 45, ..., 315
    deg, opposite edges parallel in pairs (L1/L5 ... L4/L8). The target is a regular
    octagonal frustum, top face 4 mm across flats at z = 0, 0.2 mm high (so each side face
    runs 1 mm horizontally, one laser-microscope field), standing on a flat at z = -0.2 mm
    of a 10 x 10 mm base, 3 mm thick, centred on the C axis (x = y = 0). The rough part is
    that shape with every machined face (top, eight sides, flat) moved out by ``oversize``
    along its normal; the finishing cut then removes ``oversize`` (seed 002 Table 2: 10 um).
    """
    normal_xy = math.sin(slope)
    normal_z = math.cos(slope)
    top_z = oversize
    flat_z = -crown_height + oversize
    bottom_z = -crown_height - base_height
    # Side plane k: normal (sin(slope) u_k, cos(slope)) . p = apothem_top * sin(slope) + d.
    offset = 0.5 * top_across_flats * normal_xy + oversize

    def apothem(z: float) -> float:
        return (offset - z * normal_z) / normal_xy

    corners = []
    # The frustum reaches half its height into the base so the union meets it in clean lines.
    for z in (top_z, flat_z - 0.5 * crown_height):
        circum = apothem(z) / math.cos(math.pi / 8.0)
        for k in range(8):
            angle = (k + 0.5) * math.pi / 4.0
            corners.append((circum * math.cos(angle), circum * math.sin(angle), z))
    frustum = manifold3d.Manifold.hull_points(np.array(corners))
    base = manifold3d.Manifold.cube((base_size, base_size, flat_z - bottom_z), center=True)
    base = base.translate((0.0, 0.0, 0.5 * (flat_z + bottom_z)))
    return Part(base + frustum)


_STOCK_FORMS = (
    "'block:LxWxH', 'cylinder:RxH', 'spheres:LxWxH:R', 'spheres:LxWxH:R:dimples', "
    "'crown' or 'crown:OVERSIZE' (mm), each optionally followed by '@x,y,z' (mm); a number "
    "may end in 'mm' ('block:10x10x2mm')"
)


#: Range of a size in a stock spec (mm): from 1 nm (below it float64 squares of the size
#: underflow: a cylinder of radius 1e-200 mm has volume 0) to 10 m, twenty times the largest
#: machine travel (beyond it a 1 nm chord polygon needs billions of vertices). Placements
#: stay within +-10 m too: 1e300 + 1 == 1e300 would swallow the part's own size.
STOCK_SIZE_MM = (1e-6, 1e4)


def _numbers(where: str, text: str, count: int, separator: str,
             sizes: bool = True) -> list[float]:
    """``count`` numbers of ``text`` between ``separator``s; ``where`` (the spec as the
    caller names it) begins a refusal."""
    # a number may end in mm, as every size of a tool spec may ('block:10x10x2mm')
    fields = [f.strip()[:-2] if f.strip().lower().endswith("mm") else f
              for f in text.split(separator)]
    try:
        values = [typed_float(field) for field in fields]
    except ValueError:
        _other_unit(where, fields)
        values = []
    if len(values) != count:
        raise InputError(
            f"{where}: expected {count} numbers separated by {separator!r} in "
            f"{text!r}; forms: {_STOCK_FORMS}")
    unbounded = [field.strip() for field, v in zip(fields, values, strict=True)
                 if not math.isfinite(v)]
    if unbounded:  # '1e400' reads as inf: it is a number, just not a finite one
        raise InputError(f"{where}: {unbounded[0]!r} in {text!r} is not a finite number of mm")
    low, high = STOCK_SIZE_MM
    if sizes and not all(low <= v <= high for v in values):
        raise InputError(f"{where}: sizes {text!r} must lie in {low:g} .. {high:g} mm")
    if not sizes and not all(abs(v) <= high for v in values):
        raise InputError(f"{where}: placement {text!r} must lie within +-{high:g} mm")
    return values


#: Units a stock spec's number may be written in by mistake (its numbers are mm), and their mm.
_OTHER_UNITS_MM = {"in": 25.4, '"': 25.4, "inch": 25.4, "cm": 10.0, "um": 1e-3, "m": 1e3}
_UNIT_SHOWN = {'"': "in", "inch": "in"}


def _other_unit(where: str, fields: list[str]) -> None:
    """Refuse the first of ``fields`` that is a number in another unit (`_OTHER_UNITS_MM`,
    ``0.08in``), saying what it is in mm: such a field was refused as 'expected 3 numbers',
    not as the unit it is."""
    for field in fields:
        text = field.strip()
        for unit, mm in _OTHER_UNITS_MM.items():
            if not text.lower().endswith(unit):
                continue
            try:
                value = float(text[:-len(unit)])
            except ValueError:
                continue
            raise InputError(f"{where}: {text!r} is not in mm: a stock spec's numbers are mm "
                             f"(and may end in 'mm'); {value:g} {_UNIT_SHOWN.get(unit, unit)} is "
                             f"{value * mm:g} mm")


def stock_from_spec(spec: str, *, name: str = "stock spec") -> Part:
    """Build stock from a text spec in mm (see the module docstring for the forms).

    ``name`` is what a refusal calls the spec: ``"--stock"`` on the command line, so that
    it reads ``--stock 'block:10x10': expected 3 numbers ...``.

    Raises
    ------
    InputError
        Naming the spec once and the expected forms when it cannot be read.
    """
    where = f"{name} {brief(str(spec))!r}"
    text = str(spec).strip()
    body, at, placement = text.partition("@")
    # an '@' with nothing after it (a shell's '@$POS' with POS unset) is refused, not read
    # as no placement: the stock would stand at the origin where it was meant elsewhere
    origin = (
        [v * M_PER_MM for v in _numbers(where, placement, 3, ",", sizes=False)] if at
        else [0.0] * 3
    )
    fields = body.split(":")
    kind = fields[0].lower()
    try:
        if kind == "block" and len(fields) == 2:
            size = [v * M_PER_MM for v in _numbers(where, fields[1], 3, "x")]
            return block(*size, origin=origin)
        if kind == "cylinder" and len(fields) == 2:
            radius, height = (v * M_PER_MM for v in _numbers(where, fields[1], 2, "x"))
            return cylinder(radius, height, origin=origin)
        if kind == "spheres" and len(fields) in (3, 4):
            size = [v * M_PER_MM for v in _numbers(where, fields[1], 3, "x")]
            radius = _numbers(where, fields[2], 1, ",")[0] * M_PER_MM
            if len(fields) == 4 and fields[3].lower() != "dimples":
                raise InputError(f"{where}: expected 'dimples', got {fields[3]!r}")
            part = block_with_spheres(*size, radius, dimples=len(fields) == 4)
            return Part(part.manifold.translate(tuple(origin)))
        if kind == "crown" and len(fields) in (1, 2):
            oversize = (
                _numbers(where, fields[1], 1, ",", sizes=False)[0] * M_PER_MM
                if len(fields) == 2 else 10.0 * M_PER_UM
            )
            if not 0.0 <= oversize <= 1.0 * M_PER_MM:
                raise InputError(f"{where}: crown oversize must lie in 0 .. 1 mm, "
                                 f"got {length_text(oversize)}")
            return Part(diamond_crown(oversize).manifold.translate(tuple(origin)))
    except InputError as error:
        if error.message.startswith(where):
            raise
        # a size the solid refuses names itself (radius, ...): not again as a key
        raise InputError(f"{where}: {error.message}") from None
    raise InputError(f"{where}: expected {_STOCK_FORMS}")


__all__ = [
    "CYLINDER_CHORD_M",
    "EXPORT_UNITS",
    "STOCK_SIZE_MM",
    "SPHERE_CHORD_M",
    "Part",
    "block",
    "block_with_spheres",
    "cylinder",
    "diamond_crown",
    "stock_from_spec",
]
