"""Virtual instruments reading a machined part (never the injected errors).

The exact, noise-free core: top-surface height maps and profiles (`surface`), and the
contact of a touch-probe ball swept against the part's triangles (`probe`), found through
a tree over them (`meshindex`).
"""

from __future__ import annotations

from machinesim.metrology.meshindex import MeshIndex
from machinesim.metrology.probe import Contact, Contacts, touch, touch_many
from machinesim.metrology.surface import height_map, profile

__all__ = ["Contact", "Contacts", "MeshIndex", "height_map", "profile", "touch", "touch_many"]
