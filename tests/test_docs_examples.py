"""Every ```python block of docs/ runs as written, and prints what its page says it prints.

A newcomer copies these blocks first; before this test nothing ran them, so a renamed
argument or a changed figure would have left a page that fails or misleads. Each block runs
in a fresh namespace, in a temporary folder linking the repository's folders (as
tests/test_readme.py runs the README's). The few blocks that cannot run within the suite
are listed with the reason and what covers them instead.
"""

from __future__ import annotations

import contextlib
import io

import pytest
from fenced import ROOT, fenced_blocks, link_repository_folders, stated_output

DOCS = ROOT / "docs"

#: Pages whose blocks are not run here, with why and what covers them.
NOT_RUN = {
    "budget.md": "seven runs of paper 000's procedure, about a minute; "
                 "tests/test_budget.py and the scenario's budget tests cover it",
    "campaigns.md": "24 trials on two workers, and a reading of a crown campaign made "
                    "before; tests/test_campaign*.py run campaigns",
    "procedures/tool_setting_6axis.md": "ten seeded runs of the procedure, about 90 s; "
                                        "tests/test_tool_setting_6axis*.py run it",
    "procedures/workpiece_setting.md": "sixteen seeded runs of the grooves load, 3-10 min; "
                                       "tests/test_workpiece_setting*.py run the procedure",
    "viewer.md": "serves a page until Ctrl-C; tests/test_viewer_live.py serves and stops one",
}


def doc_blocks() -> list[tuple[str, int, str]]:
    return [(str(page.relative_to(DOCS)), line, code)
            for page in sorted(DOCS.rglob("*.md"))
            for line, code in fenced_blocks(page, "python")]


BLOCKS = [block for block in doc_blocks() if block[0] not in NOT_RUN]


def test_the_docs_have_the_blocks_this_test_runs_and_skips():
    pages = {page for page, _, _ in doc_blocks()}
    assert set(NOT_RUN) <= pages, set(NOT_RUN) - pages  # a moved page: update NOT_RUN
    assert len(BLOCKS) >= 7


def test_a_stated_output_is_read_from_the_page(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```python\nprint(1)\n```\n\nprints\n\n```\n1\n```\n\n"
                    "```python\nprint(2)\n```\n\nIt prints `2` (two).\n\n"
                    "```python\nprint(3)\n```\n\nThen nothing.\n")
    assert [stated_output(page, line) for line, _ in fenced_blocks(page, "python")] == [
        "1\n", "2\n", None]


@pytest.mark.parametrize(("page", "line", "code"), BLOCKS,
                         ids=[f"{page}:{line}" for page, line, _ in BLOCKS])
def test_python_block_runs_and_prints_what_its_page_says(page, line, code, tmp_path,
                                                          monkeypatch):
    link_repository_folders(tmp_path)
    monkeypatch.chdir(tmp_path)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(code, f"docs/{page}:{line}", "exec"), {"__name__": "__docs__"})
    stated = stated_output(DOCS / page, line)
    if stated is not None:
        assert printed.getvalue() == stated, f"docs/{page}:{line}"
