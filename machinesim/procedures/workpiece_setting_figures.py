"""Paper 002's figures: the grooves' and the crown's readings made into the report's figures
and details, beside the paper's own.

`RobotLoadedWorkpiece.evaluate` (`machinesim.procedures.workpiece_setting`) cuts and reads the
parts; here its readings become figures: the grooves' depths and their spread against
Fig. 8b (`groove_figures`, and `_spread_over_labs`, where that spread falls among labs with
the stated tilt uncertainty), the crown's edge distances L and inclinations S against
Table 3, read as the paper reads them (10x images) and from fitted planes, with why a figure
is n/a (`crown_figures`, `image_unread`, `planes_unread`), the machining times of section
3.2.4 (`crown_times`), and the identification's own quantities with the fit's agreement
(`_identification_details`). docs/procedures/workpiece_setting.md has the figures.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.cam.crown import CROWN, SETTING_S, CrownPlan, crown_passes, machining_time
from machinesim.experiment import Evaluation, Figure, Identified
from machinesim.identification.workpiece_setting_uncertainty import (
    tilt_spread_quantile,
    tilt_spread_quantiles,
)
from machinesim.metrology.crown_image import CrownImageReading
from machinesim.metrology.part_features import UNCUT_DEPTH, CrownFeatures, GrooveDepths
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM

__all__ = [
    "PAPER_GROOVE_SPREAD_NM", "PAPER_L", "PAPER_S", "PAPER_TIME", "SPREAD_QUANTILES",
    "crown_figures", "crown_times", "groove_figures", "image_unread", "planes_unread",
]

MM, UM = M_PER_MM, M_PER_UM

#: Table 3 of paper 002: errors before and after compensation (um for L, deg for S).
PAPER_L = {"L1_L5": (149.15, -0.31), "L2_L6": (152.60, 0.82), "L3_L7": (138.43, -1.69),
           "L4_L8": (163.21, 1.14)}
PAPER_S = ((-1.73, -0.10), (0.95, 0.05), (2.30, 0.02), (0.93, 0.03), (-1.56, 0.04),
           (-1.53, 0.03), (-2.06, -0.17), (-1.35, -0.08))
#: Section 3.2.4: machining time of the finishing, from the cuboid, and the saving.
PAPER_TIME = {"finishing_h": 9.5, "cuboid_h": 40.0, "saved_percent": 76.0}
#: Fig. 8b: the four grooves' depths "within about 100 nm" of each other after.
PAPER_GROOVE_SPREAD_NM = 100.0


def groove_figures(depths: dict[str, GrooveDepths], after_only: bool = False
                   ) -> tuple[tuple[Figure, ...], dict]:
    """The grooves' figures (each end's depth before and after, and their spread against
    Fig. 8b) and details (the depths at every station, the model-based route's unless
    ``after_only``), from `groove_depths` of the parts ``"before"``, ``"after"`` and
    ``"after_model"``. An end where no groove was cut (`GrooveDepths.uncut`: it reads the
    top face) is n/a, and so is the spread of that state, the note saying which and what
    was read: a depth of the face's noise is no groove's depth."""
    before, after = depths["before"], depths["after"]
    unread = {name: groove_unread(d) for name, d in (("before", before), ("after", after))}

    def end(d: GrooveDepths, k: int):
        return None if d.uncut[k, -1] else float(d.ends[k] / UM)

    def spread(d: GrooveDepths):
        return None if d.uncut[:, -1].any() else float(np.ptp(d.ends) / M_PER_NM)

    def why(k: int) -> str:
        return "".join(f"; {name} n/a: {texts[k]}" for name, texts in unread.items()
                       if k in texts)

    uncut_ends = "".join(
        f"; {name} n/a: no groove cut at the end of the groove at C = "
        f"{', '.join(str(90 * k) for k in texts)} deg" for name, texts in unread.items() if texts)

    figures = [Figure(f"groove_depth_C{90 * k}", "um", end(before, k), end(after, k),
                      note="depth at the end of the groove cut at "
                      f"C = {90 * k} deg (3 um programmed){why(k)}") for k in range(4)]
    figures.append(Figure("groove_depth_spread", "nm", spread(before), spread(after),
                          paper_after=PAPER_GROOVE_SPREAD_NM,
                          note=f"paper Fig. 8b: within about 100 nm of each other{uncut_ends}"))
    details = {"groove_stations_mm": (before.stations / MM).tolist(),
               **{f"groove_depths_{name}_um": (d.depths / UM).tolist()
                  for name, d in depths.items()},
               **{f"groove_uncut_stations_{name}_count": d.uncut.sum(axis=1).tolist()
                  for name, d in depths.items()},
               **{f"groove_{name}_unread": {f"groove_depth_C{90 * k}": text
                                            for k, text in texts.items()}
                  for name, texts in unread.items() if texts},
               **({} if after_only else {
                   "groove_depth_spread_after_model_nm": spread(depths["after_model"]),
                   "groove_end_depths_after_model_um": [end(depths["after_model"], k)
                                                        for k in range(4)]})}
    return tuple(figures), details


def groove_unread(d: GrooveDepths) -> dict[int, str]:
    """Why each groove's end (k: cut at C = 90 k deg) is not read, for those not cut there."""
    return {k: f"no groove at its end: it reads {d.ends[k] / UM * 1e3:.1f} nm deep, less than "
               f"the {UNCUT_DEPTH / UM * 1e3:.0f} nm a cut groove reads, the top face (not cut "
               f"at {int(d.uncut[k].sum())} of its {d.uncut.shape[1]} stations: the tool above "
               "the face there, the block set low or tilted, tool.z?)"
            for k in range(4) if d.uncut[k, -1]}


