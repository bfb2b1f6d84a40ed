// Part display colours: partscale's palette (partscale.color.palette, golden-angle hues in HLS),
// mirrored once here; tests/test_browser.py compares the two.

import { roundHalfEven } from './recipe';

export type RGB8 = [number, number, number];

// colorsys.hls_to_rgb's helper, with Python's float modulo (the result takes the divisor's sign)
function hlsValue(m1: number, m2: number, hue: number): number {
  hue = ((hue % 1.0) + 1.0) % 1.0;
  if (hue < 1.0 / 6.0) return m1 + (m2 - m1) * hue * 6.0;
  if (hue < 0.5) return m2;
  if (hue < 2.0 / 3.0) return m1 + (m2 - m1) * (2.0 / 3.0 - hue) * 6.0;
  return m1;
}

/** sRGB bytes of part i: golden-angle hues, alternating lightness (as Python's palette_colour). */
export function paletteColour(i: number): RGB8 {
  const h = (i * 0.618033988749895) % 1.0;
  const l = i % 2 === 0 ? 0.55 : 0.42;
  const s = 0.65;
  const m2 = l <= 0.5 ? l * (1.0 + s) : l + s - l * s;
  const m1 = 2.0 * l - m2;
  const rgb = [hlsValue(m1, m2, h + 1.0 / 3.0), hlsValue(m1, m2, h), hlsValue(m1, m2, h - 1.0 / 3.0)];
  return rgb.map((v) => roundHalfEven(v * 255)) as RGB8;
}

/** sRGB bytes of part i from its parts_info colour ([r, g, b] bytes, fractions or '#rrggbb'),
 *  or the palette's when it has none. */
export function partColour(c: unknown, i: number): RGB8 {
  if (typeof c === 'string' && /^#?[0-9a-f]{6}$/i.test(c)) {
    const v = parseInt(c.replace('#', ''), 16);
    return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
  }
  if (Array.isArray(c) && c.length >= 3 && c.every((v) => typeof v === 'number')) {
    // partscale writes sRGB bytes ([r, g, b] integers); fractions in [0, 1] are accepted too
    const scale = !c.every(Number.isInteger) && c.every((v) => v <= 1) ? 255 : 1;
    return [c[0] * scale, c[1] * scale, c[2] * scale].map((v) => Math.round(v)) as RGB8;
  }
  return paletteColour(i);
}
