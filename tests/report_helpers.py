"""What the report folder test files (tests/test_report_*.py) share (not collected: no
test_ prefix): a folder's files as bytes, and the names beside it."""

from __future__ import annotations


def _snapshot(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _siblings(folder):
    return sorted(p.name for p in folder.parent.iterdir() if p != folder)