def crown_figures(machine, crown: CrownPlan, features: dict[str, CrownFeatures],
                  images: dict[str, CrownImageReading]) -> tuple[tuple[Figure, ...], dict]:
    """The crown's figures (Table 3's L and S as the paper reads them and from the fitted
    planes, the foot distances, the machining times) and details, from `crown_features` and
    `crown_image_reading` of the parts ``"after"`` and, when read, ``"before"``; a figure
    not read says why in its note."""
    errors = {name: {**_crown_errors(f, crown), **_image_errors(images[name], crown)}
              for name, f in features.items()}
    errors.setdefault("before", dict.fromkeys(("edge", "inclination", "foot", "edge_image",
                                               "inclination_image"), [None] * 8))
    # a figure the images could not read (n/a) says why: which face's profile, what it
    # found (a face left uncut by a setting far off: its profile never falling from the top,
    # or lying where the rough face does)
    unread = image_unread(images)
    # and a plane fit on a window that holds no cut face (a face left uncut, or a band of
    # stock): the face's fitted slope, residual or place (where the rough face lies)
    planes = planes_unread(features)
    whys = {name: {**unread[name], **planes[name]} for name in images}

    def why(figure: str) -> str:
        return "".join(f"; {name} not read: {whys[name][figure]}"
                       for name in images if figure in whys[name])

    figures = []
    for i, (key, (paper_before, paper_after)) in enumerate(PAPER_L.items()):
        figures.append(Figure(f"edge_distance_{key}", "um",
                              errors["before"]["edge_image"][i],
                              errors["after"]["edge_image"][i], paper_before, paper_after,
                              note="distance between opposite top edges less its design, "
                              "as the paper reads it: two points on one edge and one on "
                              "the other in 10x images, mean of three readings"
                              + why(f"edge_distance_{key}")))
    for i, (paper_before, paper_after) in enumerate(PAPER_S):
        figures.append(Figure(f"inclination_S{i + 1}", "deg",
                              errors["before"]["inclination_image"][i],
                              errors["after"]["inclination_image"][i], paper_before,
                              paper_after,
                              note=f"side face at C = {45 * i} deg, angle to the flat "
                              "less its design, as the paper reads it: height over "
                              "length between the edges of a 10x profile"
                              + why(f"inclination_S{i + 1}")))
    for i, key in enumerate(PAPER_L):
        figures.append(Figure(f"edge_distance_planes_{key}", "um",
                              errors["before"]["edge"][i], errors["after"]["edge"][i],
                              note="distance between the lines where the fitted side "
                              "planes meet the fitted top plane, less its design "
                              "(not in the paper)" + why(f"edge_distance_planes_{key}")))
    for i in range(8):
        figures.append(Figure(f"inclination_planes_S{i + 1}", "deg",
                              errors["before"]["inclination"][i],
                              errors["after"]["inclination"][i],
                              note=f"side face at C = {45 * i} deg: angle between the "
                              "fitted side and flat planes less its design (not in the "
                              "paper)" + why(f"inclination_planes_S{i + 1}")))
    for i, key in enumerate(PAPER_L):
        figures.append(Figure(f"foot_distance_{key}", "um", errors["before"]["foot"][i],
                              errors["after"]["foot"][i],
                              note="distance between opposite foot edges less its design "
                              "(not in the paper)" + why(f"foot_distance_{key}")))
    finishing, cuboid = crown_times(machine, crown)
    saved = 100.0 * (1.0 - finishing / cuboid)
    figures.append(Figure("machining_time", "h", cuboid / 3600.0, finishing / 3600.0,
                          PAPER_TIME["cuboid_h"], PAPER_TIME["finishing_h"],
                          note="12 min of setting included; before: the crown cut from "
                          "the cuboid with the same passes; after: finishing the "
                          "robot-loaded rough crown"))
    figures.append(Figure("machining_time_saved", "percent", None, saved, None,
                          PAPER_TIME["saved_percent"]))
    details = {**{f"crown_{name}_{kind}": values for name, e in errors.items()
                  if name in features
                  for kind, values in (("edge_distance_error_um", e["edge"]),
                                       ("inclination_error_deg", e["inclination"]),
                                       ("foot_distance_error_um", e["foot"]),
                                       ("image_edge_distance_error_um", e["edge_image"]),
                                       ("image_inclination_error_deg",
                                        e["inclination_image"]))},
               "machining_time": {"finishing_h": finishing / 3600.0,
                                  "cuboid_h": cuboid / 3600.0, "saved_percent": saved,
                                  "setting_h": SETTING_S / 3600.0},
               **{f"crown_{name}_image_unread": whys
                  for name, whys in unread.items() if whys},
               **{f"crown_{name}_planes_unread": whys
                  for name, whys in planes.items() if whys}}
    return tuple(figures), details


