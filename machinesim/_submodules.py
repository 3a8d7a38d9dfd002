"""A package's modules reached as its attributes without their own import (PEP 562).

``machinesim.cutting.lathe.turn(program, "sts_lathe", "nose:0.5:90")``, as docs/cli.md and
`cut`'s refusal of a turning program write it, raised AttributeError after ``import
machinesim`` (module 'machinesim.cutting' has no attribute 'lathe'): Python sets a
submodule as its package's attribute only once something has imported it. Each package's
``__getattr__`` hands a name it does not hold to `submodule`."""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType


def submodule(package: str, name: str) -> ModuleType:
    """The module ``package.name``, imported, when ``name`` is a public name (an identifier
    not starting with ``_``) of a module or subpackage of ``package``; else the
    AttributeError Python gives for a missing attribute. Only names: find_spec of a dotted
    one imports its parent, and a missing parent raised ModuleNotFoundError out of getattr
    and hasattr."""
    if (name.isidentifier() and not name.startswith("_")
            and importlib.util.find_spec(f"{package}.{name}") is not None):
        return importlib.import_module(f"{package}.{name}")
    raise AttributeError(f"module {package!r} has no attribute {name!r}")
