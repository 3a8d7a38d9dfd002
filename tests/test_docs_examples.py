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
import re
import sys

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


#: A script's guard: a block holding it runs its guarded part only as ``__main__``
#: (`test_your_own_procedures_campaign_block_runs_its_campaign`), not as ``__docs__``.
GUARD = 'if __name__ == "__main__":'
BLOCKS = [block for block in doc_blocks() if block[0] not in NOT_RUN and GUARD not in block[2]]


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


def test_your_own_procedures_campaign_block_runs_its_campaign(tmp_path, monkeypatch):
    """docs/procedures/your_own.md's campaign block, run as the script the page says to save
    beside tool_offset.py (the example's class): run as ``__docs__``, as the blocks above,
    its campaign under the ``__main__`` guard never ran, so that check could not fail. Its
    8 trials on 2 workers take 2 on 1 here (a Dask worker still imports tool_offset), the
    first 2 of the page's 8 (trial i's seed is the same in both)."""
    pytest.importorskip("distributed")
    import machinesim.campaign as campaign

    page = DOCS / "procedures" / "your_own.md"
    codes = [code for _, code in fenced_blocks(page, "python")]
    example = next(code for code in codes if "class ToolOffsetRTest" in code)
    line, script = next((line, code) for line, code in fenced_blocks(page, "python")
                        if GUARD in code)
    link_repository_folders(tmp_path)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))  # a script's own folder is on its sys.path
    monkeypatch.delitem(sys.modules, "tool_offset", raising=False)
    (tmp_path / "tool_offset.py").write_text(example[:example.index("errors = {")],
                                             encoding="utf-8")
    given, full = [], campaign.run

    def smaller(procedure, trials, **options):
        given.append((trials, options["workers"]))
        return full(procedure, 2, **{**options, "workers": 1, "progress": False})

    monkeypatch.setattr(campaign, "run", smaller)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(script, f"docs/procedures/your_own.md:{line}", "exec"),
             {"__name__": "__main__"})
    sys.modules.pop("tool_offset", None)
    assert given == [(8, 2)]
    # the page: no trial failed, the groove's Y error after compensation at most 0.028 um
    said = re.fullmatch(r"(\d+) failed; groove Y error after: at most (\d\.\d{3}) um\n",
                        printed.getvalue())
    assert said is not None, printed.getvalue()
    assert said[1] == "0" and float(said[2]) <= 0.028, printed.getvalue()
    assert "no trial failed, the groove's Y error after compensation at most 0.028 um" in \
        " ".join(page.read_text(encoding="utf-8").split())
    assert (tmp_path / "reports" / "campaign_tool_offset" / "campaign.nc").exists()
