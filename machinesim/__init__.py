"""machinesim: a virtual multi-axis ultraprecision machine tool."""

from __future__ import annotations

from machinesim.exceptions import MachineSimError

__all__ = ["MachineSimError"]
__version__ = "0.1.0"
