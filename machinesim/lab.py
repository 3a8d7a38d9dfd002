"""The lab: a machine with its injected errors in its room, and the instruments beside it.

A `Lab` stands for the real machine. It keeps the injected errors (the truth) privately, cuts
programs on the machine that has them, and hands out instruments bound to it. Nothing a
procedure can call returns the truth: a lab answers only by cutting and by measuring, as a
real one does (the honesty rule of DESIGN.md). The truth comes out through one named call,
`Lab.reveal`, meant for reports and tests; the identification and compensation code never
calls it, and a test scans them to keep it so. The checks of what a lab's calls are given,
and of its attributes fixed when made, are in `machinesim.lab_checks`.

Noise. Each instrument draws its noise from its own stream, derived from the lab's seed, the
instrument's kind and its label (`machinesim.streams.stream`). A reading therefore depends on
(seed, kind, label) and on what was read with that same instrument before it, never on the
readings of another: adding a microscope reading does not change what the probe reads.
Instruments handed out without a label are numbered per kind in the order they are asked
for ("microscope/0", "microscope/1", ...); give a label to make a stream independent of
that order too.

Realism. By default the lab is exact but for its instruments' noise. ``realism=`` (a
`machinesim.realism.Realism`) switches on, one by one, what a real lab adds: the optical
instruments' spot, lateral noise and registration, the probe's pre-travel and ball form, the
laser interferometer's beam alignment, reference spheres off their design
(`Lab.make_artefacts`), and the machine's own residual errors (the background, added to the
injected errors in everything the lab cuts and measures). Each imperfection an instrument
has is drawn once, when the lab hands it out, from its own stream: (seed, kind, label, the
switch's name). So switching one off changes nothing that another draws.

>>> import machinesim
>>> lab = machinesim.Lab("robonano_a0ib", {"tool": {"offset_um": [5.0, 0.0, 0.0]}}, seed=1)
>>> lab
Lab(robonano_a0ib, noise=on, seed=1)
>>> from machinesim.realism import Realism
>>> machinesim.Lab("robonano_a0ib", seed=1, realism=Realism.lab())
Lab(robonano_a0ib, noise=on, seed=1, realism=lab)
"""

from __future__ import annotations

import os
import warnings
from dataclasses import replace

import numpy as np

from machinesim import realism as _realism
from machinesim._keywords import keywords_checked
from machinesim.cutting.memo import CutMemo
from machinesim.errors import ErrorModel, as_error_model
from machinesim.exceptions import InputError, MachineSimWarning
from machinesim.lab_checks import Fixed, check_cut_options, check_options
from machinesim.metrology.imperfections import Lobing, Registration, ZonalForm
from machinesim.realism import Realism, SphereArtefacts
from machinesim.servo import check_servo as _check_servo
from machinesim.streams import stream
from machinesim.tools import NoseRadiusMisfit

__all__ = ["CUTS", "Lab"]

#: The cuts this process made, for `Lab.cut` to hand back when asked for again.
CUTS = CutMemo()


def _misfit(tool, has_radius: bool) -> InputError:
    """The refusal of a tool the lab's nose radius error does not fit, naming the tool as
    commanded: `with_nose_radius_error`'s own names the error's key, value and file (the
    lab's truth), and the radius with it."""
    kind = type(tool).__name__
    if not has_radius:
        return InputError(f"the lab's tool has a nose radius error (tool_geometry.nose_radius of "
                          f"the errors it was made with), which a {kind} cannot take (it has "
                          "no nose radius); expected a round-nose ('nose:R:ANGLE'), ball or "
                          "flat end mill", key="tool")
    radius = getattr(tool, "nose_radius", None)
    radius = getattr(tool, "radius", None) if radius is None else radius
    return InputError(f"the {kind} of radius {radius * 1e3:g} mm as commanded does not fit the "
                      "lab's tool: with its nose radius error (tool_geometry.nose_radius of "
                      "the errors it was made with) the radius would not be positive; "
                      "expected a tool of a larger radius", key="tool")


