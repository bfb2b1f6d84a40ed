// window.__partscale: what scripts (tests/browser/editor.mjs, bench/bench_editor.py) read and call.
import type { Zone } from './recipe';
import { toSource } from './remap';
import type { Scene } from './scene';
import { type AppState, type PlaneName, type ResolvedZone, recipe, resolvedZones, type Store, type ZoneInput } from './state';
import type { Recipe } from './recipe';
import type { Candidate, ServerState } from './api';

export interface Hooks {
  /** The object is loaded. */
  readonly ready: boolean;
  readonly busy: boolean;
  readonly frameTimeMs: number;
  readonly lastFrameMs: number;
  readonly frames: number;
  /** Loaded with its suggestions, nothing in flight, and the last change has been drawn. */
  readonly idle: boolean;
  state(): ServerState | null;
  /** The zones as applied (each in the frame the earlier ones leave). */
  zones(): ResolvedZone[];
  /** The zones as the user set them, on the loaded object (what the recipe sends). */
  zoneInputs(): readonly ZoneInput[];
  suggestions(): readonly Candidate[] | null;
  fitWhy(): readonly string[];
  recipe(): Recipe;
  handleScreen(name: PlaneName): { x: number; y: number };
  /** GLSL toSource() of the shader on points (N, 3) through zones (applied in order). */
  evalRemap(zones: Zone[], points: number[][]): number[][];
  /** The TypeScript mirror, for comparison. */
  evalRemapTS(zones: Zone[], points: number[][]): number[][];
  /** Render n frames orbiting the object; mean and median GPU-synchronised frame time in ms. */
  benchmark(n?: number): { mean: number; median: number; n: number };
}

export function exposeHooks(store: Store, scene: Scene): Hooks {
  const get = (): AppState => store.get();
  const hooks: Hooks = {
    get ready() {
      return get().server !== null;
    },
    get busy() {
      return get().busy;
    },
    get frameTimeMs() {
      return scene.perf.frameTimeMs;
    },
    get lastFrameMs() {
      return scene.perf.lastFrameMs;
    },
    get frames() {
      return scene.perf.frames;
    },
    get idle() {
      return hooks.ready && !get().busy && !scene.renderQueued && get().suggestions !== null;
    },
    state: () => get().server,
    zones: () => resolvedZones(get()),
    zoneInputs: () => get().zones,
    suggestions: () => get().suggestions,
    fitWhy: () => get().fit.why,
    recipe: () => recipe(get()),
    handleScreen: scene.handleScreen,
    evalRemap: scene.evalRemap,
    evalRemapTS: (zones, points) => points.map((p) => toSource(zones, p)),
    benchmark: scene.benchmark,
  };
  (window as unknown as { __partscale: Hooks }).__partscale = hooks;
  return hooks;
}
