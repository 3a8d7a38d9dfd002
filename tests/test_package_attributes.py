"""``machinesim.<subpackage>`` works after a bare ``import machinesim``, as the README and
docs/metrology.md write ``Part.from_mesh(*machinesim.viewer.read_ply("part.ply"))``."""

from __future__ import annotations

import subprocess
import sys

from fenced import ROOT


def _run(code: str) -> subprocess.CompletedProcess:
    # a fresh interpreter: in the test process another test may have imported the subpackage
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=300, check=False)


def test_a_subpackage_is_reached_as_an_attribute_without_its_own_import(tmp_path):
    ply = tmp_path / "block.ply"
    code = (
        "import sys\n"
        "import machinesim\n"
        "from machinesim.workpiece import Part, stock_from_spec\n"
        "assert 'machinesim.viewer' not in sys.modules\n"
        f"stock_from_spec('block:10x10x2').export_ply({str(ply)!r})\n"
        f"part = Part.from_mesh(*machinesim.viewer.read_ply({str(ply)!r}))\n"
        "print(part.volume * 1e9)\n")
    done = _run(code)
    assert done.returncode == 0, done.stderr
    assert abs(float(done.stdout) - 200.0) < 1e-9  # mm^3: the 10 x 10 x 2 mm block


def test_a_name_that_is_no_subpackage_is_still_an_attribute_error():
    done = _run("import machinesim\n"
                "for name in ('nope', '_private', 'viewerx'):\n"
                "    try:\n"
                "        getattr(machinesim, name)\n"
                "    except AttributeError as error:\n"
                "        print(error)\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        f"module 'machinesim' has no attribute {name!r}"
        for name in ("nope", "_private", "viewerx")]


def test_a_dotted_name_is_an_attribute_error_too():
    # getattr and hasattr with 'foo.bar' had raised ModuleNotFoundError (find_spec imports
    # the parent), and getattr(machinesim, 'nc.words') had given machinesim.nc.words
    names = ("foo.bar", "nc.words", "viewer.nope", "a b")
    done = _run("import machinesim\n"
                f"for name in {names!r}:\n"
                "    print(hasattr(machinesim, name))\n"
                "    try:\n"
                "        getattr(machinesim, name)\n"
                "    except AttributeError as error:\n"
                "        print(error)\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        line for name in names
        for line in ("False", f"module 'machinesim' has no attribute {name!r}")]
