// Zones that are no slab across an axis (partscale.edit.warp): a radial zone, an oblique slab, a
// flight's steps (screw), a spiral stair's steps (helix) and elements about the vertical (rotation:
// a star base's arms). Their maps in TypeScript (bounds,
// the step bound, the tests' mirror) and in GLSL (the raymarcher), both exactly
// partscale.edit.warp_source: tests/test_browser.py evaluates the GLSL on the GPU and this module
// in node, and compares both with it. Each kind is one entry of KINDS (its recipe edit, its map,
// its bounds, its uniforms) and one branch of warpSource() in WARP_GLSL: a new kind adds both.
import { AXES, type Axis } from './recipe';

/** Voxels either side of a step's cut over which the two sides are blended (warp.CUT_BLEND). */
export const CUT_BLEND = 2.0;

export interface RadialWarp {
  kind: 'radial';
  axis: Axis;
  /** On the two other axes, in order. */
  center: [number, number];
  /** 0 round; else the regular polygon's sides (its gauge radius). */
  sides: number;
  /** Degrees: the first face normal's direction. */
  phase: number;
  /** Levels along the axis between which it applies (null: everywhere). */
  span: [number, number] | null;
  r0: number;
  r1: number;
  to: number;
}

export interface ObliqueWarp {
  kind: 'oblique';
  normal: [number, number, number];
  s0: number;
  s1: number;
  to: number;
}

export interface ScrewWarp {
  kind: 'screw';
  axis: Axis;
  step: [number, number, number];
  cut: number;
  copies: number;
  /** The floor the flight stands on beyond the cut (edit.screw_ground), or null. */
  ground: number | null;
}

export interface HelixWarp {
  kind: 'helix';
  center: [number, number];
  angle: number;
  rise: number;
  cut: number;
  copies: number;
}

export interface RotationWarp {
  kind: 'rotation';
  /** The vertical axis' place on x and z. */
  center: [number, number];
  /** Degrees from one element to the next (from x toward z). */
  angle: number;
  /** Degrees: the first element's direction. */
  phase: number;
  /** Elements now. */
  count: number;
  /** A whole ring (else an open arc). */
  closed: boolean;
  /** Radii the elements lie between (within hub nothing moves). */
  hub: number;
  radius: number;
  /** Levels (y) the elements lie between. */
  span: [number, number];
  copies: number;
}

export type Warp = RadialWarp | ObliqueWarp | ScrewWarp | HelixWarp | RotationWarp;
export type WarpKind = Warp['kind'];

/** A warp's recipe edit (partscale.edit.RadialZone.to_json and its siblings). */
export type WarpEdit = Record<string, unknown>;

/** A recipe of one warp edit (the page sends a warp alone). */
export interface WarpRecipe {
  version: 1;
  edits: WarpEdit[];
}

type Vec3 = [number, number, number];

interface KindSpec<W extends Warp> {
  /** The shader's number for it (WARP_GLSL's branches). */
  code: number;
  edit(w: W): WarpEdit;
  /** Output point -> [source point, its weight] (warp_source). */
  source(w: W, p: readonly number[], h: number): [Vec3, number];
  /** The box [lo, hi] holding the box lo..hi and what the warp moves there. */
  bounds(w: W, lo: number[], hi: number[], h: number): [number[], number[]];
  /** Largest step along a ray, as a share of the distance sampled (the map's Lipschitz bound). */
  stepScale(w: W): number;
  /** Four vec4 uniforms. */
  pack(w: W, h: number): number[];
  /** Why apply_warp would refuse it (null: valid). */
  problem(w: W): string | null;
  /** It leaves the object as it is. */
  noop(w: W): boolean;
}

const finite = (...v: number[]) => v.every(Number.isFinite);
const deg = Math.PI / 180;

/** The gauge radius of a 2D offset: Euclidean, or that of a regular polygon (edit.gauge). */
export function gauge(d: readonly number[], sides: number, phase: number): number {
  if (sides === 0) return Math.hypot(d[0], d[1]);
  let best = -Infinity;
  for (let k = 0; k < sides; k++) {
    const a = phase * deg + (2 * Math.PI * k) / sides;
    best = Math.max(best, d[0] * Math.cos(a) + d[1] * Math.sin(a));
  }
  return best / Math.cos(Math.PI / sides);
}

function radialSource(r: number, w: RadialWarp): number {
  if (r <= w.r0) return r;
  if (r <= w.to) return w.r0 + ((r - w.r0) * (w.r1 - w.r0)) / (w.to - w.r0);
  return r - (w.to - w.r1);
}

