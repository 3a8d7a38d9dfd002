"""Cuts remembered within one process: the same cut asked for again is not cut again.

Cutting is deterministic: the part depends only on the program, the machine, the machine's
errors, the tool, the stock and the cutter's options. An error budget reruns a procedure once
per source of error switched off, on a lab of its own; where the source acts only on an
instrument (a microscope's spot, its stage), every cut of the rerun is one the first run
already made. `CutMemo` keeps the last parts cut, under a SHA-256 digest of all their inputs,
so that `machinesim.Lab.cut` hands such a part back instead of cutting it again.

The digest covers the errors as the lab holds them, but the memo keeps only digests: nothing
in it gives the errors back (the honesty rule of DESIGN.md). A key that cannot be made (an
input that does not pickle, such as a servo model holding a closure) means no reuse, never
a wrong one; two inputs that differ in any bit give two keys.
"""

from __future__ import annotations

import hashlib
import pickle
from collections import OrderedDict
from dataclasses import replace

import numpy as np

from machinesim.workpiece import Part

__all__ = ["CutMemo", "REUSED_NOTE"]

#: The note a reused cut's report carries (besides the first cut's own notes and times).
REUSED_NOTE = ("reused: this process cut the same program on the same machine, errors, "
               "tool, stock and options before; the part and report are that cut's")


class CutMemo:
    """The last cuts made, by digest of their inputs, least recently used dropped first.

    Parameters
    ----------
    max_cuts : int
        How many cuts to keep. 64: paper 002's error budget makes about 30 cuts (two of
        the grooves and one of the crown per source) and must still find the first run's
        crown at its last source; memory is bounded by ``max_triangles``.
    max_triangles : int
        At most this many triangles over all kept parts (about 50 bytes each).
    """

    def __init__(self, max_cuts: int = 64, max_triangles: int = 20_000_000) -> None:
        self.max_cuts = max_cuts
        self.max_triangles = max_triangles
        self._cuts: OrderedDict[str, tuple[Part, object, int]] = OrderedDict()

    def __len__(self) -> int:
        return len(self._cuts)

    def clear(self) -> None:
        self._cuts.clear()

    @staticmethod
    def key(*inputs) -> str | None:
        """The digest of ``inputs`` (Parts by their vertices and set of triangles, the rest
        pickled), or None when one of them cannot be pickled."""
        digest = hashlib.sha256()
        for value in inputs:
            if isinstance(value, Part):
                vertices, triangles = value.mesh()
                for array in (vertices, _triangle_set(triangles)):
                    digest.update(str((array.dtype.str, array.shape)).encode())
                    digest.update(np.ascontiguousarray(array).tobytes())
                continue
            try:
                digest.update(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))
            except (pickle.PicklingError, TypeError, AttributeError):
                return None
            digest.update(b"\x00")
        return digest.hexdigest()

    def update(self, other: CutMemo) -> None:
        """Keep ``other``'s cuts too, as if put here in its order (an error budget's worker
        process is handed the cuts its parent made, `machinesim.budget.error_budget`)."""
        for key, (part, report, _) in other._cuts.items():
            self.put(key, part, report)

    def get(self, key: str | None):
        """(Part, report) cut under ``key`` before, its report noted as reused; or None."""
        if key is None or key not in self._cuts:
            return None
        self._cuts.move_to_end(key)
        part, report, _ = self._cuts[key]
        return part, replace(report, notes=tuple(report.notes) + (REUSED_NOTE,))

    def put(self, key: str | None, part: Part, report) -> None:
        """Keep a cut under ``key`` (nothing when ``key`` is None or it alone is too big)."""
        if key is None or self.max_cuts < 1:
            return
        size = part.triangle_count
        if size > self.max_triangles:
            return
        self._cuts[key] = (part, report, size)
        self._cuts.move_to_end(key)
        while (len(self._cuts) > self.max_cuts
               or sum(kept for _, _, kept in self._cuts.values()) > self.max_triangles):
            self._cuts.popitem(last=False)


def _triangle_set(triangles: np.ndarray) -> np.ndarray:
    """``triangles`` in one order whatever order they came in: each turned (its orientation
    kept) to start at its lowest vertex index, then sorted. Two builds of one solid can list
    its triangles in different orders (manifold3d does so between the first build of a
    workpiece in a process and the next); they are the same solid, with one key."""
    first = np.argmin(triangles, axis=1)
    turned = triangles[np.arange(len(triangles))[:, None], (first[:, None] + np.arange(3)) % 3]
    return turned[np.lexsort(turned.T[::-1])]