_TIMES: dict = {}


def crown_times(machine, crown: CrownPlan = CROWN) -> tuple[float, float]:
    """Section 3.2.4's two times, s, each with the paper's 12 min of setting (`SETTING_S`):
    finishing the rough crown (Table 2's ten layers) and cutting it from the cuboid with the
    same passes (`machinesim.cam.crown.machining_time`; remembered per machine and plan)."""
    key = (machine.name, crown)
    if key not in _TIMES:
        _TIMES[key] = (machining_time(machine, crown_passes(crown)) + SETTING_S,
                       machining_time(machine, crown_passes(crown, cuboid=True)) + SETTING_S)
    return _TIMES[key]


def image_unread(images: dict[str, CrownImageReading]) -> dict[str, dict[str, str]]:
    """Why each Table 3 figure the 10x images could not read is n/a, per reading
    (``"before"``, ``"after"``), keyed by figure name (``edge_distance_L2_L6``,
    ``inclination_S2``): `CrownImageReading.unread`'s reasons, read by the crown's figures
    as their notes and by the scenario under its Table 3."""
    return {name: {f"{'edge_distance' if key[0] == 'L' else 'inclination'}_{key}": why
                   for key, why in reading.unread.items()}
            for name, reading in images.items()}


def planes_unread(features: dict[str, CrownFeatures]) -> dict[str, dict[str, str]]:
    """Why each plane-fit figure is n/a, per reading, keyed by figure name
    (``inclination_planes_S2``, ``edge_distance_planes_L2_L6``, ``foot_distance_L2_L6``):
    `CrownFeatures.unread`'s reasons, used as `image_unread`'s."""
    return {name: {figure: why for key, why in reading.unread.items()
                   for figure in ((f"edge_distance_planes_{key}", f"foot_distance_{key}")
                                  if key[0] == "L" else (f"inclination_planes_{key}",))}
            for name, reading in features.items()}


