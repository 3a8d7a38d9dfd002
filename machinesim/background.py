"""The machine's own residual geometric errors (a lab's ``background_errors``), and how they
are added to the errors a scenario injects.

A background is shipped per machine (``models/errors/background_<machine>.toml``, its values
and their sources in the file). `add_errors` is the machine as a lab has it: the injected
errors and the background together.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from machinesim.errors import ComponentError, ErrorModel
from machinesim.errors.turns import table_each_turn
from machinesim.exceptions import InputError
from machinesim.tolerances import TABULATED_SUM

#: At most this many positions in the table of a polynomial plus a table (`add_errors`): a
#: polynomial so curved over the travel that more would be needed is refused, not rounded.
TABULATED_SUM_MAX_POSITIONS = 200_000


def background_path(machine_name: str):
    """``models/errors/background_<machine>.toml`` (shipped with the machines)."""
    from machinesim.machines import models_dir

    return models_dir() / "errors" / f"background_{machine_name}.toml"


def background_model(machine) -> ErrorModel:
    """The machine's own residual geometric errors (a well-compensated one), from its file.

    Raises
    ------
    InputError
        When the machine has no background file (a machine loaded from elsewhere): give the
        lab one with ``background=``.
    """
    path = background_path(machine.name)
    if not path.is_file():
        raise InputError(f"Expected a background error model for {machine.name} at {path}; "
                         f"give one with Lab(..., background=...)", key="background")
    model = ErrorModel.from_toml(path)
    machine.check_errors(model)
    return model


def add_errors(a: ErrorModel, b: ErrorModel,
               travel: Mapping[str, tuple[float, float]] | None = None) -> ErrorModel:
    """The errors of ``a`` and ``b`` together: location errors add, component errors add.

    Component tables of an axis are put on the union of the two models' positions (each
    table is piecewise linear, so their sum is exactly the table of the sums there, and both
    hold their end values beyond; on a rotary axis a table of a whole turn is read a whole
    number of turns back into it instead, as the kinematics reads it); polynomials add
    coefficient by coefficient. A polynomial in one model and a table in the other (the
    README's example errors on a machine whose background holds tables) have a sum that is
    neither: it is tabulated over the axis's ``travel``, on the table's positions and
    between them at a spacing at which the polynomial's linear interpolation is off by at
    most `TABULATED_SUM` (m or rad; its error is at most h^2/8 times its largest second
    derivative over the travel, found exactly). Beyond the travel the sum holds its end
    values, as any table does.

    Parameters
    ----------
    a, b : ErrorModel
        ``b`` must carry no tool or workpiece setting (a setting belongs to a set-up, not to
        the machine); the sum keeps ``a``'s `ErrorModel.source` and what that source wrote
        of the settings.
    travel : mapping of axis letter to (lower, upper), m or rad, optional
        The machine's travels, needed only to tabulate a polynomial plus a table.

    Raises
    ------
    InputError
        When ``b`` has a setting; or one symbol is a table in one model and a polynomial in
        the other and no travel is given for its axis, or the polynomial is too curved to be
        tabulated within `TABULATED_SUM_MAX_POSITIONS` positions.
    """
    if not (b.tool == ErrorModel().tool and b.workpiece == ErrorModel().workpiece
            and b.tool_geometry == ErrorModel().tool_geometry):
        raise InputError("Expected a background without tool or workpiece setting errors",
                         key="background")
    location = {axis: dict(table) for axis, table in a.location.items()}
    for axis, table in b.location.items():
        merged = location.setdefault(axis, {})
        for symbol, value in table.items():
            merged[symbol] = merged.get(symbol, 0.0) + value
    component = {}
    for axis in sorted(set(a.component) | set(b.component)):
        ta, tb = a.component.get(axis, {}), b.component.get(axis, {})
        symbols = list(ta) + [s for s in tb if s not in ta]
        grids = [e.positions for t in (ta, tb) for e in t.values() if e.kind == "table"]
        span = None if travel is None else travel.get(axis)
        for symbol in symbols:  # the tables of an axis share their positions
            pair = [e for e in (ta.get(symbol), tb.get(symbol)) if e is not None]
            if {e.kind for e in pair} == {"table", "poly"}:
                poly = next(e for e in pair if e.kind == "poly")
                grids.append(poly_positions(poly.values, span, axis, symbol))
        grid = np.unique(np.concatenate(grids)) if grids else None
        component[axis] = {symbol: _add_component(ta.get(symbol), tb.get(symbol), grid,
                                                  axis in "ABC")
                           for symbol in symbols}
    # the settings are a's as its file wrote them: a refusal of one (a nose radius the tool
    # cannot take) names that file and key; the summed location and component values are not
    # what any file wrote
    settings = {k: v for k, v in a.written.items()
                if k.startswith(("tool.", "tool_geometry.", "workpiece."))}
    return ErrorModel(a.tool, a.workpiece, location, component, a.tool_geometry,
                      source=a.source, written=settings, lines=a.lines)


def _add_component(ea, eb, grid, rotary: bool) -> ComponentError:
    """The sum of ``ea`` and ``eb`` (either may be None), on ``grid`` when a table. On a
    rotary axis a table of a whole turn repeats each turn (`table_each_turn`), so it is read
    so at the grid's positions beyond it (held at its end values instead, an ECC of -180 ..
    180 deg, 3 urad at 90 deg, read 2 urad at -270 deg beside a table of -360 .. 360 deg)."""
    present = [e for e in (ea, eb) if e is not None]
    if {e.kind for e in present} == {"poly"}:
        size = max(e.values.size for e in present)
        total = np.zeros(size)
        for e in present:
            total[:e.values.size] += e.values
        return ComponentError("poly", None, total)
    if len(present) == 1 and np.array_equal(present[0].positions, grid):
        return present[0]
    return ComponentError("table", grid, sum((table_each_turn(e) if rotary else e).evaluate(grid)
                                             for e in present))


def poly_positions(coefficients: np.ndarray, span, axis: str, symbol: str) -> np.ndarray:
    """Positions over ``span`` (lower, upper) at which the polynomial's linear interpolation
    is off by at most `TABULATED_SUM`: spacing h with h^2/8 max|p''| <= TABULATED_SUM."""
    key = f"component.{axis}.{symbol}"
    if span is None:
        raise InputError(f"Expected {key} as a table in both models or a polynomial in both, "
                         f"got one of each and no travel of axis {axis} to tabulate their sum "
                         "over", key=key)
    lower, upper = float(span[0]), float(span[1])
    curvature = np.polynomial.polynomial.polyder(np.asarray(coefficients, np.float64), 2)
    # |p''| is largest at an end of the travel or where p''' vanishes inside it
    stationary = np.polynomial.polynomial.polyroots(
        np.polynomial.polynomial.polyder(curvature)) if curvature.size > 1 else np.zeros(0)
    inside = stationary.real[(np.abs(stationary.imag) <= 1e-12 * max(1.0, upper - lower))
                             & (stationary.real > lower) & (stationary.real < upper)]
    peak = float(np.max(np.abs(np.polynomial.polynomial.polyval(
        np.concatenate([[lower, upper], inside]), curvature)), initial=0.0))
    if peak == 0.0:  # a straight line: exact between its ends
        return np.array([lower, upper])
    count = int(np.ceil((upper - lower) / np.sqrt(8.0 * TABULATED_SUM / peak))) + 1
    if count > TABULATED_SUM_MAX_POSITIONS:
        raise InputError(f"{key}: the polynomial plus the other model's table would need "
                         f"{count} positions over axis {axis}'s travel to hold the sum within "
                         f"{TABULATED_SUM:g}; expected at most {TABULATED_SUM_MAX_POSITIONS} "
                         "(give it as a table)", key=key)
    return np.linspace(lower, upper, max(count, 2))
