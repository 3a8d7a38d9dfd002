"""Seeded random error models and axis values: Monte Carlo error budgets, tests, benchmarks."""

from __future__ import annotations

import numpy as np

from machinesim.errors import ComponentError, ErrorModel, ToolSetting, WorkpieceSetting

UM = 1e-6
URAD = 1e-6


def random_errors(machine, rng: np.random.Generator, *, tool_offset=200 * UM,
                  tool_rotation=2e-3, workpiece_delta=50 * UM, workpiece_rotation=5e-3,
                  location_length=20 * UM, location_angle=50 * URAD,
                  component_length=5 * UM, component_angle=20 * URAD,
                  table_points=5) -> ErrorModel:
    """Errors of every family on every axis of ``machine``, normally distributed.

    Each argument is a standard deviation in SI (m or rad). Every axis gets all its valid
    location errors, a table of each of its six component errors over its travel (over
    +-10 rad for a spindle), and its first straightness error as a quadratic polynomial
    instead, so both kinds are exercised (not on a spindle, whose errors repeat each turn).
    """
    location, component = {}, {}
    for letter in machine.axes:
        ax = machine.axis(letter)
        location[letter] = {
            s: rng.normal(0, location_length if s[1] in "XYZ" else location_angle)
            for s in ax.location_symbols()}
        span = (ax.lower, ax.upper) if ax.upper - ax.lower < 20 else (-10.0, 10.0)
        positions = np.linspace(*span, table_points)
        table = {}
        for s in ax.component_symbols():
            scale = component_length if s[1] in "XYZ" else component_angle
            table[s] = ComponentError("table", positions, rng.normal(0, scale, table_points))
        straightness = ax.component_symbols()[(ax.direction + 1) % 3]
        coefficients = rng.normal(0, component_length, 3) * np.array([1.0, 0.4, 0.2])
        if not (ax.rotary and (ax.lower < -2 * np.pi or ax.upper > 2 * np.pi)):
            # a spindle keeps its table: a polynomial in the angle does not repeat each turn
            # (`machinesim.errors.turns.each_turn`); drawn anyway, so later draws stay the same
            table[straightness] = ComponentError("poly", None, coefficients)
        component[letter] = table
    return ErrorModel(
        tool=ToolSetting(rng.normal(0, tool_offset, 3), rng.normal(0, tool_rotation, 3)),
        workpiece=WorkpieceSetting(rng.normal(0, workpiece_delta, 3),
                                   *rng.normal(0, workpiece_rotation, 3)),
        location=location, component=component)


def random_axis_values(machine, rng: np.random.Generator, n: int,
                       fraction: float = 0.9) -> np.ndarray:
    """``n`` axis-value vectors (n, n_axes), uniform over the middle ``fraction`` of each
    travel (a spindle's over +-2 pi)."""
    lower = np.maximum(machine.lower, -2 * np.pi)
    upper = np.minimum(machine.upper, 2 * np.pi)
    mid, half = (lower + upper) / 2, (upper - lower) / 2 * fraction
    return rng.uniform(mid - half, mid + half, size=(n, len(machine.axes)))
