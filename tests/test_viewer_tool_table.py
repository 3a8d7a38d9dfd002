"""`machinesim view MACHINE --program P --tools T`: a table tool of the shape `--tool` gives
is viewed (the animation cuts with that one tool, so the part is the same); another shape or
a length is refused at its T line (docs/viewer.md)."""

from __future__ import annotations

import pytest
import viewer_helpers
from viewer_helpers import run

from machinesim.exceptions import InputError
from machinesim.tool_specs import tool_from_spec

#: A Fusion 360-style block: T1 M06, then G43 H1, one slot 2 mm wide across x = 1..3 mm.
PROGRAM = ("%\nO1001 (SLOT)\nG90 G94 G17\nG21\nT1 M6\nG54\nG0 X1. Y0.4\nG43 Z5. H1\n"
           "G1 Z-0.1 F200.\nX3. F400.\nG0 Z5.\nM30\n%\n")
#: `machinesim view`'s scene recorded, not drawn (a fixture: imported by name, pytest's
#: argument of that name would read as its redefinition)
captured = viewer_helpers.captured


def test_a_table_tool_of_the_tools_own_shape_is_viewed(tmp_path, captured):
    program = tmp_path / "slot.nc"
    program.write_text(PROGRAM)
    tools = tmp_path / "tools.toml"
    # written as a post's tool table writes it, '1.0' where --tool says '1mm'
    tools.write_text('[tool.1]\nlength_mm = 0.0\nradius_mm = 1.0\nshape = "flat:1.0"\n')
    page = tmp_path / "slot.html"
    assert run(["grooving_4axis", "--program", str(program), "--tools", str(tools),
                "--tool", "flat:1mm", "--stock", "block:4x1x0.5", "--html", str(page)]) == 0
    assert captured["tool"] == tool_from_spec("flat:1")
    change, = captured["program"].tool_changes
    assert (change.number, change.line, change.length_m) == (1, 5, 0.0)
    # Z as programmed: tool 1's length is 0
    assert captured["program"].targets[-1, 2] == pytest.approx(5e-3, abs=1e-15)


@pytest.mark.parametrize(("table", "what"), [
    ('shape = "flat:0.5"', "shape flat:0.5"),
    ('shape = "flat:1.0:h=3"', "shape flat:1.0:h=3"),
    ('shape = "flat:1.0"\nlength_mm = 2.5', "length 2.5 mm"),
])
def test_another_shape_or_a_length_is_still_refused(tmp_path, captured, table, what):
    program = tmp_path / "slot.nc"
    program.write_text(PROGRAM)
    tools = tmp_path / "tools.toml"
    lines = ["[tool.1]", *table.splitlines()]
    if "length_mm" not in table:
        lines.append("length_mm = 0.0")
    tools.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=f"T1 at line 5 puts a tool of {what} in the spindle"):
        run(["grooving_4axis", "--program", str(program), "--tools", str(tools),
             "--tool", "flat:1", "--stock", "block:4x1x0.5", "--html",
             str(tmp_path / "slot.html")])
    assert not captured