const others = (axis: Axis): [number, number] => {
  const a = AXES.indexOf(axis);
  return [0, 1, 2].filter((i) => i !== a) as [number, number];
};

function unitNormal(n: readonly number[]): Vec3 {
  const l = Math.hypot(n[0], n[1], n[2]);
  return [n[0] / l, n[1] / l, n[2] / l];
}

/** The whole shift of a screw: each step snapped to whole voxels, times copies (world units). */
export function screwShift(w: ScrewWarp, h: number): Vec3 {
  return w.step.map((v) => Math.round(v / h) * w.copies * h) as Vec3;
}

const union = (lo: number[], hi: number[], lo2: number[], hi2: number[]): [number[], number[]] => [
  lo.map((v, i) => Math.min(v, lo2[i])),
  hi.map((v, i) => Math.max(v, hi2[i])),
];

function turn(d: readonly number[], degrees: number): [number, number] {
  const c = Math.cos(degrees * deg);
  const s = Math.sin(degrees * deg);
  return [c * d[0] - s * d[1], s * d[0] + c * d[1]];
}

const radial: KindSpec<RadialWarp> = {
  code: 1,
  edit: (w) => ({
    radial: { axis: w.axis, center: [...w.center], sides: w.sides, phase: w.phase, ...(w.span ? { span: [...w.span] } : {}) },
    zone: [w.r0, w.r1],
    to: w.to,
  }),
  source(w, p) {
    const [u, v] = others(w.axis);
    const a = AXES.indexOf(w.axis);
    const d = [p[u] - w.center[0], p[v] - w.center[1]];
    const r = gauge(d, w.sides, w.phase);
    let k = r > 0 ? radialSource(r, w) / r : 1;
    if (w.span && !(p[a] >= w.span[0] && p[a] <= w.span[1])) k = 1;
    const q = [...p] as Vec3;
    q[u] = w.center[0] + d[0] * k;
    q[v] = w.center[1] + d[1] * k;
    return [q, 1];
  },
  bounds(w, lo, hi) {
    const grow = Math.max(w.to - w.r1, 0) / (w.sides ? Math.cos(Math.PI / w.sides) : 1);
    const [u, v] = others(w.axis);
    const a = [...lo];
    const b = [...hi];
    for (const i of [u, v]) {
      a[i] -= grow;
      b[i] += grow;
    }
    return [a, b];
  },
  stepScale(w) {
    // radial: (to - r0) / (r1 - r0) in the annulus; across it the ratio rs / r; a polygon's
    // gauge changes up to 1 / cos(180 / sides) faster than the distance
    const k = Math.min(1, (w.to - w.r0) / (w.r1 - w.r0), w.to > w.r1 ? 1 : w.to / w.r1);
    return k * (w.sides ? Math.cos(Math.PI / w.sides) : 1);
  },
  pack(w) {
    const span = w.span ?? [0, 0];
    return [
      ...[AXES.indexOf(w.axis), w.center[0], w.center[1], w.sides],
      ...[w.phase * deg, w.r0, w.r1, w.to],
      ...[w.span ? 1 : 0, span[0], span[1], 0],
      ...[0, 0, 0, 0],
    ];
  },
  problem(w) {
    if (!finite(w.r0, w.r1, w.to, ...w.center, w.phase)) return 'radii must be finite numbers';
    if (!(w.r0 >= 0 && w.r0 < w.r1)) return 'radii must be 0 <= R0 < R1';
    if (!(w.to > w.r0)) return 'the target radius must lie beyond R0';
    if (w.sides !== 0 && !(w.sides >= 3 && w.sides <= 64)) return 'sides must be 0 (round) or 3..64';
    return null;
  },
  noop: (w) => w.to === w.r1,
};

