"""Paper 002's report: the two robot loads' results as one, and its tables, plots and views.

`scenarios/workpiece_setting.py` runs the two loads (`machinesim.procedures.workpiece_setting`)
and writes their report folder (`machinesim.report.ReportFolder`): `combined` makes the one
result the report is written from (the crown's load, the grooves' figures, parts and programs
added), and the table functions write Table 3 of the paper beside the simulated one, the groove
depths, the identification and its cross-check by the generic fit and the machining times; `views`
and `groove_plot` the HTML views and the groove depths' plot. They read the runs' results only
(the injected values the results carry for the report), never a lab.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from types import MappingProxyType

from machinesim.identification.workpiece_setting import PARAMETERS
from machinesim.report import ReportFolder
from machinesim.units import M_PER_NM, M_PER_UM
from machinesim.viewer import part_scene, write_html

__all__ = ["TABLE3_ROWS", "VIEW_TRIANGLES", "combined", "fit_table", "groove_plot",
           "groove_table", "identification_table", "table3_table", "time_table", "views"]

UM = M_PER_UM
#: Display budget of each HTML view: ~1 MB files, enough for a 3 mm window.
VIEW_TRIANGLES = 40_000


def combined(results, routes):
    """One result for the report: the crown's load (Table 3, the flagship: its injected and
    identified parameters) with the grooves' figures, parts and programs added, the
    grooves' load under ``details.grooves_load``, and both loads' fit notes, each led by
    its load."""
    crown, grooves = results["crown"], results["grooves"]
    details = {"crown": dict(crown.evaluation.details),
               "grooves": dict(grooves.evaluation.details),
               "grooves_load": [{"name": name, **_si(name, "injected",
                                                     grooves.injected.get(name, 0.0)),
                                 **_si(name, "identified", value), **_si(name, "std", std)}
                                for name, (value, std) in grooves.identified.items()],
               "routes": routes,
               "note": "two robot loads, one lab each: injected and identified are the "
               "crown's load; the grooves' load is in grooves_load"}
    evaluation = replace(crown.evaluation, figures=crown.figures + grooves.figures,
                         details=MappingProxyType(details),
                         parts=MappingProxyType({**crown.evaluation.parts,
                                                 **grooves.evaluation.parts}),
                         programs=MappingProxyType({**crown.evaluation.programs,
                                                    **grooves.evaluation.programs}))
    elapsed = {**crown.elapsed_s, **{f"grooves_{k}": v for k, v in grooves.elapsed_s.items()}}
    notes = tuple(f"{load} load, {note}" for load in ("crown", "grooves")
                  for note in results[load].notes)
    return replace(crown, figures=evaluation.figures, evaluation=evaluation,
                   programs=MappingProxyType({**crown.programs, **grooves.programs}),
                   elapsed_s=MappingProxyType(elapsed),
                   identification=replace(crown.identification, notes=notes))


def _si(name: str, key: str, value: float) -> dict:
    unit = "rad" if name.split(".")[-1] in ("alpha", "beta", "gamma") else "m"
    return {f"{key}_{unit}": value}


def views(folder: ReportFolder, result) -> None:
    parts = result.evaluation.parts
    for work, reference in (("grooves", "grooves_ideal"), ("crown", "crown_design")):
        for name in ("before", "after"):
            write_html(part_scene(parts[f"{work}_{name}"], parts[reference],
                                  title=f"paper 002 {work}, {name} compensation",
                                  max_triangles=VIEW_TRIANGLES),
                       folder.path / f"{work}_{name}.html")
            folder.files.append(f"{work}_{name}.html")


def groove_plot(folder: ReportFolder, details) -> None:
    stations = details["groove_stations_mm"]
    folder.plot("groove_depths.png",
                [(f"{w}, C = {90 * k} deg", stations, details[f"groove_depths_{w}_um"][k])
                 for w in ("before", "after") for k in range(4)],
                xlabel="distance from the crossing (mm)", ylabel="groove depth (um)",
                title="Depth along each groove", hlines=[(3.0, "programmed 3 um")])


#: Table 3's rows: figure name stem -> label prefix. First the paper's readings (edges in
#: 10x images), then the plane fits and the feet (not in the paper).
TABLE3_ROWS = {"edge_distance": "", "inclination": "", "edge_distance_planes": "planes: ",
               "inclination_planes": "planes: ", "foot_distance": "feet: "}


def table3_table(folder: ReportFolder, crown) -> str:
    rows, unread = [], []
    details = crown.evaluation.details
    for f in crown.figures:
        match = re.fullmatch(r"(.+?)_([LS]\d.*)", f.name)
        if match is None or match[1] not in TABLE3_ROWS:
            continue
        unit = "um" if match[2].startswith("L") else "deg"
        label = f"{TABLE3_ROWS[match[1]]}{match[2].replace('_', ' and ')} ({unit})"
        rows.append([label, "" if f.paper_before is None else f.paper_before,
                     "" if f.paper_after is None else f.paper_after,
                     "n/a" if f.before is None else f.before,
                     "n/a" if f.after is None else f.after])
        # an n/a the 10x images or the plane fits could not read: why (the evaluation's
        # details)
        unread += [f"- {label}, simulated {state}: {why}" for state in ("before", "after")
                   for how in ("image", "planes")
                   if (why := details.get(f"crown_{state}_{how}_unread", {}).get(f.name))]
    return folder.write_table(
        "table3", ["measured parameter", "paper before", "paper after", "simulated before",
                   "simulated after"], rows,
        title="Paper 002, Table 3: machining errors of the crown (edge distances um, "
        "inclinations deg)", digits=4,
        note="n/a: not read (the 10x images, the plane fits), where\n" + "\n".join(unread)
        if unread else "")


def groove_table(folder: ReportFolder, grooves) -> str:
    details = grooves.evaluation.details
    model = details["groove_end_depths_after_model_um"]
    figures = [grooves.figure(f"groove_depth_C{90 * k}") for k in range(4)]
    # an end where no groove was cut: why (the evaluation's details)
    unread = [f"- C = {90 * k} deg, simulated {state}: {why}" for k in range(4)
              for state in ("before", "after")
              if (why := details.get(f"groove_{state}_unread", {}).get(f"groove_depth_C{90 * k}"))]
    spread = grooves.figure("groove_depth_spread")

    def cell(value):  # None: an end where no groove was cut (the note says why)
        return "n/a" if value is None else value

    rows = [[f"C = {90 * k} deg", cell(f.before), cell(f.after), cell(model[k])]
            for k, f in enumerate(figures)]
    rows.append(["spread of the four (nm)", cell(spread.before), cell(spread.after),
                 cell(details["groove_depth_spread_after_model_nm"])])
    labs = details.get("groove_spread_after_over_labs")
    if labs is not None:
        # docs/procedures/workpiece_setting.md: one run is one draw of the lab
        rows += [["spread over labs of the stated tilts: median (nm)", "", labs["median_nm"],
                  ""],
                 ["  10 % and 90 % of labs below (nm)", "",
                  f"{labs['q10_nm']:.3g} and {labs['q90_nm']:.3g}", ""],
                 ["  share of labs below this run's spread, the paper's 100 nm", "",
                  (f"{labs['simulated_quantile_ratio']:.0%}"
                   if "simulated_quantile_ratio" in labs else "n/a")
                  + f", {labs['paper_quantile_ratio']:.0%}", ""]]
        if "tilt_correlation_ratio" in labs:  # not in a report written before it was kept
            rows.append(["  the two tilts' stated correlation (both read sphere S1)", "",
                         f"{labs['tilt_correlation_ratio']:.2f}", ""])
    return folder.write_table(
        "grooves", ["groove", "before (um)", "after, eqs 5-7 (um)", "after, model-based (um)"],
        rows, title="Depth at the end of each groove (3 um programmed; paper Fig. 8b: "
        "within about 100 nm of each other after)", digits=4,
        note="n/a: no groove cut there, where\n" + "\n".join(unread) if unread else "")


def identification_table(folder: ReportFolder, results) -> str:
    """Injected and identified setting and C centre of each load, the error beside the std
    the procedure states (docs/procedures/workpiece_setting.md, "Stated uncertainty")."""
    rows = []
    for load, result in results.items():
        truth = result.injected
        found = result.identification.detail.found
        std = {name: s for name, (_, s) in result.identified.items()}
        s = found.setting
        for i, a in enumerate("xyz"):
            t = truth.get(f"workpiece.{a}", 0.0)
            rows.append([f"{load}: delta {a}", t / UM, s.delta[i] / UM,
                         (s.delta[i] - t) / M_PER_NM, std[f"workpiece.{a}"] / M_PER_NM, "nm"])
        for a in ("alpha", "beta", "gamma"):
            t, g = truth.get(f"workpiece.{a}", 0.0), getattr(s, a)
            rows.append([f"{load}: {a} (deg, urad)", math.degrees(t), math.degrees(g),
                         (g - t) * 1e6, std[f"workpiece.{a}"] * 1e6, "urad"])
        for i, a in enumerate("XY"):
            name = f"location.C.E{a}0C"
            t = truth.get(name, 0.0)
            rows.append([f"{load}: C centre {a.lower()}", t / UM, found.c_centre[i] / UM,
                         (found.c_centre[i] - t) / M_PER_NM, std[name] / M_PER_NM, "nm"])
    return folder.write_table(
        "identification", ["quantity (um unless stated)", "injected", "identified", "error",
                           "std", "error unit"], rows,
        title="Workpiece setting errors: injected and identified", digits=4)


def fit_table(folder: ReportFolder, results) -> str:
    rows = []
    for load in ("grooves", "crown"):
        detail = results[load].identification.detail
        agreement = detail.agreement()
        eqs = dict(results[load].identified)
        for name, value, std in zip(detail.check.names, detail.check.values,
                                    detail.check.std, strict=True):
            angle = name.split(".")[-1] in ("alpha", "beta", "gamma")
            scale, unit = (1e-6, "urad") if angle else (M_PER_NM, "nm")
            rows.append([f"{load}: {name}", eqs[name][0] / scale, value / scale,
                         agreement[name] / scale, std / scale, unit])
    return folder.write_table(
        "fit_check", ["parameter", "eqs 1-4, Fig. 6", "fit", "fit - eqs", "fit std", "unit"],
        rows, title="Cross-check: the generic fit (machinesim.identification.fit) on the same "
        f"probe readings ({', '.join(PARAMETERS)})", digits=4)


def time_table(folder: ReportFolder, crown) -> str:
    time, saved = crown.figure("machining_time"), crown.figure("machining_time_saved")
    return folder.write_table(
        "machining_time", ["crown", "paper (h)", "simulated (h)"],
        [["finishing the rough crown (10 x 1 um)", time.paper_after, time.after],
         ["from the cuboid, same passes", time.paper_before, time.before],
         ["time saved (%)", saved.paper_after, saved.after]],
        title="Machining time from the feeds (motion.plan), 12 min of setting included",
        digits=2)
