"""How uncertain paper 002's identified setting is: the lab's stated imperfections, through
eqs 1-4 and Fig. 6.

The probe's noise reaches the identification through the generic fit's covariance
(`machinesim.identification.workpiece_setting.fit_setting`). Two more sources are stated by
the lab and propagated here, never taken from what the lab drew:

- **the spheres' places** (`design_std`): eqs 1-4 take the designed centres as where the
  spheres are, and the workshop states how far it makes them (`Lab.artefact_scatter`, 1 um
  per coordinate): about 1 um of position and 0.1 mrad of angle, the paper's "less than
  1-2 um". Linear, by central differences.
- **each contact** (`contact_std`): the probe's maker states the lobing's amplitude per
  order and the ball's sphericity, the workshop the spheres' form (2 um peak to valley),
  none of them their phases and axes. The recorded scan points and bottom touches are moved
  as such a probe on such spheres would have moved them, for `CONTACT_DRAWS` labs drawn from
  the statements, and identified again: the RMS of what that moves is the uncertainty. It
  is what the C centre carries (tens of nanometres: the 180-deg turn takes out the
  spheres' places, not the probe's lobing nor the forms, which turn with the table).

docs/procedures/workpiece_setting.md gives the figures.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.workpiece_setting import (
    PARAMETERS,
    Identification,
    ReferenceSpheres,
    SphereReading,
    SphereReadings,
    identify,
    parameters,
    setting_from_centres,
    sphere_reading,
)
from machinesim.metrology import fit_sphere
from machinesim.metrology.imperfections import Lobing, ZonalForm
from machinesim.metrology.probe_instrument import GRAZING_COSINE
from machinesim.rotations import rot_z

__all__ = ["CONTACT_DRAWS", "DESIGN_STEP_M", "contact_covariance", "contact_std",
           "design_covariance", "design_std", "setting_covariance", "tilt_correlation",
           "tilt_spread_quantile", "tilt_spread_quantiles"]

#: Step (m) of the central differences of `design_std`: eqs 1-4 are smooth on the 12 mm
#: scale of the sphere triangle, so 1 nm is exact to ~1e-7 relative.
DESIGN_STEP_M = 1e-9
#: Labs drawn from the stated pre-travel, sphericity and sphere form (`contact_std`): the
#: RMS of 64 draws is within ~9 % (1 / sqrt(2 x 64)) of the statement's.
CONTACT_DRAWS = 64
#: Seed of those draws: the statement's uncertainty, the same for every lab and run.
CONTACT_DRAWS_SEED = 20021


def design_std(found: Identification, designed, position_sigma: float) -> dict[str, float]:
    """Standard uncertainties (SI) of eqs 1-4 from the spheres' places: the square roots of
    `design_covariance`'s diagonal.

    Returns
    -------
    dict
        `PARAMETERS` -> standard uncertainty (m or rad).
    """
    return _stds(design_covariance(found, designed, position_sigma))


def design_covariance(found: Identification, designed, position_sigma: float) -> np.ndarray:
    """Covariance (SI, `PARAMETERS` order, 8 x 8) of eqs 1-4 from the spheres' places: eqs
    1-4 take the designed centres as where the spheres are, and a workshop makes each centre
    within ``position_sigma`` (m, per coordinate, independent) of its design.

    A sphere made ``e`` off its design is found where the workpiece puts ``design + e``:
    the measured centre moves by ``R e``, which for an isotropic scatter is a move of the
    same size. So the tolerance is propagated to first order (central differences of 1 nm
    on each coordinate, the Jacobian ``J``; ``sigma^2 J J^T``) through
    `setting_from_centres` on the measured centres. Alpha and beta both read sphere S1
    (S1 -> S3 and S1 -> S2), which correlates them. The C-axis centre (Fig. 6) compares
    each sphere with itself turned by 180 deg, so its places do not enter it (0).
    """
    designed = ReferenceSpheres(designed).centres
    sigma = float(position_sigma)
    if not (math.isfinite(sigma) and sigma >= 0.0):
        raise InputError(f"Expected position_sigma >= 0 (m), got {position_sigma!r}",
                         key="position_sigma")

    def values(centres):
        setting, _ = setting_from_centres(centres, designed)
        return np.r_[setting.delta, setting.alpha, setting.beta, setting.gamma]

    h = DESIGN_STEP_M
    jacobian = np.zeros((6, found.centres.size))
    for i in range(found.centres.size):
        step = np.zeros(found.centres.size)
        step[i] = h
        step = step.reshape(found.centres.shape)
        jacobian[:, i] = (values(found.centres + step) - values(found.centres - step)) / (2.0 * h)
    covariance = np.zeros((len(PARAMETERS), len(PARAMETERS)))
    covariance[:6, :6] = sigma ** 2 * jacobian @ jacobian.T
    return covariance


def _stds(covariance: np.ndarray) -> dict[str, float]:
    """`PARAMETERS` -> the square root of ``covariance``'s diagonal."""
    return dict(zip(PARAMETERS, np.sqrt(np.diag(covariance)).tolist(), strict=True))


