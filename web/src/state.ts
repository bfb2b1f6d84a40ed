// The editor's one state object and its transitions. Handlers dispatch named actions; the scene
// and the panel subscribe and draw what the state says. Everything else the page shows (resolved
// zones, the recipe, the output box) is derived from the state by the pure functions below.
import type { AxisElements, Candidate, ServerState, WarpFound } from './api';
import { forwardCoordinate, MAX_ZONES, sourceCoordinate } from './remap';
import {
  AXES,
  type Axis,
  type Mode,
  RECIPE_VERSION,
  type Recipe,
  removesZone,
  snapDest,
  type Zone,
  zoneEdit,
  type ZoneProblem,
  zoneProblem,
} from './recipe';
import {
  gauge,
  type Warp,
  type WarpKind,
  warpBounds,
  warpEdit,
  warpFromEdit,
  warpNoop,
  warpProblem,
  type WarpRecipe,
} from './warp';

export type PlaneName = 'start' | 'end' | 'dest';
export const PLANES: readonly PlaneName[] = ['start', 'end', 'dest'];
export type Units = 'units' | '%';
export type ViewMode = 'colour' | 'parts' | 'slice';
/** Applies whose zones undo can bring back. */
const MAX_UNDONE = 48;

/** A zone as the user set it: world units on the loaded object as it is (every zone's positions
 *  refer to it, as in a recipe), the destination unsnapped. */
export interface ZoneInput {
  axis: Axis;
  mode: Mode;
  start: number;
  end: number;
  dest: number;
}

/** A zone as apply_recipe applies it: its planes carried through the earlier valid zones on its
 *  axis (forwardCoordinate), its change dest - end kept and snapped to whole voxels; lo/hi the
 *  solid's extent the earlier zones leave; problem: why the server would refuse it (null: valid).
 *  The shader maps through these, each in the frame the zones before it leave. */
export interface ResolvedZone extends Zone {
  problem: ZoneProblem | null;
}

export interface AppState {
  /** The server's object (null until loaded): revision, undo/redo availability, bounds... */
  readonly server: ServerState | null;
  readonly zones: readonly ZoneInput[];
  readonly active: number;
  readonly units: Units;
  /** A request (apply, undo, redo, save) is in flight. */
  readonly busy: boolean;
  readonly view: { readonly mode: ViewMode; readonly sliceAxis: Axis; readonly slicePos: number };
  readonly overwrite: boolean;
  readonly status: { readonly message: string; readonly error: boolean };
  /** Zone candidates of the loaded object (GET /api/suggest), best first; null: not fetched. */
  readonly suggestions: readonly Candidate[] | null;
  /** The loaded object's elements along x, y, z (GET /api/elements); null: not fetched. */
  readonly elements: readonly AxisElements[] | null;
  /** The zones are the page's first one, untouched: the best suggestion replaces it when the
   *  suggestions come. */
  readonly initialZone: boolean;
  /** Snap the planes while dragging (POST /api/snap), as `partscale scale --snap`. */
  readonly snap: boolean;
  /** The fit panel: one size per axis ('=', '2.1', '210cm', '+20cm', '120%'), why fit (or a
   *  count edit) chose the zones it previews (empty: none previewed), whether a size only a
   *  deformation reaches is taken (thin slabs, global scaling) rather than refused, and why the
   *  last fit was refused ('' when it was not). */
  readonly fit: {
    readonly size: readonly [string, string, string];
    readonly why: readonly string[];
    readonly allowDeform: boolean;
    readonly refused: string;
  };
  /** The zones of each apply, last last: undo brings them back (and redo those it undid). */
  readonly appliedZones: readonly (readonly ZoneInput[])[];
  readonly redoZones: readonly (readonly ZoneInput[])[];
  /** The loaded object's warp zones (radial plan, flights, spiral stairs: GET /api/suggest);
   *  null: not fetched. */
  readonly warps: WarpFound | null;
  /** The shaped zone (radial, oblique, steps) previewed and applied instead of the planar
   *  zones; null: the planar zones. Positions on the loaded object, world units. */
  readonly warp: Warp | null;
  /** The shaped zone of each apply (null where the planar zones made it), as appliedZones. */
  readonly appliedWarps: readonly (Warp | null)[];
  readonly redoWarps: readonly (Warp | null)[];
}