const oblique: KindSpec<ObliqueWarp> = {
  code: 2,
  edit: (w) => ({ normal: [...w.normal], zone: [w.s0, w.s1], to: w.to }),
  source(w, p) {
    const n = unitNormal(w.normal);
    const s = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
    const back = s <= w.s0 ? 0 : s <= w.to ? (s - w.s0) * (1 - (w.s1 - w.s0) / (w.to - w.s0)) : w.to - w.s1;
    return [[p[0] - back * n[0], p[1] - back * n[1], p[2] - back * n[2]], 1];
  },
  bounds(w, lo, hi) {
    const n = unitNormal(w.normal);
    const m = n.map((v) => v * (w.to - w.s1));
    return union(lo, hi, lo.map((v, i) => v + m[i]), hi.map((v, i) => v + m[i]));
  },
  stepScale: (w) => Math.min(1, (w.to - w.s0) / (w.s1 - w.s0)),
  pack(w) {
    const n = unitNormal(w.normal);
    return [n[0], n[1], n[2], 0, w.s0, w.s1, w.to, 0, 0, 0, 0, 0, 0, 0, 0, 0];
  },
  problem(w) {
    if (!finite(...w.normal) || Math.hypot(...w.normal) < 1e-9) return 'the normal must be a non-zero vector';
    if (!finite(w.s0, w.s1, w.to)) return 'positions must be finite numbers';
    if (!(w.s0 < w.s1)) return 'start must be below end';
    if (!(w.to > w.s0)) return 'the destination must lie beyond start';
    return null;
  },
  noop: (w) => w.to === w.s1,
};

const screw: KindSpec<ScrewWarp> = {
  code: 3,
  edit: (w) => ({ screw: { axis: w.axis, step: [...w.step], cut: w.cut }, copies: w.copies }),
  source(w, p, h) {
    const a = AXES.indexOf(w.axis);
    const direction = Math.round(w.step[a] / h) > 0 ? 1 : -1;
    const beyond = ((p[a] - w.cut) * direction) / h;
    const s = screwShift(w, h);
    const weight = Math.min(1, Math.max(0, beyond / (2 * CUT_BLEND) + 0.5));
    return [[p[0] - s[0], p[1] - s[1], p[2] - s[2]], weight];
  },
  bounds(w, lo, hi, h) {
    const s = screwShift(w, h);
    return union(lo, hi, lo.map((v, i) => v + s[i]), hi.map((v, i) => v + s[i]));
  },
  stepScale: () => 0.5, // the blend across the cut mixes two distances
  pack(w, h) {
    const s = screwShift(w, h);
    const a = AXES.indexOf(w.axis);
    const direction = Math.round(w.step[a] / h) > 0 ? 1 : -1;
    return [s[0], s[1], s[2], a, w.cut, direction, h, w.ground === null ? 0 : 1, w.ground ?? 0, 0, 0, 0, 0, 0, 0, 0];
  },
  problem(w) {
    if (!finite(...w.step, w.cut) || !Number.isInteger(w.copies) || w.copies === 0) {
      return 'steps: finite values and a whole number of steps other than 0';
    }
    return null;
  },
  noop: () => false,
};

const helix: KindSpec<HelixWarp> = {
  code: 4,
  edit: (w) => ({ helix: { center: [...w.center], angle: w.angle, rise: w.rise, cut: w.cut }, copies: w.copies }),
  source(w, p, h) {
    const t = turn([p[0] - w.center[0], p[2] - w.center[1]], -w.copies * w.angle);
    const weight = Math.min(1, Math.max(0, (p[1] - w.cut) / h / (2 * CUT_BLEND) + 0.5));
    return [[t[0] + w.center[0], p[1] - w.copies * w.rise, t[1] + w.center[1]], weight];
  },
  bounds(w, lo, hi, h) {
    // warp._helix_bounds: the upper part (from the blend's lowest layer) turned and raised
    const n = w.copies;
    const y0 = Math.max(lo[1], w.cut - (CUT_BLEND + 1) * h - n * w.rise);
    if (y0 >= hi[1]) return [lo, hi];
    const corners = [lo[0], hi[0]].flatMap((x) => [lo[2], hi[2]].map((z) => turn([x - w.center[0], z - w.center[1]], n * w.angle)));
    const xs = corners.map((c) => c[0] + w.center[0]);
    const zs = corners.map((c) => c[1] + w.center[1]);
    const mlo = [Math.min(...xs), y0 + n * w.rise, Math.min(...zs)];
    const mhi = [Math.max(...xs), hi[1] + n * w.rise, Math.max(...zs)];
    return union(lo, hi, mlo, mhi);
  },
  stepScale: () => 0.5,
  pack(w, h) {
    // the turn's cosine and sine in double precision (a GPU's own trigonometry may be coarser)
    const t = -w.copies * w.angle * deg;
    return [w.center[0], w.center[1], Math.cos(t), Math.sin(t), w.cut, h, w.copies * w.rise, 0, 0, 0, 0, 0, 0, 0, 0, 0];
  },
  problem(w) {
    if (!finite(...w.center, w.angle, w.rise, w.cut) || !Number.isInteger(w.copies) || w.copies === 0) {
      return 'steps: finite values and a whole number of steps other than 0';
    }
    if (!(Math.abs(w.angle) > 0 && Math.abs(w.angle) < 180)) return 'the turn must be 0 < |angle| < 180 degrees';
    return null;
  },
  noop: () => false,
};

