"""``machinesim.<subpackage>`` works after a bare ``import machinesim``, as the README and
docs/metrology.md write ``Part.from_mesh(*machinesim.viewer.read_ply("part.ply"))``."""

from __future__ import annotations

import subprocess
import sys

import pytest
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


def _looked_up(names) -> list[str]:
    """For each name, in a fresh interpreter after ``import machinesim``: hasattr, then the
    AttributeError's message getattr raises (or what else it raised)."""
    done = _run("import machinesim\n"
                f"for name in {tuple(names)!r}:\n"
                "    print(hasattr(machinesim, name))\n"
                "    try:\n"
                "        getattr(machinesim, name)\n"
                "    except AttributeError as error:\n"
                "        print(error)\n")
    assert done.returncode == 0, done.stderr
    return done.stdout.splitlines()


@pytest.mark.parametrize("names", [
    ("nope", "_private", "viewerx"),
    # dotted: getattr and hasattr with 'foo.bar' had raised ModuleNotFoundError (find_spec
    # imports the parent), and getattr(machinesim, 'nc.words') had given machinesim.nc.words
    ("foo.bar", "nc.words", "viewer.nope", "a b"),
])
def test_a_name_that_is_no_module_of_the_package_is_an_attribute_error(names):
    assert _looked_up(names) == [
        line for name in names
        for line in ("False", f"module 'machinesim' has no attribute {name!r}")]


def test_a_module_of_a_subpackage_is_reached_as_an_attribute_too():
    # docs/cli.md and cut's refusal of a turning program write
    # machinesim.cutting.lathe.turn(program, "sts_lathe", "nose:0.5:90"): after 'import
    # machinesim' it had raised "module 'machinesim.cutting' has no attribute 'lathe'"
    done = _run("import sys, pkgutil, importlib\n"
                "import machinesim\n"
                "print(machinesim.cutting.lathe.turn.__module__)\n"
                "print(machinesim.viewer.views.report_scene.__module__)\n"
                "wrong = []\n"
                "for package in ('cam', 'campaign', 'cutting', 'errors', 'identification',\n"
                "                'metrology', 'motion', 'nc', 'procedures', 'viewer'):\n"
                "    folder = importlib.util.find_spec('machinesim.' + package)\n"
                "    for info in pkgutil.iter_modules(folder.submodule_search_locations):\n"
                "        if info.name.startswith('_') or info.name in vars(\n"
                "                getattr(machinesim, package)):  # a name the package binds\n"
                "            continue\n"
                "        module = getattr(getattr(machinesim, package), info.name)\n"
                "        if module.__name__ != f'machinesim.{package}.{info.name}':\n"
                "            wrong.append(module.__name__)\n"
                "    for name in ('nope', 'lathe.turn', '_private'):\n"
                "        try:\n"
                "            getattr(getattr(machinesim, package), name)\n"
                "            wrong.append(name)\n"
                "        except AttributeError as error:\n"
                "            assert str(error) == (f\"module 'machinesim.{package}' has no \"\n"
                "                                  f\"attribute {name!r}\"), error\n"
                "print(wrong)\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["machinesim.cutting.lathe", "machinesim.viewer.views",
                                        "[]"]
