"""Servo loops read from a file: one TOML table per axis letter, SI with the unit in every
key (``machinesim cut --servo``, docs/cli.md; `servo_from_toml`, which `machinesim.servo`
gives too). The loops themselves are `machinesim.servo`'s."""

from __future__ import annotations

from typing import TYPE_CHECKING

from machinesim.exceptions import InputError

if TYPE_CHECKING:
    from machinesim.servo import PIDServo

__all__ = ["SERVO_KEYS", "SERVO_OPTIONAL_KEYS", "servo_from_toml"]


#: The keys of an axis' table in a servo file (`servo_from_toml`), linear and rotary axes:
#: ``AxisServo`` field -> key with its unit. ``acc_ff``, ``bandwidth_hz`` and
#: ``sample_time_s`` are optional (no feed-forward, no filter, 10 kHz).
SERVO_KEYS = {
    "linear": {"kp": "kp_N_per_m", "ki": "ki_N_per_m_s", "kd": "kd_N_s_per_m",
               "mass": "mass_kg", "damping": "damping_N_s_per_m"},
    "rotary": {"kp": "kp_N_m_per_rad", "ki": "ki_N_m_per_rad_s", "kd": "kd_N_m_s_per_rad",
               "mass": "inertia_kg_m2", "damping": "damping_N_m_s_per_rad"},
}
SERVO_OPTIONAL_KEYS = ("acc_ff", "bandwidth_hz", "sample_time_s")


def servo_from_toml(path, machine) -> PIDServo:
    """The servo loops of a TOML file, one table per axis letter of ``machine`` (``[X]``,
    ``[C]``), SI with the unit in every key (`SERVO_KEYS`); an axis without a table follows
    its command exactly. Errors name the file, the line, the table and the key."""
    from machinesim.errors.toml import read_toml_lines
    from machinesim.metrology.instruments import as_machine
    from machinesim.servo import AxisServo, PIDServo, ServoDivergenceError

    machine = as_machine(machine)  # a shipped machine's name too, as Lab takes it
    source = str(path)
    data, lines = read_toml_lines(path)
    axes = tuple(machine.axes)
    loose = [name for name, value in data.items() if not isinstance(value, dict)]
    if loose:
        raise InputError(f"{loose[0]!r} stands outside any table; expected one table per "
                         f"axis letter of {machine.name} ({', '.join(f'[{a}]' for a in axes)})",
                         source=source, line=lines.get(loose[0]), key=loose[0])
    unknown = [name for name in data if name not in axes]
    if unknown:
        raise InputError(f"table [{unknown[0]}] is not an axis of {machine.name} (axes "
                         f"{', '.join(axes)}); one table per axis letter", source=source,
                         line=lines.get(unknown[0]), key=unknown[0])
    columns = []
    for letter, rotary in zip(axes, machine.rotary, strict=True):
        table = data.get(letter)
        if table is None:
            columns.append(None)
            continue
        keys = SERVO_KEYS["rotary" if rotary else "linear"]
        kind = "a rotary" if rotary else "a linear"
        allowed = [*keys.values(), *SERVO_OPTIONAL_KEYS]
        extra = [k for k in table if k not in allowed]
        if extra:
            raise InputError(f"unknown key {extra[0]!r} in [{letter}], {kind} axis; expected "
                             f"{', '.join(allowed)}", source=source,
                             line=lines.get(f"{letter}.{extra[0]}"), key=f"{letter}.{extra[0]}")
        missing = [k for k in keys.values() if k not in table]
        if missing:
            raise InputError(f"[{letter}] lacks {', '.join(missing)} ({kind} axis; SI, the "
                             "unit in the key)", source=source, line=lines.get(letter),
                             key=f"{letter}.{missing[0]}")
        values = {field: table[key] for field, key in keys.items()}
        values.update({key: table[key] for key in SERVO_OPTIONAL_KEYS if key in table})
        try:
            columns.append(AxisServo(**values, name=letter))
        except InputError as error:
            field = error.key
            if field is None:  # the loop as a whole (every value named): at its table's line
                raise InputError(f"[{letter}]: {error.message}", source=source,
                                 line=lines.get(letter), key=letter) from None
            key = keys.get(field, field)
            raise InputError(f"[{letter}] {key}: {error.message}", source=source,
                             line=lines.get(f"{letter}.{key}", lines.get(letter)),
                             key=f"{letter}.{key}") from None
        except ServoDivergenceError as error:  # at its table's line, as the other refusals
            line = f", line {lines[letter]}" if letter in lines else ""
            raise ServoDivergenceError(f"{source}{line}, [{letter}]: {error}") from None
    return PIDServo(tuple(columns))