/** numpy's rint: halves to the even neighbour. */
function rint(x: number): number {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/** numpy's mod: the remainder with the divisor's sign. */
function mod(x: number, y: number): number {
  const r = x % y;
  return r !== 0 && r < 0 !== y < 0 ? r + y : r;
}

/** Source direction (degrees) of an output direction about a rotation zone's axis
 *  (edit.warp.rotation_source). */
export function rotationSource(theta: number, w: RotationWarp): number {
  const sign = w.angle > 0 ? 1 : -1;
  const a = Math.abs(w.angle);
  let rel = mod(sign * (theta - w.phase), 360);
  const k = w.count;
  const n = w.copies;
  if (w.closed) {
    const step = 360 / (k + n);
    const m = rint(rel / step);
    const alpha = Math.min(a / 2, Math.max(-a / 2, rel - m * step));
    return w.phase + sign * (mod(rint((m * k) / (k + n)), k) * a + alpha);
  }
  const mid = ((k - 1 + Math.max(n, 0)) * a) / 2;
  rel = mod(rel - mid + 180, 360) + mid - 180;
  const m = rint(rel / a);
  let src = rel;
  if (n > 0 && m >= k && m <= k - 1 + n) src = rel - (m - (k - 1)) * a;
  else if (n < 0 && m >= k + n && m <= k - 1) src = rel + (k - m) * a;
  return w.phase + sign * src;
}

const rotation: KindSpec<RotationWarp> = {
  code: 5,
  edit: (w) => ({
    rotation: {
      center: [...w.center],
      angle: w.angle,
      phase: w.phase,
      count: w.count,
      closed: w.closed,
      hub: w.hub,
      radius: w.radius,
      span: [...w.span],
    },
    copies: w.copies,
  }),
  source(w, p) {
    const d = [p[0] - w.center[0], p[2] - w.center[1]];
    const r = Math.hypot(d[0], d[1]);
    if (!(r > w.hub && p[1] >= w.span[0] && p[1] <= w.span[1])) return [[p[0], p[1], p[2]], 1];
    const t = rotationSource((Math.atan2(d[1], d[0]) * 180) / Math.PI, w) * deg;
    return [[w.center[0] + r * Math.cos(t), p[1], w.center[1] + r * Math.sin(t)], 1];
  },
  bounds(w, lo, hi, h) {
    // warp.warp_grid: the disc the elements turn in
    const reach = w.radius + h;
    const a = [Math.min(lo[0], w.center[0] - reach), lo[1], Math.min(lo[2], w.center[1] - reach)];
    const b = [Math.max(hi[0], w.center[0] + reach), hi[1], Math.max(hi[2], w.center[1] + reach)];
    return [a, b];
  },
  // each sector shows a turned element, but the next one may lie nearer than in the source
  stepScale: () => 0.5,
  pack(w, h) {
    return [
      ...[w.center[0], w.center[1], w.phase, w.angle > 0 ? 1 : -1],
      ...[Math.abs(w.angle), w.count, w.copies, w.closed ? 1 : 0],
      ...[w.hub, w.span[0], w.span[1], h],
      ...[w.radius, 0, 0, 0],
    ];
  },
  problem(w) {
    if (!finite(...w.center, w.angle, w.phase, w.hub, w.radius, ...w.span)) return 'elements: finite values';
    if (!Number.isInteger(w.copies) || w.copies === 0) return 'elements: a whole number other than 0';
    if (!(Math.abs(w.angle) > 0 && Math.abs(w.angle) <= 180)) return 'the turn must be 0 < |angle| <= 180 degrees';
    if (w.count + w.copies < 1) return `at most ${w.count - 1} of the ${w.count} elements can go`;
    if (w.closed && Math.abs(w.count * Math.abs(w.angle) - 360) > 1e-6 * 360) return 'a closed ring turns a whole turn';
    if (!(w.hub >= 0 && w.hub < w.radius && w.span[0] < w.span[1])) return 'hub below radius, span low to high';
    return null;
  },
  noop: () => false,
};

const KINDS: { [K in WarpKind]: KindSpec<Extract<Warp, { kind: K }>> } = { radial, oblique, screw, helix, rotation };
export const WARP_KINDS = Object.keys(KINDS) as WarpKind[];

function spec<W extends Warp>(w: W): KindSpec<W> {
  return KINDS[w.kind] as unknown as KindSpec<W>;
}

export const warpEdit = (w: Warp): WarpEdit => spec(w).edit(w);
export const warpProblem = (w: Warp): string | null => spec(w).problem(w);
export const warpNoop = (w: Warp): boolean => spec(w).noop(w);
export const warpStepScale = (w: Warp): number => spec(w).stepScale(w);
export const warpBounds = (w: Warp, lo: number[], hi: number[], h: number): [number[], number[]] =>
  spec(w).bounds(w, lo, hi, h);
/** The shader's uniforms: the kind's code and four vec4s. */
export const packWarp = (w: Warp, h: number): { kind: number; data: number[] } => ({ kind: spec(w).code, data: spec(w).pack(w, h) });

/** Output point -> [source point, weight] (edit.warp_source). */
export function warpSource(w: Warp, p: readonly number[], h: number): [number[], number] {
  return spec(w).source(w, p, h);
}

/** The warp of a recipe edit as the server lists it (its JSON form; ground: a flight's floor). */
export function warpFromEdit(e: WarpEdit, ground: number | null = null): Warp | null {
  const num = (v: unknown) => Number(v);
  const pair = (v: unknown) => (v as unknown[]).map(num) as [number, number];
  if ('radial' in e) {
    const r = e.radial as Record<string, unknown>;
    const [r0, r1] = pair(e.zone);
    return {
      kind: 'radial',
      axis: (r.axis as Axis) ?? 'y',
      center: pair(r.center),
      sides: num(r.sides ?? 0),
      phase: num(r.phase ?? 0),
      span: r.span ? pair(r.span) : null,
      r0,
      r1,
      to: num(e.to),
    };
  }
  if ('normal' in e) {
    const [s0, s1] = pair(e.zone);
    return { kind: 'oblique', normal: (e.normal as unknown[]).map(num) as Vec3, s0, s1, to: num(e.to) };
  }
  if ('screw' in e) {
    const s = e.screw as Record<string, unknown>;
    return { kind: 'screw', axis: s.axis as Axis, step: (s.step as unknown[]).map(num) as Vec3, cut: num(s.cut), copies: num(e.copies), ground };
  }
  if ('helix' in e) {
    const s = e.helix as Record<string, unknown>;
    return { kind: 'helix', center: pair(s.center), angle: num(s.angle), rise: num(s.rise), cut: num(s.cut), copies: num(e.copies) };
  }
  if ('rotation' in e) {
    const s = e.rotation as Record<string, unknown>;
    return {
      kind: 'rotation',
      center: pair(s.center),
      angle: num(s.angle),
      phase: num(s.phase),
      count: num(s.count),
      closed: s.closed === true,
      hub: num(s.hub),
      radius: num(s.radius),
      span: pair(s.span),
      copies: num(e.copies),
    };
  }
  return null;
}

export const WARP_GLSL = /* glsl */ `
// partscale.edit.warp_source, one branch per kind (warp.ts KINDS): output point -> source point,
// and in weight the share of it in the output (the rest is the point's own place).
uniform int uWarpKind;     // 0 none, 1 radial, 2 oblique, 3 screw, 4 helix, 5 rotation
uniform vec4 uWarp[4];

float warpGauge(vec2 d, float sides, float phase) {
  if (sides < 0.5) return length(d);
  float sector = 6.283185307179586 / sides;
  float a = atan(d.y, d.x) - phase + 0.5 * sector;
  float off = a - sector * floor(a / sector) - 0.5 * sector;  // angle to the nearest face normal
  return length(d) * cos(off) / cos(0.5 * sector);
}

// cos and sin of an angle in degrees to float32's precision (a GPU's own sin and cos may be
// coarser): to the nearest quarter turn, then Taylor series on |x| <= pi / 4
vec2 warpCosSin(float degs) {
  float q = floor(degs / 90.0 + 0.5);
  float x = radians(degs - 90.0 * q);
  float x2 = x * x;
  float s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (1.0 - x2 / 110.0)))));
  float c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0 * (1.0 - x2 / 90.0))));
  int quarter = int(mod(q, 4.0));
  return quarter == 0 ? vec2(c, s) : quarter == 1 ? vec2(-s, c) : quarter == 2 ? vec2(-c, -s) : vec2(s, -c);
}

// A distance no larger than the way from an output point to what the warp puts where the source
// had something else (huge where the source's own distance is a bound already): a rotation's
// elements lie on the span's levels beyond the hub, so off those levels or within the hub the
// way to them is at least the gap (at least a voxel, so that a ray crosses into them)
float warpGap(vec3 p) {
  if (uWarpKind != 5) return 1e9;
  vec4 a = uWarp[0], c = uWarp[2], e = uWarp[3];
  float r = length(p.xz - a.xy);
  float below = c.y - p.y, above = p.y - c.z;
  if (below > 0.0 || above > 0.0) return max(length(vec2(max(below, above), max(r - e.x, 0.0))), c.w);
  if (r <= c.x) return max(c.x - r, c.w);
  return 1e9;
}

vec3 warpSource(vec3 p, out float weight) {
  weight = 1.0;
  vec4 a = uWarp[0], b = uWarp[1], c = uWarp[2];
  if (uWarpKind == 1) {
    int axis = int(a.x + 0.5);
    int u = axis == 0 ? 1 : 0;
    int v = axis == 2 ? 1 : 2;
    if (c.x > 0.5 && !(p[axis] >= c.y && p[axis] <= c.z)) return p;
    vec2 d = vec2(p[u], p[v]) - a.yz;
    float r = warpGauge(d, a.w, b.x);
    float r0 = b.y, r1 = b.z, to = b.w;
    float rs = r <= r0 ? r : (r <= to ? r0 + (r - r0) * (r1 - r0) / (to - r0) : r - (to - r1));
    float k = r > 0.0 ? rs / r : 1.0;
    p[u] = a.y + d.x * k;
    p[v] = a.z + d.y * k;
    return p;
  }
  if (uWarpKind == 2) {
    float s = dot(p, a.xyz);
    float s0 = b.x, s1 = b.y, to = b.z;
    float back = s <= s0 ? 0.0 : (s <= to ? (s - s0) * (1.0 - (s1 - s0) / (to - s0)) : to - s1);
    return p - back * a.xyz;
  }
  if (uWarpKind == 3) {
    int axis = int(a.w + 0.5);
    float beyond = (p[axis] - b.x) * b.y / b.z;
    weight = clamp(beyond / (2.0 * ${CUT_BLEND.toFixed(1)}) + 0.5, 0.0, 1.0);
    return p - a.xyz;
  }
  if (uWarpKind == 4) {
    vec2 d = p.xz - a.xy;
    weight = clamp((p.y - b.x) / b.y / (2.0 * ${CUT_BLEND.toFixed(1)}) + 0.5, 0.0, 1.0);
    return vec3(a.z * d.x - a.w * d.y + a.x, p.y - b.z, a.w * d.x + a.z * d.y + a.y);
  }
  if (uWarpKind == 5) {
    // rotation (edit.warp.rotation_source): beyond the hub, on the span's levels, turned by
    // delta degrees, a whole multiple of the angles where the map turns an element rigidly (no
    // error of atan enters); where it squeezes a gap, the source direction itself
    vec2 d = p.xz - a.xy;
    float r = length(d);
    if (!(r > c.x && p.y >= c.y && p.y <= c.z)) return p;
    float sgn = a.w, ang = b.x, k = b.y, n = b.z;
    float rel = mod(sgn * (degrees(atan(d.y, d.x)) - a.z), 360.0);
    float delta = 0.0;
    if (b.w > 0.5) {
      float stp = 360.0 / (k + n);
      float m = roundEven(rel / stp);
      float alpha = rel - m * stp;
      float q = mod(roundEven(m * k / (k + n)), k);
      if (abs(alpha) > 0.5 * ang) {
        vec2 cs = warpCosSin(a.z + sgn * (q * ang + sign(alpha) * 0.5 * ang));
        return vec3(a.x + r * cs.x, p.y, a.y + r * cs.y);
      }
      delta = q * ang - m * stp;
    } else {
      float mid = (k - 1.0 + max(n, 0.0)) * ang / 2.0;
      float m = roundEven((mod(rel - mid + 180.0, 360.0) + mid - 180.0) / ang);
      if (n > 0.0 && m >= k && m <= k - 1.0 + n) delta = -(m - (k - 1.0)) * ang;
      else if (n < 0.0 && m >= k + n && m <= k - 1.0) delta = (k - m) * ang;
    }
    vec2 cs = warpCosSin(sgn * delta);
    return vec3(a.x + cs.x * d.x - cs.y * d.y, p.y, a.y + cs.y * d.x + cs.x * d.y);
  }
  return p;
}
`;
