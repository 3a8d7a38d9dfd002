"""Pickling of frozen dataclasses that hold read-only mappings (`types.MappingProxyType`).

Python cannot pickle a mappingproxy ("cannot pickle 'mappingproxy' object"), so a
`machinesim.experiment.Result` could be neither saved nor sent to a Dask worker and back.
A class that sets ``__reduce__ = reduce_frozen`` pickles each of its fields as it is, a
mappingproxy as a plain dict, and comes back with the same fields, those dicts read-only
again. Nothing but the fields is pickled: the object holds nothing more after a round trip
than before.

A copy comes back through the checks its constructor runs (``__post_init__``): a saved
result is a file (`machinesim.result_file.load_result`), which may have been cut short,
written by another version (a field missing, or one this class does not have) or edited (a
figure in a unit no figure has); it is refused as the constructor refuses it, an
`InputError` naming the class and the field, not accepted to fail later in a report.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, fields
from types import MappingProxyType

from machinesim.exceptions import InputError, brief

__all__ = ["reduce_frozen"]


def reduce_frozen(self):
    """``__reduce__`` of a frozen dataclass: its fields, mappingproxies as dicts."""
    values, proxies = {}, []
    for f in fields(self):
        value = getattr(self, f.name)
        if isinstance(value, MappingProxyType):
            value = dict(value)
            proxies.append(f.name)
        values[f.name] = value
    return _rebuild, (type(self), values, tuple(proxies))


def _rebuild(cls, values, proxies):
    """The object `reduce_frozen` pickled: its fields set as they were, the named ones
    read-only mappings again, then checked as its constructor checks them. A field the
    pickle lacks takes the default the constructor gives it (a result saved before the field
    was added); one without a default, or a field the class does not have, is refused."""
    name = cls.__name__
    if not isinstance(values, dict) or not all(isinstance(k, str) for k in values):
        raise InputError(f"a pickled {name} whose fields are not named: {brief(repr(values))}")
    known = {f.name: f for f in fields(cls)}
    unknown = [k for k in values if k not in known]
    if unknown:
        raise InputError(f"a pickled {name} with fields it does not have ({', '.join(unknown)}"
                         f"; it has {', '.join(known)}): written by another version of "
                         "machinesim?", key=unknown[0])
    out = cls.__new__(cls)
    for key, f in known.items():
        if key in values:
            value = values[key]
        elif f.default is not MISSING:
            value = f.default
        elif f.default_factory is not MISSING:
            value = f.default_factory()
        else:
            raise InputError(f"a pickled {name} without its field {key!r}: cut short, or "
                             "written by another version of machinesim?", key=key)
        if key in proxies:
            if not isinstance(value, Mapping):
                raise InputError(f"a pickled {name}'s {key} as {type(value).__name__}; "
                                 "expected a mapping", key=key)
            value = MappingProxyType(dict(value))
        object.__setattr__(out, key, value)
    check = getattr(out, "__post_init__", None)
    if check is not None:
        check()
    return out
