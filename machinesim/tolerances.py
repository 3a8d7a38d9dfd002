"""Central numerical tolerances, each with the reason it has its value (as trimesh.tol does)."""

from __future__ import annotations

import math

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

#: A polynomial error summed with a table (an injected polynomial on a machine whose
#: background holds a table, `machinesim.background.add_errors`) is tabulated so that
#: its linear interpolation is off by at most this, m or rad: 1/10 of `POSE_M`, so the
#: tabulated machine agrees with the exact sum as two float64 chains agree.
TABULATED_SUM = 1e-13

# --- kinematics
#: Below this angle (rad) `_cos_sin` uses its series: the first omitted terms, x**9/9! and
#: x**10/10!, are then below 3e-24 relative, far under float64's 1.1e-16, and error angles
#: (micro- to milliradians) always qualify.
SERIES_MAX_RAD = 1e-2

# --- motion
#: Default chord tolerance of a rotary move, m: the issue's 1 nm, the resolution of the axes.
CHORD_TOLERANCE_M = 1e-9
#: A cut's arcs and rotary moves are split into chords within this share of its finest
#: tool's own facet tolerance (`machinesim.tools.path_chord_tolerance`), never finer than
#: `CHORD_TOLERANCE_M`: the path's polygon then adds at most a tenth to the tool's. A ball
#: end mill's 1 um facets (`BALL_CHORD_M`) give 100 nm chords, 4.9 um -> 49 um long on a
#: 3 mm arc, ten times fewer sweeps than 1 nm chords for the same part within 1.1 um.
PATH_CHORD_SHARE = 0.1

# --- cutting.engine
#: Largest turn of the tool (rad) between two poses of a path, the turn of its axis for a
#: round tool (a spin about its own axis moves none of its points): a quarter turn. A sweep
#: is the hull of its two poses, cut in pieces where the turn tilts the tool across its
#: straight faces (`machinesim.cutting.tilted_solids`, `tilted_profiles`), each face
#: measured along its mean normal n0 + n1; that normal stands for the face at both poses
#: only while the face looks the same way at both (n0 . n1 > 0), a turn under a quarter
#: turn for every face. Beyond it a point's arc leaves its chord by over 0.29 of its
#: distance from the axis (1 - cos 45 deg), and at a half turn no face has a mean normal at
#: all: the hull is then no sweep, not even a rough one.
MAX_STEP_TURN_RAD = math.pi / 2.0
#: Sweeps are clipped at z = stock top + CLIP_MARGIN_REL * (largest stock coordinate). The
#: margin is 10^6 times manifold3d's own tolerance (1e-12 relative), so the clip plane never
#: merges with the top face, and small enough (10 nm on a 10 mm part) that the slivers by
#: which neighbouring clipped grooves still overlap are tiny.
CLIP_MARGIN_REL = 1e-6
#: Two poses have the same orientation when their rotation matrices differ by at most this:
#: then the sweep is a translation and its hull edges are known, so clipping needs no pair
#: search. 1e-12 is the kinematic agreement of two float64 chains (tolerances.POSE_M / 1 m).
SAME_ORIENTATION = 1e-12
#: A sweep whose tool turns so little between its poses that no tool vertex moves more than
#: this (m) from where the start pose's orientation, translated, would put it is cut as that
#: translation (a prism of the start profile). It then differs from the hull of the two
#: poses by at most this, and both stand for the tool turning continuously along the move
#: within it: 1/100 of the planner's chord tolerance (`CHORD_TOLERANCE_M`, 1 nm). A
#: machine's angular motion errors turn the tool by 1e-9 - 1e-7 rad along a move (1e-12 -
#: 8e-12 m over a sub-millimetre tool); as hulls, the crown passes of paper 002 on a machine
#: with such errors cut 13 times slower than as prisms.
TWIST_M = 1e-11
#: A non-rotational tool is dragged sideways when its move direction, in the tool frame, has
#: a Y component above this fraction of the move: 1 urad, i.e. the groove widens by more than
#: 1 nm per mm of travel, far above float64 round-off of a kinematic chain (~1e-15).
SIDEWAYS_REL = 1e-6
#: A feed is reported by line (`CutReport.sideways_lines`, a warning on the command line)
#: when it drags a non-rotational tool sideways by more than this angle (rad): 1 deg, below
#: the several degrees of clearance a tool's flanks are ground with (within which its body
#: stays inside the cut) and far above a machine's angular errors (urad to mrad), which
#: skew every groove by their own small angle without spoiling it.
SIDEWAYS_WARN_RAD = math.radians(1.0)
#: A sweep whose XY travel is below this fraction of its travel (a plunge, a turn in place)
#: has no XY direction and joins the group of such sweeps.
PLANAR_TRAVEL_REL = 1e-3
#: Poses are rigid when R^T R = I within this: a float64 kinematic chain gives ~1e-15, so
#: this rejects scaled or sheared matrices, never round-off.
RIGID_TOL = 1e-9

