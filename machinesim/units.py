"""Unit conversion at the edges: SI inside (m, rad, s), mm/um/nm/deg only in names at the edges.

Every conversion goes through the factors below, so a unit is never guessed. `to_si` and
`from_si` take a unit name as written in file keys (``offset_um`` -> ``"um"``).
"""

from __future__ import annotations

import math
import re

import numpy as np

#: Length units, as factors to metres.
LENGTH = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}
#: Angle units, as factors to radians.
ANGLE = {
    "rad": 1.0,
    "mrad": 1e-3,
    "urad": 1e-6,
    "deg": math.pi / 180.0,
    "arcsec": math.pi / (180.0 * 3600.0),
}
#: Every unit machinesim reads, with its factor to SI.
FACTORS = {**LENGTH, **ANGLE}

M_PER_MM = LENGTH["mm"]
M_PER_UM = LENGTH["um"]
M_PER_NM = LENGTH["nm"]
RAD_PER_DEG = ANGLE["deg"]


#: Significant digits of a number in a message (`length_text`, `angle_text`): every number a
#: user types, clean of the round-off of converting it (9 mm is 0.009000000000000001 m).
SHOWN_DIGITS = 12


#: A number as typed in a spec or option (``--tool``, ``--stock``, ``--roi``): ASCII digits, a
#: point, an exponent, a sign (or inf, nan, which their callers refuse as not finite).
#: Python's float() reads more: '0_5' as 5 (a typo of 0.5 made a ball of 5 mm, ten times the
#: one meant, exit 0), and full-width or other Unicode digits ('０.５').
_TYPED_NUMBER = re.compile(r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                           r"|inf|infinity|nan)", re.IGNORECASE)


def typed_float(text: str) -> float:
    """``text`` (blanks around it allowed) as a float when it is written as a plain number
    (`_TYPED_NUMBER`); ValueError otherwise, as float() raises it."""
    text = str(text).strip()
    if not _TYPED_NUMBER.fullmatch(text):
        raise ValueError(f"could not convert string to float: {text!r}")
    return float(text)


def quotient_text(value: float, factor: float, digits: int = SHOWN_DIGITS) -> str:
    """``value`` (SI) over ``factor`` (SI per unit) to ``digits`` significant digits, as
    ``:g`` writes it, also where the quotient leaves float64 (1e306 m is 1e309 mm): worked
    out in decimal then, not shown as inf."""
    value = float(value)
    quotient = value / factor
    if math.isfinite(quotient) or not math.isfinite(value):
        return f"{quotient:.{digits}g}"
    from decimal import Decimal, localcontext

    with localcontext() as context:
        context.prec = digits
        text = format(+(Decimal(value) / Decimal(factor)), f".{digits}g")
    mantissa, _, exponent = text.partition("e")  # :g's form: no trailing zeros
    if "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{exponent}" if exponent else mantissa


def length_text(value_m: float) -> str:
    """A length (m) as a refusal shows it: in mm, the unit of the tool and stock specs, then
    in m, the Python API's: ``9 mm (0.009 m)``; ``1e+309 mm (1e+306 m)`` (not ``inf mm``)
    beyond float64 in mm."""
    return f"{quotient_text(value_m, M_PER_MM)} mm ({value_m:.{SHOWN_DIGITS}g} m)"


def angle_text(value_rad: float) -> str:
    """An angle (rad) as a refusal shows it: in deg, the unit of the specs, then in rad:
    ``180 deg (3.14159265359 rad)``."""
    return (f"{quotient_text(value_rad, RAD_PER_DEG)} deg "
            f"({value_rad:.{SHOWN_DIGITS}g} rad)")


def is_length(unit: str) -> bool:
    """True when ``unit`` names a length unit."""
    return unit in LENGTH


def is_angle(unit: str) -> bool:
    """True when ``unit`` names an angle unit."""
    return unit in ANGLE


def to_si(value, unit: str):
    """Convert ``value`` given in ``unit`` to SI (m or rad), as float64."""
    return np.asarray(value, dtype=np.float64) * FACTORS[unit] if np.ndim(value) else (
        float(value) * FACTORS[unit]
    )


def from_si(value, unit: str):
    """Convert an SI ``value`` (m or rad) to ``unit``, as float64."""
    return np.asarray(value, dtype=np.float64) / FACTORS[unit] if np.ndim(value) else (
        float(value) / FACTORS[unit]
    )


def mm(value):
    """Millimetres to metres."""
    return to_si(value, "mm")


def um(value):
    """Micrometres to metres."""
    return to_si(value, "um")


def deg(value):
    """Degrees to radians."""
    return to_si(value, "deg")