export type Action =
  // a new object. 'first': one default zone; 'applied': the zones stay, their destinations at
  // their ends (the object already has the change); 'undone': the zones of the undone apply
  | { type: 'loaded'; server: ServerState; how?: 'first' | 'applied' | 'undone' | 'redone' }
  | { type: 'suggested'; suggestions: readonly Candidate[]; warps?: WarpFound }
  // the shaped zone: set (null: back to the planar zones), a kind's default, or changed
  | { type: 'set-warp'; warp: Warp | null; why?: readonly string[] }
  | { type: 'set-warp-kind'; kind: WarpKind | null }
  | { type: 'patch-warp'; patch: Partial<Record<string, unknown>> }
  | { type: 'found-elements'; elements: readonly AxisElements[] }
  | { type: 'use-candidate'; candidate: Candidate } // the active zone takes its axis, zone and mode
  | { type: 'set-zones'; zones: readonly ZoneInput[]; why?: readonly string[] } // e.g. a fit
  | { type: 'set-snap'; snap: boolean }
  | { type: 'set-fit-size'; axis: number; value: string }
  | { type: 'set-allow-deform'; allowDeform: boolean }
  | { type: 'fit-refused'; message: string }
  | { type: 'saved'; server: ServerState }
  // the server's history moved but the page still shows the object it had (its load failed)
  | { type: 'history'; can_undo: boolean; can_redo: boolean }
  | { type: 'select-zone'; index: number }
  | { type: 'add-zone' }
  | { type: 'remove-zone' }
  | { type: 'set-zone'; patch: Partial<ZoneInput> }
  | { type: 'set-axis'; axis: Axis } // the default zone on that axis, keeping the mode
  | { type: 'reset-zone' }
  | { type: 'set-units'; units: Units }
  | { type: 'set-view'; view: Partial<AppState['view']> }
  | { type: 'set-overwrite'; overwrite: boolean }
  | { type: 'set-busy'; busy: boolean }
  | { type: 'set-status'; message: string; error?: boolean };

export const initialState: AppState = {
  server: null,
  zones: [],
  active: 0,
  units: 'units',
  busy: false,
  view: { mode: 'colour', sliceAxis: 'x', slicePos: 50 },
  overwrite: false,
  status: { message: '', error: false },
  suggestions: null,
  elements: null,
  initialZone: false,
  snap: false,
  fit: { size: ['=', '=', '='], why: [], allowDeform: false, refused: '' },
  appliedZones: [],
  redoZones: [],
  warps: null,
  warp: null,
  appliedWarps: [],
  redoWarps: [],
};

// -- derived ----------------------------------------------------------------------------------

export function voxel(s: AppState): number {
  return s.server ? s.server.voxel_size : 1e-3;
}

export function solidBounds(s: AppState): [number[], number[]] {
  if (!s.server) return [[0, 0, 0], [1, 1, 1]];
  return s.server.solid_bounds ?? s.server.grid_bounds;
}

/** The fallback zone: 35 % to 65 % of the solid's extent [lo, hi], destination at its end. */
function zoneAt(axis: Axis, mode: Mode, lo: number, hi: number): ZoneInput {
  const len = hi - lo;
  return { axis, mode, start: lo + 0.35 * len, end: lo + 0.65 * len, dest: lo + 0.65 * len };
}

/** A candidate as a zone with no change yet: its axis, planes and kind, destination at its end. */
function candidateZone(c: Candidate): ZoneInput {
  return { axis: c.axis, mode: c.kind, start: c.zone[0], end: c.zone[1], dest: c.zone[1] };
}

/** The zone a new, reset or re-axed zone starts as: the best suggestion along the axis (its
 *  kind, destination at its end), or, where there is none (or none yet), 35 % to 65 % of the
 *  solid's extent in the given mode. */
export function defaultZone(s: AppState, axis: Axis = 'x', mode: Mode = 'stretch'): ZoneInput {
  const best = s.suggestions?.find((c) => c.axis === axis);
  if (best) return candidateZone(best);
  const [smin, smax] = solidBounds(s);
  const a = AXES.indexOf(axis);
  return zoneAt(axis, mode, smin[a], smax[a]);
}

/** The page's first zone once the suggestions are in: the top-ranked one on its axis, else the
 *  fallback along x. */
export function startZone(s: AppState): ZoneInput {
  const best = s.suggestions?.[0];
  return best ? candidateZone(best) : defaultZone(s, 'x');
}

/** The loaded solid's size along x, y, z (object units). */
export function extents(s: AppState): [number, number, number] {
  const [lo, hi] = solidBounds(s);
  return [0, 1, 2].map((a) => hi[a] - lo[a]) as [number, number, number];
}

