"""How uncertain paper 001's identified values are: every error of the readings, through the
formulas that use them.

An identified value is a function of the plates' readings (`GrooveReading`). Three kinds of
reading error move it, and each is propagated here (first order, central differences of
`PROPAGATION_STEP`) through the same function the identification uses:

- **each reading's own**: a groove centre across its groove (`point_sigma`: the profile fit,
  and the stage's positioning of that profile), a depth (`depth_sigma`), an end point along
  its groove (`end_sigma`). Independent from reading to reading.
- **each plate's registration**: the microscope reads a whole plate in one frame that sits off
  the workpiece's by an offset (x, y) and a turn about z (`RegistrationScatter`, the lab's
  stated practice, never the drawn registration). Common to every reading of the plate.
  The A sets are read between lines of one plate and the triangle is placed by its mark,
  so neither feels it; the generic fit, which compares absolute positions, does.
- **the plates cut with an earlier result**: the C and B plates are cut with the A sets' dx,
  dy compensated, so an error of those moves every groove on them by
  ``-Rz(C) Ry(B) Rz(A) (delta dx, delta dy, 0)`` (the edge displacement of
  `corrected_axes`). The triangle's centre does not move (its three sides move alike), but
  the reference mark that places it does: e is off by (-1, +1) times the error of dy. The B
  depths move with the commanded Z and are taken back to one command, so dZ does not; the
  generic fit compares each reading with the program as cut, so it does not either.

`propagated_std` takes any function of the readings, so the model-based cross-check
(`machinesim.identification.tool_setting_6axis_fit`) gets its uncertainty the same way, and
`after_std` carries the same errors on into what the compensated plates read: the spread of
Table 1's "after" over labs.
docs/procedures/tool_setting_6axis.md gives the figures.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.tool_setting_6axis import (
    AXES,
    GrooveReading,
    a_axis_sets,
)
from machinesim.metrology import fit_line
from machinesim.metrology.imperfections import RegistrationScatter
from machinesim.metrology.prisms import SIGMA_FLOOR_M
from machinesim.rotations import rot_y, rot_z

__all__ = ["PLATES", "PROPAGATION_STEP", "after_std", "propagated_std"]

#: The plates in the order their readings are passed: the A sets, the C triangle (with its
#: mark), the B grooves. The C and B plates are cut with the A sets' dx, dy compensated.
PLATES = ("a", "c", "b")
#: Step of the central differences (m for readings and offsets, rad for the registration's
#: turn), from the plateau where neither round-off nor truncation limits them (scanned
#: 1e-10 .. 1e-5 in factors of sqrt(10) on the scenario's defaults, `--budget off`):
#:
#: - round-off ~ eps / h: the values differenced come out of fits, which agree with
#:   themselves to eps ~ 4e-17 m (measured: column x h scatters 1e-17 .. 3.5e-17 m at every
#:   step), so a column is off by eps / h. It matters where a column is small: tool.y's fit
#:   std (3.344 nm) holds 1.9 nm from the registration, 1.8 nm of it through plate a's turn
#:   (1.8e-6 m/rad times 1 mrad), which is off by 1e-3 eps / h: 0.016 nm at h = 1e-9 (printed
#:   3.3288 nm), 1e-4 nm at 1e-7 (3.3445), 2e-5 nm at 3e-7 (3.3444, the limit 3.344395 that
#:   1e-6 .. 1e-5 give to 1e-6 nm). The paper's formulas (and Table 1's after std) take
#:   readings, 1e-19 m on mm: there it is below 3e-8 relative at every step.
#: - truncation ~ h^2 f''' / 6 f': the paper's formulas are curved on a ~2 mm scale (C
#:   centre y's std grows as 5e4 h^2 relative: +9e-5 nm of 1728.821 at h = 1e-6, +8e-3 nm at
#:   1e-5; Table 1's after std alike, 5.6e-6 relative at 1e-5); the fit stays within 1e-6
#:   relative up to 1e-5.
#:
#: Both are below the printed 1e-4 nm from 2e-7 to 7e-7; at 3e-7 every printed std is its
#: limit (the largest moves: tool.y's fit std 2e-5 nm by round-off, C centre y's paper std
#: 8e-6 nm by truncation); 3x smaller moves tool.y's fit std by 1.3e-4 nm, 3x larger C centre
#: y's paper std by 6.5e-5 nm (tests/test_tool_setting_6axis_uncertainty.py holds both).
PROPAGATION_STEP = 3e-7

Plates = tuple[Sequence[GrooveReading], Sequence[GrooveReading], Sequence[GrooveReading]]


def propagated_std(function: Callable[..., np.ndarray], a: Sequence[GrooveReading],
                   c: Sequence[GrooveReading], b: Sequence[GrooveReading], length: float,
                   registration: Mapping[str, RegistrationScatter | None] | None = None,
                   *, own_errors: bool = True, staged: bool = True) -> np.ndarray:
    """Standard uncertainties of ``function(a, c, b)`` from every error of the readings
    (module docstring).

    Parameters
    ----------
    function : callable
        ``function(a, c, b) -> ndarray``: the identified values from the three plates'
        readings (tuples of `GrooveReading`).
    a, c, b : sequence of GrooveReading
        The A sets (each groove with its end point), the triangle and its mark, the B
        grooves.
    length : float
        The A grooves' programmed length (m): the A result the C and B plates were cut with
        is `a_axis_sets` of the A readings and it.
    registration : mapping, optional
        Plate (`PLATES`) -> the scatter of its microscope's registration, as the lab states
        it; a plate missing or None is read in the workpiece frame exactly.
    own_errors : bool
        False: leave out each reading's own errors (and with them the plates cut with the
        A result, which move only with the A readings), for a function whose own covariance
        holds them already (a least-squares fit weighted by the same sigmas).
    staged : bool
        True (the identification's plates): the C and B plates were cut with the A sets'
        result, so an error of the A readings moves them too. False (plates all cut with
        one compensation fixed beforehand, as the compensated plates are): it does not.

    Returns
    -------
    ndarray
        One standard uncertainty per value of ``function``, in its units.
    """
    registration = dict(registration or {})
    unknown = set(registration) - set(PLATES)
    if unknown:
        raise InputError(f"Expected registration scatters for plates {PLATES}, got "
                         f"{sorted(unknown)}", key="registration")
    for plate, scatter in registration.items():
        if scatter is not None and not isinstance(scatter, RegistrationScatter):
            raise InputError(f"Expected plate {plate!r}'s registration as a "
                             f"RegistrationScatter or None, got {scatter!r}",
                             key="registration")
    plates = (tuple(a), tuple(c), tuple(b))
    scatters = [registration.get(plate) for plate in PLATES]
    own = np.concatenate([_sigmas(g) for g in (*plates[0], *plates[1], *plates[2])])
    sigma = np.concatenate(
        [own if own_errors else np.zeros_like(own)]
        + [[s.offset_xy, s.offset_xy, s.rotation] for s in scatters if s is not None])
    cut_with = a_axis_sets(plates[0], length).offset

    def shifted(step):
        moved = _shifted(plates, iter(step), [s is not None for s in scatters])
        if not staged:
            return function(*moved)
        found = a_axis_sets(moved[0], length).offset
        delta = np.r_[found - cut_with, 0.0]
        return function(moved[0], *(tuple(_displaced(g, delta) for g in plate)
                                    for plate in moved[1:]))

    h = PROPAGATION_STEP
    variance = 0.0
    for i in np.flatnonzero(sigma):
        step = np.zeros(sigma.size)
        step[i] = h
        column = (np.asarray(shifted(step)) - np.asarray(shifted(-step))) / (2.0 * h)
        variance = variance + (column * sigma[i]) ** 2
    return np.sqrt(variance) if sigma.any() else np.zeros(np.asarray(function(*plates)).shape)


def _sigmas(g: GrooveReading) -> np.ndarray:
    """A reading's standard uncertainties in the order `_shifted` takes their shifts: end
    point (if any), centres, depths (floored at `SIGMA_FLOOR_M`)."""
    end = [max(g.end_sigma, SIGMA_FLOOR_M)] if g.end is not None else []
    return np.concatenate([end, np.maximum(g.point_sigma, SIGMA_FLOOR_M),
                           np.maximum(g.depth_sigma, SIGMA_FLOOR_M)])


def _shifted(plates: Plates, step, registered: Sequence[bool]) -> Plates:
    """The plates' readings, each moved by its own shifts from ``step`` (an iterator, in
    `_sigmas`' order: end points along the groove, centres across it, depths), then each
    registered plate turned and offset by its next three (x, y, turn about the workpiece
    origin).

    An end point lies on its groove's centre line: moving the centres moves the line and
    the end point with it (the face is read along the line, the line across it).
    """
    moved = []
    for plate in plates:
        out = []
        for g in plate:
            along = next(step) if g.end is not None else 0.0
            across = np.array([next(step) for _ in g.points])
            deeper = np.array([next(step) for _ in g.depths])
            if along == 0.0 and not across.any() and not deeper.any():
                out.append(g)  # not moved: one shift at a time moves one reading
                continue
            line = g.line
            normal = np.array([-line.direction[1], line.direction[0]])
            points = g.points + across[:, None] * normal
            depths = g.depths + deeper
            end = None
            if g.end is not None:
                new = fit_line(points)
                t = (g.end - new.point) @ new.direction + along
                end = new.point + t * new.direction
            out.append(replace(g, points=points, depths=depths, end=end))
        moved.append(out)
    registered_plates = []
    for plate, has in zip(moved, registered, strict=True):
        if has:
            x, y, turn = next(step), next(step), next(step)
            plate = [_registered(g, np.array([x, y]), turn) for g in plate]
        registered_plates.append(tuple(plate))
    return tuple(registered_plates)


def _registered(g: GrooveReading, offset: np.ndarray, turn: float) -> GrooveReading:
    """``g`` as read in a frame offset by ``offset`` and turned by ``turn`` about the
    workpiece origin (first order, as the propagation needs)."""
    def frame(p):
        p = np.asarray(p)
        return p + offset + turn * np.stack([-p[..., 1], p[..., 0]], axis=-1)

    return replace(g, points=frame(g.points),
                   end=None if g.end is None else frame(g.end))


def _displaced(g: GrooveReading, delta: np.ndarray, centre=None) -> GrooveReading:
    """``g`` had its plate been cut with the tool offset compensated by ``delta`` (m, tool
    axes) more, and the C centre line by ``centre`` (m, xy; none by default) more: the
    program's X Y Z move by ``-Ry(B) Rz(A) delta + (centre - Rz(-C) centre, 0)``
    (`corrected_axes`), the edge with them, so the groove moves by ``Rz(C)`` of that in the
    workpiece frame and its depth by minus its z."""
    centre = np.zeros(2) if centre is None else np.asarray(centre, dtype=np.float64)
    if not delta.any() and not centre.any():
        return g
    a, b, c = (float(g.q_start[AXES.index(axis)]) for axis in "ABC")
    program = -(rot_y(b) @ rot_z(a) @ delta)
    program[:2] += centre - rot_z(-c)[:2, :2] @ centre
    edge = rot_z(c) @ program
    xyz = [AXES.index(axis) for axis in "XYZ"]
    q_start, q_end = g.q_start.copy(), g.q_end.copy()
    q_start[xyz] += program
    q_end[xyz] += program
    return replace(g, q_start=q_start, q_end=q_end, points=g.points + edge[:2],
                   depths=g.depths - edge[2],
                   end=None if g.end is None else g.end + edge[:2])


def after_std(figures: Callable[..., np.ndarray],
              identified: Callable[..., tuple[np.ndarray, np.ndarray]], before: Plates,
              after: Plates, length: float,
              registration_before: Mapping[str, RegistrationScatter | None] | None = None,
              registration_after: Mapping[str, RegistrationScatter | None] | None = None,
              ) -> np.ndarray:
    """Standard uncertainties of figures read on the compensated plates: how far another lab
    of the same stated instruments would land from this one's "after".

    An "after" figure is what is left of an error once it is compensated, as read. Two
    independent sets of reading errors move it:

    - **the identification's**: an error of the plates read before moves the identified d
      and e, so the compensated plates are cut with a compensation off by as much, and
      their grooves move (`_displaced`, `corrected_axes`): propagated through the
      identification, the compensation and the reading of the compensated plates;
    - **the compensated plates' own readings**: propagated as any reading
      (`propagated_std`), but not staged: every compensated plate is cut with the one
      compensation found before.

    Correlations are kept where they arise: the C plates are cut with the A sets' dy
    before and after, and the reference mark reads it alike both times, so it cancels from
    the C figures after (it does not from e identified).

    Parameters
    ----------
    figures : callable
        ``figures(a, c, b) -> ndarray``: the figures from one set of plate readings.
    identified : callable
        ``identified(a, c, b) -> (d, e)``: the compensation the identification finds from the
        plates read before (d = tool offset, 3; e = C centre, 2; m).
    before, after : tuple of 3 sequences of GrooveReading
        The plates read for the identification (A, C, B) and the compensated plates.
    length : float
        The A grooves' programmed length (m).
    registration_before, registration_after : mapping, optional
        The stated registration scatter of each plate's microscope, as for
        `propagated_std`.

    Returns
    -------
    ndarray
        One standard uncertainty per figure, in its units.
    """
    base_d, base_e = (np.asarray(v, dtype=np.float64) for v in identified(*before))
    after = tuple(tuple(plate) for plate in after)

    def through_compensation(a, c, b):
        d, e = identified(a, c, b)
        return figures(*(tuple(_displaced(g, np.asarray(d) - base_d, np.asarray(e) - base_e)
                               for g in plate) for plate in after))

    from_before = propagated_std(through_compensation, *before, length,
                                 registration_before)
    from_after = propagated_std(figures, *after, length, registration_after,
                                staged=False)
    return np.hypot(from_before, from_after)
