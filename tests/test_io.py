"""Atomic writes: whole or not at all, with ordinary permissions."""

from __future__ import annotations

import os

import pytest

from machinesim import _io


def test_new_files_get_the_umask_permissions_and_old_ones_keep_theirs(tmp_path):
    umask = os.umask(0o022)
    try:
        target = tmp_path / "a.txt"
        _io.write_atomic(target, "one")
        assert target.stat().st_mode & 0o777 == 0o644
        target.chmod(0o600)
        _io.write_atomic(target, b"two")
        assert target.read_bytes() == b"two" and target.stat().st_mode & 0o777 == 0o600
    finally:
        os.umask(umask)


def test_an_interrupted_write_leaves_the_old_file_and_no_debris(tmp_path, monkeypatch):
    target = tmp_path / "part.ply"
    target.write_text("old")

    def fail(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(_io.os, "replace", fail)
    with pytest.raises(KeyboardInterrupt):
        _io.write_atomic(target, "new")
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.ply"]
