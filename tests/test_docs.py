"""The README and the documents in docs/ link only to files that exist, and every
citation of a docs file in the code names a file that exists."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

#: A Markdown link or image: [text](target) or ![alt](target).
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
#: A docs file named in code or prose: docs/<name>.md or docs/<name>.png.
DOCS_FILE = re.compile(r"\bdocs/[A-Za-z0-9_]+\.(?:md|png)\b")


def _local_targets(text: str) -> list[str]:
    targets = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue  # a web address or an anchor in the same page
        targets.append(target.split("#", 1)[0])
    return targets


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: p.name)
def test_links_and_images_resolve(document: Path) -> None:
    missing = [
        target
        for target in _local_targets(document.read_text(encoding="utf-8"))
        if not (document.parent / target).exists()
    ]
    assert not missing, f"{document.name} links to missing files: {missing}"


def test_every_cited_docs_file_exists() -> None:
    sources = [
        path
        for folder in ("graspenv", "agents", "tests", "envs_configs", "docs")
        for path in sorted((ROOT / folder).rglob("*"))
        if path.suffix in (".py", ".md", ".toml", ".yml")
    ]
    cited: dict[str, set[str]] = {}
    for path in [*sources, ROOT / "README.md"]:
        for match in DOCS_FILE.findall(path.read_text(encoding="utf-8")):
            cited.setdefault(match, set()).add(str(path.relative_to(ROOT)))
    missing = {doc: sorted(where) for doc, where in cited.items() if not (ROOT / doc).exists()}
    assert cited, "no docs file is cited anywhere: the pattern is wrong"
    assert not missing, f"cited but missing: {missing}"
