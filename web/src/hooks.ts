// window.__partscale: what scripts (tests/browser/editor.mjs, bench/bench_editor.py) read and call.
import type { Zone } from './recipe';
import { toSource } from './remap';
import type { Scene } from './scene';
import {
  type AppState,
  extents,
  type PlaneName,
  type ResolvedZone,
  recipe,
  resolvedZones,
  type Store,
  targetExtents,
  type ZoneInput,
} from './state';
import type { Recipe } from './recipe';
import type { AxisElements, Candidate, ServerState } from './api';

export interface Hooks {
  /** The object is loaded. */
  readonly ready: boolean;
  readonly busy: boolean;
  readonly frameTimeMs: number;
  readonly lastFrameMs: number;
  readonly frames: number;
  /** Loaded with its suggestions and elements, nothing in flight, and the last change drawn. */
  readonly idle: boolean;
  state(): ServerState | null;
  /** The zones as applied (each in the frame the earlier ones leave). */
  zones(): ResolvedZone[];
  /** The zones as the user set them, on the loaded object (what the recipe sends). */
  zoneInputs(): readonly ZoneInput[];
  suggestions(): readonly Candidate[] | null;
  /** The object's elements along x, y, z (null: not fetched yet). */
  elements(): readonly AxisElements[] | null;
  /** The solid's size per axis (object units) and the size the previewed zones make (null: no
   *  change previewed). */
  sizes(): { extent: number[]; target: number[] | null };
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
      const s = get();
      return hooks.ready && !s.busy && !scene.renderQueued && s.suggestions !== null && s.elements !== null;
    },
    state: () => get().server,
    zones: () => resolvedZones(get()),
    zoneInputs: () => get().zones,
    suggestions: () => get().suggestions,
    elements: () => get().elements,
    sizes: () => ({ extent: extents(get()), target: targetExtents(get()) }),
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
