"""A picture of the suggestions: the object with its candidate bands, axes and ticks in object units."""

from __future__ import annotations

import math

import numpy as np

from ..csdf import CSDF
from ..errors import InputError
from .suggest import AXES, Candidate

#: Band colours (sRGB) and opacity per kind.
COLOURS = {"tile": (0, 114, 178), "stretch": (0, 158, 115)}
ALPHA = 0.28
#: Most bands drawn (the best ones).
MAX_BANDS = 6


def view_for(axis: str | None) -> str:
    """The render view showing ``axis`` across the image: ``side`` for z, else ``front``."""
    return "side" if axis == "z" else "front"


def _ticks(lo: float, hi: float) -> np.ndarray:
    span = max(hi - lo, 1e-12)
    step = 10 ** math.floor(math.log10(span / 4))
    for m in (1, 2, 5, 10):
        if span / (m * step) <= 6:
            step *= m
            break
    return np.arange(math.ceil(lo / step) * step, hi + 1e-9 * span, step)


def draw_candidates(
    csdf: CSDF, candidates: list[Candidate], *, axis: str | None = None, size: int = 640
) -> np.ndarray:
    """(size, size, 3) uint8: ``csdf`` rendered with the bands of ``candidates`` on the axes the
    view shows (front: x across, y up; side for ``axis='z'``: z across), the best
    :data:`MAX_BANDS` numbered by rank, with
    ticks on both axes and a scale bar in object units."""
    from PIL import Image, ImageDraw, ImageFont

    from ..render import SCALE_BAR_BAND, camera, render

    view = view_for(axis)
    frame = csdf.surface_bounds()
    image = render(csdf, view=view, size=size, scale_bar=True)
    cam = camera(view, frame, size, reserve_bottom=SCALE_BAR_BAND)
    units = csdf.meta.get("units") or ""

    def pixel(p: np.ndarray) -> tuple[float, float]:
        d = p - cam.centre
        return size / 2 + (d @ cam.right) * cam.scale, size / 2 - cam.shift - (
            d @ cam.up
        ) * cam.scale

    corner_lo, corner_hi = pixel(frame[0]), pixel(frame[1])
    x0, x1 = sorted((corner_lo[0], corner_hi[0]))
    y0, y1 = sorted((corner_lo[1], corner_hi[1]))
    im = Image.fromarray(image).convert("RGBA")
    over = Image.new("RGBA", im.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(over)
    font = ImageFont.load_default(size=max(10, size // 48))
    across = next(a for a in range(3) if abs(cam.right[a]) > 0.5)
    up = next(a for a in range(3) if abs(cam.up[a]) > 0.5)
    shown = [c for c in candidates if AXES.index(c.axis) in (across, up)]
    if not shown:
        raise InputError(
            f"--png: expected a candidate along an axis the {view} view shows, got none"
        )
    # the best on top: drawn last; at most MAX_BANDS, so the object stays visible
    ranked = list(enumerate(candidates[:MAX_BANDS], start=1))
    for rank, c in reversed(ranked):
        a = AXES.index(c.axis)
        if a not in (across, up):
            continue
        p0, p1 = frame[0].copy(), frame[0].copy()
        p0[a], p1[a] = c.zone
        (u0, v0), (u1, v1) = pixel(p0), pixel(p1)
        rgba = (*COLOURS[c.kind], round(255 * ALPHA))
        if a == across:
            box = [min(u0, u1), y0, max(u0, u1), y1]
        else:
            box = [x0, min(v0, v1), x1, max(v0, v1)]
        width = 3 if c.kind == "tile" else 1
        draw.rectangle(box, fill=rgba, outline=(*COLOURS[c.kind], 255), width=width)
        draw.text(
            (box[0] + 3, box[1] + 2), f"{rank} {c.kind}", fill=(*COLOURS[c.kind], 255), font=font
        )
    ink = (0, 0, 0, 255)
    # axes with ticks in object units along the frame's bottom and left edges
    draw.line([x0, y1, x1, y1], fill=ink, width=1)
    draw.line([x0, y0, x0, y1], fill=ink, width=1)
    for a, horizontal in ((across, True), (up, False)):
        sign = 1.0 if (cam.right if horizontal else cam.up)[a] > 0 else -1.0
        for t in _ticks(frame[0, a], frame[1, a]):
            p = frame[0].copy()
            p[a] = t
            u, v = pixel(p)
            if horizontal:
                draw.line([u, y1, u, y1 + 5], fill=ink)
                draw.text((u, y1 + 6), f"{t:g}", fill=ink, font=font, anchor="ma")
            else:
                draw.line([x0 - 5, v, x0, v], fill=ink)
                draw.text((x0 - 7, v), f"{t:g}", fill=ink, font=font, anchor="rm")
        label = f"{AXES[a]}{'' if sign > 0 else ' (-)'} [{units}]" if units else AXES[a]
        if horizontal:
            draw.text((x1, y1 + 6 + size // 40), label, fill=ink, font=font, anchor="ra")
        else:
            draw.text((x0 + 4, y0 - 4), label, fill=ink, font=font, anchor="ld")
    return np.asarray(Image.alpha_composite(im, over).convert("RGB"))