def contact_std(readings: SphereReadings, sphere_form: float = 0.0,
                draws: int = CONTACT_DRAWS) -> dict[str, float]:
    """Standard uncertainties (SI) of eqs 1-4 and Fig. 6 from what the lab states of each
    contact: the square roots of `contact_covariance`'s diagonal.

    Returns
    -------
    dict
        `PARAMETERS` -> standard uncertainty (m or rad); zeros when nothing is stated.
    """
    return _stds(contact_covariance(readings, sphere_form, draws))


def contact_covariance(readings: SphereReadings, sphere_form: float = 0.0,
                       draws: int = CONTACT_DRAWS) -> np.ndarray:
    """Covariance (SI, `PARAMETERS` order, 8 x 8) of eqs 1-4 and Fig. 6 from what the lab
    states of each contact: the probe's pre-travel (`SphereReadings.lobing_amplitudes`), its
    ball's form (`SphereReadings.sphericity`) and the spheres' own form (``sphere_form``, m
    peak to valley, `Lab.artefact_scatter`).

    A contact of normal ``n`` (surface to ball centre) is read as if the ball had pressed
    ``p(n) - f(-n) + g(-n)`` further along ``n`` (`machinesim.metrology.probe_instrument`;
    ``p`` the lobing, ``f`` the ball's form, ``g`` the sphere's, whose wall standing out by
    ``g`` lets the ball in that much further): a scan point (moving down -Z) then lies that
    much over ``n_z`` lower, a bottom touch (``n`` = +z, no lobing there) that much higher,
    under the refitted centre (the touch goes down under the fit). For each of ``draws``
    labs drawn from the statements (phases and axes unknown; one probe for all readings,
    one form per sphere, turned with the table for the readings at C = 180 deg), every
    reading is moved so, the spheres refitted and identified again; the result is the RMS
    of the change of each parameter (the mean of the changes' outer products). ``n`` is the
    direction from each scanned ball centre to the fitted cavity centre, in machine
    coordinates: a fixed turn of the probe's frame only turns the unknown phases and axes.
    Zeros when nothing is stated.
    """
    amplitudes, sphericity = dict(readings.lobing_amplitudes), float(readings.sphericity)
    sphere_form = float(sphere_form)
    if not (math.isfinite(sphere_form) and sphere_form >= 0.0):
        raise InputError(f"Expected sphere_form >= 0 (m), got {sphere_form!r}",
                         key="sphere_form")
    if not amplitudes and sphericity == 0.0 and sphere_form == 0.0:
        return np.zeros((len(PARAMETERS), len(PARAMETERS)))
    if any(r.points is None for r in (*readings.first, *readings.turned)):
        raise InputError("Expected the scanned points of every sphere reading (sphere_reading "
                         "keeps them) to propagate the stated imperfections", key="points")
    base = parameters(identify(readings))
    normals = {name: [_contact_normals(r) for r in getattr(readings, name)]
               for name in ("first", "turned")}
    rng = np.random.default_rng(CONTACT_DRAWS_SEED)
    products = np.zeros((len(PARAMETERS), len(PARAMETERS)))
    for _ in range(int(draws)):
        lobing = Lobing.draw(rng, amplitudes) if amplitudes else None
        ball = ZonalForm.draw(rng, sphericity) if sphericity > 0.0 else None
        forms = [ZonalForm.draw(rng, sphere_form) if sphere_form > 0.0 else None
                 for _ in readings.first]
        moved = replace(readings, **{
            name: tuple(_as_read(r, normal, lobing, ball, form, readings.ball_radius)
                        for r, normal, form in zip(getattr(readings, name), normals[name],
                                                   forms, strict=True))
            for name in ("first", "turned")})
        found = parameters(identify(moved))
        change = np.array([found[n] - base[n] for n in PARAMETERS])
        products += np.outer(change, change)
    return products / draws


