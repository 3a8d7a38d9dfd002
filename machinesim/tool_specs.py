"""Tools from text specs in mm and degrees (``"v:90"``, ``"flat:0.5:h=3:d=4"``,
``"ball:0.5mm"``), as the command line, the tool tables and the Python API take them
(`tool_from_spec`)."""

from __future__ import annotations

import functools
import math
import warnings

from machinesim.end_mills import ball_rings
from machinesim.exceptions import InputError, MachineSimWarning, brief
from machinesim.part import UNIT_SLIP_SIZE_M
from machinesim.tolerances import BALL_CHORD_M
from machinesim.tool_sizes import MAX_TOOL_SIZE_M
from machinesim.tools import BallEndMill, FlatEndMill, RoundNoseTool, Tool, VTool
from machinesim.units import M_PER_MM, RAD_PER_DEG, typed_float

_SPEC_FORMS = ("'v:ANGLE_DEG', 'nose:RADIUS_MM:ANGLE_DEG', 'ball:RADIUS_MM' or "
               "'flat:RADIUS_MM', optionally "
               "followed by ':h=HEIGHT_MM' (e.g. 'v:90:h=5'), and for ball and flat by "
               "':d=SHANK_DIAMETER_MM' (e.g. 'flat:0.5:h=3:d=4'); a size may end in 'mm' "
               "and an angle in 'deg' ('ball:0.5mm', 'v:90deg')")
#: The numbers after each kind: what each is and its unit (mm for a size, deg for an angle).
_SPEC_VALUES = {"v": (("an included angle", "deg"),),
                "nose": (("a nose radius", "mm"), ("an included angle", "deg")),
                "ball": (("a radius", "mm"),), "flat": (("a radius", "mm"),)}
#: The trailing fields of a spec: the letter, the keyword it sets, what it is, and how a
#: value in mm becomes it (m).
_SPEC_FIELDS = {"h": ("height", "a height", "h=HEIGHT_MM", M_PER_MM),
                "d": ("shank_radius", "a shank diameter", "d=SHANK_DIAMETER_MM",
                      0.5 * M_PER_MM)}


def _spec_field(where: str, field: str, spec: str) -> tuple[str, float]:
    """The keyword and value (m) of a spec's ``h=HEIGHT_MM`` or ``d=SHANK_DIAMETER_MM`` field
    (a trailing ``mm`` is allowed); ``where`` begins a refusal (`tool_from_spec`)."""
    name, what, form, scale = _SPEC_FIELDS[field.strip()[0].lower()]
    return name, _spec_number(where, field.strip()[2:], what, "mm",
                              f"'{form}', e.g. '{form[0]}=5'", spec, field) * scale


def _spec_number(where: str, text: str, what: str, unit: str, form: str, spec: str,
                 field: str | None = None) -> float:
    """A spec's number in ``unit`` (mm or deg), which it may end in (``0.5mm``, ``90 deg``,
    as ``h=20mm`` always could); ``form`` shows the field in a refusal, ``spec`` corrected
    for a decimal comma, ``field`` the whole field (``h=...``) when ``text`` is its value."""
    text = text.strip()
    number = text[:-len(unit)] if text.lower().endswith(unit) else text
    try:
        return typed_float(number)
    except ValueError:
        pass
    shown = repr(field if field is not None else text)
    if "," in text:  # '0,5' as a German or French keyboard writes a half
        raise InputError(f"{where}: {shown} is not a number: the decimal mark is a point, e.g. "
                         f"{spec.strip().replace(',', '.')!r}") from None
    raise InputError(f"{where}: {shown} is not {what}; expected {form}: a number in {unit}, "
                     f"which may end in '{unit}'") from None


