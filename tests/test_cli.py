"""The command line: `machinesim machines` and clear errors."""

from __future__ import annotations

import pytest

from machinesim.cli import main


def test_machines_lists_each_machine_with_its_axes(capsys):
    assert main(["machines"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in out] == [
        ["grooving_4axis", "XYZC"], ["planer_4axis", "XYZA"], ["robonano_a0ib", "XYZBC"],
        ["robonano_ui", "XYZABC"], ["sts_lathe", "XZC"]]
    assert "A -45..45 deg" in out[1]


def test_help_documents_every_cut_option_with_an_example(capsys):
    with pytest.raises(SystemExit):
        main(["cut", "--help"])
    out = capsys.readouterr().out
    for option in ("--machine", "--tool", "--stock", "--errors", "--out", "--report", "--roi"):
        assert option in out
    assert "e.g. block:10x10x2" in out and "e.g. v:90" in out