/** The solid's size along x, y, z once the valid zones apply (what a preview shows, in whole
 *  voxels as the server makes it); null where nothing would change. */
export function targetExtents(s: AppState): [number, number, number] | null {
  if (!s.server || isNoop(s)) return null;
  if (s.warp) return warpExtents(s, s.warp);
  const [smin, smax] = solidBounds(s);
  const lo = [...smin];
  const hi = [...smax];
  for (const z of validZones(s)) {
    const a = AXES.indexOf(z.axis);
    lo[a] = forwardCoordinate(lo[a], z);
    hi[a] = forwardCoordinate(hi[a], z);
  }
  return [0, 1, 2].map((a) => hi[a] - lo[a]) as [number, number, number];
}

/** The zones resolved once per change of the zones or of the object: every derived value the
 *  page reads (the scene, the panel, a drag's clamps, the recipe) asks for them, many times per
 *  pointer move. Keyed by the state's zones array (states are immutable: a new array is a
 *  change), checked against the object they were resolved on. */
interface DerivedZones {
  readonly server: ServerState | null;
  readonly resolved: readonly ResolvedZone[];
  readonly valid: readonly ResolvedZone[];
}
const derivedZones = new WeakMap<readonly ZoneInput[], DerivedZones>();
let resolutions = 0;

/** How many times the zones were resolved so far (scripts read it: once per change). */
export function zoneResolutions(): number {
  return resolutions;
}

function derived(s: AppState): DerivedZones {
  const hit = derivedZones.get(s.zones);
  if (hit && hit.server === s.server) return hit;
  resolutions += 1;
  const resolved = Object.freeze(resolveZones(s));
  const d = { server: s.server, resolved, valid: Object.freeze(resolved.filter((z) => z.problem === null)) };
  derivedZones.set(s.zones, d);
  return d;
}

/** The zones as apply_recipe applies them (see ResolvedZone), in order (the same array for the
 *  same zones and object: read only). */
export function resolvedZones(s: AppState): readonly ResolvedZone[] {
  return derived(s).resolved;
}

/** The valid ones of resolvedZones (read only, as it). */
export function validZones(s: AppState): readonly ResolvedZone[] {
  return derived(s).valid;
}

function resolveZones(s: AppState): ResolvedZone[] {
  const [smin, smax] = solidBounds(s);
  const lo = [...smin];
  const hi = [...smax];
  const h = voxel(s);
  const applied: ResolvedZone[] = [];
  return s.zones.map((z) => {
    const a = AXES.indexOf(z.axis);
    const earlier = applied.filter((e) => e.axis === z.axis);
    const start = carry(z.start, earlier);
    const end = carry(z.end, earlier);
    // a destination at the start stays there (tile: the zone removed), as apply_recipe carries it
    const dest = z.dest === z.start ? start : end + (z.dest - z.end);
    const given: Zone = { ...z, start, end, dest, lo: lo[a], hi: hi[a] };
    const problem = zoneProblem(given, h);
    // preview what the server will make: the end moves by whole voxels (a removed zone's start
    // with it)
    const snapped = snapDest(given, h);
    const zone: ResolvedZone = removesZone(given)
      ? { ...given, start: snapped, dest: snapped, problem }
      : { ...given, dest: snapped, problem };
    if (problem === null) {
      lo[a] = forwardCoordinate(lo[a], zone);
      hi[a] = forwardCoordinate(hi[a], zone);
      applied.push(zone);
    }
    return zone;
  });
}

/** A position on the loaded object -> where it lies after the zones (same axis), in order. */
function carry(v: number, zones: readonly Zone[]): number {
  for (const z of zones) v = forwardCoordinate(v, z);
  return v;
}

/** The inverse of carry: the zones' source maps, last first. */
function uncarry(v: number, zones: readonly Zone[]): number {
  for (let i = zones.length - 1; i >= 0; i--) v = sourceCoordinate(v, zones[i]);
  return v;
}

/** The solid's size once the shaped zone applies: a radial zone moves the outline by to - r1
 *  along its radius (a polygon's by its support across the axis); the others move a box. */
