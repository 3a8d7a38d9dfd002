"""Cutting: `cut` runs an NC program on a machine; `remove` is the exact material-removal engine."""

from machinesim._submodules import submodule
from machinesim.cutting.engine import EngineReport, remove, rotary_substeps
from machinesim.cutting.program import cut
from machinesim.cutting.report import CutReport
from machinesim.cutting.windows import clip_to, cut_turned

__all__ = ["CutReport", "EngineReport", "clip_to", "cut", "cut_turned", "remove",
           "rotary_substeps"]


def __getattr__(name: str):
    # machinesim.cutting.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
