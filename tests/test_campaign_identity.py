"""A campaign folder knows the code its procedure ran and the state of the procedure's object
(`machinesim.campaign.identity`): a resume after the user edited the procedure's class (or
its module), or with an instance made with other arguments, or under another machinesim
version, is refused naming what changed; the same code and state resume, and a campaign.json
written before these were kept is resumed as it was."""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys

import pytest

import machinesim
from machinesim.campaign import CampaignSpec, run
from machinesim.campaign.identity import attributes_of, code_of, state_of
from machinesim.campaign.results import IDENTITY_KEYS, CampaignFolder
from machinesim.exceptions import InputError

MACHINE = "grooving_4axis"
MODULE = "identity_probe_module"
SOURCE = '''\
class Probe:
    name = "probe"
    paper = "tests/test_campaign_identity.py"
    lab_uses = {{"measure": (), "evaluate": ()}}

    def __init__(self, gain=1.0):
        self.gain = gain
        self.table = {{"b": [1, 2.5], "a": {{3, 4}}}}

    def measure(self, lab):
        return None

    def identify(self, reading):
        return {body}

    def compensate(self, identified):
        return {{}}

    def evaluate(self, lab, identified, programs):
        return None
{tail}'''


@pytest.fixture
def module(tmp_path):
    """Write the procedure's module (``write(body, tail)``) and import it afresh, as a new
    process would after an edit."""
    sys.path.insert(0, str(tmp_path))

    def write(body="1.0", tail=""):
        (tmp_path / f"{MODULE}.py").write_text(SOURCE.format(body=body, tail=tail),
                                               encoding="utf-8")
        importlib.invalidate_caches()
        if MODULE in sys.modules:  # as a notebook's user reloads it after an edit
            return importlib.reload(sys.modules[MODULE])
        return importlib.import_module(MODULE)

    try:
        yield write
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop(MODULE, None)


def _folder(out, procedure):
    return CampaignFolder(out, CampaignSpec(procedure, 2, machine_name=MACHINE).describe())


def test_a_resume_after_the_procedures_class_was_edited_is_refused(module, tmp_path):
    out = tmp_path / "out"
    module()
    _folder(out, f"{MODULE}:Probe")  # begun: campaign.json holds the code's digests
    stored = json.loads((out / "campaign.json").read_text())
    assert set(stored["code"]["classes"]) == {f"{MODULE}:Probe"}
    assert set(stored["code"]["modules"]) == {MODULE}
    assert stored["machinesim"] == machinesim.__version__
    module(body="2.0")  # the user edits identify
    with pytest.raises(InputError) as info:
        run(f"{MODULE}:Probe", 2, machine=MACHINE, out=out, workers=0, progress=False,
            report=False)
    said = str(info.value)
    assert str(out) in said
    assert (f"holds another campaign (code: the source of class {MODULE}:Probe changed; the "
            f"file of module {MODULE} changed, since the campaign began: its trials ran the "
            "code as it was, and a resume would mix them with the new code's in one "
            "summary); give another --out or empty it (or put the procedure's code back as "
            "it was, to resume)") in said, said
    assert not (out / "trials" / "trial_000000.json").exists()  # refused before any trial
    # an edit beside the class (a helper it may call) changes the module's file alone
    module(tail="\n\ndef helper():\n    return 2\n")
    with pytest.raises(InputError, match=rf"code: the file of module {MODULE} changed, since"):
        _folder(out, f"{MODULE}:Probe")
    module()  # put back: the same campaign again
    assert _folder(out, f"{MODULE}:Probe").spec == stored


