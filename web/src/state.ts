// The editor's one state object and its transitions. Handlers dispatch named actions; the scene
// and the panel subscribe and draw what the state says. Everything else the page shows (resolved
// zones, the recipe, the output box) is derived from the state by the pure functions below.
import type { ServerState } from './api';
import { forwardCoordinate, MAX_ZONES, sourceCoordinate } from './remap';
import {
  AXES,
  type Axis,
  type Mode,
  RECIPE_VERSION,
  type Recipe,
  snapDest,
  type Zone,
  zoneEdit,
  type ZoneProblem,
  zoneProblem,
} from './recipe';

export type PlaneName = 'start' | 'end' | 'dest';
export const PLANES: readonly PlaneName[] = ['start', 'end', 'dest'];
export type Units = 'units' | '%';
export type ViewMode = 'colour' | 'parts' | 'slice';

/** A zone as the user set it (world units; the destination unsnapped). */
export interface ZoneInput {
  axis: Axis;
  mode: Mode;
  start: number;
  end: number;
  dest: number;
}

/** A zone resolved on the solid as the earlier zones leave it: dest snapped to whole voxels as
 *  the server will apply it; problem: why the server would refuse it (null: valid). */
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
}

export type Action =
  | { type: 'loaded'; server: ServerState } // a new object: one default zone on the same axis
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
};

// -- derived ----------------------------------------------------------------------------------

export function voxel(s: AppState): number {
  return s.server ? s.server.voxel_size : 1e-3;
}

export function solidBounds(s: AppState): [number[], number[]] {
  if (!s.server) return [[0, 0, 0], [1, 1, 1]];
  return s.server.solid_bounds ?? s.server.grid_bounds;
}

/** The default zone: 35 % to 65 % of the solid's extent [lo, hi], destination at its end. */
function zoneAt(axis: Axis, mode: Mode, lo: number, hi: number): ZoneInput {
  const len = hi - lo;
  return { axis, mode, start: lo + 0.35 * len, end: lo + 0.65 * len, dest: lo + 0.65 * len };
}

export function defaultZone(s: AppState, axis: Axis = 'x', mode: Mode = 'stretch'): ZoneInput {
  const [smin, smax] = solidBounds(s);
  const a = AXES.indexOf(axis);
  return zoneAt(axis, mode, smin[a], smax[a]);
}

/** The zones in world units with lo/hi: the solid's extent before each one (forward-mapped
 *  through the earlier valid zones). */
export function resolvedZones(s: AppState): ResolvedZone[] {
  const [smin, smax] = solidBounds(s);
  const lo = [...smin];
  const hi = [...smax];
  const h = voxel(s);
  return s.zones.map((z) => {
    const a = AXES.indexOf(z.axis);
    const given: Zone = { ...z, lo: lo[a], hi: hi[a] };
    const problem = zoneProblem(given, h);
    // preview what the server will make: the end moves by whole voxels
    const zone: ResolvedZone = { ...given, dest: snapDest(given, h), problem };
    if (problem === null) {
      lo[a] = forwardCoordinate(lo[a], zone);
      hi[a] = forwardCoordinate(hi[a], zone);
    }
    return zone;
  });
}

export function validZones(s: AppState): ResolvedZone[] {
  return resolvedZones(s).filter((z) => z.problem === null);
}

/** The output grid's box [min, max] after the valid zones. */
export function outputBounds(s: AppState): [number[], number[]] {
  const [gmin, gmax] = s.server ? s.server.grid_bounds : [[0, 0, 0], [1, 1, 1]];
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
export function recipe(s: AppState): Recipe {
  const edits = resolvedZones(s).flatMap((z, i) => (z.problem === null ? [zoneEdit(s.zones[i])] : []));
  return { version: RECIPE_VERSION, edits };
}

/** dest == end leaves the object as it is in every mode: nothing to send. */
export function isNoop(s: AppState): boolean {
  return resolvedZones(s).every((z) => z.dest === z.end);
}

export function firstProblem(s: AppState): ZoneProblem | null {
  return resolvedZones(s).find((z) => z.problem !== null)?.problem ?? null;
}

export function canApply(s: AppState): boolean {
  return !s.busy && !!s.server && firstProblem(s) === null && !isNoop(s);
}

/** The valid zones after the active one on its axis: they move its planes in the preview. */
function laterOnAxis(s: AppState): ResolvedZone[] {
  const axis = s.zones[s.active]?.axis;
  return resolvedZones(s)
    .slice(s.active + 1)
    .filter((z) => z.axis === axis && z.problem === null);
}

/** Active zone's coordinate -> where the preview shows it (through the later zones). */
export function toPreview(s: AppState, v: number): number {
  for (const z of laterOnAxis(s)) v = forwardCoordinate(v, z);
  return v;
}

/** Preview coordinate -> the active zone's coordinate (the later zones' maps, last first). */
export function fromPreview(s: AppState, v: number): number {
  const later = laterOnAxis(s);
  for (let i = later.length - 1; i >= 0; i--) v = sourceCoordinate(v, later[i]);
  return v;
}

// -- transitions ------------------------------------------------------------------------------

function patchActive(s: AppState, patch: Partial<ZoneInput>): AppState {
  const zones = s.zones.map((z, i) => (i === s.active ? { ...z, ...patch } : z));
  return { ...s, zones };
}

export function reduce(s: AppState, action: Action): AppState {
  switch (action.type) {
    case 'loaded': {
      const next: AppState = { ...s, server: action.server };
      return { ...next, zones: [defaultZone(next, s.zones[0]?.axis ?? 'x')], active: 0 };
    }
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
      const axis = s.zones[s.active]?.axis ?? 'x';
      const added: AppState = { ...s, zones: [...s.zones, defaultZone(s, axis)], active: s.zones.length };
      // the new zone's default sits on the solid as it is after the earlier zones
      const z = resolvedZones(added)[added.active];
      return patchActive(added, zoneAt(axis, 'stretch', z.lo, z.hi));
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
