// The recipe schema (partscale.edit.recipe) and the rules partscale.edit.scale.resolve_edit
// applies to one zone, mirrored for the page: what the editor sends (api.ts) and what it refuses
// before sending (ui.ts, drag.ts). tests/test_browser.py checks the rules against Python's on a
// table of cases (tests/browser/page_node.mjs runs this module in node).

export type Axis = 'x' | 'y' | 'z';
export type Mode = 'stretch' | 'tile' | 'global';
export const AXES: readonly Axis[] = ['x', 'y', 'z'];
export const MODES: readonly Mode[] = ['stretch', 'tile', 'global'];
export const RECIPE_VERSION = 1;

/** A position: object units, or a percentage of the solid's extent like '30%'. */
export type Position = number | `${number}%`;

/** One edit of partscale.edit.JSON_SCHEMA. */
export interface Edit {
  axis: Axis;
  zone: [Position, Position];
  to: Position;
  mode: Mode;
}

/** A recipe: edits apply in order, each to the result of the previous one; all positions refer
 *  to the recipe's input (apply_recipe carries them through the earlier edits on their axis). */
export interface Recipe {
  version: typeof RECIPE_VERSION;
  edits: Edit[];
}

/** One zone in world units as it applies (in the frame the earlier edits leave). lo/hi: the
 *  solid's extent along the axis before this edit. */
export interface Zone {
  axis: Axis;
  mode: Mode;
  start: number;
  end: number;
  dest: number;
  lo: number;
  hi: number;
}

/** max(1, round(target / length)), half-way rounding up, as recipe.tile_count: a ratio within
 *  1e-9 below a half counts as the half (0.3 / 0.2 is 1.4999999999999998). 0 only for a zero
 *  target (destination at the start: the zone removed), never by rounding. */
export function tileCount(length: number, target: number): number {
  if (target === 0) return 0;
  return Math.max(1, Math.floor(target / length + 0.5 + 1e-9));
}

/** Python's round() of a float: to the nearest integer, exact halves to the even one. */
export function roundHalfEven(x: number): number {
  const f = Math.floor(x);
  const d = x - f; // exact for |x| < 2**52
  if (d > 0.5) return f + 1;
  if (d < 0.5) return f;
  return f % 2 === 0 ? f : f + 1;
}

/** The destination the server applies: the end moves by a whole number of voxels h. */
export function snapDest(z: Pick<Zone, 'end' | 'dest'>, h: number): number {
  return z.end + roundHalfEven((z.dest - z.end) / h) * h;
}

/** Whether the zone is removed: tile with the destination at the start (0 copies). */
export function removesZone(z: Pick<Zone, 'mode' | 'start' | 'dest'>): boolean {
  return z.mode === 'tile' && z.dest === z.start;
}

/** Which of resolve_edit's rules a zone breaks (its checks, in its order). */
/** 'warp': the shaped zone's own rules (warp.ts warpProblem). */
export type ZoneRule = 'finite' | 'order' | 'dest' | 'inside' | 'thickness' | 'snapped-dest' | 'vanish' | 'warp';

export interface ZoneProblem {
  rule: ZoneRule;
  message: string;
}

/**
 * Why apply_recipe would refuse the zone (partscale.edit.scale.resolve_edit), or null: finite
 * positions, start < end, destination beyond start (tile: or at it, the zone removed), the zone
 * within the solid's extent (h/2 slack), at least two voxels thick, and the snapped destination a
 * voxel beyond the start.
 * 'vanish' (global mode shrinking the solid to nothing) is the page's own guard: the rules before
 * it leave that only at exact equality.
 */
export function zoneProblem(z: Zone, h: number): ZoneProblem | null {
  const { start: s, end: e, dest: d } = z;
  if (![s, e, d, (d - e) / h].every(Number.isFinite)) {
    return { rule: 'finite', message: 'positions must be finite numbers' };
  }
  if (!(s < e)) return { rule: 'order', message: 'start must be below end' };
  const removed = removesZone(z);
  if (!(d > s || removed)) {
    const hint = d === s ? ' (tile with the destination at the start removes the zone)' : '';
    return { rule: 'dest', message: `destination must be beyond start${hint}` };
  }
  if (s < z.lo - h / 2 || e > z.hi + h / 2) {
    return { rule: 'inside', message: 'the zone must lie within the object' };
  }
  if (e - s < 2 * h - 1e-6 * h) return { rule: 'thickness', message: 'the zone must be at least two voxels thick' };
  const snapped = snapDest(z, h);
  if (!removed && snapped - s < h) return { rule: 'snapped-dest', message: 'destination must be a voxel beyond start' };
  if (z.mode === 'global' && !(z.hi - z.lo + snapped - e > 0)) {
    return { rule: 'vanish', message: 'the solid would vanish' };
  }
  return null;
}

/** The recipe edit of a zone, positions in world units (the destination as given, unsnapped). */
export function zoneEdit(z: Pick<Zone, 'axis' | 'mode' | 'start' | 'end' | 'dest'>): Edit {
  return { axis: z.axis, zone: [z.start, z.end], to: z.dest, mode: z.mode };
}