def test_another_instance_state_is_another_campaign(module, tmp_path):
    probe = module().Probe
    out = tmp_path / "out"
    _folder(out, probe(gain=1.0))
    # the refusal names the attribute that differs, and its values: the one digest of the
    # whole state had said only that something did
    with pytest.raises(InputError, match=r"holds another campaign \(state: the procedure "
                       r"object's attributes \(the arguments it was made with\) differ: gain "
                       r"1\.0 there, 2\.0 now\); give another --out"):
        _folder(out, probe(gain=2.0))
    other = probe()
    other.table = {"b": [1, 2.5 + 2**-51], "a": {3, 4}}  # one bit, deep inside
    other.extra = None
    with pytest.raises(InputError, match=r"differ: extra is new; table changed\)"):
        _folder(out, other)
    # one begun before the attributes were kept: the digests, as it said then
    stored = json.loads((out / "campaign.json").read_text())
    del stored["state_attributes"]
    (out / "campaign.json").write_text(json.dumps(stored))
    with pytest.raises(InputError, match=r"holds another campaign \(state: the procedure "
                       r"object's state \(its attributes: the arguments it was made with\) is "
                       r"digest [0-9a-f]{16} now, [0-9a-f]{16} there"):
        _folder(out, probe(gain=2.0))
    _folder(out, probe(gain=-0.0 + 1.0))  # and it resumes as before
    # the class (called with no arguments) and a reference make the same state
    _folder(out, probe)
    _folder(out, f"{MODULE}:Probe")
    # a digest of the state as written out, not of its text in this process: a set's
    # order, a dict's insertion order and a float to the bit
    a, b = probe(), probe()
    b.table = {"a": {4, 3}, "b": [1, 2.5]}
    assert state_of(a, "a") == state_of(b, "b")
    b.table["b"][1] = 2.5 + 2**-51
    assert state_of(a, "a") != state_of(b, "b")


def test_state_that_cannot_be_digested_is_refused_for_an_object_not_a_class(module, tmp_path):
    probe = module().Probe()
    probe.scale = lambda x: 2 * x
    with pytest.raises(InputError, match=r"key 'procedure': procedure "
                       rf"{MODULE}:Probe: its state cannot be digested at its attribute "
                       r"scale \(function .*has no name to digest it by\).*expected an "
                       r"object whose attributes are plain values"):
        _folder(tmp_path / "out", probe)
    assert not (tmp_path / "out").exists()
    made = module(tail="\n\nclass Made(Probe):\n    def __init__(self):\n"
                  "        self.scale = lambda x: 2 * x\n").Made
    described = CampaignSpec(made, 1, machine_name=MACHINE).describe()
    assert described["state"] is None  # its code decides it: the code's digest holds it
    assert set(described["code"]["classes"]) == {f"{MODULE}:Made", f"{MODULE}:Probe"}


def test_a_resume_under_another_machinesim_version_is_refused(monkeypatch, tmp_path):
    spec = CampaignSpec("tool_rotation_arm", 2)
    CampaignFolder(tmp_path, spec.describe())
    begun = machinesim.__version__
    monkeypatch.setattr(machinesim, "__version__", "99.0")
    with pytest.raises(InputError, match=r"holds another campaign \(machinesim: version "
                       rf"{begun.replace('.', '[.]')} there, 99[.]0 now \(its trials ran the "
                       r"other version's code\)\); give another --out or empty it"):
        CampaignFolder(tmp_path, spec.describe())


def test_a_campaign_json_written_before_the_identity_was_kept_resumes(module, tmp_path):
    module()
    out = tmp_path / "out"
    folder = _folder(out, f"{MODULE}:Probe")
    old = {k: v for k, v in folder.spec.items() if k not in IDENTITY_KEYS}
    (out / "campaign.json").write_text(json.dumps(old))
    module(body="2.0")  # nothing tells what code its trials ran: taken as it was
    assert _folder(out, f"{MODULE}:Probe").spec == old


def test_code_of_a_class_without_a_source_file_is_its_bytecode():
    namespace = {"__name__": "__main__"}
    exec("class Typed:\n    def identify(self, r):\n        return 1\n", namespace)  # noqa: S102
    first = code_of(namespace["Typed"])
    exec("class Typed:\n    def identify(self, r):\n        return 2\n", namespace)  # noqa: S102
    assert code_of(namespace["Typed"]) != first
    exec("class Typed:\n    def identify(self, r):\n        return 1\n", namespace)  # noqa: S102
    assert code_of(namespace["Typed"]) == first


