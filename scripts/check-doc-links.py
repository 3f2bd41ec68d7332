#!/usr/bin/env python3
"""Check the guide's internal links: every relative link in README.md,
CHANGELOG.md and docs/src/**/*.md must name a file of the repository, and a
`#anchor` must name a heading of that page (GitHub's and mdBook's slugs).
Every page of docs/src must be listed in docs/src/SUMMARY.md. One line per
broken link, exit 1 when there is any."""

import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)


def slug(heading):
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page):
    text = FENCE.sub("", page.read_text())
    return {slug(m.group(1)) for m in re.finditer(r"^#+\s+(.*)$", text, re.M)}


def main():
    pages = [ROOT / "README.md", ROOT / "CHANGELOG.md"] + sorted((ROOT / "docs" / "src").rglob("*.md"))
    broken = []
    for page in pages:
        text = FENCE.sub("", page.read_text())
        for m in LINK.finditer(text):
            target = m.group(1) or m.group(2)
            if re.match(r"^[a-z]+:", target):
                continue  # http(s), mailto: not checked here
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            where = f"{page.relative_to(ROOT)}: link {target}"
            if not dest.exists():
                broken.append(f"{where}: no such file")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                broken.append(f"{where}: no heading #{anchor} in {dest.relative_to(ROOT)}")
    summary = (ROOT / "docs" / "src" / "SUMMARY.md").read_text()
    listed = {(ROOT / "docs" / "src" / m).resolve() for m in re.findall(r"\]\(([^)]+\.md)\)", summary)}
    for page in sorted((ROOT / "docs" / "src").rglob("*.md")):
        if page.name != "SUMMARY.md" and page.resolve() not in listed:
            broken.append(f"{page.relative_to(ROOT)}: not listed in docs/src/SUMMARY.md")
    for line in broken:
        print(line, file=sys.stderr)
    print(f"check-doc-links: {len(pages)} pages, {len(broken)} broken")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
