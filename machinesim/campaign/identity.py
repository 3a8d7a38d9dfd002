"""What a campaign's procedure is, beyond its name: the code a user's own procedure runs and
the state its object holds (`code_of`, `state_of`), digested into campaign.json so that a
folder is resumed only by the procedure it was begun with
(`machinesim.campaign.CampaignSpec.describe`, `machinesim.campaign.results.same_campaign`).

Without them a campaign of ``mine:Probe`` resumed after the user edited ``Probe`` ran its
missing trials with the new code, and the summary took the mean of old and new trials as
one; two instances of one class with other constructor arguments were one campaign.

- The code: the SHA-256 (first 16 hex digits) of the source of each class in the
  procedure's MRO outside machinesim and the standard library (`inspect.getsource`), and of
  each such class's module file (a helper function beside the class is code it runs too),
  but a script's (``__main__``), which holds the campaign's call as well; and (``imports``)
  of each module of the user's that those modules import (a script: those its classes
  name), one level deep (a helper from another file): not an installed package's
  (site-packages), nor deeper.
  A class without a source file (one typed at the interactive prompt or fed on stdin) is
  digested by its methods' bytecode, constants and names instead.
- The state: a digest of the object's state as `copy` and `pickle` take it
  (``__reduce_ex__``: ``vars()`` for a plain object), written out in a canonical form (keys
  and sets sorted, floats to the bit but -0.0 as 0.0, arrays by dtype, shape and bytes), so
  that it is the same in every process whatever ``PYTHONHASHSEED``; a loaded machinesim
  ``Machine`` by the digest of its URDF (`Machine.digest`), not the path it was loaded by;
  an absolute ``pathlib.Path``, or a text naming a file that is there by an absolute path, as
  its real path (``os.path.realpath``), a relative one as it is;
  an object that holds what holds it (a method bound to the procedure itself) by where that
  lies; without the values of its ``functools.cached_property``s (there once read, from the
  rest); a class or reference is digested by the instance it makes (the class called with no
  arguments), so that the class and an instance made alike are one campaign. State it cannot
  write so (an open file, a lock, a lambda) is refused, naming where it lies in the object
  (`InputError`).

machinesim's own code (the shipped procedures, the lab) is named by its version
(`machinesim.__version__`), which campaign.json keeps as ``machinesim``.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import json
import math
import os
import sys
import sysconfig
import types
from pathlib import Path

from machinesim.exceptions import InputError, brief

__all__ = ["DIGITS", "attributes_of", "code_of", "state_of"]

#: Hex digits of each SHA-256 digest kept.
DIGITS = 16

#: How deep `state_of` follows an object's state before refusing it.
_DEEPEST = 40


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:DIGITS]


def _outside(cls: type) -> bool:
    """Whether ``cls`` is a user's: not machinesim's (its version names it), nor a builtin's
    or the standard library's."""
    module = sys.modules.get(cls.__module__)
    if cls.__module__ == "builtins" or module is None:
        return False
    if cls.__module__ == "machinesim" or cls.__module__.startswith("machinesim."):
        return False
    path = getattr(module, "__file__", None)
    if path is None:
        return cls.__module__ == "__main__"  # the interactive prompt, stdin
    stdlib = Path(sysconfig.get_paths()["stdlib"]).resolve()
    where = Path(path).resolve()
    return stdlib not in where.parents or "site-packages" in where.parts


def code_of(procedure) -> dict:
    """``{"classes": {module:qualname: digest}, "modules": {module: digest}}`` of the code
    ``procedure`` (a class or an object) runs, outside machinesim (module docstring)."""
    cls = procedure if isinstance(procedure, type) else type(procedure)
    classes, modules, users = {}, {}, []
    for each in cls.__mro__:
        if not _outside(each):
            continue
        users.append(each)
        try:
            source = inspect.getsource(each).encode()
        except (OSError, TypeError):  # no source file: typed in, or fed on stdin
            source = _bytecode(each)
        classes[f"{each.__module__}:{each.__qualname__}"] = _digest(source)
        path = getattr(sys.modules[each.__module__], "__file__", None)
        # a script's own file holds the campaign's call too: extending N, the script edited
        # for it, was refused as another campaign; its classes' sources are what it runs
        if path is not None and each.__module__ not in modules | {"__main__": None}:
            try:
                modules[each.__module__] = _digest(Path(path).read_bytes())
            except OSError:  # gone since it was imported: its class's source still counts
                pass
    return {"classes": classes, "modules": modules, "imports": _imports(users, modules)}