def test_a_class_in_the_script_is_known_by_its_source_not_the_scripts_file(tmp_path,
                                                                          monkeypatch):
    """A script that defines its procedure and calls the campaign is edited to extend N (the
    call's --trials): its file changes, its class does not, and the campaign resumes."""
    import types

    script = tmp_path / "campaign_script.py"

    def load(trials):
        script.write_text("class Mine:\n    def identify(self, r):\n        return 1\n\n\n"
                          f"TRIALS = {trials}\n", encoding="utf-8")
        main = types.ModuleType("__main__")
        main.__file__ = str(script)
        monkeypatch.setitem(sys.modules, "__main__", main)
        exec(compile(script.read_text(), str(script), "exec"), main.__dict__)  # noqa: S102
        return main.Mine

    first = code_of(load(10))
    assert first == {"classes": {"__main__:Mine": first["classes"]["__main__:Mine"]},
                     "modules": {}, "imports": {}}
    assert code_of(load(20)) == first


def test_a_class_that_makes_another_state_each_time_is_known_by_its_code(module, tmp_path):
    """A procedure class whose __init__ keeps a time or a counter has another state each time
    the campaign makes it: with that state in campaign.json no resume could ever match."""
    counted = module(tail="\n\nclass Counted(Probe):\n    made = [0]\n\n"
                     "    def __init__(self):\n        super().__init__()\n"
                     "        Counted.made[0] += 1\n        self.serial = Counted.made[0]\n"
                     ).Counted
    first = CampaignSpec(counted, 1, machine_name=MACHINE).describe()
    assert first["state"] is None
    _folder(tmp_path / "out", counted)
    _folder(tmp_path / "out", counted)  # resumed
    assert CampaignSpec(module().Probe, 1, machine_name=MACHINE).describe()["state"] \
        is not None


def test_a_reference_runs_the_module_as_reloaded(module):
    """A notebook's user edits the module and reloads it: a campaign by its reference ran the
    class first resolved in the process (kept per reference), while campaign.json's code
    digest read the file as edited."""
    module()
    assert CampaignSpec(f"{MODULE}:Probe", 1, machine_name=MACHINE).build().identify(None) == 1.0
    module(body="2.0")
    assert CampaignSpec(f"{MODULE}:Probe", 1, machine_name=MACHINE).build().identify(None) == 2.0


def test_the_state_digest_is_the_same_whatever_the_hash_seed():
    """A resume is another process, with another PYTHONHASHSEED: a set of texts iterates in
    another order there (a pickle's bytes differ), its digest must not."""

    code = ("from machinesim.campaign.identity import state_of\n"
            "class P:\n    def __init__(self):\n"
            "        self.tags = {'alpha', 'beta', 'gamma', 'delta', 'epsilon'}\n"
            "        self.by = {'y': frozenset({'p', 'q', 'r'}), 'x': (1.5, 'z')}\n"
            "print(state_of(P(), 'P'), list(P().tags))\n")
    said = _under_hash_seeds(code, " ")
    assert len({digest for digest, _ in said}) == 1, said
    assert len({order for _, order in said}) > 1  # the sets did iterate otherwise


def test_a_machine_held_is_known_by_its_urdf_not_the_path_it_was_loaded_by(module,
                                                                            monkeypatch):
    """A procedure that keeps a loaded Machine, resumed from another folder (the URDF by
    another path, relative or absolute, or through a symlink) or after reading its digest:
    the same machine, the same state; another URDF, another."""
    from machinesim.machine import Machine
    from machinesim.machines import models_dir

    urdf = models_dir() / "grooving_4axis.urdf"
    probe = module().Probe
    made = []
    for path in (urdf, urdf.parent / ".." / urdf.parent.name / urdf.name):
        made.append(probe())
        made[-1].machine = Machine(path)
    monkeypatch.chdir(urdf.parent)
    made.append(probe())
    made[-1].machine = Machine(urdf.name)
    assert made[-1].machine.digest  # read (cached on the machine) in one run, not in another
    assert len({state_of(p, "p") for p in made}) == 1
    other = probe()
    other.machine = Machine(models_dir() / "sts_lathe.urdf")
    assert state_of(other, "p") != state_of(made[0], "p")


