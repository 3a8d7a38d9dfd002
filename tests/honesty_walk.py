"""What a procedure's identification can reach, walked as an adversary would walk it
(tests/test_lab_doors.py; not collected: no test_ prefix).

`HandingLab` stands between a procedure and its lab and notes everything the lab hands out
(the parts and reports of its cuts, the workpieces it makes, its instruments); `doors` walks
every attribute, public and private, every item and every closure cell from the objects a
procedure's ``identify`` and ``compensate`` hold (the procedure itself, the measurements, the
`Identified`) and names the path to each of those, to the lab, and to its truth.
"""

from __future__ import annotations

import functools
import types
from collections import deque

import numpy as np

from machinesim.machines import Machine


class HandingLab:
    """``lab`` as a procedure receives it, noting what it hands out (``handed``: id ->
    what). Everything else is the lab's own: its ``reveal`` too, as `check_lab` asks."""

    def __init__(self, lab) -> None:
        self._lab = lab
        self.handed: dict[int, str] = {id(lab): "the lab"}
        self._kept: list = []  # held, so that no id in handed is taken by a later object

    def __getattr__(self, name):
        value = getattr(self._lab, name)
        if not callable(value) or name.startswith("reveal"):
            return value

        def handing(*args, **options):
            out = value(*args, **options)
            self._kept.append(out)
            for k, item in enumerate(out if isinstance(out, tuple) else (out,)):
                self.handed[id(item)] = f"lab.{name}(...)[{k}] ({type(item).__name__})"
            return out
        return handing


def truth_of(lab) -> dict[int, str]:
    """The lab's truth by id: every error model and servo it reveals, its artefacts as made,
    its instruments' draws, and the lab itself."""
    found = {id(lab): "the lab"}
    for name in ("reveal", "reveal_background", "reveal_servo"):
        value = getattr(lab, name)()
        if value is not None:
            found[id(value)] = f"lab.{name}()"
    found[id(lab.reveal(background=False))] = "lab.reveal(background=False)"
    if lab.reveal_servo(as_made=True) is not None:
        found[id(lab.reveal_servo(as_made=True))] = "lab.reveal_servo(as_made=True)"
    for label, actual in lab.reveal_artefacts().items():
        found[id(actual)] = f"lab.reveal_artefacts()[{label!r}]"
    return found


def _children(obj):
    if isinstance(obj, type):
        if obj.__module__ != "builtins":  # a class's own attributes: a cache kept there
            yield from ((f".{name}", value) for name, value in vars(obj).items())
        return
    if isinstance(obj, str | bytes | int | float | complex | bool | type(None)
                  | types.ModuleType | Machine):
        return  # a Machine's private caches: the door docs/lab.md names and leaves
    if isinstance(obj, functools.partial):
        yield ".func", obj.func
        yield ".args", obj.args
        yield ".keywords", obj.keywords
    if isinstance(obj, np.ndarray):
        if obj.dtype == object:
            yield from ((f"[{i}]", v) for i, v in enumerate(obj.ravel()))
        return
    if isinstance(obj, types.FunctionType):
        for name, cell in zip(obj.__code__.co_freevars, obj.__closure__ or (), strict=True):
            try:
                yield f".__closure__({name})", cell.cell_contents
            except ValueError:  # an empty cell
                pass
        return
    if isinstance(obj, types.MethodType):
        yield ".__self__", obj.__self__
        yield ".__func__", obj.__func__
        return
    if isinstance(obj, dict | types.MappingProxyType):
        for key, value in obj.items():
            yield f"[{key!r}]", value
            yield f".keys()[{key!r}]", key
        return
    if isinstance(obj, list | tuple | set | frozenset | deque):
        yield from ((f"[{i}]", v) for i, v in enumerate(obj))
        return
    yield ".__class__", type(obj)
    for name, value in getattr(obj, "__dict__", {}).items():
        yield f".{name}", value
    for cls in type(obj).__mro__:
        for name in getattr(cls, "__slots__", ()):
            if hasattr(obj, name):
                yield f".{name}", getattr(obj, name)


def doors(roots: dict[str, object], forbidden: dict[int, str]) -> list[str]:
    """The paths from ``roots`` (name -> object) to any object in ``forbidden`` (id ->
    what), breadth first: each forbidden object once, by its shortest path."""
    seen = {id(root) for root in roots.values()}
    queue = deque(roots.items())
    found = []
    while queue:
        path, obj = queue.popleft()
        if id(obj) in forbidden:
            found.append(f"{path} -> {forbidden[id(obj)]}")
            continue
        for step, child in _children(obj):
            if id(child) not in seen:
                seen.add(id(child))
                queue.append((path + step, child))
    return found
