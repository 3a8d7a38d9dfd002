"""Procedures: each published calibration experiment in the one shape of
`machinesim.experiment` (measure on a lab, identify, compensate, evaluate).

One module per procedure, named by what it identifies; each cites its paper:

- `tool_rotation_arm`: a planer's tool-rotation arm, r and e_ys (paper 000);
- `tool_setting_6axis`: the tool edge's offset from the A, B, C centres (paper 001);
- `workpiece_setting`: a robot-loaded workpiece's setting and the C centre (paper 002);
- `xy_plane_errors`: the XY plane's 2-D errors (ISO 230-2/-6, eq 1), the C table's
  squareness and pyramids across a 400 mm plate (paper 003).

Run one with `machinesim.experiment.run(procedure, lab)`. The formulas live in
`machinesim.identification`, which sees measurements only; the test pieces' design in
`machinesim.cam`.
"""

from machinesim._submodules import submodule


def __getattr__(name: str):
    # machinesim.procedures.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
