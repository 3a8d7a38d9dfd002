"""A procedure that measures nothing, for tests of what runs, reports and report folders do
with a result whatever a procedure reads (tests/test_lab_report.py, tests/test_report_summary.py,
tests/test_report_write_result.py)."""

from __future__ import annotations

from machinesim.experiment import Evaluation, Figure, Identified


class WorkpieceX:
    """Identifies ``workpiece.x`` as 0 (std 1 nm) from no reading, compensates nothing, and
    evaluates one figure ``x`` (um): 1.0 before, ``after`` after, with a 1 mm block for
    each name of ``parts`` as its parts."""

    name, paper = "workpiece_x", "none"

    def __init__(self, after: float = 0.0, parts=()) -> None:
        self.after, self.parts = after, tuple(parts)

    def measure(self, lab):
        return 0.0

    def identify(self, measurements):
        return Identified({"workpiece.x": (measurements, 1e-9)}, None)

    def compensate(self, identified):
        return {}

    def evaluate(self, lab, identified, programs):
        from machinesim.workpiece import stock_from_spec

        return Evaluation((Figure("x", "um", 1.0, self.after),),
                          parts={name: stock_from_spec("block:1x1x1") for name in self.parts})
