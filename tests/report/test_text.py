"""Text from files reaches figures and pages as text: matplotlib draws any text literally
(no math), pages and plotly show it escaped."""

from __future__ import annotations

import html
import io

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.figure import Figure

from armkit.report.text import MAX_CHARS, figure_text, page_text, plotly_text

TRICKY = ["ws$\\frac{$", "$x$", "a$b", "\\", "$$", "<b>x</b>", "<a href='http://x'>y</a>",
          "&amp;", ":x: [bold]red[/bold]", "\x00\x1b[31m", "%s %d {0}"]


def _drawn(text: str) -> str:
    """What matplotlib drew for `text` as a title (after a full draw)."""
    fig = Figure(figsize=(3, 1))
    ax = fig.add_subplot()
    title = ax.set_title(figure_text(text))
    fig.savefig(io.BytesIO(), format="png", dpi=30)
    return title.get_text()


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:Glyph")          # characters the font lacks: boxes
@settings(max_examples=200, deadline=None)
@given(st.one_of(st.sampled_from(TRICKY), st.text(max_size=80)))
def test_any_text_draws_in_a_figure(text):
    _drawn(text)             # no exception: no math mode, no parse error


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.sampled_from(TRICKY), st.text(max_size=400)))
def test_pages_and_plotly_get_text_not_markup(text):
    shown = page_text(text)
    assert "<" not in shown and ">" not in shown and '"' not in shown and "'" not in shown
    assert len(html.unescape(shown)) <= MAX_CHARS
    if len(text) <= MAX_CHARS and text.isprintable():
        assert html.unescape(shown) == text
    assert "$" not in plotly_text(text) and "<" not in plotly_text(text)


def test_dollars_are_drawn_as_dollars():
    assert figure_text("ws$\\frac{$") == "ws\\$\\frac{\\$"
    assert figure_text("x" * 500).endswith("…") and len(figure_text("x" * 500)) == MAX_CHARS
