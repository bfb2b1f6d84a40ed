// The server's API (src/partscale/serve/app.py): one object, no paths in requests.

export interface PartInfo {
  color?: number[] | string;
  name?: string;
  [k: string]: unknown;
}

export interface State {
  shape: [number, number, number];
  origin: [number, number, number];
  voxel_size: number;
  grid_bounds: [number[], number[]];
  solid_bounds: [number[], number[]] | null;
  units: string;
  n_parts: number;
  parts_info: PartInfo[];
  history: unknown[];
  revision: number;
  can_undo: boolean;
  can_redo: boolean;
  unsaved: boolean;
  name: string;
  save_as: string;
  apply_ms?: number;
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

export async function getState(): Promise<State> {
  return (await check(await fetch('/api/state', { cache: 'no-store' }))).json();
}

/** (X, Y, Z, 4) float16 bits, C order: z fastest (see session.encode_grid). */
export async function getGrid(): Promise<Uint16Array> {
  const r = await check(await fetch('/api/grid', { cache: 'no-store' }));
  return new Uint16Array(await r.arrayBuffer());
}

/** (X, Y, Z) int16 part indices, C order, -1 = none. */
export async function getParts(): Promise<Int16Array> {
  const r = await check(await fetch('/api/parts', { cache: 'no-store' }));
  return new Int16Array(await r.arrayBuffer());
}

export async function post(path: string, body: unknown = {}): Promise<State> {
  const r = await fetch(path, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify(body),
  });
  return (await check(r)).json();
}
