// What the editor asks of the server (api.ts), as transitions of the store: busy while a request
// is in flight, the status line, the new object loaded into the scene.
import * as api from './api';
import { ApiError } from './api';
import { type Parts, partsFrom, type Volume, volumeFrom } from './grid';
import type { Scene } from './scene';
import { type Axis, zoneEdit } from './recipe';
import { MAX_ZONES } from './remap';
import { recipe, type Store, type ZoneInput } from './state';
import { warpFromEdit } from './warp';

export interface Commands {
  /** Fetch the object (state, grid, parts) and show it (see the 'loaded' action); its zone
   *  suggestions and its elements follow (the 'suggested' and 'found-elements' actions) without
   *  being waited for. */
  load(how?: 'first' | 'applied' | 'undone' | 'redone'): Promise<void>;
  /** Ask the server for the fit panel's sizes and preview the recipe as the zones; whether it
   *  could. */
  previewFit(): Promise<boolean>;
  /** Ask the server for the recipe adding n whole elements along the axis (n < 0: removing
   *  them) and preview it as the zones (Apply makes it); whether it could. */
  previewCount(axis: Axis, n: number): Promise<boolean>;
  /** The active zone snapped for its mode by the server (null when that fails, said in the
   *  status); its planes are set unless the zone changed meanwhile. */
  snapActive(): Promise<ZoneInput | null>;
  apply(): Promise<void>;
  undo(): Promise<void>;
  redo(): Promise<void>;
  save(): Promise<void>;
  fit(): void;
}

