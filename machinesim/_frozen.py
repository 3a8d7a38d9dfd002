"""Pickling of frozen dataclasses that hold read-only mappings (`types.MappingProxyType`).

Python cannot pickle a mappingproxy ("cannot pickle 'mappingproxy' object"), so a
`machinesim.experiment.Result` could be neither saved nor sent to a Dask worker and back.
A class that sets ``__reduce__ = reduce_frozen`` pickles each of its fields as it is, a
mappingproxy as a plain dict, and comes back with the same fields, those dicts read-only
again. Nothing but the fields is pickled: the object holds nothing more after a round trip
than before.
"""

from __future__ import annotations

from dataclasses import fields
from types import MappingProxyType

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


def _rebuild(cls, values: dict, proxies: tuple[str, ...]):
    """The object `reduce_frozen` pickled: its fields set as they were (no re-check; they
    were checked when it was made), the named ones read-only mappings again."""
    out = cls.__new__(cls)
    for name, value in values.items():
        object.__setattr__(out, name, MappingProxyType(value) if name in proxies else value)
    return out