def setting_covariance(check, found: Identification, readings: SphereReadings,
                       artefact_scatter=None) -> np.ndarray:
    """Covariance (SI, `PARAMETERS` order, 8 x 8) of the identified setting and C centre:
    the fit cross-check's (``check``, `fit_setting`'s `Estimate`: the probe's stated noise
    to first order), the spheres' stated places (`design_covariance`, when the lab states
    an ``artefact_scatter``) and each contact as stated (`contact_covariance`), summed:
    independent sources. NaN where the fit cannot see a parameter."""
    order = [check.names.index(name) for name in PARAMETERS]
    covariance = np.asarray(check.covariance, dtype=np.float64)[np.ix_(order, order)]
    if artefact_scatter is not None:
        covariance = covariance + design_covariance(found, readings.spheres.centres,
                                                    artefact_scatter.position)
    form = artefact_scatter.form if artefact_scatter is not None else 0.0
    return covariance + contact_covariance(readings, form)


def tilt_correlation(covariance) -> float:
    """The correlation of alpha and beta in ``covariance`` (`PARAMETERS` order, SI): 0 when
    either has no spread, NaN when either is unknown (NaN)."""
    covariance = np.asarray(covariance, dtype=np.float64)
    a, b = PARAMETERS.index("workpiece.alpha"), PARAMETERS.index("workpiece.beta")
    scale = math.sqrt(covariance[a, a] * covariance[b, b])
    if not math.isfinite(scale) or not math.isfinite(covariance[a, b]):
        return math.nan
    return float(np.clip(covariance[a, b] / scale, -1.0, 1.0)) if scale > 0.0 else 0.0


def _contact_normals(r: SphereReading) -> np.ndarray:
    """Unit contact normals (N, 3) of a reading's scan points: from each scanned ball centre
    to the fitted cavity centre (surface to ball centre)."""
    normal = fit_sphere(r.points).centre - r.points
    return normal / np.linalg.norm(normal, axis=1, keepdims=True)


def _as_read(r: SphereReading, normal: np.ndarray, lobing, ball, form,
             ball_radius: float) -> SphereReading:
    """``r`` (its scan points' contact ``normal``) as a probe with ``lobing`` and ``ball``
    form would have read a sphere of ``form`` (its own axes, turned with the table by the
    reading's C)."""
    points = np.array(r.points, dtype=np.float64)
    turn = rot_z(r.c_angle)
    down = np.array([0.0, 0.0, -1.0])

    def press(n):
        total = np.zeros(n.shape[:-1])
        if lobing is not None:
            total = total + lobing(n)
        if ball is not None:
            total = total - ball(-n)
        if form is not None:
            total = total + form(-n @ turn)  # machine -> the sphere's own (table) frame
        return total

    points[:, 2] -= press(normal) / np.maximum(normal[:, 2], GRAZING_COSINE)
    moved = sphere_reading(points, r.bottom, ball_radius, r.c_angle)
    # the bottom touch goes down under the fitted centre (`read_sphere`), so it moves with it
    bottom = np.array(r.bottom, dtype=np.float64)
    bottom[:2] += moved.xy - r.xy
    bottom[2] -= float(press(-down[None])[0])
    return replace(moved, bottom=bottom)


def _spread_cdf(spread, sigma_alpha: float, sigma_beta: float, span: float,
                correlation: float = 0.0) -> float:
    """P(span max(|da|, |db|) <= spread) for normal da, db of stds ``sigma_alpha``,
    ``sigma_beta`` and ``correlation`` (`tilt_spread_quantiles`)."""
    from scipy.integrate import quad
    from scipy.special import erf, ndtr

    limit = spread / span  # each tilt within +-limit
    if sigma_alpha == 0.0 or sigma_beta == 0.0 or correlation == 0.0:
        def inside(sigma):
            return erf(limit / (sigma * math.sqrt(2.0))) if sigma > 0.0 else 1.0

        return inside(sigma_alpha) * inside(sigma_beta)
    rho = correlation
    if abs(rho) == 1.0:  # db = +-(sigma_beta / sigma_alpha) da: one variable
        return erf(min(limit / sigma_alpha, limit / sigma_beta) / math.sqrt(2.0))
    # da = sigma_alpha z; given z, db is normal about rho sigma_beta z of std
    # sigma_beta sqrt(1 - rho^2): P = integral over |z| <= limit / sigma_alpha of
    # phi(z) P(|db| <= limit | z), even in z
    width = sigma_beta * math.sqrt(1.0 - rho * rho)

    def given(z):
        mean = rho * sigma_beta * z
        return (math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)
                * (ndtr((limit - mean) / width) - ndtr((-limit - mean) / width)))

    half, _ = quad(given, 0.0, limit / sigma_alpha, epsabs=1e-14, epsrel=1e-12, limit=200)
    return min(2.0 * half, 1.0)


