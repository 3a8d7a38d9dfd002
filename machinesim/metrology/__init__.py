"""Virtual instruments reading a machined part (never the injected errors).

The exact, noise-free core: top-surface height maps and profiles (`surface`), and the
contact of a touch-probe ball swept against the part's triangles (`probe`), found through
a tree over them (`meshindex`).
"""

from __future__ import annotations

from machinesim.metrology.instruments import Readout
from machinesim.metrology.interferometer import (
    InterferometerReading,
    LaserInterferometer,
    squareness_from_diagonal,
)
from machinesim.metrology.meshindex import MeshIndex
from machinesim.metrology.optical import HeightMap, Microscope, Profile, WhiteLightInterferometer
from machinesim.metrology.probe import Contact, Contacts, touch, touch_many
from machinesim.metrology.probe_instrument import ScanReading, TouchProbe
from machinesim.metrology.surface import height_map, profile

__all__ = ["Contact", "Contacts", "MeshIndex", "height_map", "profile", "touch", "touch_many"]
__all__ += [
    "HeightMap", "InterferometerReading", "LaserInterferometer", "Microscope", "Profile",
    "Readout", "ScanReading", "TouchProbe", "WhiteLightInterferometer", "squareness_from_diagonal",
]
