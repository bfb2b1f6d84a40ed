// The 1D edit maps of partscale.edit.recipe.source_coordinate, in TypeScript (for the planes,
// bounds and the step bound) and in GLSL (for the raymarcher). Both must match the Python exactly:
// tests/test_browser.py evaluates the GLSL on the GPU and this module in node, and compares both
// with source_coordinate. Zones, tile counts and the validation rules live in recipe.ts.
//
// A zone maps output coordinates y (after the edit) to source coordinates x (before):
//   y < start            -> x = y                      (rigid before the zone)
//   start <= y <= dest   -> stretch: linear [start,dest] -> [start,end]
//                           tile: n = tileCount copies, each a linear map onto [start,end];
//                           n = 0 (dest == start): the zone removed, y >= start -> y - shift
//   y > dest             -> x = y - (dest - end)       (rigid after the zone, translated)
//   global               -> x = lo + (y - lo) / f,  f = (hi - lo + dest - end) / (hi - lo)

import { AXES, MODES, tileCount, type Zone } from './recipe';

/** Zones the shader holds: fit's recipe has a tile and a stretch per axis, or, where it is allowed
 *  to deform, a few thin slabs per axis (a round top: four along x and four along z). */
export const MAX_ZONES = 16;

export function sourceCoordinate(y: number, z: Zone): number {
  const shift = z.dest - z.end;
  if (z.mode === 'global') {
    const f = (z.hi - z.lo + shift) / (z.hi - z.lo);
    return z.lo + (y - z.lo) / f;
  }
  if (y < z.start) return y;
  if (y > z.dest) return y - shift;
  const length = z.end - z.start;
  if (z.mode === 'tile' && tileCount(length, z.dest - z.start) === 0) return y - shift;
  const t = (y - z.start) / (z.dest - z.start);
  if (z.mode === 'stretch') return z.start + t * length;
  const n = tileCount(length, z.dest - z.start);
  const u = t * n;
  const k = Math.min(Math.floor(u), n - 1);
  return z.start + (u - k) * length;
}

/** A point (x, y, z) after the zones -> before them: edits apply in order, so the last goes first. */
export function toSource(zones: readonly Zone[], p: readonly number[]): number[] {
  const q = [...p];
  for (let i = zones.length - 1; i >= 0; i--) {
    const a = AXES.indexOf(zones[i].axis);
    q[a] = sourceCoordinate(q[a], zones[i]);
  }
  return q;
}

/** Where a plane at source coordinate x lies after the zone: recipe.forward_coordinate. The
 *  inverse of sourceCoordinate outside the zone; inside, it follows the stretch, the first copy
 *  (tile) or the scaling about lo (global). Recipes carry positions through earlier zones with it. */
export function forwardCoordinate(x: number, z: Zone): number {
  const shift = z.dest - z.end;
  if (z.mode === 'global') return z.lo + (x - z.lo) * ((z.hi - z.lo + shift) / (z.hi - z.lo));
  const n = z.mode === 'stretch' ? 1 : tileCount(z.end - z.start, z.dest - z.start);
  // 0 copies: planes inside a removed zone collapse onto its start
  const scale = n === 0 ? 0 : (z.dest - z.start) / (n * (z.end - z.start));
  if (x <= z.start) return x;
  if (x >= z.end) return x + shift;
  return z.start + (x - z.start) * scale;
}

/** Smallest dy/dx of the zone's output-from-source map, capped at 1 (ray step safety). */
export function minJacobian(z: Zone): number {
  if (z.mode === 'global') return Math.min(1, (z.hi - z.lo + z.dest - z.end) / (z.hi - z.lo));
  const length = z.end - z.start;
  const target = z.dest - z.start;
  const n = z.mode === 'tile' ? tileCount(length, target) : 1;
  // a removed zone is no slab: the rest are translations
  return n === 0 ? 1 : Math.min(1, target / (n * length));
}

/** Uniform packing: a = (start, end, dest, lo), b = (hi, axis, mode, tile count). */
export function packZone(z: Zone): [number[], number[]] {
  const n = z.mode === 'tile' ? tileCount(z.end - z.start, z.dest - z.start) : 1;
  return [
    [z.start, z.end, z.dest, z.lo],
    [z.hi, AXES.indexOf(z.axis), MODES.indexOf(z.mode), n],
  ];
}

export const REMAP_GLSL = /* glsl */ `
#define MAX_ZONES ${MAX_ZONES}
uniform int uZoneCount;
uniform vec4 uZoneA[MAX_ZONES];
uniform vec4 uZoneB[MAX_ZONES];

// recipe.source_coordinate for one zone: output coordinate y -> source coordinate.
float sourceCoordinate(float y, vec4 a, vec4 b) {
  float start = a.x, end = a.y, dest = a.z, lo = a.w, hi = b.x;
  int mode = int(b.z + 0.5);
  float shift = dest - end;
  if (mode == 2) {
    float f = (hi - lo + shift) / (hi - lo);
    return lo + (y - lo) / f;
  }
  if (y < start) return y;
  if (y > dest) return y - shift;
  if (mode == 1 && b.w < 0.5) return y - shift;  // tile, 0 copies: the zone removed
  float t = (y - start) / (dest - start);
  if (mode == 0) return start + t * (end - start);
  float n = b.w;
  float u = t * n;
  float k = min(floor(u), n - 1.0);
  return start + (u - k) * (end - start);
}

// Zones apply in order, so the output point goes back through the last zone first. The loop runs
// over the zones set only (GLSL ES 3.00 loops may end at a uniform): a frame costs what its zones
// cost, however many the shader could hold.
vec3 toSource(vec3 p) {
  for (int i = min(uZoneCount, MAX_ZONES) - 1; i >= 0; --i) {
    int axis = int(uZoneB[i].y + 0.5);
    p[axis] = sourceCoordinate(p[axis], uZoneA[i], uZoneB[i]);
  }
  return p;
}
`;