def _imports(classes: list, modules: dict) -> dict:
    """``{module: digest}`` of the file of each module of the user's that the modules of
    ``classes`` import (a module, or a function or class from it, among their globals),
    one level deep: a helper the class calls from another file of the user's. Not the
    standard library's, an installed package's (site-packages) nor machinesim's. A script's
    (``__main__``) imports those its classes name alone: it imports for its other work too
    (a plot's module, edited after the campaign began, was a change of its code)."""
    found = {}
    for holder in sorted({each.__module__ for each in classes}):
        named = None if holder != "__main__" else \
            {n for each in classes if each.__module__ == holder for n in _names(each)}
        for key, value in list(vars(sys.modules[holder]).items()):
            if named is not None and key not in named:
                continue
            if isinstance(value, types.ModuleType):
                name = value.__name__
            elif isinstance(value, type | types.FunctionType):
                name = getattr(value, "__module__", None)
            else:
                continue
            if not isinstance(name, str) or name in modules or name in found \
                    or name in (holder, "__main__"):
                continue
            path = _user_file(sys.modules.get(name))
            if path is not None:
                try:
                    found[name] = _digest(path.read_bytes())
                except OSError:  # gone since it was imported
                    pass
    return dict(sorted(found.items()))


def _names(cls: type) -> set:
    """The global and attribute names the functions of ``cls``'s body use (their code's
    ``co_names``, nested code too)."""
    found, codes = set(), []
    for value in vars(cls).values():
        if isinstance(value, staticmethod | classmethod):
            value = value.__func__
        if isinstance(value, property):
            codes += [f.__code__ for f in (value.fget, value.fset, value.fdel) if f is not None]
        elif isinstance(value, types.FunctionType):
            codes.append(value.__code__)
    while codes:
        code = codes.pop()
        found.update(code.co_names)
        codes += [c for c in code.co_consts if isinstance(c, types.CodeType)]
    return found


def _user_file(module) -> Path | None:
    """The file of ``module`` when it is the user's own: neither machinesim's, the standard
    library's nor an installed package's."""
    name = getattr(module, "__name__", "")
    path = getattr(module, "__file__", None)
    if not isinstance(path, str) or name == "machinesim" or name.startswith("machinesim."):
        return None
    where = Path(path).resolve()
    stdlib = Path(sysconfig.get_paths()["stdlib"]).resolve()
    if stdlib in where.parents or {"site-packages", "dist-packages"} & set(where.parts):
        return None
    return where if where.suffix == ".py" else None


def _bytecode(cls: type) -> bytes:
    """A class's methods and attributes, for one without source: each function's bytecode,
    constants and names (not its line numbers), other attributes by their canonical state."""
    parts = []
    for name, value in sorted(vars(cls).items()):
        if name in ("__dict__", "__weakref__", "__module__", "__qualname__", "__doc__"):
            continue
        if isinstance(value, staticmethod | classmethod):
            value = value.__func__
        if isinstance(value, property):
            codes = [_code(f.__code__) for f in (value.fget, value.fset, value.fdel)
                     if f is not None]
        elif isinstance(value, types.FunctionType):
            codes = [_code(value.__code__)]
        else:
            try:
                codes = [_canonical(value, name, {}, 0)]
            except _Undigestible:
                codes = [type(value).__qualname__]
        parts.append([name, codes])
    return json.dumps(parts, sort_keys=True, default=str).encode()


def _code(code: types.CodeType) -> list:
    return [code.co_code.hex(), list(code.co_names), list(code.co_varnames),
            [_code(c) if isinstance(c, types.CodeType) else _constant(c)
             for c in code.co_consts]]


def _constant(value) -> str | list:
    """A code object's constant by its repr, but one that holds a frozenset (``x in {"a",
    "b"}`` compiles to one) in its canonical form: a frozenset's repr is in the order of its
    texts' hashes, another in each process (``PYTHONHASHSEED``)."""
    def holds_set(c) -> bool:
        return isinstance(c, frozenset) or isinstance(c, tuple) and any(map(holds_set, c))

    return _canonical(value, "", {}, 0) if holds_set(value) else repr(value)


class _Undigestible(Exception):
    """State `_canonical` cannot write out; its text says where and why."""


