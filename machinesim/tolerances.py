"""Central numerical tolerances, each with the reason it has its value (as trimesh.tol does)."""

from __future__ import annotations

#: Agreement of two float64 kinematic chains on a ~1 m machine: 1e-12 m is ~4500 ulp of 1 m
#: (ulp 2.2e-16), room for ~100 compositions of 4x4 transforms, yet 1000x below 1 nm.
POSE_M = 1e-12
#: The same for angles: rotation matrices are unit-scale, so the same float64 budget holds.
ANGLE_RAD = 1e-12
#: Inverse kinematics stops when the position residual is below this: far under the 1 nm axis
#: resolution, while still reachable in float64 at 1 m scale.
IK_POSITION_M = 1e-13
#: Inverse kinematics orientation residual, on the same reasoning.
IK_ANGLE_RAD = 1e-13
#: A pose is reported unreachable when the best position residual exceeds this: 1 pm is far
#: below any axis resolution, so a larger residual is a real miss, not round-off.
UNREACHABLE_M = 1e-12
#: Axis values may exceed their limits by this much (round-off of a value written at the
#: limit), relative to SI units: 1e-12 m or 1e-12 rad.
LIMIT_SLACK = 1e-12