def test_a_run_describes_its_campaign_once(module, tmp_path):
    """The runner keeps one description of its campaign (for campaign.json, the vary texts'
    check and the Dataset): describing it builds the procedure twice (its state, and a
    second instance to tell whether it makes the same state each time), and the runner
    described it three times, building the user's class six times before any trial."""
    counted = module(tail="\n\nclass Counted(Probe):\n    made = [0]\n\n"
                     "    def __init__(self):\n        super().__init__()\n"
                     "        Counted.made[0] += 1\n").Counted
    spec = CampaignSpec(counted, 1, machine_name=MACHINE)
    counted.made[0] = 0
    spec.describe()
    assert counted.made[0] == 2  # its state, and a second instance's
    counted.made[0] = 0
    run(counted, 1, machine=MACHINE, out=tmp_path / "out", workers=0, progress=False,
        report=False)
    # the spec's own check (1) and its parameters' lab_uses (1), one description (2), the one
    # trial (1)
    assert counted.made[0] == 5


def test_an_object_holding_a_method_bound_to_itself_is_digested(module):
    """A procedure object that picks one of its methods in __init__ (self.step = self._fast)
    holds itself: it was refused as a cycle ('it holds itself'), though copy.deepcopy and
    pickle take it. It is written out by where it lies, as a pickle's memo does."""
    probe = module(tail="\n\nclass Picks(Probe):\n    def __init__(self, fast=True):\n"
                   "        super().__init__()\n"
                   "        self.step = self.fast if fast else self.slow\n\n"
                   "    def fast(self):\n        return 1\n\n"
                   "    def slow(self):\n        return 2\n").Picks
    fast, slow = state_of(probe(), "p"), state_of(probe(fast=False), "p")
    assert fast == state_of(probe(), "p") != slow
    # a parent link: the child's link back is the root's, wherever the child lies
    a, b = probe(), probe()
    a.child, b.child = {"up": a}, {"up": b}
    assert state_of(a, "a") == state_of(b, "b") != fast
    b.child = {"up": {"up": b}}  # one level more before the link: another state
    assert state_of(b, "b") != state_of(a, "a")


def test_a_cached_propertys_value_is_not_state(module):
    """A functools.cached_property's value is kept in the object's attributes once read: a
    script that read it before the run (in one run, not in the next) made another state of
    the same procedure object."""
    probe = module(tail="\n\nimport functools\n\n\nclass Cached(Probe):\n"
                   "    @functools.cached_property\n    def doubled(self):\n"
                   "        return 2 * self.gain\n").Cached
    unread, read = probe(), probe()
    assert read.doubled == 2.0
    assert state_of(unread, "p") == state_of(read, "p") != state_of(probe(gain=3.0), "p")


def test_minus_zero_is_the_zero_it_equals(module):
    """Probe(gain=-0.0) and Probe(gain=0.0) are equal arguments (-0.0 == 0.0, and so in an
    array): one campaign; the smallest float above zero is another."""
    import numpy as np

    probe = module().Probe
    zero = state_of(probe(gain=0.0), "p")
    assert state_of(probe(gain=-0.0), "p") == zero != state_of(probe(gain=5e-324), "p")
    assert state_of(probe(gain=complex(-0.0, -0.0)), "p") == state_of(probe(gain=0j), "p")
    assert state_of(probe(gain=np.array([-0.0, 1.0], dtype=np.float32)), "p") == \
        state_of(probe(gain=np.array([0.0, 1.0], dtype=np.float32)), "p")
    assert state_of(probe(gain=np.float64(-0.0)), "p") == zero  # a float's subclass