function warpExtents(s: AppState, w: Warp): [number, number, number] {
  const [lo, hi] = solidBounds(s);
  if (w.kind === 'radial') {
    const axis = AXES.indexOf(w.axis);
    const out = [0, 1, 2].map((a) => hi[a] - lo[a]) as [number, number, number];
    const uv = [0, 1, 2].filter((a) => a !== axis);
    uv.forEach((a, i) => {
      // the polygon's half-width along this axis per unit of gauge radius
      const e = i === 0 ? [1, 0] : [0, 1];
      const support = w.sides ? 1 / gauge(e, w.sides, w.phase) : 1;
      out[a] += 2 * (w.to - w.r1) * support;
    });
    return out;
  }
  const [a, b] = warpBounds(w, [...lo], [...hi], voxel(s));
  return [0, 1, 2].map((i) => b[i] - a[i]) as [number, number, number];
}

/** The shaped zone's problem (null: valid), or null where there is none. */
export function warpIssue(s: AppState): string | null {
  return s.warp ? warpProblem(s.warp) : null;
}

/** The output grid's box [min, max] after the valid zones (or the shaped zone). */
export function outputBounds(s: AppState): [number[], number[]] {
  const [gmin, gmax] = s.server ? s.server.grid_bounds : [[0, 0, 0], [1, 1, 1]];
  if (s.warp) return warpIssue(s) === null ? warpBounds(s.warp, [...gmin], [...gmax], voxel(s)) : [[...gmin], [...gmax]];
  const lo = [...gmin];
  const hi = [...gmax];
  for (const z of validZones(s)) {
    const a = AXES.indexOf(z.axis);
    lo[a] = forwardCoordinate(lo[a], z);
    hi[a] = forwardCoordinate(hi[a], z);
  }
  return [lo, hi];
}

/** The recipe (partscale.edit.JSON_SCHEMA) of the valid zones, with the destinations as given. */
export function recipe(s: AppState): Recipe | WarpRecipe {
  if (s.warp) return { version: RECIPE_VERSION, edits: warpIssue(s) === null ? [warpEdit(s.warp)] : [] };
  const edits = resolvedZones(s).flatMap((z, i) => (z.problem === null ? [zoneEdit(s.zones[i])] : []));
  return { version: RECIPE_VERSION, edits };
}

/** dest == end leaves the object as it is in every mode: nothing to send. */
export function isNoop(s: AppState): boolean {
  if (s.warp) return warpNoop(s.warp);
  return resolvedZones(s).every((z) => z.dest === z.end);
}

export function firstProblem(s: AppState): ZoneProblem | null {
  const issue = warpIssue(s);
  if (issue !== null) return { rule: 'warp', message: issue };
  if (s.warp) return null;
  return resolvedZones(s).find((z) => z.problem !== null)?.problem ?? null;
}

export function canApply(s: AppState): boolean {
  return !s.busy && !!s.server && firstProblem(s) === null && !isNoop(s);
}

/** The valid zones before (or after) the active one on its axis. */
function onAxis(s: AppState, which: 'before' | 'after'): ResolvedZone[] {
  const axis = s.zones[s.active]?.axis;
  const rz = resolvedZones(s);
  const part = which === 'before' ? rz.slice(0, s.active) : rz.slice(s.active + 1);
  return part.filter((z) => z.axis === axis && z.problem === null);
}

/** Where the active zone's plane is drawn: as applied (ResolvedZone), then through the later
 *  zones on its axis. */
export function previewPlane(s: AppState, name: PlaneName): number {
  const z = resolvedZones(s)[s.active];
  return carry(z[name], onAxis(s, 'after'));
}

/** A preview coordinate -> the active zone's frame as it applies (back through the later zones
 *  on its axis, last first). */
export function appliedFromPreview(s: AppState, v: number): number {
  return uncarry(v, onAxis(s, 'after'));
}

/** A preview coordinate -> the active zone's value of that plane on the loaded object. */
export function fromPreview(s: AppState, name: PlaneName, v: number): number {
  return fromApplied(s, name, appliedFromPreview(s, v));
}

/** A plane of the active zone as it applies -> its value on the loaded object (ZoneInput): back
 *  through the earlier zones on its axis; the destination keeps its change dest - end. */
export function fromApplied(s: AppState, name: PlaneName, v: number): number {
  if (name !== 'dest') return uncarry(v, onAxis(s, 'before'));
  return s.zones[s.active].end + (v - resolvedZones(s)[s.active].end);
}

/** The shaped zone of a kind the page starts with: the object's own (its radial plan's longest
 *  annulus, unchanged; its flight's or spiral's step, one more), else one drawn on its solid. */
