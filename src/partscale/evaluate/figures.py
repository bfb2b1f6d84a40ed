"""Figures of the evaluation: one row of renders per object, and a contact sheet of all rows."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

BACKGROUND = (255, 255, 255)
INK = (20, 20, 20)
MUTED = (110, 110, 110)
FAILED = (235, 225, 225)


def _font(size: int) -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    return ImageFont.load_default(size=size)


def failed_panel(size: int, message: str) -> np.ndarray:
    """(size, size, 3) uint8: a pale panel with the reason a mode produced no result."""
    img = Image.new("RGB", (size, size), FAILED)
    draw = ImageDraw.Draw(img)
    px = max(10, size // 22)  # the font's size (bitmap fonts have no .size)
    font = _font(px)
    words, lines, line = message.split(), [], ""
    for w in words:  # wrap to the panel's width
        trial = f"{line} {w}".strip()
        if draw.textlength(trial, font=font) > size - 16 and line:
            lines.append(line)
            line = w
        else:
            line = trial
    lines.append(line)
    y = size // 3
    for text in ["failed:", *lines[:8]]:
        draw.text((8, y), text, fill=INK, font=font)
        y += px + 4
    return np.asarray(img)


def object_figure(
    title: str, subtitle: str, panels: list[tuple[str, str, np.ndarray]], *, legend: str = ""
) -> Image.Image:
    """One object's row: a title, then the panels side by side, each with a label and a note.

    Parameters
    ----------
    title, subtitle : str
        Object name and the edit in words.
    legend : str
        An optional third line under the subtitle (what the notes mean).
    panels : list of (label, note, (S, S, 3) uint8)
        Renders of equal size (same view and frame), e.g. original | global | stretch | tile | naive.
    """
    size = panels[0][2].shape[0]
    big_px, small_px = max(12, size // 14), max(10, size // 20)
    big, small = _font(big_px), _font(small_px)
    lines = [subtitle, legend] if legend else [subtitle]
    head = big_px + len(lines) * (small_px + 4) + 12
    label_h = big_px + small_px + 14
    gap = 6
    width = len(panels) * size + (len(panels) + 1) * gap
    fig = Image.new("RGB", (width, head + size + label_h + gap), BACKGROUND)
    draw = ImageDraw.Draw(fig)
    draw.text((gap, 4), title, fill=INK, font=big)
    y = 8 + big_px
    for text in lines:
        draw.text((gap, y), text, fill=MUTED, font=small)
        y += small_px + 4
    for i, (label, note, img) in enumerate(panels):
        x = gap + i * (size + gap)
        fig.paste(Image.fromarray(np.asarray(img, np.uint8)), (x, head))
        draw.rectangle((x, head, x + size - 1, head + size - 1), outline=(215, 215, 215))
        draw.text((x + 4, head + size + 4), label, fill=INK, font=big)
        draw.text(
            (x + 4, head + size + 8 + big_px),
            note,
            fill=MUTED,
            font=small,
        )
    return fig


def contact_sheet(figures: list[Image.Image], *, width: int | None = None) -> Image.Image:
    """All object rows stacked, scaled to a common width (the widest row's, or ``width``)."""
    if not figures:
        raise ValueError("contact_sheet: expected at least one figure, got none")
    w = width or max(f.width for f in figures)
    rows = [f if f.width == w else f.resize((w, round(f.height * w / f.width))) for f in figures]
    sheet = Image.new("RGB", (w, sum(r.height for r in rows)), BACKGROUND)
    y = 0
    for r in rows:
        sheet.paste(r, (0, y))
        y += r.height
    return sheet
