"""Write the five machine URDFs of machinesim from one description each.

Run ``python models/build_models.py`` after editing a description here; a test checks that
the files in models/ are what this script writes, so the two never drift apart.

Conventions every model follows (docs/machines.md explains them with figures):

- Z is drawn up and the tool points along -Z at zero axis values; at zero, on the nominal
  machine, the tool edge (``tool_tip``) sits at the workpiece origin.
- Every joint frame is parallel to the machine axes at zero. Joints are named by their NC
  letters. A joint that moves the workpiece side has its axis reversed (ISO 841), so that a
  positive command moves the tool relative to the workpiece in the positive direction on
  every machine, whichever side carries the axis.
- Rotary axis centre lines pass through the workpiece origin (workpiece side) or through the
  tool edge (tool side); the planer's tool-rotation axis is the exception, its edge on an arm
  of radius r below the axis.
- ``tool_mount`` is the tool holder reference, 20 mm above the edge, parallel to the machine
  axes; ``tool_tip`` is the edge, parallel to ``workpiece`` at zero.
- Each axis carries its resolution (m or rad) in a ``<machinesim:axis>`` element, which URDF
  parsers ignore.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

HERE = Path(__file__).resolve().parent
DEG = math.pi / 180.0
NM = 1e-9
RES_LINEAR = 1 * NM  # 1 nm, papers 001 and 002
RES_ROTARY = 0.00001 * DEG  # 0.00001 deg, papers 001 and 002
TOOL_HOLDER = 0.020  # tool_mount sits 20 mm above the edge

COLOURS = {
    "bed": "0.35 0.37 0.40 1",
    "slide": "0.55 0.60 0.66 1",
    "rotary": "0.80 0.55 0.20 1",
    "chuck": "0.25 0.45 0.70 1",
    "tool": "0.85 0.85 0.90 1",
    "probe": "0.75 0.10 0.15 1",
}


@dataclass
class Visual:
    """A box (size) or cylinder (radius, length) placed in its link frame."""

    colour: str
    box: tuple[float, float, float] | None = None
    cylinder: tuple[float, float] | None = None
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class Joint:
    """A joint: an axis (prismatic/revolute) or a fixed link-to-link placement."""

    name: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    kind: str = "fixed"
    axis: tuple[float, float, float] = (0.0, 0.0, 0.0)
    lower: float = 0.0
    upper: float = 0.0
    velocity: float = 0.0  # rapid rate, m/s or rad/s
    resolution: float = 0.0


@dataclass
class Machine:
    name: str
    summary: str
    links: dict[str, list[Visual]] = field(default_factory=dict)
    joints: list[Joint] = field(default_factory=list)

    def link(self, name: str, *visuals: Visual) -> None:
        self.links[name] = list(visuals)

    def joint(self, *args, **kwargs) -> None:
        self.joints.append(Joint(*args, **kwargs))


def _f(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def to_urdf(m: Machine) -> str:
    out = [
        '<?xml version="1.0"?>',
        f"<!-- {m.summary} -->",
        "<!-- Written by models/build_models.py: edit the description there, then rerun it. -->",
        f'<robot name="{m.name}" xmlns:machinesim="https://machinesim.invalid/urdf">',
    ]
    for colour, rgba in COLOURS.items():
        out.append(f'  <material name="{colour}"><color rgba="{rgba}"/></material>')
    for name, visuals in m.links.items():
        out.append(f'  <link name="{name}">')
        for v in visuals:
            if v.box is not None:
                geometry = f'<box size="{_f(v.box)}"/>'
            else:
                geometry = f'<cylinder radius="{v.cylinder[0]!r}" length="{v.cylinder[1]!r}"/>'
            out.append(
                f'    <visual><origin xyz="{_f(v.xyz)}" rpy="{_f(v.rpy)}"/>'
                f'<geometry>{geometry}</geometry><material name="{v.colour}"/></visual>'
            )
        out.append("  </link>")
    for j in m.joints:
        out.append(f'  <joint name="{j.name}" type="{j.kind}">')
        out.append(f'    <parent link="{j.parent}"/><child link="{j.child}"/>')
        out.append(f'    <origin xyz="{_f(j.xyz)}" rpy="0.0 0.0 0.0"/>')
        if j.kind != "fixed":
            out.append(f'    <axis xyz="{_f(j.axis)}"/>')
            out.append(
                f'    <limit lower="{j.lower!r}" upper="{j.upper!r}" '
                f'effort="1000.0" velocity="{j.velocity!r}"/>'
            )
        out.append("  </joint>")
    for j in m.joints:
        if j.kind != "fixed":
            out.append(
                f"  <machinesim:axis joint={quoteattr(j.name)} "
                f'resolution="{j.resolution!r}"/>'
            )
    out.append("</robot>")
    return "\n".join(out) + "\n"


def _bed(m: Machine, size=(0.8, 0.7, 0.1)) -> None:
    m.link("base", Visual("bed", box=size, xyz=(0.0, 0.0, -size[2] / 2)))


def _tool(m: Machine, parent: str, edge_in_parent) -> None:
    """tool_mount 20 mm above the edge, tool_tip at the edge."""
    ex, ey, ez = edge_in_parent
    m.link(
        "tool_mount",
        Visual("tool", box=(0.006, 0.006, 0.030), xyz=(0.0, 0.0, 0.015 - 0.0)),
    )
    m.link("tool_tip", Visual("tool", cylinder=(0.0015, 0.020), xyz=(0.0, 0.0, 0.010)))
    m.joint("tool_mount_fixed", parent, "tool_mount", (ex, ey, ez + TOOL_HOLDER))
    m.joint("tool_tip_fixed", "tool_mount", "tool_tip", (0.0, 0.0, -TOOL_HOLDER))


def _linear(m, name, parent, child, xyz, axis, lower, upper):
    m.joint(name, parent, child, xyz, "prismatic", axis, lower, upper, 0.025, RES_LINEAR)


def _rotary(m, name, parent, child, xyz, axis, lower_deg, upper_deg, velocity=2.0):
    m.joint(
        name, parent, child, xyz, "revolute", axis, lower_deg * DEG, upper_deg * DEG,
        velocity, RES_ROTARY,
    )


def _workpiece_side_c(m: Machine, parent: str, c_height_in_parent: float, wp_z: float) -> None:
    """C table (axis through the workpiece origin), chuck surface `table`, `workpiece`.

    `wp_z` is the height of the workpiece origin above the C joint frame.
    """
    m.link("c_table", Visual("rotary", cylinder=(0.09, 0.04), xyz=(0.0, 0.0, -0.02)))
    m.link("table", Visual("chuck", cylinder=(0.05, 0.01), xyz=(0.0, 0.0, -0.005)))
    m.link("workpiece")
    _rotary(m, "C", parent, "c_table", (0.0, 0.0, c_height_in_parent), (0, 0, -1), -360, 360)
    m.joint("table_fixed", "c_table", "table", (0.0, 0.0, wp_z - 0.005))
    m.joint("workpiece_fixed", "table", "workpiece", (0.0, 0.0, 0.005))


def robonano_ui() -> Machine:
    m = Machine(
        "robonano_ui",
        "6-axis X Y Z A B C after paper 001 (ROBOnano Ui style): workpiece on Y and C; "
        "tool on X, Z, B (tilt about Y) and A (rotation about the tool axis)",
    )
    _bed(m)
    edge_z = 0.205  # tool edge / workpiece origin height above the bed at zero
    m.link("y_carriage", Visual("slide", box=(0.30, 0.30, 0.05), xyz=(0.0, 0.0, -0.025)))
    _linear(m, "Y", "base", "y_carriage", (0.0, 0.0, 0.10), (0, -1, 0), -0.05, 0.05)
    _workpiece_side_c(m, "y_carriage", 0.08, edge_z - 0.18)
    m.link("x_carriage", Visual("slide", box=(0.30, 0.08, 0.10)))
    m.link("z_carriage", Visual("slide", box=(0.10, 0.10, 0.20), xyz=(0.0, 0.05, 0.10)))
    m.link("b_table", Visual("rotary", cylinder=(0.05, 0.03), xyz=(0.0, 0.08, 0.06),
                             rpy=(math.pi / 2, 0.0, 0.0)))
    m.link("a_spindle", Visual("rotary", cylinder=(0.02, 0.05), xyz=(0.0, 0.0, 0.06)))
    _linear(m, "X", "base", "x_carriage", (0.0, 0.30, 0.40), (1, 0, 0), -0.14, 0.14)
    _linear(m, "Z", "x_carriage", "z_carriage", (0.0, -0.30, -0.05), (0, 0, 1), -0.03, 0.10)
    _rotary(m, "B", "z_carriage", "b_table", (0.0, 0.0, edge_z - 0.35), (0, 1, 0), -100, 100)
    _rotary(m, "A", "b_table", "a_spindle", (0.0, 0.0, 0.0), (0, 0, 1), -360, 360)
    _tool(m, "a_spindle", (0.0, 0.0, 0.0))
    return m


def robonano_a0ib() -> Machine:
    m = Machine(
        "robonano_a0ib",
        "5-axis X Y Z B C after paper 002 (ROBOnano alpha-0iB style): workpiece on a vacuum "
        "chuck on C, carried by Y; diamond tool on the B table via an angle plate, touch probe "
        "(R0.25 mm ruby ball) beside it on the B table; B and the tool on Z, carried by X",
    )
    _bed(m)
    edge_z = 0.205
    m.link("y_carriage", Visual("slide", box=(0.30, 0.30, 0.05), xyz=(0.0, 0.0, -0.025)))
    _linear(m, "Y", "base", "y_carriage", (0.0, 0.0, 0.10), (0, -1, 0), -0.075, 0.075)
    _workpiece_side_c(m, "y_carriage", 0.08, edge_z - 0.18)
    m.link("x_carriage", Visual("slide", box=(0.30, 0.08, 0.10)))
    m.link("z_carriage", Visual("slide", box=(0.10, 0.10, 0.20), xyz=(0.0, 0.05, 0.10)))
    m.link(
        "b_table",
        Visual("rotary", cylinder=(0.06, 0.03), xyz=(0.0, 0.0, 0.07)),
        Visual("slide", box=(0.03, 0.07, 0.04), xyz=(0.0, 0.02, 0.045)),  # angle plate
    )
    _linear(m, "X", "base", "x_carriage", (0.0, 0.30, 0.40), (1, 0, 0), -0.14, 0.14)
    _linear(m, "Z", "x_carriage", "z_carriage", (0.0, -0.30, -0.05), (0, 0, 1), -0.03, 0.10)
    _rotary(m, "B", "z_carriage", "b_table", (0.0, 0.0, edge_z - 0.35), (0, 1, 0), -100, 100)
    _tool(m, "b_table", (0.0, 0.0, 0.0))
    # Probe ball centre on the B axis line, 40 mm along +Y from the edge and 1 mm above it, so
    # that B turns do not move it and the ball clears the part while the tool cuts.
    m.link("probe_body", Visual("probe", cylinder=(0.004, 0.030), xyz=(0.0, 0.0, 0.016)))
    m.link("probe_tip", Visual("probe", cylinder=(0.00025, 0.0005)))
    m.joint("probe_body_fixed", "b_table", "probe_body", (0.0, 0.040, 0.001))
    m.joint("probe_tip_fixed", "probe_body", "probe_tip", (0.0, 0.0, 0.0))
    return m


PLANER_ARM_RADIUS = 0.1205  # paper 000: nominal arm radius r of about 120.5 mm


def planer_4axis() -> Machine:
    m = Machine(
        "planer_4axis",
        "4-axis planer X Y Z + A after paper 000: workpiece on X; tool on Y, Z and a tool "
        "rotation axis A about X, the edge on an arm of nominal radius 120.5 mm below A",
    )
    _bed(m, size=(0.9, 0.6, 0.1))
    edge_z = 0.20
    m.link("x_carriage", Visual("slide", box=(0.40, 0.30, 0.05), xyz=(0.0, 0.0, -0.025)))
    m.link("table", Visual("chuck", box=(0.20, 0.20, 0.01), xyz=(0.0, 0.0, -0.005)))
    m.link("workpiece")
    _linear(m, "X", "base", "x_carriage", (0.0, 0.0, 0.10), (-1, 0, 0), -0.20, 0.20)
    m.joint("table_fixed", "x_carriage", "table", (0.0, 0.0, edge_z - 0.10 - 0.005))
    m.joint("workpiece_fixed", "table", "workpiece", (0.0, 0.0, 0.005))
    m.link("y_carriage", Visual("slide", box=(0.10, 0.50, 0.08)))
    m.link("z_carriage", Visual("slide", box=(0.10, 0.10, 0.20), xyz=(0.0, 0.0, 0.10)))
    m.link(
        "a_arm",
        Visual("rotary", cylinder=(0.03, 0.04), rpy=(0.0, math.pi / 2, 0.0)),
        Visual("rotary", box=(0.02, 0.015, PLANER_ARM_RADIUS - 0.02),
               xyz=(0.0, 0.0, -(PLANER_ARM_RADIUS - 0.02) / 2)),
    )
    _linear(m, "Y", "base", "y_carriage", (0.0, 0.0, 0.45), (0, 1, 0), -0.10, 0.10)
    _linear(m, "Z", "y_carriage", "z_carriage", (0.0, 0.0, -0.05), (0, 0, 1), -0.05, 0.10)
    a_height = edge_z + PLANER_ARM_RADIUS
    _rotary(m, "A", "z_carriage", "a_arm", (0.0, 0.0, a_height - 0.40), (1, 0, 0), -45, 45)
    _tool(m, "a_arm", (0.0, 0.0, -PLANER_ARM_RADIUS))
    return m


def grooving_4axis() -> Machine:
    m = Machine(
        "grooving_4axis",
        "4-axis grooving machine X Y Z C after paper 003: 500 x 500 x 150 mm travel; "
        "C table carried by Y; Z (vertical) carried by X",
    )
    _bed(m, size=(1.2, 1.2, 0.15))
    edge_z = 0.20
    m.link("y_carriage", Visual("slide", box=(0.60, 0.60, 0.06), xyz=(0.0, 0.0, -0.03)))
    _linear(m, "Y", "base", "y_carriage", (0.0, 0.0, 0.08), (0, -1, 0), -0.25, 0.25)
    m.link("c_table", Visual("rotary", cylinder=(0.28, 0.05), xyz=(0.0, 0.0, -0.025)))
    m.link("table", Visual("chuck", box=(0.40, 0.40, 0.01), xyz=(0.0, 0.0, -0.005)))
    m.link("workpiece")
    _rotary(m, "C", "y_carriage", "c_table", (0.0, 0.0, 0.06), (0, 0, -1), -360, 360)
    m.joint("table_fixed", "c_table", "table", (0.0, 0.0, edge_z - 0.14 - 0.005))
    m.joint("workpiece_fixed", "table", "workpiece", (0.0, 0.0, 0.005))
    m.link("x_carriage", Visual("slide", box=(0.20, 0.12, 0.12)))
    m.link("z_carriage", Visual("slide", box=(0.12, 0.12, 0.30), xyz=(0.0, 0.0, 0.15)))
    _linear(m, "X", "base", "x_carriage", (0.0, 0.40, 0.55), (1, 0, 0), -0.25, 0.25)
    _linear(m, "Z", "x_carriage", "z_carriage", (0.0, -0.40, -0.25), (0, 0, 1), -0.05, 0.10)
    _tool(m, "z_carriage", (0.0, 0.0, edge_z - 0.30))
    return m


def sts_lathe() -> Machine:
    m = Machine(
        "sts_lathe",
        "3-axis slow-tool-servo diamond lathe X Z C after paper 004: work spindle C on the "
        "X slide; round-nose diamond tool on the fast Z slide, facing the part (drawn with "
        "the spindle axis vertical)",
    )
    _bed(m, size=(0.8, 0.6, 0.1))
    edge_z = 0.20
    m.link("x_carriage", Visual("slide", box=(0.40, 0.30, 0.05), xyz=(0.0, 0.0, -0.025)))
    _linear(m, "X", "base", "x_carriage", (0.0, 0.0, 0.08), (-1, 0, 0), -0.10, 0.10)
    m.link("c_table", Visual("rotary", cylinder=(0.08, 0.06), xyz=(0.0, 0.0, -0.03)))
    m.link("table", Visual("chuck", cylinder=(0.04, 0.01), xyz=(0.0, 0.0, -0.005)))
    m.link("workpiece")
    # A spindle turns many revolutions in one program: wide limits, not a continuous joint,
    # so that C stays one real coordinate.
    m.joint("C", "x_carriage", "c_table", (0.0, 0.0, 0.07), "revolute", (0, 0, -1),
            -1.0e5, 1.0e5, 150.0, RES_ROTARY)
    m.joint("table_fixed", "c_table", "table", (0.0, 0.0, edge_z - 0.15 - 0.005))
    m.joint("workpiece_fixed", "table", "workpiece", (0.0, 0.0, 0.005))
    m.link("z_carriage", Visual("slide", box=(0.10, 0.20, 0.12), xyz=(0.0, 0.0, 0.06)))
    _linear(m, "Z", "base", "z_carriage", (0.0, 0.0, 0.35), (0, 0, 1), -0.05, 0.10)
    _tool(m, "z_carriage", (0.0, 0.0, edge_z - 0.35))
    return m


MACHINES = (robonano_ui, robonano_a0ib, planer_4axis, grooving_4axis, sts_lathe)


def _frames(m: Machine) -> None:
    """Every machine has base, table, workpiece, tool_mount and tool_tip; check it here."""
    for frame in ("base", "table", "workpiece", "tool_mount", "tool_tip"):
        if frame not in m.links:
            raise SystemExit(f"{m.name}: missing frame {frame}")


def build() -> dict[str, str]:
    """URDF text of every machine, by name."""
    texts = {}
    for make in MACHINES:
        m = make()
        _frames(m)
        texts[m.name] = to_urdf(m)
    return texts


if __name__ == "__main__":
    for name, text in build().items():
        (HERE / f"{name}.urdf").write_text(text)
        print(f"wrote models/{name}.urdf")