export function defaultWarp(s: AppState, kind: WarpKind): Warp {
  const found = s.warps;
  const fromFound =
    kind === 'radial' && found?.radial?.edit
      ? warpFromEdit(found.radial.edit)
      : kind === 'screw' && found?.steps.length
        ? warpFromEdit(found.steps[0].edit, found.steps[0].ground)
        : kind === 'helix' && found?.helix.length
          ? warpFromEdit(found.helix[0].edit)
          : kind === 'rotation' && found?.rotation.length
            ? warpFromEdit(found.rotation[0].edit)
            : null;
  if (fromFound) return fromFound;
  const [lo, hi] = solidBounds(s);
  const ext = [0, 1, 2].map((a) => hi[a] - lo[a]);
  const mid = [0, 1, 2].map((a) => (lo[a] + hi[a]) / 2);
  const r = Math.min(ext[0], ext[2]) / 2;
  switch (kind) {
    case 'radial':
      return { kind, axis: 'y', center: [mid[0], mid[2]], sides: 0, phase: 0, span: null, r0: 0.3 * r, r1: 0.7 * r, to: 0.7 * r };
    case 'oblique':
      return { kind, normal: [1, 0, 0], s0: lo[0] + 0.35 * ext[0], s1: lo[0] + 0.65 * ext[0], to: lo[0] + 0.65 * ext[0] };
    case 'screw':
      return { kind, axis: 'x', step: [0.1 * ext[0], 0.1 * ext[1], 0], cut: mid[0], copies: 1, ground: null };
    case 'helix':
      return { kind, center: [mid[0], mid[2]], angle: 30, rise: 0.1 * ext[1], cut: mid[1], copies: 1 };
    case 'rotation':
      return { kind, center: [mid[0], mid[2]], angle: 90, phase: 0, count: 4, closed: true, hub: 0.2 * r, radius: r, span: [lo[1], hi[1]], copies: 1 };
  }
}

// -- transitions ------------------------------------------------------------------------------

function patchActive(s: AppState, patch: Partial<ZoneInput>): AppState {
  const zones = s.zones.map((z, i) => (i === s.active ? { ...z, ...patch } : z));
  return { ...s, zones };
}

export function reduce(s: AppState, action: Action): AppState {
  const next = transition(s, action);
  // a zone changed by anything but a load is no longer the page's untouched first one
  return next.initialZone && next.zones !== s.zones && action.type !== 'loaded'
    ? { ...next, initialZone: false }
    : next;
}

