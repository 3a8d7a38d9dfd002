"""Calls of a public entry point with arguments it does not take, told as a `MachineSimError`.

``cut(..., allow_overtravle=True)`` ended in Python's "TypeError: cut() got an unexpected
keyword argument", outside machinesim's errors and with no hint; `keywords_checked` turns
it into an `ArgumentError` (an `InputError` and a `TypeError`) naming the argument, the
close name it resembles and the arguments the function takes. It costs nothing on a call
that binds: the signature is only consulted after the call raised a TypeError.
"""

from __future__ import annotations

import difflib
import functools
import inspect

from machinesim.exceptions import ArgumentError

__all__ = ["keywords_checked"]


def keywords_checked(function):
    """``function`` whose calls with arguments its signature does not bind raise
    `ArgumentError`; a TypeError its body raises is left as it is."""
    signature = inspect.signature(function)
    names = [p.name for p in signature.parameters.values()
             if p.name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]

    @functools.wraps(function)
    def checked(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except TypeError as error:
            try:
                signature.bind(*args, **kwargs)
            except TypeError:
                raise ArgumentError(_said(error, names, kwargs), key=_unknown(names, kwargs,
                                                                              signature)) from None
            raise

    return checked


def _unknown(names, kwargs, signature) -> str | None:
    """The first keyword given that the signature has no parameter for, or None."""
    if any(p.kind == p.VAR_KEYWORD for p in signature.parameters.values()):
        return None
    return next((k for k in kwargs if k not in signature.parameters), None)


def _said(error: TypeError, names: list[str], kwargs) -> str:
    hints = [f"did you mean {close[0]}?" for key in kwargs if key not in names
             for close in [difflib.get_close_matches(key, names, n=1, cutoff=0.6)] if close]
    hint = f" ({'; '.join(hints)})" if hints else ""
    return f"{error}{hint}; it takes {', '.join(names)}"