export function createCommands(store: Store, scene: Scene): Commands {
  const status = (message: string, error = false) => store.dispatch({ type: 'set-status', message, error });
  // the arrays shown: the base the server sends later objects against (only what changed)
  const held: { volume: Volume | null; parts: Parts | null } = { volume: null, parts: null };

  async function load(how: 'first' | 'applied' | 'undone' | 'redone' = 'first') {
    status('loading grid…');
    const s = await api.getState();
    if (s.encoding?.version !== api.GRID_FORMAT) {
      throw new ApiError(`grid: expected format ${api.GRID_FORMAT}, got ${s.encoding?.version} (reload the page)`);
    }
    const [X, Y, Z] = s.shape;
    const limit = scene.maxTextureSize;
    if (Math.max(X, Y, Z) > limit) {
      throw new ApiError(`grid: expected at most ${limit} voxels per axis on this GPU, got ${s.shape.join('×')}`);
    }
    const volume = volumeFrom(await api.getGrid(held.volume?.revision ?? null), held.volume);
    if (volume.shape.join() !== s.shape.join()) {
      throw new ApiError(`grid: expected ${s.shape.join('×')} voxels, got ${volume.shape.join('×')}`);
    }
    const parts = s.n_parts > 0 ? partsFrom(await api.getParts(held.parts?.revision ?? null), held.parts) : null;
    if (parts && parts.shape.join() !== s.shape.join()) {
      throw new ApiError(`parts: expected ${s.shape.join('×')} voxels, got ${parts.shape.join('×')}`);
    }
    scene.setObject(s, volume, parts?.parts ?? null);
    held.volume = volume;
    if (parts) held.parts = parts;
    store.dispatch({ type: 'loaded', server: s, how });
    status(`${s.name}: ${s.history.length} operation(s) in history`);
    // not awaited: the object is shown and usable now; its zone candidates (seconds at 256³)
    // and elements fill the panel when they come
    void suggestFor(s);
    void elementsFor(s);
  }

  /** Whether s is still the object shown (another may have been loaded meanwhile). */
  const shown = (s: api.ServerState) => store.get().server === s || store.get().server?.revision === s.revision;

  async function suggestFor(s: api.ServerState) {
    let found: api.Candidate[] = [];
    let warps: api.WarpFound = { radial: null, steps: [], helix: [], rotation: [] };
    try {
      ({ candidates: found, warps } = await api.suggestAll());
    } catch (e) {
      status(`suggestions failed: ${e instanceof Error ? e.message : String(e)}`, true);
    }
    // drop them if another object was loaded meanwhile
    if (shown(s)) store.dispatch({ type: 'suggested', suggestions: found, warps });
  }

  async function elementsFor(s: api.ServerState) {
    let found: api.AxisElements[] = [];
    try {
      found = await api.elements();
    } catch (e) {
      status(`finding elements failed: ${e instanceof Error ? e.message : String(e)}`, true);
    }
    if (shown(s)) store.dispatch({ type: 'found-elements', elements: found });
  }

  /** Run fn as the one request in flight (none starts while busy); failures go to the status. */
  async function run(label: string, fn: () => Promise<void>) {
    if (store.get().busy) return;
    store.dispatch({ type: 'set-busy', busy: true });
    status(`${label}…`);
    try {
      await fn();
    } catch (e) {
      status(`${label} failed: ${e instanceof Error ? e.message : String(e)}`, true);
    } finally {
      store.dispatch({ type: 'set-busy', busy: false });
    }
  }

  const apply = () =>
    run('applying', async () => {
      const t0 = performance.now();
      const poll = setInterval(async () => {
        try {
          const p = await api.getProgress();
          if (p.busy) status(`applying… ${Math.round(100 * p.fraction)}% ${p.message}`);
        } catch {
          /* the apply's own result reports errors */
        }
      }, 250);
      let s: api.ServerState;
      try {
        // the server refuses, before computing, a result this page could not show
        s = await api.apply(recipe(store.get()), { max_voxels_per_axis: scene.maxTextureSize });
      } finally {
        clearInterval(poll);
      }
      await loadAfter(s, 'applied');
      const took = `applied in ${(performance.now() - t0).toFixed(0)} ms (server ${s.apply_ms?.toFixed(0)} ms)`;
      // say what the tool changed from what was asked, as the CLI does on stderr
      status([took, ...(s.notes ?? [])].join('; '));
    });

  /** Show the object a history step made; if that fails, Undo and Redo still follow the server
   * (Save names the revision shown, so the server refuses to save what the page could not show). */
  async function loadAfter(s: api.ServerState, how: 'applied' | 'undone' | 'redone') {
    try {
      await load(how);
    } catch (e) {
      store.dispatch({ type: 'history', can_undo: s.can_undo, can_redo: s.can_redo });
      const why = e instanceof Error ? e.message : String(e);
      throw new ApiError(`${why}; the page still shows the previous object (Undo returns to it)`);
    }
  }

  const undo = () =>
    run('undo', async () => {
      await loadAfter(await api.undo(), 'undone');
      status('undone');
    });

  const redo = () =>
    run('redo', async () => {
      await loadAfter(await api.redo(), 'redone');
      status('redone');
    });

  const save = () =>
    run('saving', async () => {
      const shown = store.get().server;
      if (!shown) throw new ApiError('save: expected an object shown, got none');
      const s = await api.save(store.get().overwrite, shown.revision);
      store.dispatch({ type: 'saved', server: s });
      status(`saved ${s.saved}`);
    });

  const fit = () => {
    scene.fitCamera();
    scene.requestRender();
  };

  /** Preview a recipe the server chose (fit, count edit) as the zones, or as the shaped zone
   *  where it is one alone; how many zones it previews. */
  function previewRecipe(what: string, fitted: api.Fitted): number {
    // a radial zone, a stair's steps or a ring's elements ({"radial": ...}, {"screw": ...},
    // {"helix": ...}, {"rotation": ...}) is no slab across an axis: the shader previews one such zone alone, or slabs
    const other = fitted.recipe.edits.find((e) => !('axis' in e && 'mode' in e));
    const alone = other && fitted.recipe.edits.length === 1 ? warpFromEdit(other, groundOf(other)) : null;
    if (alone) {
      store.dispatch({ type: 'set-warp', warp: alone, why: fitted.why });
      return 1;
    }
    if (other) {
      const kind =
        'radial' in other
          ? 'a radial zone'
          : 'screw' in other
            ? "a flight's steps"
            : 'helix' in other
              ? "a spiral stair's steps"
              : 'rotation' in other
                ? "a ring's elements"
                : 'an oblique zone';
      throw new ApiError(
        `${what}: expected zones across x, y or z or one shaped zone alone (what this page previews), got ${kind} among others; ` +
          `run it with partscale on the command line (${fitted.why.join('; ')})`,
      );
    }
    const zones: ZoneInput[] = fitted.recipe.edits.map((e) => ({
      axis: e.axis,
      mode: e.mode,
      start: e.zone[0],
      end: e.zone[1],
      dest: e.to,
    }));
    if (zones.length > MAX_ZONES) {
      throw new ApiError(
        `${what}: expected at most ${MAX_ZONES} zones (what this page previews), got ${zones.length}; ` +
          'run it with partscale on the command line',
      );
    }
    store.dispatch({ type: 'set-zones', zones, why: fitted.why });
    return zones.length;
  }

  /** The floor a flight stands on (the server's step candidate of the same cut), or null. */
  function groundOf(e: Record<string, unknown>): number | null {
    if (!('screw' in e)) return null;
    const cut = (e.screw as { cut: number }).cut;
    return store.get().warps?.steps.find((k) => k.cut === cut)?.ground ?? null;
  }

  const previewFit = async () => {
    let ok = false;
    await run('fitting', async () => {
      const { size, allowDeform } = store.get().fit;
      let fitted: api.Fitted;
      try {
        fitted = await api.fit([...size] as [string, string, string], allowDeform);
      } catch (e) {
        // the fit panel says it too (a refusal names the alternatives: allow deform is one)
        if (e instanceof ApiError) store.dispatch({ type: 'fit-refused', message: e.message });
        throw e;
      }
      const n = previewRecipe('fit', fitted);
      status(`fit: ${n} zone(s) previewed; Apply to make it`);
      ok = true;
    });
    return ok;
  };

  const previewCount = async (axis: Axis, n: number) => {
    let ok = false;
    const what = `${n > 0 ? 'add' : 'remove'} ${Math.abs(n)} element${Math.abs(n) === 1 ? '' : 's'} along ${axis}`;
    await run(what, async () => {
      const fitted = await api.addElements(axis, n);
      previewRecipe(what, fitted);
      // the count edit's own line first (the other axes are only 'kept')
      const note = fitted.why.find((w) => w.startsWith(`${axis}:`)) ?? what;
      status(`${note}; previewed, Apply to make it`);
      ok = true;
    });
    return ok;
  };

  // one snap request at a time: a newer zone waits for the one in flight, then goes alone
  const snapping: { inFlight: boolean; again: boolean } = { inFlight: false, again: false };
  async function snapActive(): Promise<ZoneInput | null> {
    if (snapping.inFlight) {
      snapping.again = true;
      return null;
    }
    snapping.inFlight = true;
    try {
      for (;;) {
        snapping.again = false;
        const s = store.get();
        const z = s.zones[s.active];
        if (!z) return null;
        let got: api.Snapped;
        try {
          got = await api.snap(zoneEdit(z));
        } catch (e) {
          status(`${e instanceof Error ? e.message : String(e)}`, true);
          return null;
        }
        if (snapping.again) continue; // the zone moved meanwhile: snap the newer one
        const now = store.get();
        if (now.zones[now.active] !== z) return null;
        const snapped: ZoneInput = { ...z, start: got.edit.zone[0], end: got.edit.zone[1], dest: got.edit.to };
        store.dispatch({ type: 'set-zone', patch: snapped });
        status(got.message);
        return snapped;
      }
    } finally {
      snapping.inFlight = false;
    }
  }

  return { load, apply, undo, redo, save, fit, previewFit, previewCount, snapActive };
}