function transition(s: AppState, action: Action): AppState {
  switch (action.type) {
    case 'loaded': {
      const next: AppState = {
        ...s,
        server: action.server,
        suggestions: null,
        elements: null,
        warps: null,
        fit: { ...s.fit, why: [], refused: '' },
      };
      const how = s.zones.length ? action.how ?? 'applied' : 'first';
      if (how === 'first') {
        // the fallback until the suggestions come (the 'suggested' action)
        const zones = [defaultZone(next, s.zones[0]?.axis ?? 'x')];
        return { ...next, zones, active: 0, appliedZones: [], redoZones: [], initialZone: true, warp: null, appliedWarps: [], redoWarps: [] };
      }
      const last = <T>(xs: readonly T[]) => xs[xs.length - 1];
      if (how === 'undone') {
        // the zones that made the undone edit, ready to change and apply again
        const zones = last(s.appliedZones);
        if (!zones) return next;
        const redoZones = [...s.redoZones, zones];
        // the shaped zone that made it, if one did
        const warp = last(s.appliedWarps) ?? null;
        const warps = { warp, appliedWarps: s.appliedWarps.slice(0, -1), redoWarps: [...s.redoWarps, warp] };
        return { ...next, zones, active: Math.min(s.active, zones.length - 1), appliedZones: s.appliedZones.slice(0, -1), redoZones, ...warps };
      }
      // the object has the change now: the zones stay where they are, with nothing left to do
      const made = how === 'applied' ? s.zones : last(s.redoZones);
      const zones = (made ?? s.zones).map((z) => ({ ...z, dest: z.end }));
      const appliedZones = made ? [...s.appliedZones, made].slice(-MAX_UNDONE) : s.appliedZones;
      const redoZones = how === 'applied' ? [] : s.redoZones.slice(0, -1);
      // a shaped zone's positions no longer hold on the object it made: it is put away
      const madeWarp = how === 'applied' ? s.warp : last(s.redoWarps) ?? null;
      const appliedWarps = made ? [...s.appliedWarps, madeWarp].slice(-MAX_UNDONE) : s.appliedWarps;
      const redoWarps = how === 'applied' ? [] : s.redoWarps.slice(0, -1);
      const warps = { warp: null, appliedWarps, redoWarps };
      return { ...next, zones, active: Math.min(s.active, zones.length - 1), appliedZones, redoZones, ...warps };
    }
    case 'set-warp':
      return { ...s, warp: action.warp, fit: { ...s.fit, why: action.why ?? [], refused: '' } };
    case 'set-warp-kind':
      return { ...s, warp: action.kind === null ? null : defaultWarp(s, action.kind) };
    case 'patch-warp':
      return s.warp ? { ...s, warp: { ...s.warp, ...action.patch } as Warp } : s;
    case 'suggested': {
      const next = { ...s, suggestions: action.suggestions, warps: action.warps ?? s.warps };
      return s.initialZone ? { ...next, zones: [startZone(next)], active: 0, initialZone: false } : next;
    }
    case 'found-elements':
      return { ...s, elements: action.elements };
    case 'use-candidate': {
      const c = action.candidate;
      const z = s.zones[s.active];
      if (!z) return s;
      const [start, end] = c.zone;
      // keep the change the zone asked for; a tile with none yet gets one more copy
      const change = z.dest - z.end || (c.kind === 'tile' ? end - start : 0);
      return patchActive(s, { axis: c.axis, mode: c.kind, start, end, dest: end + change });
    }
    case 'set-zones':
      if (!action.zones.length || action.zones.length > MAX_ZONES) return s;
      return { ...s, zones: action.zones, active: 0, warp: null, fit: { ...s.fit, why: action.why ?? [], refused: '' } };
    case 'set-snap':
      return { ...s, snap: action.snap };
    case 'set-fit-size': {
      const size = [...s.fit.size] as [string, string, string];
      size[action.axis] = action.value;
      return { ...s, fit: { ...s.fit, size, refused: '' } };
    }
    case 'set-allow-deform':
      return { ...s, fit: { ...s.fit, allowDeform: action.allowDeform, refused: '' } };
    case 'fit-refused':
      return { ...s, fit: { ...s.fit, refused: action.message } };
    case 'saved':
      return { ...s, server: s.server ? { ...s.server, ...action.server } : action.server };
    case 'history':
      return s.server
        ? { ...s, server: { ...s.server, can_undo: action.can_undo, can_redo: action.can_redo, unsaved: true } }
        : s;
    case 'select-zone':
      return action.index >= 0 && action.index < s.zones.length ? { ...s, active: action.index } : s;
    case 'add-zone': {
      if (s.zones.length >= MAX_ZONES) return s;
      // positions refer to the loaded object, so the new zone's default is on it too
      const axis = s.zones[s.active]?.axis ?? 'x';
      return { ...s, zones: [...s.zones, defaultZone(s, axis)], active: s.zones.length };
    }
    case 'remove-zone':
      if (s.zones.length <= 1) return s;
      return { ...s, zones: s.zones.filter((_, i) => i !== s.active), active: Math.max(0, s.active - 1) };
    case 'set-zone':
      return s.zones[s.active] ? patchActive(s, action.patch) : s;
    case 'set-axis': {
      const z = s.zones[s.active];
      return z ? patchActive(s, defaultZone(s, action.axis, z.mode)) : s;
    }
    case 'reset-zone': {
      const z = s.zones[s.active];
      return z ? patchActive(s, defaultZone(s, z.axis)) : s;
    }
    case 'set-units':
      return { ...s, units: action.units };
    case 'set-view':
      return { ...s, view: { ...s.view, ...action.view } };
    case 'set-overwrite':
      return { ...s, overwrite: action.overwrite };
    case 'set-busy':
      return { ...s, busy: action.busy };
    case 'set-status':
      return { ...s, status: { message: action.message, error: action.error ?? false } };
  }
}

export type Listener = (state: AppState, previous: AppState, action: Action) => void;

export interface Store {
  get(): AppState;
  dispatch(action: Action): void;
  /** Called after every transition that changed the state; returns an unsubscribe. */
  subscribe(listener: Listener): () => void;
}

export function createStore(initial: AppState = initialState): Store {
  let state = initial;
  const listeners = new Set<Listener>();
  return {
    get: () => state,
    dispatch(action) {
      const previous = state;
      state = reduce(state, action);
      if (state === previous) return;
      for (const l of listeners) l(state, previous, action);
    },
    subscribe(listener) {
      listeners.add(listener);
      return () => listeners.delete(listener);
    },
  };
}
