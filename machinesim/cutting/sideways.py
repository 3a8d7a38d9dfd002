"""Which moves of a non-rotational (planar) tool go sideways: dragged across its edge's
plane, kept within it, or leaving it past the flank's clearance."""

from __future__ import annotations

import numpy as np

from machinesim.tolerances import SIDEWAYS_REL, SIDEWAYS_WARN_RAD


def dragged_past_clearance(poses: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Which sweeps, from poses ``starts`` to the next, leave the XZ plane of the tool at
    its start pose by more than `SIDEWAYS_WARN_RAD`: a real tool's flank rubs there."""
    local = np.einsum("nji,nj->ni", poses[starts, :3, :3],
                      poses[starts + 1, :3, 3] - poses[starts, :3, 3])
    angle = np.arctan2(np.abs(local[:, 1]), np.hypot(local[:, 0], local[:, 2]))
    return angle > SIDEWAYS_WARN_RAD


def within_edge_plane(rotation: np.ndarray, move: np.ndarray) -> np.ndarray:
    """Which moves (s, 3) keep a non-rotational tool at ``rotation`` (s, 3, 3) within the
    plane of its edge profile (its Y-Z plane: no component along its cutting direction X),
    where its zero-thickness edge sweeps no volume: a plunge, a lift, a drag across."""
    local = np.einsum("nji,nj->ni", rotation, move)
    length = np.linalg.norm(local, axis=1)
    return (np.abs(local[:, 0]) <= SIDEWAYS_REL * length) & (length > 0.0)


def dragged(rotation: np.ndarray, move: np.ndarray) -> np.ndarray:
    """Which moves (s, 3) drag a non-rotational tool at ``rotation`` (s, 3, 3) sideways."""
    local = np.einsum("nji,nj->ni", rotation, move)
    length = np.linalg.norm(local, axis=1)
    return (np.abs(local[:, 1]) > SIDEWAYS_REL * length) & (length > 0.0)


__all__ = ["dragged", "dragged_past_clearance", "within_edge_plane"]
