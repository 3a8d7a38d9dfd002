"""The lab: a machine with its injected errors in its room, and the instruments beside it.

A `Lab` stands for the real machine. It keeps the injected errors (the truth) privately, cuts
programs on the machine that has them, and hands out instruments bound to it. Nothing a
procedure can call returns the truth: a lab answers only by cutting and by measuring, as a
real one does (the honesty rule of DESIGN.md). The truth comes out through one named call,
`Lab.reveal`, meant for reports and tests; the identification and compensation code never
calls it, and a test scans them to keep it so.

Noise. Each instrument draws its noise from its own stream, derived from the lab's seed, the
instrument's kind and its label (`machinesim.streams.stream`). A reading therefore depends on
(seed, kind, label) and on what was read with that same instrument before it, never on the
readings of another: adding a microscope reading does not change what the probe reads.
Instruments handed out without a label are numbered per kind in the order they are asked
for ("microscope/0", "microscope/1", ...); give a label to make a stream independent of
that order too.

>>> import machinesim
>>> lab = machinesim.Lab("robonano_a0ib", {"tool": {"offset_um": [5.0, 0.0, 0.0]}}, seed=1)
>>> lab
Lab(robonano_a0ib, noise=on, seed=1)
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError
from machinesim.streams import stream

__all__ = ["Lab"]


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
        rounded to its resolution, so exact tests stay exact.
    seed : int
        The lab's seed (non-negative); every instrument's stream derives from it.
    """

    def __init__(self, machine, errors=None, *, noise: bool = True, seed: int = 0) -> None:
        from machinesim.machines import Machine, load_machine

        self.machine = machine if isinstance(machine, Machine) else load_machine(machine)
        truth = _error_model(errors)
        self.machine.check_errors(truth)
        if not isinstance(noise, bool):
            raise InputError(f"Expected noise as True or False, got {noise!r}", key="noise")
        stream(seed)  # refuses a bad seed here, not at the first reading
        self.noise = noise
        self.seed = seed
        self.__truth = truth
        self.__issued: dict[str, int] = {}

    def __repr__(self) -> str:
        return f"Lab({self.machine.name}, noise={'on' if self.noise else 'off'}, seed={self.seed})"

    # ------------------------------------------------------------------------------ cutting

    def cut(self, program, tool="v:90", stock="block:10x10x2", roi=None, **options):
        """Run ``program`` on the lab's machine, errors and all.

        Parameters are those of `machinesim.cutting.cut` (``start``, ``chord_tolerance``,
        ``servo``, ``progress`` as keywords), without the errors: the lab supplies its own.
        With ``turn_step`` (rad) the lab cuts by `machinesim.cutting.cut_turned` instead
        (the same part, each group of feed moves at one C position cut in its own turned
        frame: faster for faces at many C positions), which also takes ``floor``.

        Returns
        -------
        (Part, CutReport)
        """
        from machinesim.cutting import cut, cut_turned

        if "errors" in options:
            raise InputError("a lab cuts with its own errors; pass none to Lab.cut",
                             key="errors")
        cutter = cut_turned if "turn_step" in options else cut
        return cutter(program, self.machine, tool, stock, self.__truth, roi=roi, **options)

    # -------------------------------------------------------------------------- instruments

    def touch_probe(self, part, *, label: str | None = None, **options):
        """The on-machine touch probe (`machinesim.metrology.TouchProbe`) touching ``part``.

        ``options`` are the probe's own (``radius``, ``sigma``, ``resolution``, ``frame``);
        the ball moves through the lab's erroneous kinematics.
        """
        from machinesim.metrology import TouchProbe

        return TouchProbe(self.machine, self.__truth, part, noise=self.noise,
                          rng=self._stream("touch_probe", label), **options)

    def laser_interferometer(self, *, label: str | None = None, **options):
        """A laser interferometer on the machine (`machinesim.metrology.LaserInterferometer`)."""
        from machinesim.metrology import LaserInterferometer

        return LaserInterferometer(self.machine, self.__truth, noise=self.noise,
                                   rng=self._stream("laser_interferometer", label), **options)

    def r_test(self, *, label: str | None = None, **options):
        """An R-test (ISO 10791-6, `machinesim.metrology.RTest`): a ball on the tool side read
        by three displacement sensors on the table, for the machine's kinematics."""
        from machinesim.metrology import RTest

        return RTest(self.machine, self.__truth, noise=self.noise,
                     rng=self._stream("r_test", label), **options)

    def microscope(self, *, label: str | None = None, **options):
        """The laser (confocal) microscope (`machinesim.metrology.Microscope`)."""
        from machinesim.metrology import Microscope

        return Microscope(noise=self.noise, rng=self._stream("microscope", label), **options)

    def white_light_interferometer(self, *, label: str | None = None, **options):
        """The white-light interferometer (`machinesim.metrology.WhiteLightInterferometer`)."""
        from machinesim.metrology import WhiteLightInterferometer

        return WhiteLightInterferometer(noise=self.noise,
                                        rng=self._stream("white_light_interferometer", label),
                                        **options)

    # -------------------------------------------------------------------------------- truth

    def reveal(self) -> ErrorModel:
        """The injected errors: for reports and tests only, never for identification."""
        return self.__truth

    # ---------------------------------------------------------------------------- internals

    def _stream(self, kind: str, label: str | None):
        if label is None:
            count = self.__issued.get(kind, 0)
            self.__issued[kind] = count + 1
            label = str(count)
        elif not isinstance(label, str) or not label:
            raise InputError(f"Expected an instrument label as a non-empty string, got "
                             f"{label!r}", key="label")
        return stream(self.seed, kind, label)


def _error_model(errors) -> ErrorModel:
    if errors is None:
        return ErrorModel()
    if isinstance(errors, ErrorModel):
        return errors
    if isinstance(errors, Mapping):
        return ErrorModel.from_dict(errors)
    if isinstance(errors, str | Path):
        return ErrorModel.from_toml(errors)
    raise InputError(f"Expected errors as an ErrorModel, a dict or a TOML path, got "
                     f"{type(errors).__name__}", key="errors")
