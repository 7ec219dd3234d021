"""Links in README.md and docs/*.md: every relative file link names a file of the repository and every
in-page or cross-page anchor names a heading (GitHub's anchor rule), so renaming a section or moving a
file cannot leave a dead link behind."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
HEADING = re.compile(r"^#{1,6} (.+?)\s*#*\s*$")
FENCE = re.compile(r"^\s*```")


def _prose(text: str) -> list[str]:
    """The page's lines outside fenced code blocks."""
    lines, inside = [], False
    for line in text.splitlines():
        if FENCE.match(line):
            inside = not inside
            continue
        if not inside:
            lines.append(line)
    return lines


def anchor(title: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation other than '-' and '_' dropped,
    spaces to '-'."""
    return re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    seen: dict[str, int] = {}
    out = set()
    for line in _prose(page.read_text(encoding="utf-8")):
        m = HEADING.match(line)
        if not m:
            continue
        a = anchor(m.group(1))
        n = seen.get(a, 0)
        out.add(a if n == 0 else f"{a}-{n}")  # GitHub numbers repeated headings
        seen[a] = n + 1
    return out


def test_anchor_rule_matches_github_on_headings_with_code_and_punctuation():
    assert anchor("The segmenter (`src/assist3d/learn/segmenter/`)") == "the-segmenter-srcassist3dlearnsegmenter"
    assert anchor("The non-learned reference (`--method geometric`)") == "the-non-learned-reference---method-geometric"
    assert anchor("Weight averaging (`optim.ema_decay`, 821 steps)") == "weight-averaging-optimema_decay-821-steps"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_relative_link_and_anchor_resolves(page: Path):
    broken = []
    for line in _prose(page.read_text(encoding="utf-8")):
        for target in LINK.findall(line):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto: ...
                continue
            path, _, frag = target.partition("#")
            dest = page if not path else (page.parent / path).resolve()
            if not dest.exists():
                broken.append(f"{target}: no file {dest.relative_to(ROOT) if dest.is_relative_to(ROOT) else dest}")
                continue
            if frag and dest.suffix == ".md" and frag not in anchors(dest):
                broken.append(f"{target}: no heading with anchor #{frag} in {dest.name}")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)
