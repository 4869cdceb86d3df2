"""One list of blocks, two pages: the report as Markdown and as self-contained HTML.

A report is a list of blocks: ``("h1"|"h2"|"h3", text)``, ``("p", text)``, ``("ul", [items])``,
``("table", header, rows)``, ``("img", path, caption)``, ``("pre", text)``. Any text (a
paragraph, a list item, a table cell) may be a :class:`Tone`, a str that carries how it must
stand out: ``"bad"`` (an unstable loop, a diverging response: red and bold in HTML, bold in
Markdown) or ``"warn"`` (a warning: dark orange in HTML, bold in Markdown). Every text is
escaped: a title cannot inject markup into either page.
"""

from __future__ import annotations

import html
import math
import re

__all__ = ["Tone", "bad", "warn", "number", "markdown_text", "markdown", "render_html"]


class Tone(str):
    """A text with a tone: ``Tone("UNSTABLE", "bad")``."""

    tone: str

    def __new__(cls, text, tone: str):
        obj = super().__new__(cls, text)
        obj.tone = tone
        return obj


def bad(text) -> Tone:
    """A text that reports something unstable or failed (red in HTML)."""
    return Tone(str(text), "bad")


def warn(text) -> Tone:
    """A text that reports a warning (orange in HTML)."""
    return Tone(str(text), "warn")


def number(value, digits: int = 5) -> str:
    """A value as a report shows it: ``digits`` significant digits, ``n/a`` for None or NaN,
    ``inf``, ``yes``/``no`` for a bool, an int or a str as it is."""
    if value is None:
        return "n/a"
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    value = float(value)
    if math.isnan(value):
        return "n/a"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.{digits}g}"


# Inline Markdown markup (CommonMark + GFM): code, emphasis, links and images, tables,
# strikethrough; each is a literal character when backslash-escaped (CommonMark 0.31, sec. 2.4).
_MD_INLINE = re.compile(r"([\\`*\[\]|~])")
# "_" opens or closes emphasis only at a word boundary (left/right-flanking delimiter runs)
_MD_UNDERSCORE = re.compile(r"(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])")
# what turns the start of a line into a block (heading, quote, list, thematic break)
_MD_BLOCK_START = re.compile(r"^([#>+=-])|^(\d+)([.)])")


def markdown_text(text, *, line_start: bool = False) -> str:
    """Plain text as Markdown that renders as exactly that text (bold if it has a tone).

    ``&``, ``<`` and ``>`` become HTML entities (no raw HTML: a title cannot inject a
    ``<script>``); inline markup characters are backslash-escaped; line breaks become spaces.
    ``line_start``: the text begins a line (a paragraph or list item), so block markers
    (``#``, ``>``, ``-``, ``1.``) at its start are escaped too.
    """
    tone = getattr(text, "tone", None)
    text = str(text).replace("\r", " ").replace("\n", " ")
    text = html.escape(text, quote=False)
    text = _MD_INLINE.sub(r"\\\1", text)
    text = _MD_UNDERSCORE.sub(r"\\_", text)
    if line_start:
        text = _MD_BLOCK_START.sub(lambda m: ("\\" + m.group(1)) if m.group(1)
                                   else f"{m.group(2)}\\{m.group(3)}", text, count=1)
    if tone and text.strip():
        # ** must touch non-space characters to open and close emphasis (CommonMark 6.2)
        stripped = text.strip()
        lead = text[: len(text) - len(text.lstrip())]
        text = f"{lead}**{stripped}**"
    return text


def markdown(blocks: list) -> str:
    """Render blocks as Markdown; every text is escaped (:func:`markdown_text`)."""
    md = markdown_text
    out = []
    for block in blocks:
        kind = block[0]
        if kind in ("h1", "h2", "h3"):
            text = md(block[1])
            # a heading's closing #s would be dropped: escape a final one
            text = text[:-1] + "\\#" if text.endswith("#") else text
            out.append("#" * int(kind[1]) + " " + text)
        elif kind == "p":
            out.append(md(block[1], line_start=True))
        elif kind == "ul":
            out.append("\n".join(f"- {md(item, line_start=True)}" for item in block[1]))
        elif kind == "table":
            header, rows = block[1], block[2]
            lines = ["| " + " | ".join(md(h) for h in header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(md(c) for c in row) + " |" for row in rows]
            out.append("\n".join(lines))
        elif kind == "img":
            out.append(f"![{md(block[2])}](<{block[1]}>)\n\n*{md(block[2])}*")
        elif kind == "pre":
            fence = "`" * max(3, 1 + max((len(r) for r in re.findall("`+", block[1])),
                                         default=0))
            out.append(f"{fence}\n{block[1]}\n{fence}")
    return "\n\n".join(out) + "\n"


def _tone(text) -> str:
    tone = getattr(text, "tone", None)
    return f' class="{tone}"' if tone in ("bad", "warn") else ""


def render_html(blocks: list, title: str) -> str:
    """Render the same blocks as a self-contained HTML page (toned texts in colour)."""
    esc = html.escape
    body = []
    for block in blocks:
        kind = block[0]
        if kind in ("h1", "h2", "h3"):
            body.append(f"<{kind}>{esc(block[1])}</{kind}>")
        elif kind == "p":
            body.append(f"<p{_tone(block[1])}>{esc(block[1])}</p>")
        elif kind == "ul":
            body.append("<ul>" + "".join(f"<li{_tone(i)}>{esc(i)}</li>" for i in block[1])
                        + "</ul>")
        elif kind == "table":
            head = "".join(f"<th>{esc(h)}</th>" for h in block[1])
            rows = "".join("<tr>" + "".join(f"<td{_tone(c)}>{esc(str(c))}</td>" for c in row)
                           + "</tr>" for row in block[2])
            body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>")
        elif kind == "img":
            body.append(f'<figure><img src="{esc(block[1])}" alt="{esc(block[2])}">'
                        f"<figcaption>{esc(block[2])}</figcaption></figure>")
        elif kind == "pre":
            body.append(f"<pre>{esc(block[1])}</pre>")
    style = ("body{font-family:sans-serif;max-width:75em;margin:2em auto;padding:0 1em}"
             "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
             "padding:.2em .5em;text-align:right}th{background:#eee}td:first-child,"
             "th:first-child{text-align:left}img{max-width:100%}"
             "figcaption{font-size:90%;color:#444;margin:.3em 0 1.5em}"
             ".bad{color:#c00000;font-weight:bold}td.bad{background:#fde8e8}"
             ".warn{color:#a04800;font-weight:bold}td.warn{background:#fff4e0}")
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{esc(title)}</title><style>{style}</style></head><body>\n"
            + "\n".join(body) + "\n</body></html>\n")
