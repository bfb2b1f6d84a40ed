// The server's API (src/partscale/serve/app.py): one object, no paths in requests. Every request
// the page makes goes through here.
import type { Delta, Encoded, Shape } from './grid';
import type { Axis, Edit, Recipe } from './recipe';
import type { WarpEdit, WarpRecipe } from './warp';

export interface PartInfo {
  color?: number[] | string;
  name?: string;
  [k: string]: unknown;
}

export interface ServerState {
  shape: [number, number, number];
  origin: [number, number, number];
  voxel_size: number;
  grid_bounds: [number[], number[]];
  solid_bounds: [number[], number[]] | null;
  units: string;
  n_parts: number;
  parts_info: PartInfo[];
  history: unknown[];
  /** The grid protocol (session.header): version must be GRID_FORMAT. */
  encoding: { version: number };
  revision: number;
  can_undo: boolean;
  can_redo: boolean;
  unsaved: boolean;
  name: string;
  save_as: string;
  apply_ms?: number;
  /** Apply only: what the edit changed from what was asked (whole-voxel lengths, cut slivers). */
  notes?: string[];
  saved?: string;
}

export class ApiError extends Error {}

async function check(r: Response): Promise<Response> {
  if (r.ok) return r;
  let msg = `${r.status} ${r.statusText}`;
  try {
    const body = await r.json();
    if (body && typeof body.error === 'string') msg = body.error;
  } catch {
    /* not JSON: keep the status line */
  }
  throw new ApiError(msg);
}

export async function getState(): Promise<ServerState> {
  return (await check(await fetch('/api/state', { cache: 'no-store' }))).json();
}

/** The grid protocol this page reads (session.GRID_FORMAT on the server). */
export const GRID_FORMAT = 2;

/** GET path: the whole object, or with base (the revision whose object the page holds) maybe only
 * the layers that changed since (X-Partscale-Delta; see grid.ts and app.py). */
async function getEncoded(path: string, base: number | null): Promise<Encoded> {
  const url = base === null ? path : `${path}?base=${base}`;
  const r = await check(await fetch(url, { cache: 'no-store' }));
  const ints = (name: string, n: number): number[] => {
    const v = (r.headers.get(name) ?? '').split(',').map(Number);
    if (v.length !== n || !v.every((x) => Number.isInteger(x) && x >= 0)) {
      throw new ApiError(`${path}: expected ${n} integers in ${name}, got ${r.headers.get(name)}`);
    }
    return v;
  };
  const delta = r.headers.has('X-Partscale-Delta') ? (ints('X-Partscale-Delta', 3) as Delta) : null;
  return {
    shape: ints('X-Partscale-Shape', 3) as Shape,
    revision: ints('X-Partscale-Revision', 1)[0],
    delta,
    body: await r.arrayBuffer(),
  };
}

/** Float16 distances and sRGB bytes (see session.encode_grid), whole or the changed layers. */
export const getGrid = (base: number | null): Promise<Encoded> => getEncoded('/api/grid', base);

/** Int16 part indices, C order, -1 = none; whole or the changed layers. */
export const getParts = (base: number | null): Promise<Encoded> => getEncoded('/api/parts', base);

/** The apply in flight (GET /api/progress). */
export interface Progress {
  busy: boolean;
  fraction: number;
  message: string;
}

export async function getProgress(): Promise<Progress> {
  return (await check(await fetch('/api/progress', { cache: 'no-store' }))).json();
}

/** What this page can show (PageLimits on the server): an apply whose result would not fit is
 * refused before the server computes it, so the server never holds an object the page cannot show. */
export interface PageLimits {
  /** Largest grid along any axis: the GPU's MAX_3D_TEXTURE_SIZE. */
  max_voxels_per_axis: number;
}

/** A zone candidate (partscale.zones.Candidate.to_json). */
export interface Candidate {
  axis: Axis;
  kind: 'tile' | 'stretch';
  zone: [number, number];
  score: number;
  reason: string;
  region: [number, number];
  period?: number;
  count?: number;
}

/** Zone candidates of the current object, best first (all axes, or one). */
export async function suggest(axis?: Axis): Promise<Candidate[]> {
  const url = axis ? `/api/suggest?axis=${axis}` : '/api/suggest';
  return (await check(await fetch(url, { cache: 'no-store' }))).json().then((b) => b.candidates);
}

/** The zones that are no slab across an axis (partscale.zones.WarpCandidates.to_json): each with
 *  its recipe edit (``edit``), as recipes hold it. */
export interface WarpFound {
  /** A round or regular-polygon plan about an axis, its annuli of constant radial section
   *  (longest first) and the radial zone of the first, unchanged. */
  radial: {
    axis: Axis;
    center: [number, number];
    sides: number;
    phase: number;
    radius: number;
    annuli: [number, number][];
    edit?: WarpEdit;
  } | null;
  /** Flights: the step's shift, going, rise, share of the surface that repeats, count, the cut,
   *  the floor it stands on beyond the cut (or null), and the edit adding one step. */
  steps: { axis: Axis; step: [number, number, number]; going: number; rise: number; support: number; count: number; cut: number; ground: number | null; edit: WarpEdit }[];
  /** Spiral stairs: turn (degrees) and rise per step about the vertical through center. */
  helix: { center: [number, number]; angle: number; rise: number; support: number; count: number; cut: number; edit: WarpEdit }[];
  /** Rings or arcs of elements about the vertical through center (a star base's arms): the turn
   *  (degrees) from one to the next, the first one's direction, count, whether they close a ring,
   *  the radii and levels they lie between, each one's half-width (degrees), the edit adding one. */
  rotation: {
    center: [number, number];
    angle: number;
    phase: number;
    count: number;
    closed: boolean;
    support: number;
    hub: number;
    radius: number;
    span: [number, number];
    width: number;
    edit: WarpEdit;
  }[];
}

