"""The fenced code blocks of the project's Markdown files, for the tests that run them as a
new user would (README.md, docs/)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def fenced_blocks(path: Path, language: str) -> list[tuple[int, str]]:
    """(line number of the opening fence, code) of every ```language block of ``path``."""
    text = path.read_text(encoding="utf-8")
    fence = re.compile(rf"^```{language}[ \t]*\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)
    return [(text.count("\n", 0, m.start()) + 1, m.group(1)) for m in fence.finditer(text)]


def stated_output(path: Path, line: int) -> str | None:
    """What the Markdown says the block opening at ``line`` prints, or None when it says
    nothing: a bare ``` block after a paragraph "prints", or "It prints `...`" in the
    paragraph that follows the block."""
    text = path.read_text(encoding="utf-8")
    rest = text.split("\n", line)[-1]
    after = rest[rest.index("\n```") + 4:].lstrip("\n")  # past the block's closing fence
    paragraph = after.split("\n\n", 1)[0]
    if paragraph.strip() == "prints":
        shown = re.match(r"prints\s*\n```[ \t]*\n(.*?)^```", after, re.MULTILINE | re.DOTALL)
        return shown.group(1) if shown else None
    inline = re.match(r"It prints `([^`]*)`", paragraph)
    return inline.group(1) + "\n" if inline else None


def link_repository_folders(into: Path) -> None:
    """Links in ``into`` to the repository's folders, so that ``models/...`` resolves as in
    the root while what an example writes lands in ``into``."""
    for entry in ROOT.iterdir():
        if entry.is_dir() and not entry.name.startswith((".", "__")):
            (into / entry.name).symlink_to(entry, target_is_directory=True)
