"""Converts a Markdown page of docs/ into a self-contained HTML page (the FMU's documentation/index.html).

    python scripts/markdown_to_html.py docs/physics.md OUT_DIR/index.html [--title T] [--subtitle S]

Standard library only, so that building the FMU needs no extra package. It handles exactly the subset
docs/physics.md uses and refuses anything else with the line number, rather than render it wrongly:

  headings (#, ##, ###, ####; ids as GitHub makes them, so links to #anchors work in both places),
  paragraphs, flat lists ("- " and "1. ", continuation lines indented), fenced code blocks (```),
  pipe tables, and inline `code`, **bold**, *italic*, [links](target), ![images](path).

Images are copied next to the output at the same relative path (they must lie below the page's
directory). Links to "#anchor" must name a heading of the page; links to other files of the
repository, which the FMU does not contain, become their plain text.
"""
from __future__ import annotations

import argparse
import html
import pathlib
import re
import shutil
import sys

INLINE = re.compile(r"(`+)(.+?)\1|(!?)\[([^\]]+)\]\(([^)\s]+)\)")
LIST_ITEM = re.compile(r"^(-|\d+\.) (.*)$")
HEADING = re.compile(r"^(#{1,4}) (.+)$")

STYLE = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; line-height: 1.5;
       max-width: 62em; margin: 2em auto; padding: 0 1.5em; color: #1f2328; }
