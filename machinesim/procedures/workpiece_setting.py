"""Paper 002 as an experiment: a robot-loaded workpiece, its setting found and compensated.

`RobotLoadedWorkpiece` runs paper 002's procedure (Xu, Nakamoto, Takeuchi 2021) on a
`machinesim.Lab` (machine ``robonano_a0ib``) whose injected errors are one robot load of
one workpiece: the setting ``workpiece.x .. gamma`` and any other error (the C-axis centre,
``location.C.EX0C``, ``EY0C``). It probes the workpiece's three reference spheres at C = 0
and 180 deg (`read_spheres`, Fig. 4, in
`machinesim.procedures.sphere_probing`), identifies the setting and the C centre
(`machinesim.identification.workpiece_setting`: eqs 1-4, Fig. 6, and the cross-check by
`machinesim.identification.fit`), rewrites the NC program (eqs 5-7 through
`machinesim.compensation.map_program`; the model-based route through
`machinesim.compensation.model_based`; the nose arc's lowest point on the path by default,
the paper's tip on request) and machines one of the paper's two experiments before and
after compensation on the workpiece the lab made (`Lab.make_artefacts`: its spheres where
they really came out), read with the lab's laser microscope:

- ``"grooves"`` (section 3.1): four crossing grooves 3 um deep
  (`machinesim.metrology.part_features.groove_depths`, Fig. 8);
- ``"crown"`` (section 3.2): the finished diamond crown in measuring windows
  (`machinesim.metrology.part_features.crown_features`: Table 3's edge distances L and
  inclinations S) and its machining time.

The two experiments are two workpieces, each loaded by the robot: two labs, one per load
(the robot's landing is part of the truth of that load); `scenarios/workpiece_setting.py`
runs both and reports them together. The figures the readings make, beside the paper's
(Table 3, Fig. 8b, the machining times: `crown_times`, `image_unread`, `planes_unread`), are
`machinesim.procedures.workpiece_setting_figures`'s, importable from here as well.
docs/procedures/workpiece_setting.md has the geometry, the derivations and the figures.

>>> import machinesim
>>> from machinesim.experiment import run
>>> from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece
>>> lab = machinesim.Lab("robonano_a0ib", {"workpiece": {"delta_um": [5, -3, 2]}})
>>> result = run(RobotLoadedWorkpiece("grooves"), lab)  # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

from machinesim.cam.crown import (
    CROWN,
    GROOVE_BLANK,
    GROOVE_ROI,
    GROOVE_SPHERE_DESIGN,
    GROOVE_SPHERES,
    GROOVE_STOCK,
    PARK,
    CrownPlan,
    crown_blank,
    crown_design,
    crown_passes,
    crown_roi,
    crown_sphere_design,
    crown_spheres,
    crown_stock,
    crown_tool,
    groove_program,
    passes_program,
)
from machinesim.cutting import clip_to, cut
from machinesim.exceptions import InputError
from machinesim.experiment import Evaluation, Identified, check_instance, check_lab, fit_notes
from machinesim.identification.fit import Estimate
from machinesim.identification.workpiece_setting import (
    PARAMETERS,
    Identification,
    ReferenceSpheres,
    SphereReadings,
    check_machine,
    fit_setting,
    identify,
    parameters,
)
from machinesim.identification.workpiece_setting_uncertainty import (
    setting_covariance,
    tilt_correlation,
)
from machinesim.metrology._arrays import as_flag
from machinesim.metrology.crown_image import crown_image_reading, turned_placements
from machinesim.metrology.part_features import crown_features, groove_depths
from machinesim.nc import Program
from machinesim.procedures.sphere_probing import (
    PROBE_PLAN,
    ProbePlan,
    probe_axes,
    read_sphere,
    read_spheres,
)
from machinesim.procedures.step_inputs import (
    check_identified,
    check_measurements,
    check_programs,
    refuse,
)
from machinesim.procedures.workpiece_setting_figures import (
    PAPER_GROOVE_SPREAD_NM,  # noqa: F401 (importable from here, as before the split)
    PAPER_L,  # noqa: F401 (importable from here, as before the split)
    PAPER_S,  # noqa: F401 (importable from here, as before the split)
    PAPER_TIME,  # noqa: F401 (importable from here, as before the split)
    SPREAD_QUANTILES,  # noqa: F401 (importable from here, as before the split)
    _identification_details,
    _spread_over_labs,
    crown_figures,
    crown_times,
    groove_figures,
    image_unread,
    planes_unread,
)
from machinesim.procedures.workpiece_setting_programs import (
    eqs_5_to_7_program,
    model_based_program,
)
from machinesim.realism import OBJECTIVE_10X, SphereArtefacts
from machinesim.units import M_PER_MM, M_PER_UM
from machinesim.workpiece import Part, stock_from_spec

__all__ = [
    "EXPERIMENTS", "NOSE", "ProbePlan", "RobotLoadedWorkpiece", "SettingIdentification",
    "crown_times", "image_unread", "planes_unread",
    "WorkpieceMeasurements", "eqs_5_to_7_program", "model_based_program", "probe_axes",
    "read_sphere", "read_spheres",
]

MM, UM = M_PER_MM, M_PER_UM
#: The two experiments of paper 002, each on its own robot-loaded workpiece.
EXPERIMENTS = ("grooves", "crown")
#: Nose radius of Tables 1 and 2's round-nose tool, m.
NOSE = 2.0 * MM
#: The grooves' tool (Table 1).
GROOVE_TOOL = "nose:2.0:90"

# ---------------------------------------------------------------------------- procedure


@dataclass(frozen=True, eq=False)
class WorkpieceMeasurements:
    """What `RobotLoadedWorkpiece.measure` returns.

    Attributes
    ----------
    experiment : str
        ``"grooves"`` or ``"crown"``: which workpiece was loaded.
    machine : Machine
        The machine the probe moved on (its nominal kinematics: the fit cross-check's model).
    readings : SphereReadings
    artefact_scatter : ArtefactScatter or None
        The tolerance the lab states for its reference spheres (`Lab.artefact_scatter`;
        None: made as designed), for the stated uncertainty.
    """

    experiment: str
    machine: object
    readings: SphereReadings
    artefact_scatter: object = None


@dataclass(frozen=True, eq=False)
class SettingIdentification:
    """`RobotLoadedWorkpiece.identify`'s detail: eqs 1-4 and Fig. 6, and the fit's check.

    Attributes
    ----------
    found : Identification
        The paper's formulas.
    check : Estimate
        The same parameters by `machinesim.identification.fit` on the same readings.
    machine : Machine
        The machine the probe moved on (nominal kinematics), for the compensation.
    experiment : str
        Which workpiece's readings it came from (``"grooves"`` or ``"crown"``): a setting
        is one load's, and compensates that workpiece's program only. None in one saved
        (pickled) before this field was kept: which workpiece it was is not known, and each
        workpiece's steps take it, as they did then.
    tilt_correlation : float
        Correlation of the identified alpha and beta over labs, from the same sources as
        their stds (the probe's noise, the spheres' places, each contact): both read
        sphere S1. 0 (independent, as was assumed then) in one saved before it was kept.
    """

    found: Identification
    check: Estimate
    machine: object
    experiment: str | None
    tilt_correlation: float = 0.0

    def __setstate__(self, state: dict) -> None:
        # a detail pickled before `experiment` was kept holds no such key; without it every
        # step that checks the workpiece raised AttributeError on an old saved result
        for name, value in {"experiment": None, "tilt_correlation": 0.0, **state}.items():
            object.__setattr__(self, name, value)

    def agreement(self) -> dict[str, float]:
        """Fit minus eqs for each parameter, SI."""
        paper = parameters(self.found)
        return {name: float(value - paper[name])
                for name, value in zip(self.check.names, self.check.values, strict=True)}


@dataclass(frozen=True)
class _CrownLayout:
    tool: object
    windows: dict
    boxes: list
    rows: dict
    floor: float


class RobotLoadedWorkpiece:
    """Paper 002's procedure on one robot-loaded workpiece (`machinesim.experiment` protocol).

    Parameters
    ----------
    experiment : {"crown", "grooves"}
        Which workpiece the lab's robot loaded (`EXPERIMENTS`).
    nose_correction : bool
        Keep the nose arc's lowest point on the path (default), not the tip as the paper's
        eq 7 does (False: the paper's own route; the scenario reports both).
    all_layers : bool
        Crown: cut all ten 1 um finishing layers, not only the last (the same part, ten
        times longer: docs/procedures/workpiece_setting.md).
    quick : bool
        Crown: smaller measuring windows.
    after_only : bool
        Crown: cut and read only the compensated crown (the "before" figures None): what
        the variants of an error budget need, at half the cost. Grooves: leave out the cut
        on the ideal machine and the model-based route's cut (its details and the part
        ``grooves_ideal`` absent); the figures are those of the whole run.
    plan : ProbePlan
    crown : CrownPlan
    progress : callable(str), optional
        Told, one line at a time, how the crown's cuts and readings go (they take minutes).
    """

    name = "workpiece_setting"
    paper = "002"
    #: What it reads of the lab beyond the machine's errors, by step
    #: (`machinesim.experiment.LAB_USES`): a robot lands the workpiece and the touch probe
    #: reads its spheres; the grooves and the crown are cut with a round nose and read with
    #: the microscope.
    lab_uses = {"measure": ("robot", "touch_probe"), "evaluate": ("tool_geometry", "microscope")}
    #: The `machinesim.realism.Realism` switches it feels, for an error budget: every one
    #: but the laser interferometer's air (it reads no laser).
    realism_sources = ("instrument_noise", "lateral_resolution", "lateral_noise",
                       "registration", "probe_pretravel", "probe_ball_form", "artefact_errors",
                       "background_errors", "stage_positioning")

    def __init__(self, experiment: str = "crown", *, nose_correction: bool = True,
                 all_layers: bool = False, quick: bool = False, after_only: bool = False,
                 plan: ProbePlan = PROBE_PLAN,
                 crown: CrownPlan = CROWN, progress=None) -> None:
        if experiment not in EXPERIMENTS:
            raise InputError(f"Expected an experiment in {', '.join(EXPERIMENTS)}, got "
                             f"{experiment!r}", key="experiment")
        self.experiment = experiment
        # True or False only: bool("off") is True, so nose_correction="off" kept the nose on
        # the path and quick="no" cut the small windows
        self.nose = NOSE if as_flag(nose_correction, "nose_correction") else 0.0
        self.all_layers = as_flag(all_layers, "all_layers")
        self.quick = as_flag(quick, "quick")
        self.after_only = as_flag(after_only, "after_only")
        # plan=None, crown=None failed at measure as bare AttributeErrors ('NoneType' object
        # has no attribute 'half_width', 'oversize'), progress="yes" as a TypeError mid-run
        check_instance(plan, ProbePlan, "plan",
                       "a ProbePlan (machinesim.procedures.sphere_probing), e.g. ProbePlan()")
        check_instance(crown, CrownPlan, "crown",
                       "a CrownPlan (machinesim.cam.crown), e.g. machinesim.cam.crown.CROWN")
        if progress is not None and not callable(progress):
            raise InputError(f"expected progress as a callable taking one str, or None, got "
                             f"{type(progress).__name__} {progress!r}", key="progress")
        self.plan = plan
        self.crown = crown
        self.progress = progress

    def __repr__(self) -> str:
        return (f"RobotLoadedWorkpiece({self.experiment!r}, nose_correction="
                f"{self.nose > 0.0}, quick={self.quick}, all_layers={self.all_layers})")

    @property
    def spheres(self) -> ReferenceSpheres:
        """The loaded workpiece's reference spheres as designed."""
        return GROOVE_SPHERES if self.experiment == "grooves" else crown_spheres(self.crown)

    @cached_property
    def stock(self) -> Part:
        """The loaded workpiece as designed (the groove block, or the rough crown)."""
        return (stock_from_spec(GROOVE_STOCK) if self.experiment == "grooves"
                else crown_stock(self.crown))

    @cached_property
    def blank(self) -> tuple[Part, SphereArtefacts]:
        """The loaded workpiece's blank (without its spheres) and its spheres' design: what
        the lab's workshop is asked to make (`workpiece`)."""
        if self.experiment == "grooves":
            return stock_from_spec(GROOVE_BLANK), GROOVE_SPHERE_DESIGN
        return crown_blank(self.crown), crown_sphere_design(self.crown)

    def workpiece(self, lab) -> Part:
        """The loaded workpiece as the lab's workshop made it: the blank with its spheres
        cut where they really came out (`machinesim.Lab.make_artefacts`, labelled by the
        experiment: one workpiece per lab, made once, and handed back by the lab when asked
        again). The procedure keeps neither the lab nor its workpiece: nothing its
        `identify` can reach leads to them."""
        blank, design = self.blank
        return lab.make_artefacts(blank, design, label=self.experiment)

    # ------------------------------------------------------------------------- the steps

    def measure(self, lab) -> WorkpieceMeasurements:
        """Probe the three spheres at C = 0 and 180 deg (`read_spheres`)."""
        check_lab(lab)
        check_machine(lab.machine)
        probe = lab.touch_probe(self.workpiece(lab), label=self.experiment)
        return WorkpieceMeasurements(self.experiment, lab.machine,
                                     read_spheres(probe, self.spheres, self.plan),
                                     lab.artefact_scatter)

    def identify(self, measurements: WorkpieceMeasurements) -> Identified:
        """Eqs 1-4 and Fig. 6. Each std holds, in quadrature, the fit cross-check's (the
        probe's stated noise propagated to first order through the same readings), the
        spheres' stated tolerance of place through eqs 1-4 (`design_std`) and what is
        stated of each contact: the probe's pre-travel and ball form, the spheres' form
        (`contact_std`)."""
        check_measurements(measurements, "RobotLoadedWorkpiece", WorkpieceMeasurements)
        self._check_experiment("identify", "measurements", measurements.experiment)
        readings = measurements.readings
        found = identify(readings)
        check = fit_setting(measurements.machine, readings, found)
        scatter = measurements.artefact_scatter
        covariance = setting_covariance(check, found, readings, scatter)
        std = {name: math.sqrt(covariance[i, i]) for i, name in enumerate(PARAMETERS)}
        return Identified({name: (value, std[name]) for name, value in
                           parameters(found).items()},
                          SettingIdentification(found, check, measurements.machine,
                                                measurements.experiment,
                                                tilt_correlation(covariance)),
                          notes=fit_notes("fit_setting", check, sigma_leaves_out=(
                              "the spheres' stated place and form scatter"
                              if scatter is not None else None)))

    def compensate(self, identified: Identified) -> dict[str, Program]:
        """The experiment's program rewritten by eqs 5-7 (and, for the grooves, also by the
        model-based route, which the paper does not have)."""
        self._check_identified("compensate", identified)
        found, machine = identified.detail.found, identified.detail.machine
        nominal = self.nominal_program(found)
        programs = {f"{self.experiment}_compensated":
                    eqs_5_to_7_program(nominal, machine, found, self.nose)}
        if self.experiment == "grooves":
            programs["grooves_compensated_model"] = model_based_program(nominal, machine,
                                                                        found, self.nose)
        return programs

    def evaluate(self, lab, identified: Identified, programs) -> Evaluation:
        """Cut before and after compensation, read with the lab's microscope."""
        check_lab(lab)
        self._check_identified("evaluate", identified)
        check_programs(programs, "RobotLoadedWorkpiece", self._compensated_names())
        found = identified.detail.found
        extra = {"identification": _identification_details(identified),
                 "nose_correction_mm": self.nose / MM}
        if self.experiment == "grooves":
            evaluation = self._grooves(lab, programs)
            extra.update(_spread_over_labs(identified, evaluation))
        else:
            evaluation = self._crown(lab, found, programs)
        return replace(evaluation, details={**evaluation.details, **extra})

    def _check_identified(self, step: str, identified) -> None:
        check_identified(identified, "RobotLoadedWorkpiece", step, SettingIdentification)
        self._check_experiment(step, "identified", identified.detail.experiment)

    def _check_experiment(self, step: str, key: str, experiment) -> None:
        """Refuse in ``step`` what ``key`` holds of another workpiece (``experiment``) than
        this procedure's: its setting is another load's, its spheres other spheres. None (a
        setting saved before it named its workpiece) is taken: nothing says whose it is."""
        if experiment is not None and experiment != self.experiment:
            what, made = {"measurements": ("measurements", "measure(lab)"),
                          "identified": ("Identified", "identify(measurements)")}[key]
            refuse("RobotLoadedWorkpiece", step, key,
                   f"the {what} of the {self.experiment!r} workpiece (RobotLoadedWorkpiece("
                   f"{self.experiment!r}).{made} returned)",
                   f"{'those' if key == 'measurements' else 'one'} of the {experiment!r} "
                   "workpiece")

    def _compensated_names(self) -> tuple[str, ...]:
        """The programs of `compensate` that `evaluate` cuts."""
        if self.experiment == "crown":
            return ("crown_compensated",)
        return ("grooves_compensated",) + (() if self.after_only
                                           else ("grooves_compensated_model",))

    # ----------------------------------------------------------------------- programs

    def _tell(self, text: str) -> None:
        if self.progress is not None:
            self.progress(text)

    def _tell_sweeps(self, what: str):
        """A cutter's ``progress(done, total)`` told as lines, or None without ``progress``."""
        if self.progress is None:
            return None
        return lambda done, total: self._tell(f"{what}: cut {done} of {total} feed sweeps")

    def nominal_program(self, found: Identification) -> Program:
        """The experiment's NC program for the ideal workpiece. The crown's passes are those
        that reach its measuring windows, for the deepest cut the identified setting allows
        (`layout`)."""
        if self.experiment == "grooves":
            return groove_program()
        layout = self.layout(found)
        offsets = None if self.all_layers else [0.0]
        return passes_program(crown_passes(self.crown, offsets, **layout.rows))

    def layout(self, found: Identification) -> _CrownLayout:
        """The crown's tool, windows, cut boxes, pass rows and floor for the found setting.

        The deepest cut the misplaced crown can see (stock allowance, height error, the tilt
        over the crown's 4 mm, and a face moved inward by the C centre e: face k's passes
        stand e . n_k - e_x out, at most e_x + |e| in) sets the tool profile's height and
        how far from a window a pass still cuts it; the identified setting stands for the
        actual one (to nm).
        """
        crown, s = self.crown, found.setting
        e = found.c_centre
        inward = max(0.0, float(e[0]) + math.hypot(*e)) * math.tan(crown.slope)
        deepest = (crown.oversize + abs(s.delta[2]) + 4 * MM * math.hypot(s.alpha, s.beta)
                   + inward + 5 * UM)
        sizes = {"top": 0.15 * MM, "side": 0.1 * MM} if self.quick else {}
        windows, boxes, rows = crown_roi(crown, margin=math.sqrt(2 * NOSE * deepest), **sizes)
        # the windows are cut and kept below the flat as deep as the deepest cut, and more
        floor = crown.rough_flat - max(0.1 * MM, 2 * deepest)
        return _CrownLayout(crown_tool(max(50 * UM, 1.2 * deepest)), windows, boxes, rows,
                            floor)

    # ---------------------------------------------------------------------- experiments

    def _grooves(self, lab, programs) -> Evaluation:
        scope = lab.microscope(label="grooves")
        nominal = groove_program()
        parts, depths, cuts = {}, {}, {}
        if not self.after_only:
            parts["grooves_ideal"], _ = cut(nominal, lab.machine, GROOVE_TOOL, self.stock, None,
                                            roi=GROOVE_ROI, start=PARK)
        runs = (("before", nominal), ("after", programs["grooves_compensated"]),
                ("after_model", programs["grooves_compensated_model"]))
        # after_only: the before part is still read, first, so that the after part's readings
        # draw from the one microscope session as in the whole run
        for name, program in runs[:2] if self.after_only else runs:
            part, report = lab.cut(program, GROOVE_TOOL, self.workpiece(lab), roi=GROOVE_ROI,
                                   start=PARK, progress=self._tell_sweeps(f"grooves {name}"))
            depths[name] = groove_depths(part, scope)
            cuts[f"grooves_{name}"] = _cut_details(report)
            if name != "after_model":
                parts[f"grooves_{name}"] = part
        figures, details = groove_figures(depths, self.after_only)
        details = {**details, "cuts": cuts}
        return Evaluation(figures, details, parts, {"grooves_nominal": nominal})

    def _crown(self, lab, found: Identification, programs) -> Evaluation:
        crown = self.crown
        layout = self.layout(found)
        nominal = self.nominal_program(found)
        features, images, parts, cuts = {}, {}, {}, {}
        runs = (("before", nominal), ("after", programs["crown_compensated"]))
        for name, program in runs[1:] if self.after_only else runs:
            # The crown tool's profile is cut short above the depths it cuts (`crown_tool`):
            # its top is not a holder, so a side pass whose top runs under the face uphill
            # of it is no crash (the cutter lists such passes instead of refusing them).
            part, report = lab.cut(program, layout.tool, self.workpiece(lab),
                                   roi=layout.boxes, allow_holder_contact=True,
                                   floor=layout.floor, start=PARK, turn_step=math.pi / 4,
                                   progress=self._tell_sweeps(f"crown {name} compensation"))
            self._tell(f"crown {name} compensation: reading it (plane fits, 10x images)")
            # One microscope session per part (each put on the stage anew), so the after
            # part's readings draw the same whether or not the before part was read (the
            # error budget's variants read only the after part).
            scope = lab.microscope(label=f"crown_{name}")
            meshes = turned_placements(part)
            features[name] = crown_features(part, scope, layout.windows, meshes=meshes,
                                            plan=crown)
            # Table 3 as the paper reads it: edges picked in 10x images (its own session)
            images[name] = crown_image_reading(
                part, lab.microscope(label=f"crown_{name}_image", objective=OBJECTIVE_10X),
                layout.windows, crown, meshes=meshes)
            parts[f"crown_{name}"] = part
            cuts[f"crown_{name}"] = _cut_details(report)
        parts["crown_design"] = clip_to(crown_design(crown), layout.boxes, layout.floor)
        figures, details = crown_figures(lab.machine, crown, features, images)
        details = {**details,
                   "cuts": cuts,
                   "note": "crown cut in its measuring windows"
                   + (", every layer" if self.all_layers else ", last finishing layer only")}
        return Evaluation(figures, details, parts, {"crown_nominal": nominal})


def _cut_details(report) -> dict:
    return {"machining_time_s": report.machining_time_s, "sweeps_count": report.sweeps,
            "sideways_sweeps_count": report.sideways_sweeps,
            "rapids_that_cut_count": len(report.rapids_that_cut),
            "removed_volume_mm3": report.removed_volume_m3 * 1e9, "elapsed_s": report.elapsed_s}
