#!/usr/bin/env python3
"""Fails on broken internal links (Python 3 standard library only).

    python3 scripts/check_links.py [--html DIR] [--markdown FILE ...]

--html DIR: every HTML page under DIR (the built book, target/book): each
relative href / src (a, img, link, script, source, ...) must name a file that
exists under DIR, and a `#fragment` must be an id (or an <a name>) of the
page it points to.

--markdown FILE: every relative link and image of a Markdown file (README.md)
must name a file or folder of the repository, and a `#fragment` into a
Markdown file must be one of its headings (GitHub's anchors).

External links (http, https, mailto, ...) are not checked. Prints every broken
link and exits with 1 if there is one.
"""

import argparse
import html.parser
import os
import re
import sys
import urllib.parse

EXTERNAL = re.compile(r"^(?:[a-zA-Z][a-zA-Z0-9+.-]*:|//)")
LINK_ATTRS = {"href", "src"}


class Page(html.parser.HTMLParser):
    """The ids, the <base href> and the relative links of one HTML page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids = set()
        self.links = []
        self.base = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if attrs.get("id"):
            self.ids.add(attrs["id"])
        if tag == "a" and attrs.get("name"):
            self.ids.add(attrs["name"])
        if tag == "base" and attrs.get("href"):
            self.base = attrs["href"]
            return
        for name in LINK_ATTRS:
            value = attrs.get(name)
            if value is not None:
                self.links.append((tag, name, value.strip(), self.getpos()[0]))

    handle_startendtag = handle_starttag


def parse_html(path, cache):
    if path not in cache:
        page = Page()
        with open(path, encoding="utf-8", errors="replace") as f:
            page.feed(f.read())
        cache[path] = page
    return cache[path]


def check_html(root):
    root = os.path.realpath(root)
    if not os.path.isdir(root):
        return [f"{root}: not a folder (build the book first)"]
    errors, cache, pages = [], {}, 0
    for folder, _, files in os.walk(root):
        for name in sorted(files):
            if not name.endswith(".html"):
                continue
            pages += 1
            path = os.path.join(folder, name)
            page = parse_html(path, cache)
            base_dir = folder
            if page.base is not None and page.base.startswith("/"):
                base_dir = os.path.join(root, page.base.lstrip("/"))
            for tag, attr, link, line in page.links:
                if not link or EXTERNAL.match(link):
                    continue
                where = f"{os.path.relpath(path, root)}:{line}: <{tag} {attr}=\"{link}\">"
                target, _, fragment = link.partition("#")
                target = urllib.parse.unquote(target.split("?", 1)[0])
                if target:
                    resolved = os.path.normpath(os.path.join(base_dir, target))
                    if os.path.isdir(resolved):
                        resolved = os.path.join(resolved, "index.html")
                else:
                    resolved = path
                if not os.path.isfile(resolved):
                    errors.append(f"{where}: no file {os.path.relpath(resolved, root)}")
                    continue
                if not os.path.realpath(resolved).startswith(root + os.sep):
                    errors.append(f"{where}: points outside the book")
                    continue
                fragment = urllib.parse.unquote(fragment)
                if fragment and resolved.endswith(".html"):
                    if fragment not in parse_html(resolved, cache).ids:
                        errors.append(f"{where}: no id '{fragment}' in {os.path.relpath(resolved, root)}")
    if pages == 0:
        errors.append(f"{root}: no HTML page")
    return errors


FENCE = re.compile(r"^\s*(```|~~~)")
INLINE_CODE = re.compile(r"`+[^`]*`+")
# [text](target "title") and ![alt](target); the text may hold one level of [..]
MD_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
MD_REFDEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s|$)")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")


def markdown_lines(text):
    """(line number, line) outside fenced code blocks."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, line


def github_anchors(path):
    """The anchors GitHub gives the headings of a Markdown file."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    anchors, seen = set(), {}
    for _, line in markdown_lines(text):
        m = HEADING.match(line)
        if not m:
            continue
        title = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", m.group(2))  # links: their text
        title = re.sub(r"<[^>]+>", "", title)
        slug = re.sub(r"[^\w\- ]", "", title.lower()).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        anchors.add(slug if n == 0 else f"{slug}-{n}")
    return anchors


def check_markdown(path):
    errors = []
    folder = os.path.dirname(os.path.abspath(path))
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for number, line in markdown_lines(text):
        stripped = INLINE_CODE.sub("", line)
        links = [m.group(1) for m in MD_LINK.finditer(stripped)]
        m = MD_REFDEF.match(stripped)
        if m:
            links.append(m.group(1))
        for link in links:
            if EXTERNAL.match(link):
                continue
            where = f"{path}:{number}: ({link})"
            target, _, fragment = link.partition("#")
            target = urllib.parse.unquote(target)
            resolved = os.path.normpath(os.path.join(folder, target)) if target else os.path.abspath(path)
            if not os.path.exists(resolved):
                errors.append(f"{where}: no file or folder {os.path.relpath(resolved)}")
                continue
            fragment = urllib.parse.unquote(fragment)
            if fragment and resolved.endswith(".md") and fragment not in github_anchors(resolved):
                errors.append(f"{where}: no heading '#{fragment}' in {os.path.relpath(resolved)}")
    return errors


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--html", metavar="DIR", action="append", default=[])
    parser.add_argument("--markdown", metavar="FILE", nargs="+", default=[])
    args = parser.parse_args()
    if not args.html and not args.markdown:
        parser.error("nothing to check: give --html DIR and/or --markdown FILE")
    errors = []
    for root in args.html:
        errors += check_html(root)
    for path in args.markdown:
        errors += check_markdown(path)
    for e in errors:
        print(f"broken link: {e}", file=sys.stderr)
    checked = ", ".join(args.html + args.markdown)
    if errors:
        print(f"{len(errors)} broken link(s) in {checked}", file=sys.stderr)
        return 1
    print(f"no broken internal link in {checked}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
