"""Tools from text specs in mm and degrees (``"v:90"``, ``"flat:0.5:h=3:d=4"``), as the
command line, the tool tables and the Python API take them (`tool_from_spec`)."""

from __future__ import annotations

from machinesim.exceptions import InputError, brief
from machinesim.tools import BallEndMill, FlatEndMill, RoundNoseTool, Tool, VTool
from machinesim.units import M_PER_MM, RAD_PER_DEG

_SPEC_FORMS = ("'v:ANGLE_DEG', 'nose:RADIUS_MM:ANGLE_DEG', 'ball:RADIUS_MM' or "
               "'flat:RADIUS_MM', optionally "
               "followed by ':h=HEIGHT_MM' (e.g. 'v:90:h=5'), and for ball and flat by "
               "':d=SHANK_DIAMETER_MM' (e.g. 'flat:0.5:h=3:d=4')")
#: The trailing fields of a spec: the letter, the keyword it sets, what it is, and how a
#: value in mm becomes it (m).
_SPEC_FIELDS = {"h": ("height", "a height", "h=HEIGHT_MM", M_PER_MM),
                "d": ("shank_radius", "a shank diameter", "d=SHANK_DIAMETER_MM",
                      0.5 * M_PER_MM)}


def _spec_field(where: str, field: str) -> tuple[str, float]:
    """The keyword and value (m) of a spec's ``h=HEIGHT_MM`` or ``d=SHANK_DIAMETER_MM`` field
    (a trailing ``mm`` is allowed); ``where`` begins a refusal (`tool_from_spec`)."""
    name, what, form, scale = _SPEC_FIELDS[field.strip()[0].lower()]
    text = field.strip()[2:].strip()
    if text.lower().endswith("mm"):
        text = text[:-2]
    try:
        return name, float(text) * scale
    except ValueError:
        raise InputError(f"{where}: {field!r} is not {what}; expected "
                         f"'{form}' with a number in mm, e.g. '{form[0]}=5'") from None


def tool_from_spec(spec: str, *, name: str = "tool spec") -> Tool:
    """Build a tool from a text spec in mm and degrees.

    Parameters
    ----------
    spec : str
        ``"v:90"`` (included angle, deg), ``"nose:2.0:90"`` (nose radius mm, included angle
        deg), ``"ball:2.0"`` (radius mm) or ``"flat:1.0"`` (a flat end mill, radius mm: 2 mm
        across), optionally followed by ``":h=5"``: the tool's
        height from its edge to the holder in mm (default `TOOL_HEIGHT_M`, 10 mm; ``"h=5mm"``
        reads the same), and for a ball or flat end mill by ``":d=4"``: the diameter of the
        shank or holder above that height, mm, for the holder check (default: as wide as
        the tool).
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
        keyword, value = _spec_field(where, fields.pop())
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
    try:
        values = [float(field) for field in fields[1:]]
    except ValueError:
        if any("," in field for field in fields[1:]):
            # '0,5' as a German or French keyboard writes a half
            raise InputError(f"{where}: {next(f for f in fields[1:] if ',' in f)!r} is not a "
                             "number: the decimal mark is a point, e.g. "
                             f"{str(spec).strip().replace(',', '.')!r}") from None
        raise InputError(f"{where}: expected numbers after the kind, as in {_SPEC_FORMS}"
                         ) from None
    try:
        if kind == "v":
            return VTool(values[0] * RAD_PER_DEG, **extra)
        if kind == "nose":
            return RoundNoseTool(values[0] * M_PER_MM, values[1] * RAD_PER_DEG, **extra)
        if kind == "flat":
            return FlatEndMill(values[0] * M_PER_MM, **extra)
        return BallEndMill(values[0] * M_PER_MM, **extra)
    except InputError as error:
        # the tool's own message names its parameter (radius, height, ...): not again as a key
        message = error.message
        if error.key == "shank_radius":
            message = message.replace("shank_radius", "shank_radius (half the d= diameter)", 1)
        raise InputError(f"{where}: {message}") from None


__all__ = ["tool_from_spec"]
