"""Wall labels: Chinese and Japanese titles drawn with a CJK font (Pillow's own font draws
every such character as the same box), long titles wrapped onto a second line, the rest cut
with an ellipsis.

References: two titles of different characters must give different images (boxes would
not); where ink lies on the card against the layout (a second title line only for a title
that does not fit one); `wrap` against its own contract (each line within the width, the
words kept in order)."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

from gigascroll.exhibit.labels import _fonts, _length, label_image, wrap
from gigascroll.exhibit.model import Painting


def _label(title, **kw) -> np.ndarray:
    return label_image(Painting(0, title, 100, 50, "x", **kw))


def _ink_rows(a: np.ndarray) -> np.ndarray:
    return np.flatnonzero((a.mean(axis=2) < 120).any(axis=1))


def test_cjk_titles_are_drawn_not_boxed():
    assert _fonts(40)[1] is not None, "no CJK font: the Makefile installs fonts-droid-fallback"
    a, b = _label("溪山行旅图"), _label("早春图山水")
    assert not np.array_equal(a, b)
    # Mixed text: the Latin part in Pillow's font, the CJK part in the CJK font; the Latin
    # part then looks as it does alone.
    mixed, latin = _label("山 Fan Kuan"), _label("Fan Kuan")
    assert not np.array_equal(mixed, latin)


def test_a_long_title_takes_a_second_line():
    short = _ink_rows(_label("Long scroll"))
    long = _ink_rows(_label("A landscape with a very long title that wraps onto a second "
                            "line of the card"))
    # The title's first line: rows 20..70; a second one at 70..120, only for the long title.
    assert short.max() < 75 and long.max() > 90


def test_wrap_keeps_the_words_within_the_width():
    draw = ImageDraw.Draw(Image.new("RGB", (8, 8)))
    fonts = _fonts(40)
    text = "Travelers among Mountains and Streams by the river"
    lines = wrap(draw, text, fonts, 472, 3)
    assert len(lines) <= 3 and all(_length(draw, ln, fonts) <= 472 for ln in lines)
    assert " ".join(lines) == text  # fits in three lines: nothing cut
    cut = wrap(draw, text * 3, fonts, 472, 2)
    assert len(cut) == 2 and cut[-1].endswith("…") and _length(draw, cut[-1], fonts) <= 472
    assert wrap(draw, "x" * 500, fonts, 472, 1)[0].endswith("…")