# --- cutting.program
#: A rapid whose sweep overlaps material by more than this volume (m^3) has cut: (10 nm)^3,
#: far above boolean round-off on a millimetre part, far below any real collision.
RAPID_CUT_VOLUME_M3 = 1e-24
#: Half thickness (m) given to a zero-thickness cutting edge for the rapid check only: an
#: edge plunging into material sweeps no volume, so the check thickens it (and the feed sweeps
#: it subtracts) by this much along the tool's X. 0.1 um: a plunge 1 um deep still shows
#: 1e-19 m^3, a million times the threshold.
RAPID_EDGE_HALF_THICKNESS_M = 1e-7
#: Stock thinner than this (m) between two faces of a part is a sheet left by round-off
#: where two sweeps' faces coincide, and is cut away (`machinesim.cutting.sheets`): 1 pm, a
#: hundredth of an atom's diameter, a thousandth of the axes' 1 nm resolution, and 4x the
#: thickest such sheet found (2.6e-13 m, paper 002's crown).
SHEET_M = 1e-12
#: A face of a part whose centroid lies deeper than this (m) inside a convex sweep just
#: subtracted is material the subtraction left (`machinesim.cutting.run_check`): 1 pm, the
#: sheet's thickness; the deepest centroid of a correct run measured 4.2e-16 m, the faces of
#: the wedge manifold3d left 1.9e-10 to 9.0e-8 m (a rotary turn, docs/cutting.md).
INSIDE_SWEEP_M = 1e-12

# --- tools
#: Chord tolerance of profile arcs (m): 1 nm, the axis resolution of the machines (1 nm),
#: so the tessellation never shows in a simulated measurement of a nose-radius profile.
PROFILE_CHORD_M = 1e-9
#: Chord tolerance of the ball end mill sphere (m). A ball end mill roughs (seed 002 leaves
#: the crown 10 um oversize), so 1 um is ten times finer than the stock allowance while a
#: R2 mm sphere stays at a few thousand vertices, keeping the hull of a sweep (two spheres)
#: a few milliseconds.
BALL_CHORD_M = 1e-6

# --- workpiece
#: Chord tolerance of cylindrical stock (m): 1 nm, the machines' axis resolution, so the
#: polygon never shows in a measurement of an unmachined face.
CYLINDER_CHORD_M = 1e-9
#: Chord tolerance of the reference spheres (m): they are rough-machined features whose form
#: error in seed 002 is 1-2 um, so 0.1 um is well below it while a R2 mm sphere stays at
#: ~10^5 triangles (facet depth, not chord sagitta: see tools.sphere_polygon).
SPHERE_CHORD_M = 1e-7

# --- machines
#: Singular values below this (per m or per rad of axis motion) are directions the axes cannot
#: move the tool in: an absolute cut-off, so that a null-space task with nothing left to move
#: does not amplify round-off into a step.
IK_SINGULAR = 1e-9
#: The inverse, matching the tool's whole orientation, leaves unmatched (and reports) what
#: the axes could produce only by turning the tool less than this (rad) per unit length of
#: the axis step (rad and m together), in the null space of the position task: to match a
#: residual tau there the step would be tau / s long. On robonano_ui A and C are nearly one
#: axis while B is near 0: A against C turns the tool by |sin B| per rad of each, a step of
#: unit length turns each by 1/sqrt(2), so s = |sin B| / sqrt(2) (the singular value there):
#: a 10 urad tool tilt at A = 0.3 rad, B = 0 had B take 3 urad, then C turn by
#: 253 deg and A by as much against it (an AxisLimitError of the model-based compensation,
#: blaming the errors' size), or Newton leave its linear range (an UnreachableError of a
#: reachable point). 1e-3 drops such gimbal lock, where B is within an error's size of 0,
#: and keeps every direction of B beyond asin(sqrt(2) 1e-3) = 0.0810 deg (a step of at most
#: 1000 tau, A and C at most 707 tau each). Matching the
#: tool axis alone keeps `IK_SINGULAR`: there a C turn at a small B is how the axis tilts,
#: and `inverse.axis_values` tries turned starts for what is left.
IK_WEAK_TURN = 1e-3

# --- metrology.surface
#: A grid whose coordinates lie within this fraction of a spacing of an arithmetic progression
#: is binned by arithmetic instead of binary search (a linspace grid is within ~1e-13).
UNIFORM_GRID = 1e-3
#: Bins found by arithmetic are widened by this many spacings beyond the grid's own deviation
#: and the round-off of the arithmetic, so that they are a superset of the samples in a
#: triangle's box whatever the rounding; extra samples are rejected by the exact test.
INDEX_SLACK = 1e-6
#: A profile line is taken to pass near a triangle's box, and a grid row's span of a
#: triangle is widened, by this fraction of the largest coordinate: far above the ~1e-16
#: relative round-off of the line test, the span's crossings and the sample points, far
#: below any feature; again only a superset for the exact test.
LINE_MARGIN = 1e-12
#: The end of a profile is sampled when the length is a whole number of spacings to within this
#: fraction of a spacing (round-off of length / spacing).
END_SLACK = 1e-9