def test_a_helper_imported_from_another_file_is_code_the_campaign_knows(module, tmp_path):
    """The class's module imports a helper from another file of the user's: an edit of the
    helper (its body, or a default argument) was resumed with the campaign's old code's
    trials; it is refused naming that file. One level deep, and not an installed package."""
    helper = tmp_path / "identity_probe_helper.py"
    helper.write_text("def gain(x=1.0):\n    return x\n", encoding="utf-8")
    tail = ("\n\nimport numpy\nfrom identity_probe_helper import gain\n\n\n"
            "class Helped(Probe):\n    def identify(self, reading):\n        return gain()\n")
    try:
        module(tail=tail)
        out = tmp_path / "out"
        begun = _folder(out, f"{MODULE}:Helped").spec["code"]
        assert set(begun["imports"]) == {"identity_probe_helper"}  # not numpy
        helper.write_text("def gain(x=2.0):\n    return x\n", encoding="utf-8")
        with pytest.raises(InputError, match=r"holds another campaign \(code: the file of "
                           r"imported module identity_probe_helper changed, since the "
                           r"campaign began"):
            _folder(out, f"{MODULE}:Helped")
        # a campaign.json written before the imports were kept resumes as it was
        stored = json.loads((out / "campaign.json").read_text())
        del stored["code"]["imports"]
        (out / "campaign.json").write_text(json.dumps(stored))
        assert _folder(out, f"{MODULE}:Helped").spec == stored
    finally:
        sys.modules.pop("identity_probe_helper", None)


def test_code_of_a_class_without_a_source_file_is_the_same_whatever_the_hash_seed():
    """A class typed in (no source file) is digested by its bytecode: a set of texts in a
    method (``r in {"alpha", ...}``, a frozenset constant) was written by its repr, in
    another order in each process, so a resume of such a campaign was refused."""

    code = ("from machinesim.campaign.identity import code_of\n"
            "ns = {'__name__': '__main__'}\n"
            "exec('class Typed:\\n    def identify(self, r):\\n"
            "        return r in {\"alpha\", \"beta\", \"gamma\", \"delta\"}\\n', ns)\n"
            "print(code_of(ns['Typed'])['classes'], repr(frozenset({'alpha', 'beta', 'gamma', "
            "'delta'})))\n")
    said = _under_hash_seeds(code, "} ")
    assert len({digest for digest, _ in said}) == 1, said
    assert len({order for _, order in said}) > 1  # the sets did iterate otherwise


def test_a_path_the_class_makes_from_its_file_is_the_same_through_a_symlink(module, tmp_path):
    """A class that keeps Path(__file__).parent / 'cal.csv' (its data beside it), imported
    through a symlinked folder on sys.path (another checkout's link, another sys.path entry):
    the same file, the same state; a relative path is kept as written (from another folder
    it names another file)."""
    from pathlib import Path

    probe = module(tail="\n\nfrom pathlib import Path\n\n\nclass Data(Probe):\n"
                   "    def __init__(self):\n        super().__init__()\n"
                   "        self.data = Path(__file__).parent / 'cal.csv'\n").Data
    (tmp_path / "link").symlink_to(tmp_path, target_is_directory=True)
    direct, linked = probe(), probe()
    linked.data = tmp_path / "link" / "cal.csv"
    assert linked.data != direct.data
    assert state_of(direct, "p") == state_of(linked, "p")
    linked.data = tmp_path / "link" / "other.csv"
    assert state_of(direct, "p") != state_of(linked, "p")
    relative, linked_relative = probe(), probe()
    relative.data, linked_relative.data = Path("cal.csv"), Path("link/cal.csv")
    assert state_of(relative, "p") != state_of(linked_relative, "p")


