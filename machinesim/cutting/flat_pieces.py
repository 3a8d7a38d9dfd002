"""Separate pieces of a part thinner than an atom, taken away whole.

A sheet (`machinesim.cutting.sheets`) usually stands on the cut surface; the booleans can
also leave one free, beside the part: a piece of a few triangles whose vertices lie in one
plane to round-off. `flat_pieces` finds such pieces and puts the part together without
them, every other triangle kept bit for bit with its origin.
"""

from __future__ import annotations

import manifold3d

from machinesim.tolerances import SHEET_M

__all__ = ["flat_pieces"]


def flat_pieces(solid: manifold3d.Manifold, thickness: float = SHEET_M
                ) -> tuple[manifold3d.Manifold, list[tuple[float, float, float]]]:
    """``solid`` without its separate pieces thinner than ``thickness`` on average (volume
    below ``thickness`` times half the surface area), and each such piece's half area (m^2),
    mean thickness (m) and volume (m^3, of either sign: round-off).

    The booleans can leave such a piece beside the part: a V tool led in a spiral under
    servo lag left three flat tetrahedra in its groove, 10-24 um long and 20 um high, of
    -1.3e-29 to 1.5e-29 m^3 (their four vertices in one plane to 1e-18 m). Their faces
    face each other within round-off, so `find_sheets` reads some pairs as cracks and
    keeps them; a height map reads such a piece as a wall, and `machinesim cut` warned of a
    part "in 4 separate pieces". No material is that thin.

    The other pieces are put together again by `manifold3d.Manifold.compose`, which keeps
    each triangle bit for bit with its origin. It drops a void's shell (a piece of negative
    volume, a cut closed under the surface), so a part with a void keeps its flat pieces;
    so does a part of one piece, or of flat pieces only. A mesh rebuilt from the kept
    triangles is not the same part: manifold3d's constructor simplifies it anew (a cross
    of nose-tool grooves gained 7.4e-18 m^3 so)."""
    pieces = solid.decompose()  # most parts one piece: 0.03 s on 1,000,000 triangles
    if len(pieces) < 2:
        return solid, []
    kept, flat = [], []
    for piece in pieces:
        volume, half_area = piece.volume(), 0.5 * piece.surface_area()
        if abs(volume) < thickness * half_area:
            flat.append((half_area, abs(volume) / half_area, volume))
        else:
            kept.append((piece, volume))
    if not flat or not kept or any(volume < 0.0 for _, volume in kept):
        return solid, []
    return manifold3d.Manifold.compose([piece for piece, _ in kept]), flat