def state_of(procedure, shown: str, made: bool = False) -> str | None:
    """The digest of ``procedure``'s state (an object; module docstring). Raises InputError
    naming ``shown`` and the attribute whose value has no canonical form; with ``made`` (the
    object is one the campaign made, a class called with no arguments, whose state its code
    decides), None for such state instead."""
    try:
        canonical = _canonical(procedure, "", {}, 0)
    except _Undigestible as error:
        if made:
            return None
        raise InputError(f"procedure {shown}: {error}", key="procedure") from None
    return _digest(json.dumps(canonical, sort_keys=True, separators=(",", ":"),
                              ensure_ascii=True).encode())


def attributes_of(procedure) -> dict | None:
    """Each attribute of ``procedure``'s state (`state_of`'s form, taken apart at the top):
    its name -> [the digest of its canonical form, its value as shown when a number, a text,
    a bool or None (else None)]. campaign.json keeps it beside ``state`` so that a refused
    resume names the attributes that differ ("gain 1.0 there, 2.0 now"), where the one
    digest said only that something did. A function of the digested form, so one state has
    one entry. None where `state_of` has no attributes to take apart (a list, an object
    pickled by its arguments, state it cannot digest)."""
    try:
        canonical = _canonical(procedure, "", {}, 0)
    except _Undigestible:
        return None
    if canonical[0] != "object":
        return None
    found = [part for part in canonical[1][2:] if part[0] == "attributes"]
    if len(found) != 1:
        return None
    return {name: [_digest(json.dumps(value, sort_keys=True, separators=(",", ":"),
                                      ensure_ascii=True).encode()), _shown(value)]
            for name, value in found[0][1]}


def _shown(canonical) -> str | None:
    """A plain value's text from its canonical form (`_canonical`), for a message."""
    kind = canonical[0]
    if kind == "float" and len(canonical) == 2:
        text = canonical[1]
        return repr(float.fromhex(text) if text not in ("nan", "inf", "-inf") else float(text))
    if kind == "int" and len(canonical) == 2:  # a number, or its text (`_int_text`)
        text = canonical[1]
        return brief(text if isinstance(text, str) else repr(text))
    if kind in ("bool", "NoneType", "str") and len(canonical) == 2:
        return brief(repr(canonical[1]))
    return None


_PLAIN = (str, int, bool, type(None))