def tool_from_spec(spec: str, *, name: str = "tool spec") -> Tool:
    """Build a tool from a text spec in mm and degrees.

    Parameters
    ----------
    spec : str
        ``"v:90"`` (included angle, deg), ``"nose:2.0:90"`` (nose radius mm, included angle
        deg), ``"ball:2.0"`` (radius mm) or ``"flat:1.0"`` (a flat end mill, radius mm: 2 mm
        across), optionally followed by ``":h=5"``: the tool's
        height from its edge to the holder in mm (default `TOOL_HEIGHT_M`, 10 mm), and for a
        ball or flat end mill by ``":d=4"``: the diameter of the shank or holder above that
        height, mm, for the holder check (default: as wide as the tool). Every size may end
        in ``mm`` and every angle in ``deg`` (``"ball:0.5mm:h=5mm"``, ``"v:90deg"``). A
        ball's facets lie within `BALL_CHORD_M` (1 um), which keeps it to at most 80.6 mm
        in radius (`MAX_TOOL_VERTICES`); a larger one is a `BallEndMill` built in Python
        with a coarser ``chord_tol``.
    name : str, optional
        What a refusal calls the spec: ``"--tool"`` on the command line, so that it reads
        ``--tool 'ball:-1': radius must be ...``; a caller names the file and key around it.

    Returns
    -------
    VTool or RoundNoseTool or BallEndMill or FlatEndMill

    Raises
    ------
    InputError
        If the spec does not have one of these forms or a number is out of range (sizes,
        the height included, are bounded by `MIN_TOOL_SIZE_M` and `MAX_TOOL_SIZE_M`). The
        message names the spec once, as ``name``, then what in it is wrong: ``tool spec
        'ball:-1': radius must be a positive finite number, got -1 mm (-0.001 m)``.
    """
    where = f"{name} {brief(str(spec))!r}"
    fields = str(spec).strip().split(":")
    extra = {}
    while len(fields) > 1 and fields[-1].strip().lower()[:2] in ("h=", "d="):
        keyword, value = _spec_field(where, fields.pop(), str(spec))
        if keyword in extra:
            raise InputError(f"{where}: {keyword} given twice")
        extra[keyword] = value
    shank = extra.get("shank_radius", 1.0)
    if not shank > 0.0:
        # 0 is the API's "as wide as the tool": 'd=0' read so cut with a shank the user did
        # not give, without a word
        raise InputError(f"{where}: a shank diameter of {2.0 * shank / M_PER_MM:g} mm; "
                         "expected a diameter above 0 mm, or no 'd=' for a shank as wide as "
                         "the tool")
    kind = fields[0].lower()
    arity = {"v": 1, "nose": 2, "ball": 1, "flat": 1}
    if kind not in arity or len(fields) != arity[kind] + 1:
        raise InputError(f"{where}: expected {_SPEC_FORMS}")
    if "shank_radius" in extra and kind not in ("ball", "flat"):
        raise InputError(f"{where}: a shank diameter (d=) is for a ball or flat end "
                         f"mill; a {kind} tool's holder is its own bar")
    values = [_spec_number(where, field, what, unit, f"'{_KIND_FORMS[kind]}'", str(spec))
              for field, (what, unit) in zip(fields[1:], _SPEC_VALUES[kind], strict=True)]
    try:
        tool = _built(kind, values, extra)
    except InputError as error:
        # the tool's own message names its parameter (radius, height, ...): not again as a key
        message = error.message
        if error.key == "shank_radius":
            message = message.replace("shank_radius", "shank_radius (half the d= diameter)", 1)
        if error.key == "chord_tol":  # a ball too large for its facets: a spec sets no chord_tol
            message = (f"{message.split('; give')[0]}. A spec's ball keeps its facets within "
                       f"{BALL_CHORD_M / M_PER_MM * 1e3:g} um and is at most "
                       f"{_largest_ball_mm():g} mm in radius ({values[0]:g} um would be "
                       f"ball:{values[0] / 1e3:g}); a larger ball is built in Python, "
                       "BallEndMill(radius_m, chord_tol=...) with a coarser chord_tol")
        raise InputError(f"{where}: {message}") from None
    _wide_tool_warning(where, kind, values)  # once built: a refused spec is only refused
    return tool


def _built(kind: str, values: list[float], extra: dict[str, float]) -> Tool:
    """The tool of a spec's ``kind``, its ``values`` (mm, deg) and ``extra`` keywords (m)."""
    if kind == "v":
        return VTool(values[0] * RAD_PER_DEG, **extra)
    if kind == "nose":
        return RoundNoseTool(values[0] * M_PER_MM, values[1] * RAD_PER_DEG, **extra)
    if kind == "flat":
        return FlatEndMill(values[0] * M_PER_MM, **extra)
    return BallEndMill(values[0] * M_PER_MM, **extra)


def _wide_tool_warning(where: str, kind: str, values: list[float]) -> None:
    """Warn (`MachineSimWarning`) of a flat end mill or nose whose radius (mm, ``values[0]``)
    makes it `UNIT_SLIP_SIZE_M` (1 m) across or more: perhaps a radius in um. ``flat:500``
    meant as 500 um built a tool 1 m across, which took the whole top off a 10 mm block
    without a word. A warning, not a refusal: sizes up to `MAX_TOOL_SIZE_M` are built (a ball
    that large is refused for its facets, and that refusal says what it would be in um)."""
    if kind not in ("flat", "nose") or not 2.0 * values[0] * M_PER_MM >= UNIT_SLIP_SIZE_M:
        return
    meant = f"{kind}:{values[0] / 1e3:g}" + "".join(f":{v:g}" for v in values[1:])
    what, whole = ("radius", "a tool") if kind == "flat" else ("nose radius", "a nose")
    warnings.warn(
        f"{where}: a {what} of {values[0]:g} mm is {whole} {2.0 * values[0] / 1e3:g} m "
        "across, wider than any shipped machine's travel (0.5 m at most). A spec's sizes are "
        f"mm: if it is in um, {values[0]:g} um is {meant}",
        MachineSimWarning, stacklevel=1)  # here, not the caller's: each message shown once


#: Each kind's form, for a refusal of one of its numbers.
_KIND_FORMS = {"v": "v:ANGLE_DEG", "nose": "nose:RADIUS_MM:ANGLE_DEG", "ball": "ball:RADIUS_MM",
               "flat": "flat:RADIUS_MM"}


@functools.cache
def _largest_ball_mm() -> float:
    """The largest ball radius (mm, 3 digits, rounded down) whose polygon at `BALL_CHORD_M`
    stays within `MAX_TOOL_VERTICES`: what a spec can build."""
    low, high = 1.0, MAX_TOOL_SIZE_M / M_PER_MM  # mm: 1 mm passes, 1 m does not
    for _ in range(60):
        middle = math.sqrt(low * high)
        try:
            ball_rings(middle * M_PER_MM, BALL_CHORD_M)
            low = middle
        except InputError:
            high = middle
    digits = math.floor(math.log10(low)) - 2
    return round(math.floor(low / 10.0**digits) * 10.0**digits, -digits)


__all__ = ["tool_from_spec"]
