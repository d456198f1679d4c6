"""The README and docs/: every relative link and image resolves, anchors included, and the README
stays a front door."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
FENCE = "```"


def prose_lines(page: Path):
    """``(number, line)`` of a Markdown page outside code blocks."""
    fenced = False
    for number, line in enumerate(page.read_text().splitlines(), 1):
        if line.startswith(FENCE):
            fenced = not fenced
        elif not fenced:
            yield number, line


def anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    return {anchor(line.lstrip("#")) for _, line in prose_lines(page) if line.startswith("#")}


def broken_links(page: Path) -> list[str]:
    broken = []
    for number, line in prose_lines(page):
        for target in LINK.findall(line):
            if re.match(r"[a-z]+:", target):  # http(s), mailto: not checked offline
                continue
            path, _, fragment = target.partition("#")
            destination = (page.parent / path).resolve() if path else page
            if not destination.exists():
                broken.append(f"{page.name}:{number}: {target} (no such file)")
            elif fragment and destination.suffix == ".md" and fragment not in anchors(destination):
                broken.append(f"{page.name}:{number}: {target} (no such heading)")
    return broken


def test_the_anchor_rule_matches_githubs():
    assert anchor(" At real gravity: `earth_juggler`") == "at-real-gravity-earth_juggler"
    assert anchor("Recordings (rerun)") == "recordings-rerun"


def test_a_broken_link_is_found(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# Top\n[ok](#top) [gone](missing.md) [no heading](page.md#nowhere)\n")
    assert broken_links(page) == [
        "page.md:2: missing.md (no such file)",
        "page.md:2: page.md#nowhere (no such heading)",
    ]


@pytest.mark.parametrize("page", PAGES, ids=lambda page: str(page.relative_to(ROOT)))
def test_every_relative_link_resolves(page):
    assert broken_links(page) == []


def test_the_readme_is_a_front_door():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= 300
    quickstart = lines.index("## Quickstart")
    assert quickstart < 40  # on the first screen
    assert "bash scripts/setup.sh && .venv/bin/python scripts/train.py actor=lstm" in lines
    assert any("docs/juggling.webp" in line for line in lines[:quickstart])


def test_every_results_page_names_the_command_that_regenerates_it():
    for page in sorted((ROOT / "docs" / "results").glob("*.md")):
        head = page.read_text().split("\n## ")[0]
        assert "Regenerate" in head and "python scripts/" in head, page.name