def _canonical(value, path: str, seen: dict, depth: int):
    """``value`` as JSON whose text is the same in every process, or InputError naming
    ``path`` (the attribute, as ``.gain`` or ``.table['x'][2]``); ``seen``: the path of each
    object that holds it, by id."""
    if isinstance(value, str) and os.path.isabs(value) and os.path.exists(value):
        # a text naming a file that is there, by its real path, as an absolute Path: a tool
        # table's or a program's source (machinesim keeps it for messages), a path made
        # from __file__, through a symlinked folder, was another state
        value = os.path.realpath(value)
    if isinstance(value, _PLAIN):
        return [type(value).__name__, value] if not isinstance(value, int) or \
            isinstance(value, bool) or abs(value) < 2**53 else ["int", _int_text(value)]
    if isinstance(value, float):  # to the bit; nan and the infinities, which JSON lacks;
        # -0.0 as the 0.0 it equals (+ 0.0): Probe(offset=-0.0) was another campaign
        return ["float", (value + 0.0).hex() if math.isfinite(value) else repr(value)]
    if isinstance(value, complex):
        return ["complex", (value.real + 0.0).hex(), (value.imag + 0.0).hex()]
    if isinstance(value, bytes | bytearray):
        return [type(value).__name__, value.hex()]
    if depth > _DEEPEST:
        raise _undigestible(path, value, f"nested more than {_DEEPEST} deep")
    if id(value) in seen:  # it holds what holds it (a method bound to the object itself,
        # a parent link): by where that lies, as a pickle by its memo; it was refused
        return ["back", seen[id(value)]]
    seen = {**seen, id(value): path}
    depth += 1
    if isinstance(value, list | tuple):
        return [type(value).__name__,
                [_canonical(v, f"{path}[{k}]", seen, depth) for k, v in enumerate(value)]]
    if isinstance(value, set | frozenset):
        items = [_canonical(v, f"{path}{{...}}", seen, depth) for v in value]
        return [type(value).__name__, sorted(items, key=json.dumps)]
    if isinstance(value, dict):
        items = [[_canonical(k, f"{path} key", seen, depth),
                  _canonical(v, f"{path}[{k!r}]", seen, depth)] for k, v in value.items()]
        return [type(value).__name__, sorted(items, key=lambda kv: json.dumps(kv[0]))]
    if isinstance(value, type | types.FunctionType | types.BuiltinFunctionType):
        name = getattr(value, "__qualname__", "")
        if "<lambda>" in name or "<locals>" in name:
            raise _undigestible(path, value, "a function or class made inside a function "
                                "has no name to digest it by")
        return ["named", f"{value.__module__}:{name}"]
    array = _array(value, path)
    if array is not None:
        return array
    if isinstance(value, Path) and value.is_absolute():
        # the file it names, not the way there: Path(__file__).parent / "cal.csv" in
        # __init__ names it through the sys.path entry the module was imported by (a
        # symlinked folder: another state). Not a relative path: another folder's is another
        value = type(value)(os.path.realpath(value))
    machine = sys.modules.get("machinesim.machine")
    if machine is not None and type(value) is machine.Machine:
        # by the URDF it was built from (two machines with one digest move alike), not by
        # its attributes: they hold the path it was loaded by (relative, absolute, through
        # a symlink: a resume from another folder was another campaign) and its digest once
        # read (cached on it: a machine whose digest was read was another state)
        return ["machine", value.digest]
    try:
        reduced = value.__reduce_ex__(4)
    except RecursionError:
        raise _undigestible(path, value, "nested too deeply") from None
    except Exception as error:  # noqa: BLE001 - whatever refuses to be copied or pickled
        raise _undigestible(path, value, f"{type(error).__name__}: {error}") from None
    if isinstance(reduced, str) or not isinstance(reduced, tuple):  # a global's name
        return ["global", f"{type(value).__module__}:{reduced}"]
    cls = type(value)
    parts = [f"{cls.__module__}:{cls.__qualname__}",
             _canonical(reduced[1] if len(reduced) > 1 else (), f"{path}(...)", seen, depth)]
    state = reduced[2] if len(reduced) > 2 else None
    if isinstance(state, tuple) and len(state) == 2 and isinstance(state[1], dict) \
            and isinstance(state[0], dict | None):
        # __slots__: (dict, slots); another pair (a __getstate__ of its own returning
        # ("v2", {...})) is a tuple like any other: it was unpacked, a TypeError
        state = {**(state[0] or {}), **state[1]}
    if isinstance(state, dict) and all(isinstance(k, str) for k in state):
        # not a functools.cached_property's value: computed from the rest when first read,
        # it is there once the script read it (another state for the same object)
        parts.append(["attributes", [[k, _canonical(v, f"{path}.{k}", seen, depth)]
                                     for k, v in sorted(state.items())
                                     if not isinstance(inspect.getattr_static(cls, k, None),
                                                       functools.cached_property)]])
    else:
        parts.append(_canonical(state, f"{path}(state)", seen, depth))
    for k, items in ((3, "items"), (4, "entries")):  # a list's or dict's own items
        if len(reduced) > k and reduced[k] is not None:
            parts.append([items, _canonical(list(reduced[k]), f"{path}[...]", seen, depth)])
    return ["object", parts]


def _int_text(value: int) -> str:
    """An int beyond float64's 2**53 as text: in decimal (as ever), or in hex where Python
    refuses the decimal (more than ``sys.get_int_max_str_digits()`` digits, 4,300 by default:
    10**5000 in a procedure's attribute raised ValueError out of `state_of`, a traceback);
    a decimal text never begins 0x, so the two never meet."""
    try:
        return str(value)
    except ValueError:
        return hex(value)


def _array(value, path: str):
    """A numpy array or scalar by its dtype, shape and bytes (None for anything else)."""
    numpy = sys.modules.get("numpy")
    if numpy is None or not isinstance(value, numpy.ndarray | numpy.generic):
        return None
    array = numpy.asarray(value)
    if array.dtype.hasobject:
        return ["ndarray-object", list(array.shape),
                [_canonical(v, f"{path}[...]", {}, 0) for v in array.ravel().tolist()]]
    if array.dtype.kind in "fc":  # -0.0 as 0.0, as a float's
        array = array + array.dtype.type(0)
    return ["ndarray", array.dtype.str, list(array.shape),
            _digest(numpy.ascontiguousarray(array).tobytes())]


def _undigestible(path: str, value, why: str) -> _Undigestible:
    where = f"its attribute {path.lstrip('.')}" if path else "the object itself"
    return _Undigestible(
        f"its state cannot be digested at {where} ({type(value).__name__} "
        f"{brief(repr(value))}: {why}), and a campaign keeps that digest to tell a resume "
        "with other arguments from its own; expected an object whose attributes are plain "
        "values (numbers, texts, lists, dicts, arrays, objects of those), or give its class "
        "(called with no arguments in each trial) or a 'package.module:ClassName' reference")
