"""What a `machinesim.lab.Lab` refuses: the checks of what its factories are given, and of
the attributes it is made with.

A lab hands out instruments and cuts programs; each of those calls takes the options of the
instrument or cutting engine behind it, less what the lab sets itself (its noise, each
instrument's stream, its machine, its hidden errors, the part, its servo loops: `LAB_SETS`).
`check_options` and `check_cut_options` refuse an option the lab sets or one the instrument
or engine does not take, as a located `InputError` that names it and lists those taken; the
lab's ``machine``, ``seed``, ``noise`` and ``realism`` are `Fixed`, a `ReadOnlyError` when
set anew or deleted. The checks see only what a lab's caller gave: the lab's truth (its
errors, servo loops and draws) stays in `Lab`'s own private fields, which nothing here reads.
"""

from __future__ import annotations

from machinesim.exceptions import InputError, ReadOnlyError, brief

__all__ = ["LAB_SETS", "Fixed", "check_cut_options", "check_options"]


class Fixed:
    """An attribute a `Lab` is made with, read as a plain one and refused when set or deleted
    (`ReadOnlyError`): its instruments' streams and imperfections, the artefacts it made and
    its errors, checked against its machine, all come from it, and a value set anew had left
    them from the old one (or failed later: ``lab.machine = "sts_lathe"``). Kept in the
    lab's ``__dict__`` under its own name (a pickle or copy carries it)."""

    def __init__(self, why: str) -> None:
        self.why = why

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, lab, owner=None):
        return self if lab is None else lab.__dict__[self.name]

    def __set__(self, lab, value) -> None:
        raise ReadOnlyError(f"Lab.{self.name} cannot be set (to {brief(repr(value))}): "
                            f"{self.why}; make another Lab with the {self.name} wanted")

    def __delete__(self, lab) -> None:
        raise ReadOnlyError(f"Lab.{self.name} cannot be deleted: {self.why}")


#: What the lab sets on every instrument it hands out, and why (`check_options`).
LAB_SETS = {
    "noise": "from the lab's noise switch (Lab(noise=...) or its realism)",
    "rng": "from the lab's seed and the instrument's label; give label= for another stream",
    "machine": "the lab's own machine",
    "errors": "the lab's hidden errors, which no instrument is handed",
    "part": "the part given as the first argument",
    "follow": "from the lab's servo loops (Lab(servo=...) or lab.tune_servo)",
}


def check_options(cls, kind: str, options, also: tuple[str, ...] = ()) -> None:
    """Refuse an option the lab sets itself (``noise``, ``rng`` and ``also``) or one that
    ``cls`` does not take, naming it and listing those it does take."""
    import inspect

    sets = ("noise", "rng", *also)
    what = kind.replace("_", " ")
    whose = what + ("'" if what.endswith("s") else "'s")
    taken = [name for name, p in inspect.signature(cls).parameters.items()
             if name not in sets and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    for name in options:
        if name in sets:
            raise InputError(f"the lab sets the {whose} {name} itself ({LAB_SETS[name]}); "
                             f"leave {name!r} out. Options it takes: {', '.join(taken)}",
                             key=name)
        if name not in taken:
            raise InputError(f"{cls.__name__} has no option {name!r}; the {what} takes "
                             f"{', '.join(taken)} (and label)", key=name)


def check_cut_options(cutter, options) -> None:
    """Refuse an option ``cutter`` (`machinesim.cutting.cut` or ``cut_turned``) does not take,
    with those it takes, as the instruments refuse theirs, and a ``progress`` that cannot be
    called (the engine called it after the planning: a TypeError)."""
    import inspect

    from machinesim.cutting.program import check_progress

    taken = [name for name, p in inspect.signature(cutter).parameters.items()
             if p.kind is p.KEYWORD_ONLY and name != "roi"]
    if cutter.__name__ == "cut":
        taken.append("turn_step")
    for name in options:
        if name not in taken:
            how = "Lab.cut" + (" with turn_step" if "turn_step" in options else "")
            raise InputError(f"{how} has no option {name!r}; it takes {', '.join(taken)} "
                             "(and roi)", key=name)
    check_progress(options.get("progress"))