# --- metrology.probe
#: The swept box is padded by this fraction of (|centre| + travel + radius): far above the
#: ~1e-16 relative round-off of centre + travel * direction, far below anything measurable.
#: It only widens the candidate cull; contact itself is solved exactly.
SWEEP_PAD = 1e-12

# --- metrology.probe_instrument
#: A path piece is straight enough when every sampled centre lies within this distance of its
#: constant-speed chord, m: 100x below the probe's 1 nm resolution, 10^4x above the ~1e-15 m
#: round-off of centres computed through a ~0.5 m kinematic chain.
PROBE_CHORD_M = 1e-11

# --- cutting.stitch
#: Wall vertices of neighbouring tiles that lie within this distance (relative to the
#: largest coordinate) are one vertex. Both sides compute the same point from the same
#: float64 data; measured disagreement is ~2e-16 relative, and 1e-13 stays 10x below
#: manifold3d's own tolerance (1e-12), so no distinct vertices of a valid part are merged.
WALL_TOL_REL = 1e-13

# --- cutting.tiling
#: Tile boxes reach this far (relative to the largest stock coordinate) beyond the stock
#: wherever they are not cutting it, far from the clip plane and the cell edges.
BOX_CLEARANCE_REL = 1e-2

# --- cutting.relief
#: A move is straight along X (or Y) when its other two components are at most this fraction
#: of its length; the relief then extrudes the profile at the start pose, off by at most this
#: fraction of the travel (5e-13 m over 0.5 m), where a float64 kinematic chain leaves ~1e-16.
STRAIGHT_REL = 1e-12
#: F(y) and G(x) are equal at a grid corner when they differ by at most this fraction of the
#: largest coordinate (2.5e-15 m on a 25 mm block): their float64 evaluations from different
#: grooves differ by a few ulp (~1e-17 m) where they are equal in exact arithmetic, and
#: treating them as equal saves sliver triangles of that width.
HEIGHT_TIE_REL = 1e-13

# --- identification.fit
#: Singular values of the column-scaled weighted Jacobian below this fraction of the largest
#: are null directions (rank cut-off). Exact symmetries of a model (a rotary axis' zero offset
#: absorbed by a setting error, a parameter no reading sees) come out at 1e-16 .. 1e-13 of
#: the largest: float64 round-off of Pinocchio's entries (~1e-16) times sqrt(k). A real
#: direction as weak as 1e-8 would carry a standard uncertainty 1e8 times that of the best
#: determined one, metres or radians for nanometre sensors, which no plan should rely on; and
#: null vectors cut here are accurate to ~eps / 1e-8 ~ 2e-8, below `FIT_NULL_COMPONENT`.
FIT_RANK_REL = 1e-8
#: A parameter is identifiable on its own when its unit vector (scaled coordinates) has a
#: null-space component of at most this (the sine of its angle to the row space); the
#: coefficients of a named null-space combination below this fraction of the largest (scaled
#: coordinates: their effect on the readings) are dropped. 50x above the round-off of the null
#: basis (see `FIT_RANK_REL`); and a parameter so weakly tied to a symmetry moves by at most
#: 1e-6 of the symmetry's displacement, the relative accuracy identification is held to.
FIT_NULL_COMPONENT = 1e-6
#: A parameter whose weighted RMS sensitivity (m per m, or m per rad: a lever arm) is at most
#: this moves no reading: its column is set to zero instead of being scaled to unit norm,
#: which would turn Pinocchio's ~1e-16 round-off into a direction. 1e-12 is 10^4 above that
#: round-off and a 1 pm lever, far below any real sensitivity.
FIT_ZERO_COLUMN = 1e-12
#: Gauss-Newton stops when every length step is below this (m): 1000x below the 1 nm axis
#: resolution of the machines, and far above the float64 floor of the steps (~1e-16 m on
#: the R-test fits of tests/test_identification_fit_r_test.py, noisy or not, iterated past
#: this rule), so it is reached, not approached: quadratic convergence lands well under it.
FIT_STEP_M = 1e-12
#: The same for angle steps (rad): 1e5x below the 0.00001 deg (1.7e-7 rad) rotary resolution
#: (a 1e-12 rad step moves a point 0.1 m away by 1e-13 m); the floor measured as above is
#: ~1e-15 rad.
FIT_STEP_RAD = 1e-12
