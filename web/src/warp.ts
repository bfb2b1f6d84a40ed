// Zones that are no slab across an axis (partscale.edit.warp): a radial zone, an oblique slab, a
// flight's steps (screw) and a spiral stair's steps (helix). Their maps in TypeScript (bounds,
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

export type Warp = RadialWarp | ObliqueWarp | ScrewWarp | HelixWarp;
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

const KINDS: { [K in WarpKind]: KindSpec<Extract<Warp, { kind: K }>> } = { radial, oblique, screw, helix };
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
  return null;
}

export const WARP_GLSL = /* glsl */ `
// partscale.edit.warp_source, one branch per kind (warp.ts KINDS): output point -> source point,
// and in weight the share of it in the output (the rest is the point's own place).
uniform int uWarpKind;     // 0 none, 1 radial, 2 oblique, 3 screw, 4 helix
uniform vec4 uWarp[4];

float warpGauge(vec2 d, float sides, float phase) {
  if (sides < 0.5) return length(d);
  float sector = 6.283185307179586 / sides;
  float a = atan(d.y, d.x) - phase + 0.5 * sector;
  float off = a - sector * floor(a / sector) - 0.5 * sector;  // angle to the nearest face normal
  return length(d) * cos(off) / cos(0.5 * sector);
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
  return p;
}
`;
