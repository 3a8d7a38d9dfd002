"""The scripts of ``benchmarks/`` still start as documented (nothing is run or timed here).

Every ``benchmarks/NAME.py --option ...`` command written in the docs, the README and the
scripts' own docstrings is parsed by that script's argument parser (its ``main`` stopped
right after parsing), so a renamed or removed option, or a script that no longer imports,
fails here rather than at the next measurement. The scripts that compare two variants of the
engine patch it in a child process (their ``RUNNER``): each name a runner imports or patches
must still exist where it patches it and be read there, or the two variants would silently
be one.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import importlib.util
import re
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
SCRIPTS = sorted(p.stem for p in BENCHMARKS.glob("*.py") if not p.stem.startswith("_"))
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")),
             *sorted(BENCHMARKS.glob("*.py"))]
COMMAND = re.compile(r"benchmarks/(\w+)\.py")


def documented_commands() -> list[tuple[str, str, tuple[str, ...]]]:
    """(where, script, options) for each benchmark command written out in the documents: the
    words after ``benchmarks/NAME.py`` on its line (brackets of optional ones dropped, and a
    docstring's next line when it goes on with ``[``), up to a backtick, ``(`` or ``#``; a
    mention followed by prose rather than an option counts as the bare command."""
    found = []
    for document in DOCUMENTS:
        lines = document.read_text().splitlines()
        for number, line in enumerate(lines):
            for match in COMMAND.finditer(line):
                rest = line[match.end():]
                if number + 1 < len(lines) and lines[number + 1].lstrip().startswith("["):
                    rest += " " + lines[number + 1]
                rest = re.split(r"[`(#]", rest)[0].replace("[", " ").replace("]", " ")
                words = tuple(rest.split())
                if words and not words[0].startswith("-"):
                    words = ()
                where = f"{document.relative_to(ROOT)}:{number + 1}"
                found.append((where, match.group(1), words))
    return found


COMMANDS = documented_commands()


@pytest.fixture(autouse=True)
def _benchmarks_importable(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))


def benchmark(script: str) -> types.ModuleType:
    """``benchmarks/SCRIPT.py`` imported as ``benchmark_SCRIPT`` (its own name, ``nc`` or
    ``cutting``, stays free)."""
    name = f"benchmark_{script}"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{script}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules[name] = module
    return sys.modules[name]


class _Parsed(Exception):
    """Raised by the patched parser once the options are parsed: ``main`` goes no further."""


def test_every_command_names_a_benchmark():
    assert {script for _, script, _ in COMMANDS} >= set(SCRIPTS)
    unknown = [(where, script) for where, script, _ in COMMANDS if script not in SCRIPTS]
    assert unknown == []


@pytest.mark.parametrize("where, script, options", COMMANDS,
                         ids=[f"{w} {s} {' '.join(o)}".strip() for w, s, o in COMMANDS])
def test_documented_command_parses(where, script, options, monkeypatch):
    module = benchmark(script)
    if "argparse" not in vars(module):  # a script without options: importing it is the check
        assert options == (), f"{where}: {script}.py takes no options, documented {options}"
        return
    parse = argparse.ArgumentParser.parse_args

    def parse_only(self, args=None, namespace=None):
        parse(self, args, namespace)
        raise _Parsed

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_only)
    monkeypatch.setattr(sys, "argv", [f"benchmarks/{script}.py", *options])
    try:
        module.main()
    except SystemExit as exit:  # argparse refused the options: say where they are written
        pytest.fail(f"{where}: benchmarks/{script}.py {' '.join(options)} refused "
                    f"(exit {exit.code})")
    except _Parsed:
        return
    pytest.fail(f"{script}.main() returned without parsing its options")


def runner_patches(source: str) -> list[tuple[str, str, str]]:
    """(imported module, attribute, how) for each name ``source`` imports from a module
    (``from M import A``: "imported") or assigns on an imported module or class
    (``m.A = ...``, ``C.A = ...``: "patched")."""
    aliases: dict[str, str] = {}  # local name -> "module" or "module:attribute"
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.asname:
                    aliases[alias.asname] = alias.name
        elif isinstance(node, ast.ImportFrom) and node.module.startswith("machinesim"):
            for alias in node.names:
                aliases[alias.asname or alias.name] = f"{node.module}:{alias.name}"
                found.append((node.module, alias.name, "imported"))
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Attribute):
                    owner = _dotted(target.value, aliases)
                    if owner is not None:
                        found.append((owner, target.attr, "patched"))
    return found


def _dotted(node: ast.expr, aliases: dict[str, str]) -> str | None:
    """``m``, ``m.C`` or ``C`` of an imported module ``m`` or class ``C`` as
    "module[:Class[.Inner]]", or None for anything else."""
    if isinstance(node, ast.Name):
        return aliases.get(node.id)
    if isinstance(node, ast.Attribute):
        owner = _dotted(node.value, aliases)
        if owner is not None:
            return f"{owner}.{node.attr}" if ":" in owner else f"{owner}:{node.attr}"
    return None


def names_read(code: types.CodeType) -> set[str]:
    """The global and attribute names read inside the functions and classes of ``code``
    (a module's code object): not its top-level imports."""
    names = set()
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            names |= set(constant.co_names) | names_read(constant)
    return names


RUNNERS = [script for script in SCRIPTS if "\nRUNNER = " in (BENCHMARKS / f"{script}.py")
           .read_text()]


@pytest.mark.parametrize("script", RUNNERS)
def test_runner_patches_names_that_are_read(script):
    runner = benchmark(script).RUNNER
    patches = runner_patches(runner)
    assert patches
    for owner, attribute, how in patches:
        module_name, _, path = owner.partition(":")
        module = importlib.import_module(module_name)
        where = module
        for name in filter(None, path.split(".")):
            assert hasattr(where, name), f"{script}.RUNNER: {module_name} has no {path}"
            where = getattr(where, name)
        assert hasattr(where, attribute), f"{script}.RUNNER: {owner} has no {attribute}"
        if how == "patched" and not path:  # a module's name: read by the code it changes
            source = Path(module.__file__).read_text()
            code = compile(source, module.__file__, "exec")
            assert attribute in names_read(code), (
                f"{script}.RUNNER patches {owner}.{attribute}, which {module_name} never reads")


def test_wrapped_tables_edits_a_table_of_the_example():
    """wrapped_tables.RUNNER replaces the example model's C table ends (three values)."""
    import tomllib

    example = tomllib.loads((ROOT / "models" / "errors" / "example.toml").read_text())
    assert len(example["component"]["C"]["ECC_arcsec"]) == 3


@pytest.mark.parametrize("end, said", [("os.kill(os.getpid(), signal.SIGKILL)",
                                         "failed, killed by signal 9 (SIGKILL: out of memory?)"),
                                        ("sys.exit(3)", "failed, exit status 3")])
def test_timed_cut_says_how_a_run_ended(end, said, tmp_path):
    """A variant killed for memory leaves no stderr: the benchmark said only 'failed:'."""
    timed_cut = benchmark("_timed_cut").timed_cut
    runner = f"import os, signal, sys\n{end}\n"
    with pytest.raises(SystemExit) as stopped:
        timed_cut(runner, "variant", [], tmp_path / "report.json", "case")
    assert str(stopped.value).startswith(f"case (variant) {said}:")