h1, h2, h3, h4 { line-height: 1.25; margin-top: 1.6em; }
h1 { border-bottom: 1px solid #d0d7de; padding-bottom: .3em; }
h2 { border-bottom: 1px solid #d8dee4; padding-bottom: .2em; }
code { font-family: ui-monospace, Consolas, "DejaVu Sans Mono", monospace; font-size: 90%;
       background: #eff1f3; padding: .1em .3em; border-radius: 4px; }
pre { background: #f6f8fa; padding: .8em 1em; overflow-x: auto; border-radius: 6px; }
pre code { background: none; padding: 0; font-size: 88%; }
table { border-collapse: collapse; margin: 1em 0; display: block; overflow-x: auto; }
th, td { border: 1px solid #d0d7de; padding: .3em .6em; vertical-align: top; }
th { background: #f6f8fa; }
img { max-width: 100%; }
figure { margin: 1em 0; text-align: center; }
.subtitle { color: #59636e; margin-top: -.5em; }
"""


class MarkdownError(ValueError):
    pass


def slug(text: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`", "", text.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


class Converter:
    def __init__(self, source: pathlib.Path, out_dir: pathlib.Path):
        self.source, self.out_dir = source, out_dir
        self.images: list[pathlib.Path] = []
        self.anchors: dict[str, int] = {}
        self.ids: set[str] = set()
        self.fragments: list[tuple[str, int]] = []
        self.line = 0

    def fail(self, message: str):
        raise MarkdownError(f"{self.source}:{self.line}: {message}")

    # -- inline ---------------------------------------------------------------------------------
    def inline(self, text: str) -> str:
        """Code spans, links and images become placeholders first, so that emphasis around them works."""
        pieces: list[str] = []

        def hold(rendered: str) -> str:
            pieces.append(rendered)
            return f"\x00{len(pieces) - 1}\x00"

        def replace(match: re.Match) -> str:
            if match.group(1):
                return hold(f"<code>{html.escape(match.group(2).strip(), quote=False)}</code>")
            bang, label, target = match.group(3), match.group(4), match.group(5)
            if bang:
                return hold(self.image(label, target))
            return hold(self.link(label, target))

        text = INLINE.sub(replace, text)
        if "`" in text:
            self.fail("unmatched backtick")
        text = html.escape(text, quote=False)
        text = re.sub(r"\*\*(\S(?:.*?\S)?)\*\*", r"<strong>\1</strong>", text)
        text = re.sub(r"\*(\S(?:.*?\S)?)\*", r"<em>\1</em>", text)
        if "*" in text:
            self.fail("a '*' that is neither emphasis nor inside `code`")
        if re.search(r"\[[^\]]*\]\(", text):
            self.fail("a link this converter does not understand")
        return re.sub("\x00(\\d+)\x00", lambda m: pieces[int(m.group(1))], text)

    def image(self, alt: str, target: str) -> str:
        path = (self.source.parent / target).resolve()
        if re.match(r"^[a-z]+:", target) or not path.is_file():
            self.fail(f"image {target!r} is not a file next to the page")
        try:
            path.relative_to(self.source.parent.resolve())
        except ValueError:
            self.fail(f"image {target!r} lies outside {self.source.parent}: it could not be shipped")
        self.images.append(pathlib.Path(target))
        return f'<img src="{html.escape(target)}" alt="{html.escape(alt)}">'

    def link(self, label: str, target: str) -> str:
        text = self.inline(label)
        if target.startswith("#"):
            self.fragments.append((target[1:], self.line))
            return f'<a href="{html.escape(target)}">{text}</a>'
        if re.match(r"^https?://", target):
            return f'<a href="{html.escape(target)}">{text}</a>'
        # A file of the repository: the FMU does not carry it, so keep only the text.
        if not (self.source.parent / target.split("#")[0]).exists():
            self.fail(f"link to {target!r}, which does not exist")
        return text

    # -- blocks ---------------------------------------------------------------------------------
    def heading(self, level: int, text: str) -> str:
        anchor = slug(text)
        count = self.anchors.get(anchor, 0)
        self.anchors[anchor] = count + 1
        if count:
            anchor = f"{anchor}-{count}"
        self.ids.add(anchor)
        return f'<h{level} id="{anchor}">{self.inline(text)}</h{level}>'

    def table(self, rows: list[str]) -> str:
        def cells(row: str) -> list[str]:
            row = row.strip()
            if not (row.startswith("|") and row.endswith("|")):
                self.fail("a table row must start and end with '|'")
            return [c.strip() for c in re.split(r"(?<!\\)\|", row[1:-1])]

        header = cells(rows[0])
        if len(rows) < 2 or not all(re.fullmatch(r":?-{3,}:?", c) for c in cells(rows[1])):
            self.fail("a table needs a separator row like |---|---|")
        out = ["<table>", "<thead><tr>" + "".join(f"<th>{self.inline(c)}</th>" for c in header) + "</tr></thead>",
               "<tbody>"]
        for row in rows[2:]:
            values = cells(row)
            if len(values) != len(header):
                self.fail(f"table row with {len(values)} cells under a header of {len(header)}")
            out.append("<tr>" + "".join(f"<td>{self.inline(c.replace(chr(92) + '|', '|'))}</td>"
                                        for c in values) + "</tr>")
        out.append("</tbody></table>")
        return "\n".join(out)

    def convert(self, text: str) -> str:
        lines = text.splitlines()
        out: list[str] = []
        i = 0
        while i < len(lines):
            self.line = i + 1
            line = lines[i]
            if not line.strip():
                i += 1
                continue
            block, i = self.block(lines, i)
            out.append(block)
        self.check_fragments()
        return "\n".join(out)

    def block(self, lines: list[str], i: int) -> tuple[str, int]:
        """The HTML of the block that starts at line i, and the line after it."""
        line = lines[i]
        if line.startswith("```"):
            return self.code_block(lines, i)
        if line != line.lstrip():
            self.fail("an indented block (nested list, indented code) is not supported: unindent it")
        if re.match(r"^(>|\* |\+ |<[a-zA-Z!/]|={3,}$|-{3,}$|#{5,})", line):
            self.fail(f"unsupported Markdown construct: {line[:30]!r}")
        heading = HEADING.match(line)
        if heading:
            return self.heading(len(heading.group(1)), heading.group(2).strip()), i + 1
        if line.startswith("|"):
            end = i
            while end < len(lines) and lines[end].startswith("|"):
                end += 1
            return self.table(lines[i:end]), end
        if LIST_ITEM.match(line):
            return self.list_block(lines, i)
        return self.paragraph(lines, i)

    def code_block(self, lines: list[str], i: int) -> tuple[str, int]:
        end = i + 1
        while end < len(lines) and lines[end].rstrip() != "```":
            end += 1
        if end == len(lines):
            self.fail("unclosed code block")
        body = "\n".join(lines[i + 1:end])
        return f"<pre><code>{html.escape(body, quote=False)}</code></pre>", end + 1

    def list_block(self, lines: list[str], i: int) -> tuple[str, int]:
        """A list of items of one kind (- or 1.), blank lines between them allowed."""
        ordered = LIST_ITEM.match(lines[i]).group(1) != "-"
        tag = "ol" if ordered else "ul"
        items = []
        while i < len(lines):
            self.line = i + 1
            item = LIST_ITEM.match(lines[i])
            if not item or (item.group(1) != "-") != ordered:
                break
            text, i = self.list_item(lines, i, item.group(2))
            items.append(f"<li>{self.inline(text)}</li>")
            while i < len(lines) and not lines[i].strip() and i + 1 < len(lines) and \
                    LIST_ITEM.match(lines[i + 1]) and (LIST_ITEM.match(lines[i + 1]).group(1) != "-") == ordered:
                i += 1
        return f"<{tag}>\n" + "\n".join(items) + f"\n</{tag}>", i

    def list_item(self, lines: list[str], i: int, first: str) -> tuple[str, int]:
        """The text of the item at line i (its continuation lines indented), and the line after it."""
        body = [first]
        i += 1
        while i < len(lines) and lines[i].startswith("  ") and lines[i].strip():
            if LIST_ITEM.match(lines[i].strip()) or lines[i].strip().startswith("```"):
                self.line = i + 1
                self.fail("nested lists and code blocks inside list items are not supported")
            body.append(lines[i].strip())
            i += 1
        return " ".join(body), i

    def paragraph(self, lines: list[str], i: int) -> tuple[str, int]:
        """A paragraph: up to a blank line or the start of another block; an image alone is a figure."""
        body = []
        while i < len(lines) and lines[i].strip() and not re.match(r"^(```|#{1,4} |\||- |\d+\. )", lines[i]):
            if lines[i] != lines[i].lstrip():
                self.line = i + 1
                self.fail("an indented line inside a paragraph")
            body.append(lines[i])
            i += 1
        rendered = self.inline(" ".join(body))
        if re.fullmatch(r'<img [^>]*>', rendered):
            return f"<figure>{rendered}</figure>", i
        return f"<p>{rendered}</p>", i

    def check_fragments(self) -> None:
        for fragment, line in self.fragments:
            if fragment not in self.ids:
                self.line = line
                self.fail(f"link to #{fragment}, which is no heading of the page")


def convert_file(source: pathlib.Path, output: pathlib.Path, title: str, subtitle: str = "") -> list[pathlib.Path]:
    """Writes `output` and the images it shows; returns the image paths (relative to the page)."""
    converter = Converter(source, output.parent)
    body = converter.convert(source.read_text(encoding="utf-8"))
    head = (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f"<title>{html.escape(title)}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n")
    note = f'<p class="subtitle">{html.escape(subtitle)}</p>\n' if subtitle else ""
    # The page's own first heading stays the visible title; the subtitle goes right after it.
    first_end = body.find("</h1>")
    if first_end >= 0:
        body = body[:first_end + 5] + "\n" + note + body[first_end + 5:]
    else:
        body = note + body
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(head + body + "\n</body>\n</html>\n", encoding="utf-8")
    for image in converter.images:
        destination = output.parent / image
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source.parent / image, destination)
    return converter.images


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", type=pathlib.Path)
    parser.add_argument("output", type=pathlib.Path)
    parser.add_argument("--title", default="Documentation")
    parser.add_argument("--subtitle", default="")
    args = parser.parse_args(argv)
    try:
        convert_file(args.source, args.output, args.title, args.subtitle)
    except MarkdownError as error:
        print(f"markdown_to_html: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
