"""Wall labels: title, artist and date rendered with Pillow's default font (a CJK font for
Chinese or Japanese text) into a small image, which the show packs as a painting of its own (named `label-NAME`) and hangs beside
its painting (the gallery shows paintings only: a label is one, LABEL_W_M x LABEL_H_M)."""

from __future__ import annotations

import numpy as np

__all__ = ["LABEL_W_M", "LABEL_H_M", "LABEL_GAP_M", "label_image", "label_lines", "wrap"]

LABEL_W_M, LABEL_H_M = 0.16, 0.08   # a museum label's size
LABEL_GAP_M = 0.10                  # from the painting's (or its frame's) edge
PIXELS_PER_M = 3200                 # 512 x 256 pixels: 3.2 px per mm, legible up close


def label_lines(painting) -> list[str]:
    """The label's lines: the title, then the artist and the date when given."""
    lines = [painting.title]
    who = ", ".join(x for x in (painting.artist, painting.date) if x)
    if who:
        lines.append(who)
    if painting.accession:
        lines.append(painting.accession)
    return lines


# Fonts with CJK glyphs (the scrolls' titles and artists are often Chinese or Japanese), in
# order of preference; Debian's fonts-droid-fallback (the Makefile installs it) is the last.
CJK_FONTS = ("/usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc",
             "/usr/share/fonts/truetype/wqy/wqy-microhei.ttc",
             "/usr/share/fonts/truetype/droid/DroidSansFallbackFull.ttf")
TITLE_LINES = 2


def _needs_cjk_font(text: str) -> bool:
    """Whether `text` has characters beyond Latin, Greek and Cyrillic (which Pillow's own
    font draws): CJK ideographs, kana, hangul, full-width forms."""
    return any(ord(c) >= 0x2E80 for c in text)


def _fonts(size: int) -> tuple:
    """(Pillow's own font, the first CJK font installed or None) at `size` pixels. The CJK
    fonts may lack Latin glyphs (Droid Sans Fallback does), so each run of text is drawn in
    the font that has it (_runs)."""
    import os

    from PIL import ImageFont
    cjk = None
    for path in CJK_FONTS:
        if os.path.isfile(path):
            try:
                cjk = ImageFont.truetype(path, size)
                break
            except OSError:
                continue
    return ImageFont.load_default(size), cjk


def _runs(text: str, fonts) -> list[tuple[str, object]]:
    """`text` as (run, font) pieces: CJK runs in the CJK font (when one is installed), the
    rest in Pillow's own."""
    out: list[tuple[str, object]] = []
    for c in text:
        font = fonts[1] if fonts[1] is not None and _needs_cjk_font(c) else fonts[0]
        if out and out[-1][1] is font:
            out[-1] = (out[-1][0] + c, font)
        else:
            out.append((c, font))
    return out


def _length(draw, text: str, fonts) -> float:
    return sum(draw.textlength(run, font=font) for run, font in _runs(text, fonts))


def _tokens(text: str) -> list[str]:
    """Where a line may break: after a space, or between two CJK characters."""
    out, word = [], ""
    for c in text:
        if _needs_cjk_font(c):
            if word:
                out.append(word)
            out.append(c)
            word = ""
        else:
            word += c
            if c == " ":
                out.append(word)
                word = ""
    return out + ([word] if word else [])


def wrap(draw, text: str, fonts, width: float, lines: int) -> list[str]:
    """`text` broken into at most `lines` lines of at most `width` pixels (`fonts` as
    _fonts gives them); the last cut with an ellipsis when the text is longer."""
    out, line = [], ""
    tokens = _tokens(text)
    for k, t in enumerate(tokens):
        if not line or _length(draw, (line + t).rstrip(), fonts) <= width:
            line += t
            continue
        if len(out) == lines - 1:  # the last line: the rest goes on it, cut below
            line += "".join(tokens[k:])
            break
        out.append(line.rstrip())
        line = t
    last = line.rstrip()
    if _length(draw, last, fonts) > width:
        while last and _length(draw, last + "…", fonts) > width:
            last = last[:-1]
        last = last.rstrip() + "…"
    return out + [last]


def label_image(painting) -> np.ndarray:
    """The label as an (H, W, 3) uint8 image: dark text on an off-white card; the title on up
    to TITLE_LINES lines, other lines one each, cut with an ellipsis when too long; CJK text
    in a CJK font."""
    from PIL import Image, ImageDraw
    w, h = round(LABEL_W_M * PIXELS_PER_M), round(LABEL_H_M * PIXELS_PER_M)
    img = Image.new("RGB", (w, h), (236, 232, 224))
    draw = ImageDraw.Draw(img)
    y = 20
    for k, line in enumerate(label_lines(painting)):
        fonts = _fonts(40 if k == 0 else 28)
        for text in wrap(draw, line, fonts, w - 40, TITLE_LINES if k == 0 else 1):
            if y > h - 40:
                break
            x = 20.0
            for run, font in _runs(text, fonts):
                draw.text((x, y), run, fill=(30, 28, 26), font=font)
                x += draw.textlength(run, font=font)
            y += 50 if k == 0 else 40
        y += 6 if k == 0 else 0
    return np.asarray(img, dtype=np.uint8)