def _check_spread_inputs(sigma_alpha, sigma_beta, span,
                         correlation=0.0) -> tuple[float, float, float, float]:
    values = tuple(float(v) for v in (sigma_alpha, sigma_beta, span))
    if not all(math.isfinite(v) and v >= 0.0 for v in values) or values[2] == 0.0 or (
            values[0] == 0.0 and values[1] == 0.0):
        raise InputError(f"Expected tilt stds >= 0 (rad, not both 0) and a span > 0 (m), got "
                         f"{sigma_alpha!r}, {sigma_beta!r} and {span!r}", key="sigma")
    rho = float(correlation)
    if not (math.isfinite(rho) and -1.0 <= rho <= 1.0):
        raise InputError(f"Expected the tilts' correlation in -1 .. 1, got {correlation!r}",
                         key="correlation")
    return (*values, rho)


def tilt_spread_quantiles(sigma_alpha: float, sigma_beta: float, span: float,
                          quantiles, correlation: float = 0.0) -> np.ndarray:
    """Quantiles over labs of the spread of depths read at the far ends of crossing grooves
    cut after compensation, from the stated uncertainty of the identified tilts.

    Four grooves run out from one point at C = 0, 90, 180 and 270 deg and are read at
    ``span / 2`` from it (paper 002, Fig. 7). A workpiece compensated with its tilt off by
    ``da`` about X and ``db`` about Y has its surface ``db span / 2`` and ``da span / 2``
    higher or lower at the ends, of either sign: the four depths spread by
    ``s = span max(|da|, |db|)`` (a height error common to all four cancels). With ``da``,
    ``db`` normal of the stated stds and independent,
    ``P(s <= t) = erf(t / (span sigma_alpha sqrt 2)) erf(t / (span sigma_beta sqrt 2))``;
    correlated (the two tilts read the sphere S1 they share), the same rectangle's
    probability is one integral over ``da`` of the normal ``db`` given ``da`` (`quad`).
    Inverted here by bisection. Left out: the depth readings' own noise (nanometres).

    Parameters
    ----------
    sigma_alpha, sigma_beta : float
        Standard uncertainty of the identified alpha and beta (rad).
    span : float
        Distance between opposite groove ends (m).
    quantiles : array_like
        Probabilities in (0, 1).
    correlation : float
        Correlation of the identified alpha and beta, -1 .. 1 (default 0: independent).

    Returns
    -------
    ndarray
        The spread at each quantile (m).
    """
    from scipy.optimize import brentq

    sa, sb, span, rho = _check_spread_inputs(sigma_alpha, sigma_beta, span, correlation)
    q = np.asarray(quantiles, dtype=np.float64)
    if q.size == 0 or not np.all((q > 0.0) & (q < 1.0)):
        raise InputError(f"Expected quantiles in (0, 1), got {quantiles!r}", key="quantiles")
    top = span * max(sa, sb) * 10.0  # erf(10 / sqrt 2) = 1 - 1.5e-23: every quantile below
    return np.array([brentq(lambda t, p=p: _spread_cdf(t, sa, sb, span, rho) - p, 0.0, top,
                            xtol=1e-15, rtol=1e-12) for p in q.ravel()]).reshape(q.shape)


def tilt_spread_quantile(spread: float, sigma_alpha: float, sigma_beta: float,
                         span: float, correlation: float = 0.0) -> float:
    """Which quantile of the spread over labs (`tilt_spread_quantiles`) ``spread`` (m) is:
    the share of labs whose four depths would spread less."""
    sa, sb, span, rho = _check_spread_inputs(sigma_alpha, sigma_beta, span, correlation)
    return float(_spread_cdf(max(float(spread), 0.0), sa, sb, span, rho))
