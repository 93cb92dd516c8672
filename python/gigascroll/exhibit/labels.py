"""Wall labels: title, artist and date rendered with Pillow's default font into a small
image, which the show packs as a painting of its own (named `label-NAME`) and hangs beside
its painting (the gallery shows paintings only: a label is one, LABEL_W_M x LABEL_H_M)."""

from __future__ import annotations

import numpy as np

__all__ = ["LABEL_W_M", "LABEL_H_M", "LABEL_GAP_M", "label_image", "label_lines"]

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


def label_image(painting) -> np.ndarray:
    """The label as an (H, W, 3) uint8 image: dark text on an off-white card; lines too long
    for the card are cut with an ellipsis."""
    from PIL import Image, ImageDraw, ImageFont
    w, h = round(LABEL_W_M * PIXELS_PER_M), round(LABEL_H_M * PIXELS_PER_M)
    img = Image.new("RGB", (w, h), (236, 232, 224))
    draw = ImageDraw.Draw(img)
    y = 20
    for k, line in enumerate(label_lines(painting)):
        font = ImageFont.load_default(40 if k == 0 else 28)
        text = line
        while text and draw.textlength(text, font=font) > w - 40:
            text = text[:-2] + "…" if len(text) > 2 else ""
        draw.text((20, y), text, fill=(30, 28, 26), font=font)
        y += 56 if k == 0 else 40
        if y > h - 30:
            break
    return np.asarray(img, dtype=np.uint8)
