"""The suite's order (tests/conftest.py): the files of the slowest tests run first, so that
pytest-xdist's workers do not end with one of them started last while the other idles."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from conftest import SLOWEST_FILES_S, pytest_collection_modifyitems

TESTS = Path(__file__).resolve().parent


def test_every_listed_slow_file_is_a_test_file_of_the_suite():
    assert SLOWEST_FILES_S, "no slow files listed"
    for name, seconds in SLOWEST_FILES_S.items():
        assert (TESTS / name).is_file(), name
        assert seconds > 0.0, name


def test_the_slow_files_come_first_slowest_first_and_the_rest_keep_their_order():
    slowest, second = sorted(SLOWEST_FILES_S, key=SLOWEST_FILES_S.get, reverse=True)[:2]
    collected = [("test_a.py", 1), (second, 1), ("test_b.py", 1), (slowest, 1), (second, 2),
                 ("test_a.py", 2), (slowest, 2), ("test_c.py", 1)]
    items = [SimpleNamespace(path=TESTS / name, name=f"{name}::{k}") for name, k in collected]
    pytest_collection_modifyitems(items)
    assert [item.name for item in items] == [
        f"{slowest}::1", f"{slowest}::2", f"{second}::1", f"{second}::2",
        "test_a.py::1", "test_b.py::1", "test_a.py::2", "test_c.py::1"]
