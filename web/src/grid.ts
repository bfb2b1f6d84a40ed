// The object's arrays as the page holds them, rebuilt from what GET /api/grid and /api/parts send:
// the whole object, or (X-Partscale-Delta) only the layers an edit changed, the rest copied from
// the arrays the page already holds (src/partscale/serve/app.py describes the protocol).

export type Shape = [number, number, number];
/** [axis, head, tail]: the first head and last tail layers along axis are the base's. */
export type Delta = [number, number, number];

/** One encoded object as the server sends it. */
export interface Encoded {
  shape: Shape;
  /** The revision that showed it: the base to name next time. */
  revision: number;
  delta: Delta | null;
  body: ArrayBuffer;
}

/** Distances (float16 bits, in voxels) and sRGB colour (RGBA, a = 255), C order (z fastest). */
export interface Volume {
  shape: Shape;
  revision: number;
  distance: Uint16Array;
  rgba: Uint8Array;
}

/** Part indices, C order, -1 = none. */
export interface Parts {
  shape: Shape;
  revision: number;
  parts: Int16Array;
}

type Layered = Uint8Array | Uint16Array | Int16Array;

const count = (s: Shape) => s[0] * s[1] * s[2];

/** The shape of the changed layers: shape cut to head..shape[axis]-tail along axis. */
export function bodyShape(shape: Shape, delta: Delta): Shape {
  const [axis, head, tail] = delta;
  const out: Shape = [...shape];
  out[axis] = shape[axis] - head - tail;
  return out;
}

/** The new array (shape, `channels` values a voxel): the base's head and tail layers along the
 * delta's axis around the body's layers. Throws when they cannot fit together. */
export function spliceLayers<T extends Layered>(
  base: T,
  baseShape: Shape,
  shape: Shape,
  channels: number,
  delta: Delta,
  body: T,
): T {
  const [axis, head, tail] = delta;
  const n = shape[axis];
  const nb = baseShape[axis];
  const mid = n - head - tail;
  const ok =
    [0, 1, 2].every((a) => a === axis || shape[a] === baseShape[a]) &&
    head >= 0 && tail >= 0 && mid >= 0 && head + tail <= nb &&
    base.length === count(baseShape) * channels && body.length === count(bodyShape(shape, delta)) * channels;
  if (!ok) {
    throw new Error(`delta: expected layers fitting ${baseShape.join('×')} -> ${shape.join('×')}, got ${delta.join(',')}`);
  }
  // (outer, layer, inner) blocks: each outer index holds n contiguous layers of `inner` values
  const outer = shape.slice(0, axis).reduce((a, b) => a * b, 1);
  const inner = shape.slice(axis + 1).reduce((a, b) => a * b, 1) * channels;
  const out = new (base.constructor as new (n: number) => T)(count(shape) * channels);
  for (let o = 0; o < outer; o++) {
    const dst = o * n * inner;
    const src = o * nb * inner;
    if (head > 0) out.set(base.subarray(src, src + head * inner), dst);
    if (mid > 0) out.set(body.subarray(o * mid * inner, (o + 1) * mid * inner), dst + head * inner);
    if (tail > 0) out.set(base.subarray(src + (nb - tail) * inner, src + nb * inner), dst + (n - tail) * inner);
  }
  return out;
}

/** 3 bytes a voxel -> 4 (a = 255): what an RGBA8 texture takes. */
function rgbToRgba(rgb: Uint8Array): Uint8Array {
  const n = rgb.length / 3;
  const out = new Uint8Array(n * 4);
  for (let i = 0, j = 0; i < n * 3; i += 3, j += 4) {
    out[j] = rgb[i];
    out[j + 1] = rgb[i + 1];
    out[j + 2] = rgb[i + 2];
    out[j + 3] = 255;
  }
  return out;
}

function needBase<B extends { revision: number }>(e: Encoded, base: B | null): B {
  if (!base) throw new Error(`delta: expected the whole object (no base held), got layers ${e.delta}`);
  return base;
}

/** The grid of GET /api/grid: float16 distances, then 3 sRGB bytes a voxel (of the body's box). */
export function volumeFrom(e: Encoded, base: Volume | null): Volume {
  const box = e.delta ? bodyShape(e.shape, e.delta) : e.shape;
  const n = count(box);
  if (e.body.byteLength !== n * 5) {
    throw new Error(`grid: expected ${n * 5} bytes for ${box.join('×')} voxels, got ${e.body.byteLength}`);
  }
  const distance = new Uint16Array(e.body, 0, n);
  const rgba = rgbToRgba(new Uint8Array(e.body, 2 * n, 3 * n));
  if (!e.delta) return { shape: e.shape, revision: e.revision, distance, rgba };
  const b = needBase(e, base);
  return {
    shape: e.shape,
    revision: e.revision,
    distance: spliceLayers(b.distance, b.shape, e.shape, 1, e.delta, distance),
    rgba: spliceLayers(b.rgba, b.shape, e.shape, 4, e.delta, rgba),
  };
}

/** The part indices of GET /api/parts: int16 a voxel (of the body's box). */
export function partsFrom(e: Encoded, base: Parts | null): Parts {
  const box = e.delta ? bodyShape(e.shape, e.delta) : e.shape;
  const n = count(box);
  if (e.body.byteLength !== n * 2) {
    throw new Error(`parts: expected ${n * 2} bytes for ${box.join('×')} voxels, got ${e.body.byteLength}`);
  }
  const parts = new Int16Array(e.body);
  if (!e.delta) return { shape: e.shape, revision: e.revision, parts };
  const b = needBase(e, base);
  return { shape: e.shape, revision: e.revision, parts: spliceLayers(b.parts, b.shape, e.shape, 1, e.delta, parts) };
}
