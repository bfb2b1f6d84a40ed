"""Figures of the evaluation: one row of renders per object, and a contact sheet of all rows."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

BACKGROUND = (255, 255, 255)
INK = (20, 20, 20)
MUTED = (110, 110, 110)
FAILED = (235, 225, 225)


def _font(size: int) -> ImageFont.ImageFont:
    return ImageFont.load_default(size=size)


def failed_panel(size: int, message: str) -> np.ndarray:
    """(size, size, 3) uint8: a pale panel with the reason a mode produced no result."""
    img = Image.new("RGB", (size, size), FAILED)
    draw = ImageDraw.Draw(img)
    font = _font(max(10, size // 22))
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
        y += font.size + 4  # type: ignore[attr-defined]
    return np.asarray(img)


def object_figure(
    title: str, subtitle: str, panels: list[tuple[str, str, np.ndarray]]
) -> Image.Image:
    """One object's row: a title, then the panels side by side, each with a label and a note.

    Parameters
    ----------
    title, subtitle : str
        Object name and the edit in words.
    panels : list of (label, note, (S, S, 3) uint8)
        Renders of equal size (same view and frame), e.g. original | global | stretch | tile | naive.
    """
    size = panels[0][2].shape[0]
    big, small = _font(max(12, size // 14)), _font(max(10, size // 20))
    head = big.size + small.size + 16  # type: ignore[attr-defined]
    label_h = big.size + small.size + 14  # type: ignore[attr-defined]
    gap = 6
    width = len(panels) * size + (len(panels) + 1) * gap
    fig = Image.new("RGB", (width, head + size + label_h + gap), BACKGROUND)
    draw = ImageDraw.Draw(fig)
    draw.text((gap, 4), title, fill=INK, font=big)
    draw.text((gap, 8 + big.size), subtitle, fill=MUTED, font=small)  # type: ignore[attr-defined]
    for i, (label, note, img) in enumerate(panels):
        x = gap + i * (size + gap)
        fig.paste(Image.fromarray(np.asarray(img, np.uint8)), (x, head))
        draw.rectangle((x, head, x + size - 1, head + size - 1), outline=(215, 215, 215))
        draw.text((x + 4, head + size + 4), label, fill=INK, font=big)
        draw.text(
            (x + 4, head + size + 8 + big.size),  # type: ignore[attr-defined]
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