def test_a_script_imports_what_its_class_names_alone(tmp_path, monkeypatch):
    """A script that defines its procedure imports a module of helpers the class calls and
    one it plots with after the campaign: an edit of the plotting module is no change of
    the procedure's code (the script's other work), an edit of the helpers is."""
    import types

    monkeypatch.syspath_prepend(str(tmp_path))
    for name in ("script_helpers", "script_plotting"):
        (tmp_path / f"{name}.py").write_text("def f():\n    return 1\n", encoding="utf-8")
        monkeypatch.delitem(sys.modules, name, raising=False)
    script = tmp_path / "campaign_script.py"
    script.write_text("import script_helpers\nimport script_plotting\n\n\nclass Mine:\n"
                      "    def identify(self, r):\n        return script_helpers.f()\n\n\n"
                      "script_plotting.f()\n", encoding="utf-8")
    main = types.ModuleType("__main__")
    main.__file__ = str(script)
    monkeypatch.setitem(sys.modules, "__main__", main)
    exec(compile(script.read_text(), str(script), "exec"), main.__dict__)  # noqa: S102
    first = code_of(main.Mine)
    assert set(first["imports"]) == {"script_helpers"}
    (tmp_path / "script_plotting.py").write_text("def f():\n    return 2\n", encoding="utf-8")
    assert code_of(main.Mine) == first
    (tmp_path / "script_helpers.py").write_text("def f():\n    return 2\n", encoding="utf-8")
    assert code_of(main.Mine)["imports"] != first["imports"]
    for name in ("script_helpers", "script_plotting"):
        sys.modules.pop(name, None)


def test_plain_data_a_procedure_may_keep_is_digested_alike_in_every_process(tmp_path):
    """What a real procedure keeps (an Enum, a dataclass, numpy's Generator and RandomState,
    a dict with int and str keys, a set of tuples, a functools.partial, an ErrorModel, a
    Path) is digested, not refused, and alike in processes with other hash seeds and
    working folders: a resume of such a campaign is not refused."""
    import os
    import subprocess

    (tmp_path / "kept_state_module.py").write_text(
        "import dataclasses, enum, functools, pathlib\nimport numpy as np\n"
        "from machinesim.errors.model import ErrorModel\n\n\n"
        "class Mode(enum.Enum):\n    FAST = 'fast'\n\n\n"
        "@dataclasses.dataclass\nclass Settings:\n    gain: float = 1.5\n"
        "    axes: tuple = ('X', 'Z')\n\n\n"
        "def scale(x, k):\n    return k * x\n\n\n"
        "class Kept:\n    def __init__(self):\n        self.mode = Mode.FAST\n"
        "        self.settings = Settings()\n        self.rng = np.random.default_rng(7)\n"
        "        self.legacy = np.random.RandomState(7)\n"
        "        self.table = {1: 'one', 'two': 2, (3, 4): {'alpha', 'beta', 'gamma'}}\n"
        "        self.pairs = {(1, 'a'), (2, 'b'), (0, 'z')}\n"
        "        self.scale = functools.partial(scale, k=2.0)\n"
        "        self.errors = ErrorModel.from_dict({'tool': {'offset_um': [1.0, 2.0, 3.0]}})\n"
        "        self.data = pathlib.Path('/tmp/cal.csv')\n", encoding="utf-8")
    code = ("from kept_state_module import Kept\n"
            "from machinesim.campaign.identity import state_of\n"
            "print(state_of(Kept(), 'Kept'))\n")
    said = set()
    for seed, folder in (("1", tmp_path), ("2", tmp_path.parent), ("3", tmp_path)):
        path = os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])
        said.add(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                check=True, cwd=folder, env={**os.environ, "PYTHONPATH": path,
                                                             "PYTHONHASHSEED": seed}).stdout)
    assert len(said) == 1 and len(said.pop().strip()) == 16


