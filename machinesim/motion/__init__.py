"""Motion: an NC program becomes a sampled axis trajectory q(t).

The controller interpolates G01 (and G00) linearly in *axis* space, so a move that turns a
rotary axis sweeps the tool along a curve in the workpiece frame. Such a move is split into
sub-steps until the chord between consecutive samples stays within ``chord_tolerance`` of
the true path for every point of the tool (the edge and the tool's extreme points): the
midpoint of each sub-step is evaluated through the kinematics and compared with the chord,
and so is every point where an axis crosses a breakpoint of an error table, where the path
has a corner (`machinesim.motion.chords`), and, along an axis with a polynomial error of
degree 3 or more, the Chebyshev points of each sub-step that the degree determines (such a
polynomial can vanish at the midpoints). A straight move of an axis whose errors vary
along it (straightness, angular or positioning tables, polynomials) bends the same way on
the erroneous machine, and is split by the same rule; on the nominal machine, and for axes
without such errors, a straight move stays one sweep.

Feed and time (FANUC rule, feed per minute, G94): a move's length is
``sqrt(sum(d_linear_mm**2) + sum(d_rotary_deg**2))`` and takes ``length / F`` minutes, so F
reads as mm/min for linear moves and deg/min for pure rotary moves (the chords of an arc
take their piece of arc over F, `machinesim.nc.Program.arc_lengths`), clamped so that no axis
runs faster than its velocity limit (the URDF's; a feed beyond it takes as long as the
move's slowest axis at that limit, as a rapid does). A rapid takes as long as its slowest
axis at its rapid rate (the URDF velocity limit), and its path is the straight line in axis
space, every axis arriving together: FANUC's linear-interpolation positioning (parameter
LRP), not the non-linear "dog-leg" positioning in which each axis runs at its own rate and
the short ones arrive first. The check of rapids that cut judges that path. A
dwell takes its time. Servo follow-up errors enter through a `ServoModel` (ideal by default):
each run of consecutive feed moves is followed as one continuous motion (the lag carries from
block to block, as on an arc's chords), each rapid and each dwell alone, from rest.

`plan` reads the program as arrays (`machinesim.nc.Program.targets`, ``kinds``, ...) and
works on all moves at once: a program of 10^6 moves is planned in numpy passes, not a
Python loop per move. The `Trajectory` it returns holds all samples end to end in ``q`` and
``t`` with ``offsets`` per move; ``trajectory.segments`` gives each move as a `Segment`.
"""

from machinesim._submodules import submodule
from machinesim.motion.chords import MAX_SUBSTEPS
from machinesim.motion.planner import move_duration, plan
from machinesim.motion.trajectory import IdealServo, Segment, Segments, ServoModel, Trajectory
from machinesim.tolerances import CHORD_TOLERANCE_M

__all__ = ["CHORD_TOLERANCE_M", "MAX_SUBSTEPS", "IdealServo", "Segment", "Segments",
           "ServoModel", "Trajectory", "move_duration", "plan"]


def __getattr__(name: str):
    # machinesim.motion.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
