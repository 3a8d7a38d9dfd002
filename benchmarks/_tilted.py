"""What benchmarks/tilted_profiles.py and tilted_solids.py share: the variants' alternating
timed runs and (from tests/tilted_cuts.py, which the tests of the same engine use) the
engine's swept cut of a posed tool and the distance to the cut's surface."""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from tilted_cuts import nearest_material, swept_cut, swing  # noqa: E402

__all__ = ["alternate", "nearest_material", "swept_cut", "swing"]


def alternate(cut: Callable[[bool], tuple], repeat: int,
              split_name: str) -> list[tuple[str, list[tuple], float]]:
    """``cut(True)`` (split, the default) and ``cut(False)`` (one hull, as before), ``repeat``
    times, alternating: for each, its name (``split_name``; "one hull (before)"), its results
    in order and the median of their wall times (s)."""
    runs = {True: [], False: []}
    for _ in range(repeat):
        for split in (True, False):
            began = time.perf_counter()
            result = cut(split)
            runs[split].append((result, time.perf_counter() - began))
    return [(name, [result for result, _ in runs[split]],
             statistics.median(seconds for _, seconds in runs[split]))
            for split, name in ((True, split_name), (False, "one hull (before)"))]