/** All of the current object's suggestions: the zone candidates and the warp zones. */
export async function suggestAll(): Promise<{ candidates: Candidate[]; warps: WarpFound }> {
  const b = await (await check(await fetch('/api/suggest', { cache: 'no-store' }))).json();
  return { candidates: b.candidates, warps: { radial: b.radial ?? null, steps: b.steps ?? [], helix: b.helix ?? [], rotation: b.rotation ?? [] } };
}

/** What POST /api/snap answers: the edit snapped for its mode (world units) and what moved. */
export interface Snapped {
  edit: { axis: Axis; zone: [number, number]; to: number; mode: Edit['mode'] };
  moves: { plane: 'start' | 'end' | 'to'; from: number; to: number }[];
  message: string;
}

/** What POST /api/fit and /api/add answer: the recipe (not applied) and why. */
export interface Fitted {
  recipe: { version: 1; edits: Snapped['edit'][] };
  why: string[];
}

/** One element along an axis (partscale.zones.Element.to_json): world units along the axis. */
export interface Element {
  start: number;
  end: number;
  length: number;
  /** Index into AxisElements.groups, or null. */
  group: number | null;
  mirrored: boolean;
}

/** Elements that repeat (partscale.zones.Group.to_json): indices into AxisElements.elements. */
export interface ElementGroup {
  members: number[];
  separators: number[];
  count: number;
  err: number;
  mirrored: boolean;
  typical: number;
}

/** The object along one axis as elements and separators (partscale.zones.AxisElements.to_json),
 *  with summary: a few words on its best repeat group ('no repeated element' where none). */
export interface AxisElements {
  axis: Axis;
  elements: Element[];
  separators: { start: number; end: number; kind: string }[];
  /** Best first: the first is the group a count edit (POST /api/add) adds to or removes from. */
  groups: ElementGroup[];
  summary: string;
}

/** The elements of the current object along x, y and z (GET /api/elements). */
export async function elements(): Promise<AxisElements[]> {
  return (await check(await fetch('/api/elements', { cache: 'no-store' }))).json().then((b) => b.axes);
}

/** POST bodies and answers by route. */
export interface PostBodies {
  '/api/apply': (Recipe | WarpRecipe) & { limits: PageLimits };
  '/api/undo': Record<string, never>;
  '/api/redo': Record<string, never>;
  /** revision: the one the page shows; the server refuses to save another. */
  '/api/save': { overwrite: boolean; revision: number };
  '/api/snap': Edit;
  /** allow_deform: where only a deformation reaches the size, take it (else refused, 400). */
  '/api/fit': { size: [string, string, string]; allow_deform: boolean };
  /** n elements more along the axis (n < 0: fewer), as `partscale fit --add AXIS N`. */
  '/api/add': { axis: Axis; n: number };
}

interface PostAnswers {
  '/api/apply': ServerState;
  '/api/undo': ServerState;
  '/api/redo': ServerState;
  '/api/save': ServerState;
  '/api/snap': Snapped;
  '/api/fit': Fitted;
  '/api/add': Fitted;
}

async function post<P extends keyof PostBodies>(path: P, body: PostBodies[P]): Promise<PostAnswers[P]> {
  const r = await fetch(path, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify(body),
  });
  return (await check(r)).json();
}

/** Bake the recipe into the object unless the result exceeds limits; the new state (with apply_ms). */
export const apply = (recipe: Recipe | WarpRecipe, limits: PageLimits): Promise<ServerState> =>
  post('/api/apply', { ...recipe, limits });
export const undo = (): Promise<ServerState> => post('/api/undo', {});
export const redo = (): Promise<ServerState> => post('/api/redo', {});
/** Write the object shown (revision; beside the input, or over it); the new state (with saved). */
export const save = (overwrite: boolean, revision: number): Promise<ServerState> =>
  post('/api/save', { overwrite, revision });
/** The edit moved to the nearest good position for its mode (`partscale scale --snap`). */
export const snap = (edit: Edit): Promise<Snapped> => post('/api/snap', edit);
/** The recipe that resizes the object to size (x, y, z), previewed, not applied; refused (ApiError,
 *  one line naming the alternatives) where only a deformation would reach it, unless allowDeform. */
export const fit = (size: [string, string, string], allowDeform = false): Promise<Fitted> =>
  post('/api/fit', { size, allow_deform: allowDeform });
/** The recipe adding n whole elements along the axis (n < 0: removing them), not applied. */
export const addElements = (axis: Axis, n: number): Promise<Fitted> => post('/api/add', { axis, n });
