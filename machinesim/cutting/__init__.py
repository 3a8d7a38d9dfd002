"""Cutting: `cut` runs an NC program on a machine; `remove` is the exact material-removal engine."""

from machinesim.cutting.engine import EngineReport, remove, rotary_substeps
from machinesim.cutting.program import CutReport, cut

__all__ = ["CutReport", "EngineReport", "cut", "remove", "rotary_substeps"]
