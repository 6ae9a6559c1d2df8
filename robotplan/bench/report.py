"""A report as a list of blocks, written as Markdown and as one self-contained HTML page
(figures embedded), so that both say the same thing.

Blocks: ``("h1" | "h2" | "p", text)``, ``("table", header, rows)``, ``("image", path,
caption)`` with ``path`` relative to the report's folder. Text may hold ``code`` spans.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from robotplan.base.files import write_atomically

__all__ = ["Block", "write_report"]

Block = tuple


def _markdown(blocks: list[Block]) -> str:
    out: list[str] = []
    for block in blocks:
        kind = block[0]
        if kind == "h1":
            out.append(f"# {block[1]}")
        elif kind == "h2":
            out.append(f"## {block[1]}")
        elif kind == "p":
            out.append(block[1])
        elif kind == "table":
            header, rows = block[1], block[2]
            out.append("| " + " | ".join(header) + " |")
            out.append("|" + " --- |" * len(header))
            out.extend("| " + " | ".join(str(c) for c in row) + " |" for row in rows)
        elif kind == "image":
            out.append(f"![{block[2]}]({block[1]})")
        else:
            raise ValueError(f"unknown report block {kind!r}")
        out.append("")
    return "\n".join(out)


def _inline(text: str) -> str:
    """HTML of a line of text whose ``code`` spans become <code>."""
    parts = re.split(r"`([^`]*)`", text)
    return "".join(f"<code>{html.escape(p)}</code>" if i % 2 else html.escape(p)
                   for i, p in enumerate(parts))


def _html(blocks: list[Block], folder: Path, title: str) -> str:
    body: list[str] = []
    for block in blocks:
        kind = block[0]
        if kind in ("h1", "h2", "p"):
            body.append(f"<{kind}>{_inline(block[1])}</{kind}>")
        elif kind == "table":
            head = "".join(f"<th>{_inline(h)}</th>" for h in block[1])
            rows = "".join("<tr>" + "".join(f"<td>{_inline(str(c))}</td>" for c in row)
                           + "</tr>" for row in block[2])
            body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>")
        elif kind == "image":
            path = folder / block[1]
            if path.is_file():
                data = base64.b64encode(path.read_bytes()).decode()
                body.append(f'<figure><img src="data:image/png;base64,{data}" '
                            f'alt="{html.escape(block[2])}"><figcaption>'
                            f"{_inline(block[2])}</figcaption></figure>")
    style = ("body{font-family:sans-serif;max-width:60em;margin:2em auto;line-height:1.4}"
             "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
             "padding:.2em .6em;text-align:left}img{max-width:100%}code{background:#f3f3f3}")
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
            f"</title><style>{style}</style></head><body>{''.join(body)}</body></html>\n")


def write_report(blocks: list[Block], folder: Path, title: str, name: str = "report"
                 ) -> tuple[Path, Path]:
    """``folder/NAME.md`` and ``folder/NAME.html``, each written whole."""
    md, page = folder / f"{name}.md", folder / f"{name}.html"
    text = _markdown(blocks)
    write_atomically(md, lambda tmp: tmp.write_text(text))
    page_text = _html(blocks, folder, title)
    write_atomically(page, lambda tmp: tmp.write_text(page_text))
    return md, page