def _crown_errors(features: CrownFeatures, plan: CrownPlan) -> dict[str, list[float]]:
    return {"edge": ((features.edge_distances - 2 * plan.apothem) / UM).tolist(),
            "inclination": np.degrees(features.inclinations - plan.slope).tolist(),
            "foot": ((features.foot_distances - plan.foot_distance) / UM).tolist()}


def _image_errors(reading: CrownImageReading, plan: CrownPlan) -> dict[str, list[float]]:
    return {"edge_image": ((reading.edge_distances - 2 * plan.apothem) / UM).tolist(),
            "inclination_image": np.degrees(reading.inclinations - plan.slope).tolist()}


#: Quantiles of the grooves' spread over labs in the report (`_spread_over_labs`).
SPREAD_QUANTILES = {"q10": 0.1, "median": 0.5, "q90": 0.9}


def _spread_over_labs(identified: Identified, grooves: Evaluation) -> dict:
    """The grooves' spread after compensation as labs with the stated tilt uncertainty
    would cut it (`tilt_spread_quantiles`, with the tilts' stated correlation; the ends read
    farthest out, 2 x the last station, apart), and where the paper's spread falls among
    them."""
    sa = identified.parameters["workpiece.alpha"][1]
    sb = identified.parameters["workpiece.beta"][1]
    if not (math.isfinite(sa) and math.isfinite(sb)) or (sa == 0.0 and sb == 0.0):
        return {}
    # both tilts read sphere S1: correlated (0 in a result saved before it was kept)
    rho = getattr(identified.detail, "tilt_correlation", 0.0)
    span = 2.0 * grooves.details["groove_stations_mm"][-1] * MM
    found = next(f.after for f in grooves.figures if f.name == "groove_depth_spread")
    spread = tilt_spread_quantiles(sa, sb, span, list(SPREAD_QUANTILES.values()), rho)
    over_labs = {f"{name}_nm": value / M_PER_NM
                 for name, value in zip(SPREAD_QUANTILES, spread.tolist(), strict=True)}
    over_labs["paper_quantile_ratio"] = tilt_spread_quantile(
        PAPER_GROOVE_SPREAD_NM * M_PER_NM, sa, sb, span, rho)
    if found is not None:  # None: an end not cut (`groove_figures`)
        over_labs["simulated_quantile_ratio"] = tilt_spread_quantile(
            found * M_PER_NM, sa, sb, span, rho)
    over_labs["tilt_correlation_ratio"] = rho
    return {"groove_spread_after_over_labs": over_labs}


def _identification_details(identified: Identified) -> dict:
    """The paper's own quantities and the fit's agreement, units in the keys."""
    detail = identified.detail
    found, check = detail.found, detail.check
    s = found.setting
    agreement = detail.agreement()
    return {"delta_um": (s.delta / UM).tolist(), "alpha_deg": math.degrees(s.alpha),
            "beta_deg": math.degrees(s.beta), "gamma_deg": math.degrees(s.gamma),
            "s1_offset_um": (found.delta / UM).tolist(),
            "c_centre_um": (found.c_centre / UM).tolist(),
            "sphere_radius_mm": found.radius / MM,
            "fit_minus_eqs": {
                "position_nm": [agreement[f"workpiece.{a}"] / M_PER_NM for a in "xyz"],
                "angles_urad": [agreement[f"workpiece.{a}"] * 1e6
                                for a in ("alpha", "beta", "gamma")],
                "c_centre_nm": [agreement[f"location.C.E{a}0C"] / M_PER_NM for a in "XY"]},
            "fit_rank_count": check.rank, "fit_condition_ratio": check.condition,
            "fit_normalised_residual_rms_ratio": check.normalised_residual_rms}