class Lab:
    """A machine with injected errors, its instruments, and its noise.

    Parameters
    ----------
    machine : Machine or str
        The machine, or the name of a shipped one (`machinesim.list_machines`).
    errors : ErrorModel, Mapping, str or Path, optional
        The injected errors: an ErrorModel, its TOML structure as a dict, or a TOML file.
        Default none (the nominal machine).
    noise : bool
        Instrument noise on (default) or off. Off, every instrument reads the exact value
        rounded to its resolution, so exact tests stay exact. With ``realism`` given, leave
        it at its default: ``realism.instrument_noise`` decides.
    seed : int
        The lab's seed (non-negative); every instrument's stream derives from it.
    realism : Realism, optional
        Which imperfections the lab has (`machinesim.realism`). Default:
        ``Realism.noise_only()`` with ``noise=True``, ``Realism.ideal()`` with False, so that
        a lab built without it reads what it always read.
    background : ErrorModel, Mapping, str or Path, optional
        The machine's own residual errors when ``realism.background_errors`` is on; default
        the shipped ``models/errors/background_<machine>.toml`` (`machinesim.realism`).
        Ignored with the switch off.
    servo : ServoModel, optional
        The machine's servo loops (``follow(t, q)``, e.g. `machinesim.servo.PIDServo`), kept
        hidden like the errors: `cut` runs every program through them and `encoders`
        records the follow-up error they leave. Default none (axes follow exactly). A servo
        with ``axes`` (a `PIDServo`) must have one column per machine axis, in the order of
        ``machine.axes``, and an `AxisServo` named by an axis letter must sit in that axis'
        column; else InputError.

    Its ``machine``, ``seed``, ``noise`` and ``realism`` read as given (``noise`` as the
    realism's) and stay so for the lab's life: setting one is a `ReadOnlyError` (its
    instruments, artefacts and checked errors all come from them); make another Lab.
    """

    #: Hand back a cut made before with the same inputs (`cut`); False cuts every time.
    reuse_cuts: bool = True

    machine = Fixed("the lab's errors were checked against its machine, its cuts made on it")
    seed = Fixed("every instrument's stream and imperfections, and the artefacts the lab "
                 "made, were drawn from its seed")
    noise = Fixed("the lab's instruments read with its noise, which follows its realism "
                  "(realism.instrument_noise)")
    realism = Fixed("the instruments the lab handed out and the artefacts it made have the "
                    "imperfections its realism switched on")

    @keywords_checked
    def __init__(self, machine, errors=None, *, noise: bool = True, seed: int = 0,
                 realism: Realism | None = None, background=None, servo=None) -> None:
        from machinesim.machines import Machine, load_machine

        fixed = self.__dict__  # what `Fixed` reads
        fixed["machine"] = machine if isinstance(machine, Machine) else load_machine(machine)
        injected = as_error_model(errors)
        self.machine.check_errors(injected)
        if not isinstance(noise, bool):
            raise InputError(f"Expected noise as True or False, got {noise!r}", key="noise")
        if realism is None:
            realism = Realism.noise_only() if noise else Realism.ideal()
            self.__told = False
        elif not isinstance(realism, Realism):
            hint = (f" {realism!r}: make one with machinesim.realism.Realism.ideal(), "
                    ".noise_only() or .lab() (the scenarios' --realism) or Realism.with_only"
                    "(...)" if isinstance(realism, str) else "")
            raise InputError(f"Expected realism as a machinesim.realism.Realism, got "
                             f"{type(realism).__name__}{hint}", key="realism")
        elif not noise:
            raise InputError("Expected either noise=False or a realism, not both: "
                             "Realism.instrument_noise turns the noise off", key="noise")
        else:
            self.__told = True
        stream(seed)  # refuses a bad seed here, not at the first reading
        fixed.update(realism=realism, noise=realism.instrument_noise, seed=seed)
        self.__injected = injected
        self.__background = ErrorModel()
        truth = injected
        if background is not None and not realism.background_errors:
            raise InputError(f"a background ({type(background).__name__}) was given, but the "
                             f"realism ({realism}) has no background_errors: it would not be "
                             "used. Give a realism with background_errors (Realism.lab()) or "
                             "leave background out", key="background")
        if realism.background_errors:
            try:
                own = (_realism.background_model(self.machine) if background is None
                       else as_error_model(background))
            except InputError as exc:
                raise InputError(exc.message, source=exc.source, line=exc.line,
                                 column=exc.column, key="background") from None
            self.machine.check_errors(own)
            self.__background = own
            travel = dict(zip(self.machine.axes,
                              zip(self.machine.lower, self.machine.upper, strict=True),
                              strict=True))
            truth = _realism.add_errors(injected, own, travel)
        room = 1.0 - _realism.TOOL_ADJUSTER_STROKE_M  # ErrorModel's 1 m, less the stroke
        if np.abs(injected.tool.offset).max() > room:
            raise InputError(f"a tool offset of {np.round(injected.tool.offset * 1e3, 6).tolist()}"
                             f" mm; expected at most {room * 1e3:g} mm along each axis (1 m "
                             "less the tool adjuster's stroke)", key="[tool] offset",
                             source=str(errors) if isinstance(errors, str | os.PathLike)
                             else None, line=injected.line_of("tool.offset"))
        self.__truth = truth  # the machine as it is: `adjust_tool` moves its tool
        self.__set_up = truth  # as it was set up: what `reveal` gives
        self.__adjusted = np.zeros(3)  # the moves as made
        self.__commanded = np.zeros(3)  # the moves as commanded: the operator's own record
        if servo is not None:
            _check_servo(self.machine, servo)
        self.__servo = servo
        self.__servo_as_made = servo  # `tune_servo` sets others; `reveal_servo(as_made=True)`
        self.__issued: dict[str, int] = {}
        self.__instruments: dict[str, dict] = {}
        self.__artefacts: dict[str, object] = {}
        self.__workpieces: dict[str, tuple] = {}  # label -> (digest of what made it, part)
        if isinstance(errors, str | os.PathLike):
            # told to whoever set the lab up, once it is made, as `machinesim cut` tells
            # them; the lab's own cuts and readings say nothing of its errors
            from machinesim.errors.notes import error_file_notes

            for note in error_file_notes(injected, self.machine, done="the lab is set up"):
                warnings.warn(note, MachineSimWarning, stacklevel=3)

    def __repr__(self) -> str:
        told = f", realism={self.realism}" if self.__told else ""
        return (f"Lab({self.machine.name}, noise={'on' if self.noise else 'off'}, "
                f"seed={self.seed}{told})")

    # ------------------------------------------------------------------------------ cutting

    def cut(self, program, tool="v:90", stock="block:10x10x2", roi=None, **options):
        """Run ``program`` on the lab's machine, errors and all.

        Parameters are those of `machinesim.cutting.cut` (``start``, ``chord_tolerance``,
        ``servo``, ``progress`` as keywords), without the errors: the lab supplies its own
        (the injected ones, and the background when `realism` has it), and its servo loops
        unless ``servo`` names others.
        With ``turn_step`` (rad) the lab cuts by `machinesim.cutting.cut_turned` instead
        (the same part, each group of feed moves at one C position cut in its own turned
        frame: faster for faces at many C positions), which also takes ``floor``.

        A cut this process made before with every input the same (program, machine, errors,
        tool, stock, options; by any lab) is handed back, not cut again
        (`machinesim.cutting.memo`): an error budget's reruns cut only what changed. Its
        report carries the note `machinesim.cutting.memo.REUSED_NOTE`; ``progress`` is told
        once, with every sweep done. ``Lab.reuse_cuts = False`` (on a lab or the class)
        cuts every time.

        Its report has no notes on the errors (`machinesim.errors.notes`, which `cut`'s
        report ends with): they name the keys and values of the lab's truth, which a
        procedure holding the report must not read.

        Returns
        -------
        (Part, CutReport)
        """
        from machinesim.cutting import cut, cut_turned
        from machinesim.cutting.program import _cut
        from machinesim.cutting.windows import _cut_turned

        if "errors" in options:
            raise InputError("a lab cuts with its own errors; pass none to Lab.cut",
                             key="errors")
        cutter = cut_turned if "turn_step" in options else cut
        check_cut_options(cutter, options)
        if options.get("servo") is not None:
            _check_servo(self.machine, options["servo"])
        if self.__servo is not None and "servo" not in options:
            options["servo"] = self.__servo
        progress = options.pop("progress", None)
        key = (CUTS.key(cutter.__name__, self.machine.digest, program, tool, stock,
                        self.__truth, roi, sorted(options.items()))
               if self.reuse_cuts else None)
        reused = CUTS.get(key)
        if reused is not None:
            if progress is not None:
                progress(reused[1].sweeps, reused[1].sweeps)
            return reused
        # the inner cutters default as the public ones; without their notes on the truth
        misfit = None
        try:
            part, report = (_cut_turned if cutter is cut_turned else _cut)(
                program, self.machine, tool, stock, self.__truth, roi=roi, progress=progress,
                file_notes=False, **options)
        except NoseRadiusMisfit as error:  # raised below, outside: no __context__ to read
            misfit = error.tool, error.has_radius
        if misfit is not None:
            raise _misfit(*misfit)
        CUTS.put(key, part, report)
        return part, report

    def turn(self, program, tool="nose:1.0:90", *, top: float = 0.0,
             allow_overtravel: bool = False):
        """Turn ``program`` on the lab's lathe: its servo loops, its errors (tool setting,
        the tool's nose radius error, geometry) and the turning engine
        (`machinesim.cutting.lathe.turn`; ``allow_overtravel`` as there).

        Returns
        -------
        (TurnedFace, TurningReport)
            The part is a height field the optical instruments read (`heights_at`,
            `heights`, `top`); the tool it was cut with and the edge's paths, which hold the
            lab's errors, are not handed out, and an empty cut's note does not say how far
            above the stock the tip stayed.
        """
        from machinesim.cutting.lathe import _turn

        misfit = None
        try:
            return _turn(program, self.machine, tool, self.__truth, servo=self.__servo,
                         top=top, allow_overtravel=allow_overtravel, truth_told=False)
        except NoseRadiusMisfit as error:  # raised below, outside: no __context__ to read
            misfit = error.tool, error.has_radius
        raise _misfit(*misfit)

    def adjust_tool(self, offset, *, label: str | None = None) -> None:
        """The operator moves the tool in its holder by ``offset`` (tool_mount X, Y, Z, m),
        e.g. to cancel an identified setting error (paper 004's tool-workpiece alignment).

        The move is made with the adjuster's resolution: with instrument noise on, each
        axis lands off the commanded amount by a draw uniform within +-half the resolution
        (`machinesim.realism.TOOL_ADJUSTER_RESOLUTION_M`, from ``label``'s stream); off, exactly.
        Every cut and turn after it has the tool there. `reveal` still gives the errors as
        injected; `reveal_adjustments` the moves as made.
        """
        from machinesim.errors import ToolSetting
        from machinesim.metrology._mesh import as_vector

        move = as_vector(offset, 3, "offset")
        stroke = _realism.TOOL_ADJUSTER_STROKE_M
        commanded = self.__commanded + move
        if np.abs(commanded).max() > stroke:
            # judged on the moves as commanded, which the operator knows: a check of where
            # the tool lands would answer, by refusing or not, where the hidden tool is
            largest = float(np.abs(move).max())
            # a move longer than the whole stroke is one no adjuster makes: a unit slip
            slip = (f"; offset is in m, {largest:g} m: given in mm or um?"
                    if largest > 2.0 * stroke else "")
            raise InputError(f"a tool adjustment of {np.round(move * 1e6, 6).tolist()} um "
                             f"takes the adjuster to {np.round(commanded * 1e6, 6).tolist()} "
                             f"um, beyond its stroke of +-{stroke * 1e3:g} mm per axis "
                             f"(machinesim.realism.TOOL_ADJUSTER_STROKE_M{slip})", key="offset")
        self.__commanded = commanded
        label = self._label("tool_adjuster", label)
        if self.noise:
            half = 0.5 * _realism.TOOL_ADJUSTER_RESOLUTION_M
            move = move + stream(self.seed, "tool_adjuster", label).uniform(-half, half, 3)
        truth = self.__truth
        # within 1 m: the injected offset leaves room for the stroke (checked when made)
        tool = ToolSetting(truth.tool.offset + move, truth.tool.rotation)
        self.__adjusted = self.__adjusted + move
        self.__truth = truth.__class__(tool, truth.workpiece, truth.location, truth.component,
                                       truth.tool_geometry)

    def tune_servo(self, servo) -> None:
        """Set new servo loops on the machine (the operator's tuning of the control's gains);
        `cut`, `turn` and `encoders` use them from now on. Checked against the machine's
        axes as the constructor's ``servo`` is."""
        _check_servo(self.machine, servo)
        self.__servo = servo

    def make_artefacts(self, stock, design: SphereArtefacts, *, label: str):
        """The workpiece with its reference spheres, as the lab's workshop made it.

        The spheres are cut into the stock (or onto it) where and as they really came out:
        with ``realism.artefact_errors`` off, exactly as designed; on, each centre off by a
        drawn amount, their common radius off, each with a drawn form error
        (`machinesim.realism.ARTEFACT`, from paper 002's own estimate). The actual spheres are
        the lab's truth: only `reveal_artefacts` gives them.

        Parameters
        ----------
        stock : Part or str
            The workpiece without its spheres, workpiece frame: a `Part`, or a spec such as
            ``"block:10x10x2"`` (mm, `machinesim.workpiece.stock_from_spec`), as `cut` takes.
        design : SphereArtefacts
            The spheres as designed (what CAM and the procedure know).
        label : str
            Names the workpiece: the same label gives the same actual spheres (one physical
            workpiece, made once), whatever else the lab did before. Asked for again with the
            same stock and design (and seed and realism), the lab hands back the very part
            it made (a procedure keeps no workpiece, nor the lab, between its steps:
            `measure` and `evaluate` ask).

        Returns
        -------
        Part
        """
        if not isinstance(design, SphereArtefacts):
            raise InputError(f"Expected design as a machinesim.realism.SphereArtefacts, got "
                             f"{type(design).__name__}", key="design")
        from machinesim.workpiece import Part, stock_from_spec

        if isinstance(stock, str):
            stock = stock_from_spec(stock)
        elif not isinstance(stock, Part):
            raise InputError(f"Expected stock as a spec such as 'block:10x10x2' or a Part, "
                             f"got {type(stock).__name__}", key="stock")
        label = self._label("artefact", label, numbered=False)
        # None (made every time) for a stock that won't pickle; the seed and the realism
        # decide the spheres too, fixed for the lab's life (`Fixed`)
        key = CUTS.key(stock, design, self.seed, self.realism.artefact_errors)
        made = self.__workpieces.get(label)
        if key is not None and made is not None and made[0] == key:
            return made[1]
        if self.realism.artefact_errors:
            actual = _realism.draw_spheres(
                design, _realism.ARTEFACT,
                *(stream(self.seed, "artefact", label, part)
                  for part in ("position", "radius", "form")))
        else:
            actual = _realism.draw_spheres(design, None)
        self.__artefacts[label] = actual
        part = _realism.make_spheres(stock, design, actual)
        self.__workpieces[label] = (key, part)
        return part

    @property
    def artefact_scatter(self):
        """The tolerance the lab's workshop states for the artefacts it makes
        (`machinesim.realism.ARTEFACT` with ``realism.artefact_errors`` on, None without):
        what a certificate says, for the uncertainty a procedure states. The spheres as they
        came out stay the lab's truth (`reveal_artefacts`)."""
        return _realism.ARTEFACT if self.realism.artefact_errors else None

    # -------------------------------------------------------------------------- instruments

    def touch_probe(self, part, *, label: str | None = None, **options):
        """The on-machine touch probe (`machinesim.metrology.TouchProbe`) touching ``part``.

        ``options`` are the probe's own (``radius``, ``sigma``, ``resolution``, ``frame``,
        ``pretravel``, ``ball_form``); the ball moves through the lab's erroneous kinematics.
        With ``realism.probe_pretravel`` / ``probe_ball_form`` the lab gives the probe a drawn
        lobing and ball form (`machinesim.realism.PROBE`) unless ``options`` name their own.
        The lab sets the machine, its errors, ``noise`` and ``rng`` itself: an option naming
        one of them, or one the probe does not take, is an InputError.
        """
        from machinesim.metrology import TouchProbe

        kind = "touch_probe"
        check_options(TouchProbe, kind, options, ("machine", "errors", "part"))
        label = self._label(kind, label)
        drawn, stated = {}, {}
        if self.realism.probe_pretravel and "pretravel" not in options:
            drawn["pretravel"] = Lobing.draw(self._imperfection(kind, label, "pretravel"),
                                             _realism.PROBE.lobing)
            stated["lobing_amplitudes"] = _realism.PROBE.lobing
        if self.realism.probe_ball_form and "ball_form" not in options:
            drawn["ball_form"] = ZonalForm.draw(self._imperfection(kind, label, "ball_form"),
                                                _realism.PROBE.sphericity)
            stated["sphericity"] = _realism.PROBE.sphericity
        self.__instruments[f"{kind}/{label}"] = drawn
        return TouchProbe(self.machine, self.__truth, part, noise=self.noise,
                          rng=stream(self.seed, kind, label), **drawn,
                          **{**stated, **options})

    def laser_interferometer(self, *, label: str | None = None, **options):
        """A laser interferometer on the machine (`machinesim.metrology.LaserInterferometer`).

        With ``realism.registration`` its beam is misaligned by a drawn pair of angles
        (`machinesim.realism.PROBE`), unless ``options`` give ``alignment``; with
        ``realism.air_refraction`` it reads on a scale off by a drawn ``scale`` (one per
        instrument: a set-up, its air compensation's miss), unless ``options`` give it. The
        lab sets the machine, its errors, ``noise`` and ``rng`` itself (InputError if
        ``options`` do).
        """
        from machinesim.metrology import LaserInterferometer

        kind = "laser_interferometer"
        check_options(LaserInterferometer, kind, options, ("machine", "errors"))
        label = self._label(kind, label)
        drawn = {}
        if self.realism.registration and "alignment" not in options:
            rng = self._imperfection(kind, label, "registration")
            drawn["alignment"] = _realism.PROBE.beam_alignment * rng.standard_normal(2)
        if self.realism.air_refraction and "scale" not in options:
            rng = self._imperfection(kind, label, "air_refraction")
            drawn["scale"] = _realism.PROBE.air_scale * float(rng.standard_normal())
        self.__instruments[f"{kind}/{label}"] = drawn
        return LaserInterferometer(self.machine, self.__truth, noise=self.noise,
                                   rng=stream(self.seed, kind, label), **drawn, **options)

    def encoders(self, *, label: str | None = None, **options):
        """The machine's axis encoders as its control records them
        (`machinesim.metrology.encoders.Encoders`): ``record(program)`` gives commands,
        positions and the follow-up error the lab's servo loops leave. ``options``: ``sigma``
        (per axis)."""
        from machinesim.metrology.encoders import Encoders

        kind = "encoders"
        check_options(Encoders, kind, options, ("machine", "follow"))
        label = self._label(kind, label)
        servo = self.__servo

        def follow(t, q):
            return q if servo is None else servo.follow(t, q)

        return Encoders(self.machine, follow, noise=self.noise,
                        rng=stream(self.seed, kind, label), **options)

    def r_test(self, *, label: str | None = None, **options):
        """An R-test (ISO 10791-6, `machinesim.metrology.RTest`): a ball on the tool side read
        by three displacement sensors on the table, for the machine's kinematics. The lab sets
        the machine, its errors, ``noise`` and ``rng`` itself (InputError if ``options`` do)."""
        from machinesim.metrology import RTest

        kind = "r_test"
        check_options(RTest, kind, options, ("machine", "errors"))
        label = self._label(kind, label)
        return RTest(self.machine, self.__truth, noise=self.noise,
                     rng=stream(self.seed, kind, label), **options)

    def microscope(self, *, label: str | None = None, objective=None, **options):
        """The laser (confocal) microscope (`machinesim.metrology.Microscope`), with the lab's
        spot, lateral noise and registration when `realism` has them
        (`machinesim.realism.MICROSCOPE`) and ``options`` do not name their own.

        ``objective`` (a `machinesim.realism.Objective`, e.g. ``OBJECTIVE_10X``): read
        through it instead of the default 50x: its spot (with lateral resolution), height
        noise and pixel pitch as the sample spacing. The lab sets ``noise`` and ``rng``
        itself (InputError if ``options`` do, or name an option the microscope does not
        take)."""
        from machinesim.metrology import Microscope

        defaults = _realism.MICROSCOPE
        if objective is not None:
            if not isinstance(objective, _realism.Objective):
                raise InputError(f"Expected objective as a machinesim.realism.Objective, got "
                                 f"{objective!r}", key="objective")
            defaults = replace(defaults, spot=objective.spot)
            options = {"sigma": objective.sigma, "lateral_spacing": objective.pixel,
                       **options}
        return self._optical(Microscope, "microscope", defaults, label, options)

    def white_light_interferometer(self, *, label: str | None = None, **options):
        """The white-light interferometer (`machinesim.metrology.WhiteLightInterferometer`),
        with the lab's imperfections as the microscope (`machinesim.realism.WHITE_LIGHT`)."""
        from machinesim.metrology import WhiteLightInterferometer

        return self._optical(WhiteLightInterferometer, "white_light_interferometer",
                             _realism.WHITE_LIGHT, label, options)

    # -------------------------------------------------------------------------------- truth

    def reveal(self, *, background: bool = True) -> ErrorModel:
        """The machine's errors: for reports and tests only, never for identification.

        Parameters
        ----------
        background : bool
            True (default): everything the machine has, the injected errors plus the
            background (what an identification should find). False: the injected errors
            alone (what a scenario chose). Without background errors the two are the same.
        Tool moves made by `adjust_tool` are not in it (`reveal_adjustments`).
        """
        if not isinstance(background, bool | np.bool_):  # "no" is no True
            raise InputError(f"Expected background as True or False, got {background!r:.60}",
                             key="background")
        return self.__set_up if background else self.__injected

    def reveal_adjustments(self):
        """The sum of the tool moves `adjust_tool` made (tool_mount X, Y, Z, m), as made."""
        return self.__adjusted.copy()

    def reveal_servo(self, *, as_made: bool = False):
        """The lab's servo loops (None: ideal axes): those set now (default), or with
        ``as_made`` those the lab was made with (before any `tune_servo`). For tests and
        reports, never for identification."""
        if not isinstance(as_made, bool | np.bool_):  # "no" is no True
            raise InputError(f"Expected as_made as True or False, got {as_made!r:.60}",
                             key="as_made")
        return self.__servo_as_made if as_made else self.__servo

    def reveal_background(self) -> ErrorModel:
        """The machine's own residual errors the lab added (none with the switch off)."""
        return self.__background

    def reveal_artefacts(self) -> dict:
        """The reference spheres the lab made, by label (`machinesim.realism.ActualSpheres`)."""
        return dict(self.__artefacts)

    def reveal_instruments(self) -> dict:
        """The imperfections drawn for each instrument handed out, by ``"kind/label"``: a dict
        of what was drawn (``registration``, ``pretravel``, ``ball_form``, ``alignment``,
        ``scale``)."""
        return {name: dict(drawn) for name, drawn in self.__instruments.items()}

    # ---------------------------------------------------------------------------- internals

    def _optical(self, cls, kind: str, defaults, label, options):
        check_options(cls, kind, options)
        label = self._label(kind, label)
        drawn, given = {}, {}
        if self.realism.lateral_resolution and "spot" not in options:
            given["spot"] = defaults.spot
        if self.realism.lateral_noise and "lateral_sigma" not in options:
            given["lateral_sigma"] = defaults.lateral_sigma
        if "lateral_rng" not in options:  # a lab's instrument is seeded, whoever sets sigma
            given["lateral_rng"] = self._imperfection(kind, label, "lateral_noise")
        if self.realism.registration and "registration" not in options:
            drawn["registration"] = Registration.draw(
                self._imperfection(kind, label, "registration"), defaults.registration)
            given["registration_scatter"] = defaults.registration
        if self.realism.stage_positioning and "stage_sigma" not in options:
            given["stage_sigma"] = defaults.stage_sigma
        if "stage_rng" not in options:
            given["stage_rng"] = self._imperfection(kind, label, "stage_positioning")
        self.__instruments[f"{kind}/{label}"] = drawn
        return cls(noise=self.noise, rng=stream(self.seed, kind, label), **given, **drawn,
                   **options)

    def _imperfection(self, kind: str, label: str, name: str):
        return stream(self.seed, kind, label, name)

    def _label(self, kind: str, label: str | None, numbered: bool = True) -> str:
        if label is None and numbered:
            count = self.__issued.get(kind, 0)
            self.__issued[kind] = count + 1
            return str(count)
        if not isinstance(label, str) or not label:
            raise InputError(f"Expected a label as a non-empty string, got {label!r}",
                             key="label")
        return label