def test_machinesims_objects_read_from_a_file_are_the_same_through_a_symlink(module, tmp_path):
    """A procedure that keeps a tool table or an NC program it read from beside its module
    (Path(__file__).parent / ...), imported through a symlinked folder: machinesim keeps the
    file's path as text (`source`, for messages), which was another state; a text naming a
    file that is there is taken by its real path. Text naming nothing is text."""
    import shutil

    from fenced import ROOT

    from machinesim.machines import models_dir
    from machinesim.nc import read_program
    from machinesim.nc.tooltable import ToolTable

    shutil.copy(models_dir() / "examples" / "grooves.nc", tmp_path / "grooves.nc")
    shutil.copy(ROOT / "tests" / "nc_corpus" / "tools.toml", tmp_path / "tools.toml")
    (tmp_path / "link").symlink_to(tmp_path, target_is_directory=True)
    probe = module().Probe
    kept = []
    for folder in (tmp_path, tmp_path / "link"):
        kept.append(probe())
        kept[-1].program = read_program(str(folder / "grooves.nc"))
        kept[-1].tools = ToolTable.from_toml(str(folder / "tools.toml"))
        kept[-1].data = str(folder / "grooves.nc")
    assert kept[0].program.source != kept[1].program.source
    assert state_of(kept[0], "p") == state_of(kept[1], "p")
    texts = [probe(), probe()]
    texts[0].note, texts[1].note = "/no/such//file", "/no/such/file"
    assert state_of(texts[0], "p") != state_of(texts[1], "p")


def _under_hash_seeds(code: str, separator: str) -> list[list[str]]:
    """``code``'s printed line, split once at ``separator`` (a digest, then the order a set
    iterated in), in processes of four PYTHONHASHSEEDs."""
    return [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           check=True, env={**os.environ, "PYTHONHASHSEED": seed}
                           ).stdout.split(separator, 1) for seed in ("1", "2", "3", "4")]


@pytest.mark.parametrize("entry", [5, [], "x", ["0123456789abcdef"]])
def test_a_hand_edited_state_attributes_entry_is_refused_by_the_digests(module, tmp_path,
                                                                        entry):
    # campaign.json's state_attributes as attributes_of writes it is name -> [digest, shown];
    # an entry edited into another shape was read into a TypeError or an IndexError (a
    # traceback) where the refusal of another state was to be told: the digests tell it
    probe = module().Probe
    out = tmp_path / "out"
    _folder(out, probe(gain=1.0))
    stored = json.loads((out / "campaign.json").read_text())
    stored["state_attributes"]["gain"] = entry
    (out / "campaign.json").write_text(json.dumps(stored))
    with pytest.raises(InputError, match=r"holds another campaign \(state: the procedure "
                       r"object's state \(its attributes: the arguments it was made with\) is "
                       r"digest [0-9a-f]{16} now, [0-9a-f]{16} there"):
        _folder(out, probe(gain=2.0))


class _Versioned:
    """A procedure whose own __getstate__ returns a pair that is not __slots__' one."""

    def __init__(self, gain=1.0):
        self.gain = gain

    def __getstate__(self):
        return ("v2", {"gain": self.gain})


def test_a_getstate_pair_that_is_not_slots_is_digested_as_a_tuple():
    # __slots__ pickle as (dict or None, slots dict); a __getstate__ of the user's returning
    # another pair ("v2", {...}) was unpacked as one, a TypeError ('str' object is not a
    # mapping) out of state_of, a traceback where a campaign was to begin
    assert state_of(_Versioned(), "v") == state_of(_Versioned(1.0), "v")
    assert state_of(_Versioned(), "v") != state_of(_Versioned(2.0), "v")
    assert attributes_of(_Versioned()) is None  # no attributes at the top: the digests tell


class _Plain:
    """A plain object: its state, its attributes (set by hand)."""

    def __init__(self, **attributes):
        self.__dict__.update(attributes)


def test_an_int_of_more_digits_than_python_writes_is_digested():
    # str() of an int of more than 4,300 digits raises ValueError (Python's limit on
    # decimal text): a procedure holding 10**5000 made state_of raise it, a traceback where
    # the campaign was to begin; it is digested by its hex, and shown so when it changes
    big = 10**5000
    assert state_of(_Plain(n=big), "a") == state_of(_Plain(n=big), "b") \
        != state_of(_Plain(n=big + 1), "c")
    assert attributes_of(_Plain(n=big))["n"][1].startswith(hex(big)[:40])
    # beyond 2**53 but within the limit: decimal text, as before, shown as the number
    assert attributes_of(_Plain(n=2**60))["n"][1] == "1152921504606846976"
