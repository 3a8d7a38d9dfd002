"""What load_machine is given: an unknown name, a folder, a file not ending in .urdf, a xacro
file, a Machine or no name, a cyclic URDF, an unreadable file, a pipe or a device, a file
edited after loading, and the size cap, each refused (or loaded) saying what it is."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from models_helpers import GROOVING, MODELS, _in_joint

from machinesim.exceptions import ModelError
from machinesim.machines import list_machines, load_machine


def test_unknown_machine_and_bad_files_are_refused(tmp_path):
    with pytest.raises(ModelError, match="unknown machine 'robonano'; expected one of"):
        load_machine("robonano")
    with pytest.raises(ModelError, match="no such URDF file"):
        load_machine(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    text = (MODELS / "planer_4axis.urdf").read_text().replace('axis xyz="-1.0 0.0 0.0"',
                                                              'axis xyz="1.0 0.0 0.0"')
    bad.write_text(text)
    with pytest.raises(ModelError, match="workpiece-side axis must point -X"):
        load_machine(bad)


def test_a_folder_or_a_file_not_ending_in_urdf_is_not_an_unknown_machine(tmp_path):
    # 'cut ... --machine DIR' or '--machine mill.xml' (a URDF saved as .xml) said "unknown
    # machine 'DIR'; expected one of ...", as if a shipped machine's name were misspelt
    from machinesim.machines import list_machines

    shipped = ", ".join(list_machines())
    folder = tmp_path / "mill"
    folder.mkdir()
    with pytest.raises(ModelError) as raised:
        load_machine(folder)
    assert str(raised.value) == (f"{folder}: is a folder; expected a machine's name "
                                 f"({shipped}) or the path of a .urdf file")
    xml = tmp_path / "mill.xml"
    xml.write_text(GROOVING)
    with pytest.raises(ModelError) as raised:
        load_machine(xml)
    assert str(raised.value) == (f"{xml}: a file whose name does not end in .urdf; expected "
                                 f"a machine's name ({shipped}) or the path of a .urdf file "
                                 "(a URDF saved under another ending: rename it to .urdf)")
    with pytest.raises(ModelError, match="unknown machine 'mill'"):
        load_machine("mill")  # not there (the folder is in tmp_path, not here)
    # '--machine /dev/null' (or a FIFO) was an "unknown machine '/dev/null'" too
    fifo = tmp_path / "mill.fifo"
    os.mkfifo(fifo)
    for path, kind in (("/dev/null", "a character device"), (fifo, "a named pipe (FIFO)")):
        with pytest.raises(ModelError) as raised:
            load_machine(path)
        assert str(raised.value) == (f"{path}: is {kind}, not a regular file; expected a "
                                     f"machine's name ({shipped}) or the path of a .urdf file")


def test_a_xacro_file_is_refused_with_how_to_expand_it(tmp_path):
    # it was taken for a machine's name: "unknown machine 'mill.urdf.xacro'"
    path = tmp_path / "mill.urdf.xacro"
    path.write_text(GROOVING)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    assert str(raised.value) == (f"{path}: a xacro file; expand it first (xacro "
                                 "mill.urdf.xacro > mill.urdf) and load the .urdf")


def test_a_machine_or_no_name_is_refused_as_what_it_is():
    # str() of each was taken for a name: "unknown machine "Machine('robonano_a0ib',
    # axes=XYZBC)"" for a machine loaded already, "unknown machine 'None'"
    machine = load_machine("robonano_a0ib")
    with pytest.raises(ModelError) as raised:
        load_machine(machine)
    assert str(raised.value) == ("got a Machine (robonano_a0ib), loaded already: use it as it "
                                 "is; expected a machine's name or the path of a .urdf file")
    shipped = ", ".join(list_machines())
    for given, shown in ((None, "NoneType None"), (7, "int 7"),
                         (b"sts_lathe", "bytes b'sts_lathe'")):
        with pytest.raises(ModelError) as raised:
            load_machine(given)
        assert str(raised.value) == (f"expected a machine's name ({shipped}) or the path of a "
                                     f".urdf file, got {shown}")
    # a name as str or as a Path is the same machine
    assert load_machine(Path("sts_lathe")).name == load_machine("sts_lathe").name == "sts_lathe"


def test_a_cyclic_urdf_fails_fast_instead_of_hanging(tmp_path):
    """Every link in one ring: no root to start from, and the walk up never ends."""
    links = "".join(f'<link name="l{i}"/>' for i in range(4))
    joints = "".join(f'<joint name="j{i}" type="fixed"><parent link="l{i}"/>'
                     f'<child link="l{(i + 1) % 4}"/></joint>' for i in range(4))
    path = tmp_path / "ring.urdf"
    path.write_text(f'<robot name="ring">{links}{joints}</robot>')
    with pytest.raises(ModelError, match=r"joints 'j\d' -> 'j\d' -> 'j\d' -> 'j\d' form a cycle"):
        load_machine(path)


def test_a_folder_or_an_unreadable_urdf_is_a_model_error_naming_it(tmp_path):
    folder = tmp_path / "machine.urdf"
    folder.mkdir()
    with pytest.raises(ModelError, match="machine.urdf: is a folder; expected a .urdf file"):
        load_machine(folder)
    binary = tmp_path / "binary.urdf"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(ModelError, match="binary.urdf: not readable XML"):
        load_machine(binary)


def test_a_pipe_or_a_device_given_as_the_urdf_says_what_it_is(tmp_path):
    # both were "no such URDF file", though ls shows them there
    fifo, link = tmp_path / "pipe.urdf", tmp_path / "zero.urdf"
    os.mkfifo(fifo)
    link.symlink_to(os.devnull)
    with pytest.raises(ModelError) as raised:
        load_machine(fifo)
    assert str(raised.value) == (f"{fifo}: is a named pipe (FIFO), not a regular file; "
                                 "expected a .urdf file")
    with pytest.raises(ModelError) as raised:
        load_machine(link)
    assert str(raised.value) == (f"{link}: links to {os.devnull}, a character device, not a "
                                 "regular file; expected a .urdf file")


def test_a_broken_link_given_as_the_urdf_says_what_it_is(tmp_path):
    # both were "no such URDF file", though ls shows the links there
    loop, dangling = tmp_path / "loop.urdf", tmp_path / "dangling.urdf"
    loop.symlink_to(tmp_path / "back.urdf")
    (tmp_path / "back.urdf").symlink_to(loop)
    dangling.symlink_to("moved.urdf")
    with pytest.raises(ModelError) as raised:
        load_machine(loop)
    assert str(raised.value) == (f"{loop}: cannot be reached: too many levels of symbolic "
                                 "links (a loop)")
    with pytest.raises(ModelError) as raised:
        load_machine(dangling)
    assert str(raised.value) == (f"{dangling}: is a symbolic link to 'moved.urdf', which "
                                 "does not exist")


def test_a_urdf_edited_after_loading_loads_again(tmp_path):
    path = tmp_path / "edited.urdf"
    path.write_text(GROOVING)
    assert load_machine(path).upper[0] == 0.25
    path.write_text(_in_joint("X", 'upper="0.25"', 'upper="0.125"'))
    os.utime(path, ns=(path.stat().st_atime_ns, path.stat().st_mtime_ns + 10**9))
    assert load_machine(path).upper[0] == 0.125


def test_a_urdf_past_the_size_cap_is_refused_and_one_at_it_loads(tmp_path):
    """A 200 MB file took 9 minutes to parse (one long comment, which expat scanned again
    with every 64 kB it was fed) or 3.6 GB of memory (links): a file larger than any
    machine's URDF is refused before it is parsed; one of exactly the cap still loads."""
    from machinesim.urdf import MAX_URDF_BYTES

    head, tail = GROOVING.split("<robot", 1)
    pad = MAX_URDF_BYTES - len(GROOVING.encode()) - len("<!---->")
    at_cap = tmp_path / "at_cap.urdf"
    at_cap.write_text(f"{head}<!--{'x' * pad}--><robot{tail}")
    assert at_cap.stat().st_size == MAX_URDF_BYTES == 16 * 2**20
    assert load_machine(at_cap).axes == ("X", "Y", "Z", "C")
    over = tmp_path / "over.urdf"
    over.write_text(f"{head}<!--{'x' * (pad + 1)}--><robot{tail}")
    with pytest.raises(ModelError) as raised:
        load_machine(over)
    assert str(raised.value) == (f"{over}: larger than 16 MB; a machine's URDF is a few kB "
                                 "(meshes are files of their own): expected at most 16 MB")
