"""The README is a landing page (<= 150 lines, the CI's marker in place) and no link in it or docs/ is dead."""

from __future__ import annotations

import re

from tests.conftest import REPO

LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


def test_readme_is_a_landing_page():
    text = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 150, "README.md: keep it <= 150 lines; move the detail to docs/"
    assert "<!-- quickstart-tests -->" in text and "<!-- quickstart-demo -->" in text  # .ci/run reads the first


def test_relative_links_resolve():
    dead = []
    for md in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        for target in LINK.findall(md.read_text(encoding="utf-8")):
            if "://" in target or target.startswith("mailto:"):
                continue
            if not (md.parent / target).exists():
                dead.append(f"{md.relative_to(REPO)} -> {target}")
    assert not dead, "dead links: " + "; ".join(dead)


def test_nothing_points_outside_the_repository():
    for md in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        assert "DESIGN.md" not in md.read_text(encoding="utf-8"), f"{md.name}: cite docs/design.md, not DESIGN.md"
