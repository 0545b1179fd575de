"""Text from files (robot, joint, obstacle and task names, reasons) made safe for where it is
shown: a figure draws it as written, a page shows it as text.

matplotlib reads ``$...$`` as math (``ws$\\frac{$`` fails to draw); plotly reads a few HTML
tags in names and titles (``<a href>`` makes a link) and ``$...$`` as LaTeX; a page reads HTML.
Every report module passes such text through one of these before it reaches a figure or page.

>>> figure_text("ws$\\\\frac{$")
'ws\\\\$\\\\frac{\\\\$'
>>> plotly_text("<a href='x'>post</a> $1")
'&lt;a href=&#x27;x&#x27;&gt;post&lt;/a&gt; &#36;1'
"""

from __future__ import annotations

import html
import re

MAX_CHARS = 200
"""Longer text is cut (with an ellipsis) so that a label cannot swamp a figure."""

CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")


def _cut(text: object) -> str:
    text = CONTROL.sub("", str(text))
    return text if len(text) <= MAX_CHARS else text[:MAX_CHARS - 1] + "…"


def figure_text(text: object) -> str:
    """Text as a matplotlib figure draws it literally: every ``$`` escaped (no math mode),
    control characters dropped, cut at `MAX_CHARS`."""
    return _cut(text).replace("$", r"\$")


def page_text(text: object) -> str:
    """Text for HTML: escaped (``<``, ``>``, ``&`` and quotes), control characters dropped,
    cut at `MAX_CHARS`."""
    return html.escape(_cut(text), quote=True)


def plotly_text(text: object) -> str:
    """Text for a plotly name, title or label: HTML-escaped (plotly renders a few tags) and
    ``$`` as an entity (plotly reads ``$...$`` as LaTeX)."""
    return page_text(text).replace("$", "&#36;")
