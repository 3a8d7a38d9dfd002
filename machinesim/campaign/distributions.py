"""What a campaign varies: ``PARAM=DIST`` texts, parsed into distributions with units.

A distribution is written ``KIND:ARGS`` with every number carrying its unit
(`machinesim.units.FACTORS`: ``m mm um nm rad mrad urad deg arcsec``):

- ``normal:MEAN,STD``, e.g. ``normal:0,5um`` (a zero needs no unit);
- ``uniform:LOW,HIGH``, e.g. ``uniform:-10um,10um``;
- ``fixed:VALUE`` or just ``VALUE``, e.g. ``30um``.

A parameter is an error parameter as `Machine.parameter_names` spells it (``tool.y``,
``workpiece.alpha``, ``location.C.EX0C``) or a lab parameter (`LAB_PARAMETERS`): the loading
robot's repeatability, from which the workpiece setting is drawn
(`machinesim.loading.RobotLoader`), and an instrument's noise ``sigma``; a campaign takes
those its procedure reads (`machinesim.campaign.CampaignSpec.parameters`).

>>> name, dist = parse_vary("tool.y=normal:-178um,5um")
>>> name, dist.kind, round(dist.a * 1e6, 6), round(dist.b * 1e6, 6)
('tool.y', 'normal', -178.0, 5.0)
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError, MachineSimError, brief
from machinesim.units import ANGLE, FACTORS, LENGTH

__all__ = ["Distribution", "INSTRUMENTS", "LAB_PARAMETERS", "checked", "parameter_kind",
           "parse_distribution", "parse_vary", "refuse_beyond_model"]

#: Instruments of a `Lab` whose noise ``sigma`` a campaign can set (``microscope.sigma``).
INSTRUMENTS = ("microscope", "white_light_interferometer", "touch_probe",
               "laser_interferometer", "r_test")
#: Parameters of the lab rather than of the machine's errors, with their kind.
LAB_PARAMETERS = {"robot.repeatability": "length",
                  **{f"{name}.sigma": "length" for name in INSTRUMENTS}}
#: Distribution kinds and how many numbers each takes.
KINDS = {"normal": 2, "uniform": 2, "fixed": 1}

#: A number and what follows it as its unit: any letters (5µm, 5Um), so that a unit not in
#: `FACTORS` is named as such, not as no number at all.
_NUMBER = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\W\d_]*)\s*")


def _shown(text) -> str:
    """A text the user gave, quoted as a message shows it (`brief`): a 100,000-character
    --vary was quoted whole, a line of 100 kB on stderr."""
    return brief(repr(text))


def parameter_kind(name: str, model=None) -> str | None:
    """``"length"``, ``"angle"`` or None (not a parameter name, or none of the two) of a
    parameter name.

    An error's symbol says which (ISO 230-1): ``E`` then the direction, X Y Z a length (a
    positioning, straightness, radial or axial error), A B C an angle; the same for a
    component table's entry ``component.X.EXX[k]``, the error's value at the table's k-th
    position. A polynomial's coefficient k >= 1 is none of the two (per m**k or rad**k,
    `machinesim.errors.ErrorModel.parameter_unit`), and the name does not tell a
    polynomial's from a table's: with ``model`` (an `ErrorModel` holding the error) such a
    coefficient is None, as a DIST has no unit for it; without, the name's
    answer is the table's (it was given for a polynomial's too, so ``normal:0,1um`` read
    as 1e-6 m/m).
    """
    if model is not None and name.startswith("component."):
        unit = model.parameter_unit(name)
        return {"m": "length", "rad": "angle"}.get(unit)
    if name in LAB_PARAMETERS:
        return LAB_PARAMETERS[name]
    if name == "tool_geometry.nose_radius":
        return "length"
    head, _, tail = name.partition(".")
    if head in ("tool", "workpiece"):
        if tail in ("x", "y", "z"):
            return "length"
        return "angle" if tail in ("rx", "ry", "rz", "alpha", "beta", "gamma") else None
    if head in ("location", "component"):
        symbol = tail.partition(".")[2].partition("[")[0]
        if len(symbol) >= 2 and symbol[0] == "E":
            return "length" if symbol[1] in "XYZ" else "angle"
    return None


@dataclass(frozen=True)
class Distribution:
    """One parameter's distribution over the trials, SI.

    Attributes
    ----------
    kind : str
        ``"normal"`` (a = mean, b = standard deviation), ``"uniform"`` (a = low, b = high)
        or ``"fixed"`` (a = the value; b unused, 0).
    a, b : float
        SI (m or rad).
    text : str
        As the user wrote it (for messages and the dataset's attributes).
    """

    kind: str
    a: float
    b: float = 0.0
    text: str = ""

    def draw(self, rng: np.random.Generator) -> float:
        """One value. A fixed value draws nothing, so fixing one parameter changes no other
        parameter's draw (each has its own stream anyway: `machinesim.campaign.trials`)."""
        if self.kind == "normal":
            return float(self.a + self.b * rng.standard_normal())
        if self.kind == "uniform":
            return float(rng.uniform(self.a, self.b))
        return float(self.a)

    @property
    def varies(self) -> bool:
        """True unless fixed."""
        return self.kind != "fixed"


def _number(text: str, where: str) -> tuple[float, str | None]:
    match = _NUMBER.fullmatch(text)
    if match is None:
        raise InputError(f"{_shown(text)} is not a number with a unit; expected e.g. 5um, "
                         "-0.2deg, 0", key=where)
    value, unit = float(match.group(1)), match.group(2) or None
    if unit is not None and unit not in FACTORS:
        raise InputError(f"unit {_shown(unit)} in {_shown(text)}; expected one of "
                         f"{' '.join(FACTORS)}", key=where)
    if not math.isfinite(value):
        raise InputError(f"{_shown(text)} is not a finite number", key=where)
    if unit is None and value != 0.0:
        raise InputError(f"{_shown(text)} has no unit; expected one of {' '.join(FACTORS)} "
                         "(e.g. 5um): only 0 may go without", key=where)
    return value * (FACTORS[unit] if unit else 1.0), unit


def parse_distribution(text: str, name: str = "") -> Distribution:
    """``text`` (``normal:0,5um``, ``uniform:-10um,10um``, ``fixed:30um``, ``30um``) as a
    `Distribution` in SI; ``name``, when given, checks the units' kind against the
    parameter's (`parameter_kind`).

    Raises
    ------
    InputError
        Naming the text and what was expected: an unknown kind, a wrong count of numbers, a
        missing or unknown unit, lengths mixed with angles, a std <= 0, low >= high.
    """
    where = f"--vary {name}={text}" if name else text
    if not isinstance(text, str) or not text.strip():
        raise InputError("empty distribution; expected KIND:ARGS, e.g. normal:0,5um",
                         key=where)
    kind, colon, args = text.strip().partition(":")
    if not colon:
        kind, args = "fixed", text.strip()
    if kind not in KINDS:
        raise InputError(f"distribution {_shown(kind)}; expected one of {', '.join(KINDS)} "
                         "(normal:MEAN,STD, uniform:LOW,HIGH, fixed:VALUE)", key=where)
    parts = args.split(",")
    if len(parts) != KINDS[kind]:
        raise InputError(f"{kind} takes {KINDS[kind]} number(s), got {len(parts)} in "
                         f"{_shown(args)}", key=where)
    values, units = zip(*(_number(p, where) for p in parts), strict=True)
    kinds = {("length" if u in LENGTH else "angle") for u in units if u is not None}
    if len(kinds) > 1:
        raise InputError(f"{_shown(text)} mixes lengths and angles", key=where)
    wanted = parameter_kind(name) if name else None
    if wanted is not None and kinds and kinds != {wanted}:
        raise InputError(f"{name} is {'a length' if wanted == 'length' else 'an angle'}; "
                         f"{_shown(text)} gives "
                         f"{'an angle' if wanted == 'length' else 'a length'} "
                         f"(units: {' '.join(LENGTH if wanted == 'length' else ANGLE)})",
                         key=where)
    a, b = (values[0], values[1]) if len(values) == 2 else (values[0], 0.0)
    if kind == "normal" and not b > 0.0:
        raise InputError(f"normal std {_shown(parts[1].strip())}; expected > 0", key=where)
    if kind == "uniform" and not b > a:
        raise InputError(f"uniform low {_shown(parts[0].strip())} >= high "
                         f"{_shown(parts[1].strip())}; expected LOW < HIGH", key=where)
    if name in LAB_PARAMETERS and kind == "fixed" and a < 0.0:
        raise InputError(f"{name} {_shown(text)}; expected >= 0", key=where)
    # a mean of exactly 3 std as written (0.6um,200nm) passes, whatever the units' rounding
    if name in LAB_PARAMETERS and kind != "fixed" and (a < 0.0 if kind == "uniform"
                                                       else a < 3.0 * b * (1.0 - 1e-12)):
        raise InputError(f"{name} {_shown(text)} reaches below zero; expected a non-negative "
                         "range (uniform with LOW >= 0, or a normal whose MEAN is at least 3 "
                         "STD: a draw in the 0.13 % below zero is then taken as zero)",
                         key=where)
    return Distribution(kind, float(a), float(b), text.strip())


def checked(name: str, dist: Distribution) -> Distribution:
    """``dist`` as `parse_distribution` makes it from its text, with the same checks: a
    `Distribution` built in Python (``Distribution("uniform", 1e-8, 2e-8)``) has no text, so
    its values are written out in SI (``uniform:1e-08m,2e-08m``) for campaign.json to hold.

    A Distribution went past every check: a negative noise was taken (and drawn as zero), a
    kind ``"gauss"`` as fixed, and its empty text was what campaign.json kept, so the same
    folder took another Distribution's trials for its own (``""`` is ``""``).

    Raises
    ------
    InputError
        As `parse_distribution`, or for a text that says other values than the object's.
    """
    unit = "rad" if parameter_kind(name) == "angle" else "m"
    for number in (dist.a, dist.b):
        if isinstance(number, bool) or not isinstance(number, (int, float, np.floating,
                                                               np.integer)):
            raise InputError(f"a Distribution({dist.kind!r}, {dist.a!r}, {dist.b!r}) with "
                             f"{number!r}; expected numbers in SI (m or rad)",
                             key=f"--vary {name}")
    # b is written whenever the kind takes it, the kind is unknown, or it was given: the
    # message shows what the user gave (poisson 1, 2 read as poisson:1.0m), and a fixed one
    # with a second number is refused, not drawn without it
    values = f"{float(dist.a)!r}{unit}" + (
        f",{float(dist.b)!r}{unit}" if KINDS.get(dist.kind) != 1 or dist.b != 0 else "")
    parsed = parse_distribution(dist.text or f"{dist.kind}:{values}", name)
    if dist.text and (parsed.kind != dist.kind or not all(
            math.isclose(x, y, rel_tol=1e-12, abs_tol=0.0)
            for x, y in ((parsed.a, dist.a), (parsed.b, dist.b)))):
        raise InputError(f"a Distribution whose text {dist.text!r} is not its values "
                         f"({dist.kind}:{values}); expected one made by parse_distribution, "
                         "or no text", key=f"--vary {name}")
    return parsed


def parse_vary(text: str) -> tuple[str, Distribution]:
    """``PARAM=DIST`` as ``(name, Distribution)``; the name is checked for its form here and
    against the machine when the campaign is built."""
    if not isinstance(text, str) or "=" not in text:
        raise InputError(f"--vary {_shown(text)}; expected PARAM=DIST, e.g. "
                         "tool.y=normal:-178um,5um", key="--vary")
    name, _, dist = text.partition("=")
    name = name.strip()
    if not name:
        raise InputError(f"--vary {_shown(text)} names no parameter; expected PARAM=DIST",
                         key="--vary")
    return name, parse_distribution(dist, name)


def _nearest(dist: Distribution) -> float | None:
    """The value a refusal of ``dist`` by the error model looks at: one no draw is nearer
    zero than, on the side every draw lies on (a fixed value; a uniform's LOW or HIGH, the
    one nearer zero, when LOW..HIGH leaves zero out), or a normal's mean (its tails reach
    any value: it is refused when its centre is, not for its tails); None for a uniform
    across zero, some of whose draws any bound takes."""
    if dist.kind == "uniform":
        return dist.a if dist.a > 0.0 else dist.b if dist.b < 0.0 else None
    return dist.a


def refuse_beyond_model(vary, model) -> None:
    """Refuse a varied error parameter whose every draw the error model refuses
    (`machinesim.errors.LARGEST_ERROR`, 1 m and 180 deg either way, or the key's own
    bound: what `ErrorModel.with_parameters` refuses), before any trial runs; a normal
    whose mean it refuses too. Lab parameters (`LAB_PARAMETERS`) are not the model's.

    ``campaign --vary tool.y=5m`` ran every trial to the same refusal, then exited 1: a
    campaign of failures, each trial's time spent to learn what the text already said.
    Draws of a normal whose mean the model takes, or of a uniform across zero, reach
    within the bound: those beyond it fail their trials one by one, as before.

    Raises
    ------
    InputError
        Naming the ``--vary`` text, and the model's refusal: the bound and its unit.
    """
    for name, dist in vary:
        value = None if name in LAB_PARAMETERS else _nearest(dist)
        if value is None:
            continue
        try:
            model.with_parameters({name: value})
        except MachineSimError as error:
            which = {"fixed": "its value", "normal": "its mean"}.get(
                dist.kind, "every value it draws")
            fail = "half its trials or more" if dist.kind == "normal" else "every trial"
            raise InputError(f"{which} is beyond what the error model takes, so {fail} "
                             f"would fail: {getattr(error, 'message', error)}",
                             key=f"--vary {name}={dist.text}") from None
