// What the editor asks of the server (api.ts), as transitions of the store: busy while a request
// is in flight, the status line, the new object loaded into the scene.
import * as api from './api';
import { ApiError } from './api';
import type { Scene } from './scene';
import { recipe, type Store } from './state';

export interface Commands {
  /** Fetch the object (state, grid, parts) and show it; one default zone. */
  load(): Promise<void>;
  apply(): Promise<void>;
  undo(): Promise<void>;
  redo(): Promise<void>;
  save(): Promise<void>;
  fit(): void;
}

export function createCommands(store: Store, scene: Scene): Commands {
  const status = (message: string, error = false) => store.dispatch({ type: 'set-status', message, error });

  async function load() {
    status('loading grid…');
    const s = await api.getState();
    const [X, Y, Z] = s.shape;
    const limit = scene.maxTextureSize;
    if (Math.max(X, Y, Z) > limit) {
      throw new ApiError(`grid: expected at most ${limit} voxels per axis on this GPU, got ${s.shape.join('×')}`);
    }
    const grid = await api.getGrid();
    if (grid.length !== X * Y * Z * 4) throw new ApiError(`grid: expected ${X * Y * Z * 4} values, got ${grid.length}`);
    const parts = s.n_parts > 0 ? await api.getParts() : null;
    scene.setObject(s, grid, parts);
    store.dispatch({ type: 'loaded', server: s });
    status(`${s.name}: ${s.history.length} operation(s) in history`);
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
      await loadAfter(s);
      status(`applied in ${(performance.now() - t0).toFixed(0)} ms (server ${s.apply_ms?.toFixed(0)} ms)`);
    });

  /** Show the object a history step made; if that fails, Undo and Redo still follow the server
   * (Save names the revision shown, so the server refuses to save what the page could not show). */
  async function loadAfter(s: api.ServerState) {
    try {
      await load();
    } catch (e) {
      store.dispatch({ type: 'history', can_undo: s.can_undo, can_redo: s.can_redo });
      const why = e instanceof Error ? e.message : String(e);
      throw new ApiError(`${why}; the page still shows the previous object (Undo returns to it)`);
    }
  }

  const undo = () =>
    run('undo', async () => {
      await loadAfter(await api.undo());
      status('undone');
    });

  const redo = () =>
    run('redo', async () => {
      await loadAfter(await api.redo());
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

  return { load, apply, undo, redo, save, fit };
}
