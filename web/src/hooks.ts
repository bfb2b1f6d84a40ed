// window.__partscale: what scripts (tests/browser/editor.mjs, bench/bench_editor.py) read and call.
import type { Zone } from './recipe';
import { toSource } from './remap';
import type { CameraView, Scene } from './scene';
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
  zoneResolutions,
} from './state';
import type { Recipe } from './recipe';
import type { AxisElements, Candidate, ServerState, WarpFound } from './api';
import { packWarp, type Warp, type WarpEdit, warpFromEdit, type WarpRecipe, warpSource } from './warp';

function parsed(edit: WarpEdit): Warp {
  const w = warpFromEdit(edit);
  if (!w) throw new Error(`expected a warp edit (radial, normal, screw, helix, rotation), got ${JSON.stringify(edit)}`);
  return w;
}

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
  zones(): readonly ResolvedZone[];
  /** How many times the page resolved its zones so far (once per change of the zones or the
   *  object, however often the scene and the panel read them). */
  readonly zoneResolutions: number;
  /** The zones as the user set them, on the loaded object (what the recipe sends). */
  zoneInputs(): readonly ZoneInput[];
  suggestions(): readonly Candidate[] | null;
  /** The object's elements along x, y, z (null: not fetched yet). */
  elements(): readonly AxisElements[] | null;
  /** The solid's size per axis (object units) and the size the previewed zones make (null: no
   *  change previewed). */
  sizes(): { extent: number[]; target: number[] | null };
  fitWhy(): readonly string[];
  recipe(): Recipe | WarpRecipe;
  /** The object's warp zones (radial plan, flights, spiral stairs; null: not fetched yet). */
  warps(): WarpFound | null;
  /** The shaped zone previewed (null: the planar zones are). */
  warp(): Warp | null;
  /** The shader's warpSource() on points (N, 3) for a warp's recipe edit (as recipes hold it):
   *  (N, 4) source point and weight; h: voxel size. */
  evalWarp(edit: WarpEdit, points: number[][], h: number): number[][];
  /** The TypeScript mirror, for comparison. */
  evalWarpTS(edit: WarpEdit, points: number[][], h: number): number[][];
  /** Show or hide the guides drawn over the object (planes, shaped zone, box, axes). */
  setGuides(visible: boolean): void;
  handleScreen(name: PlaneName): { x: number; y: number };
  /** GLSL toSource() of the shader on points (N, 3) through zones (applied in order). */
  evalRemap(zones: Zone[], points: number[][]): number[][];
  /** The TypeScript mirror, for comparison. */
  evalRemapTS(zones: Zone[], points: number[][]): number[][];
  /** Render n frames orbiting the object; mean and median GPU-synchronised frame time in ms. */
  benchmark(n?: number): { mean: number; median: number; n: number };
  /** Look from a given camera (tests place it as partscale.render's). */
  setCamera(view: CameraView): void;
  /** Draw the colours as sampled, without the lights (tests compare them with
   *  partscale.render's), or lit as users see them (false). */
  setUnlit(unlit: boolean): void;
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
    get zoneResolutions() {
      return zoneResolutions();
    },
    state: () => get().server,
    zones: () => resolvedZones(get()),
    zoneInputs: () => get().zones,
    suggestions: () => get().suggestions,
    elements: () => get().elements,
    sizes: () => ({ extent: extents(get()), target: targetExtents(get()) }),
    fitWhy: () => get().fit.why,
    recipe: () => recipe(get()),
    warps: () => get().warps,
    warp: () => get().warp,
    evalWarp: (edit, points, h) => {
      const { kind, data } = packWarp(parsed(edit), h);
      return scene.evalWarp(kind, data, points);
    },
    evalWarpTS: (edit, points, h) => {
      const warp = parsed(edit);
      return points.map((p) => {
        const [src, w] = warpSource(warp, p, h);
        return [...src, w];
      });
    },
    setGuides: scene.setGuides,
    handleScreen: scene.handleScreen,
    evalRemap: scene.evalRemap,
    evalRemapTS: (zones, points) => points.map((p) => toSource(zones, p)),
    benchmark: scene.benchmark,
    setCamera: scene.setCamera,
    setUnlit: scene.setUnlit,
  };
  (window as unknown as { __partscale: Hooks }).__partscale = hooks;
  return hooks;
}
