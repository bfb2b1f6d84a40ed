// The three.js side of the editor: the raymarched volume, its box and axes, the active zone's
// planes and handles, drawn on demand whenever the state (state.ts) or the camera changes.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import type { ServerState } from './api';
import { partColour } from './color';
import type { Volume } from './grid';
import { createRaymarchMaterial, evalRemapOnGPU, evalWarpOnGPU } from './raymarch';
import { AXES, type Zone } from './recipe';
import { MAX_ZONES, minJacobian, packZone } from './remap';
import {
  type AppState,
  outputBounds,
  PLANES,
  type PlaneName,
  previewPlane,
  solidBounds,
  type Store,
  validZones,
  voxel,
  warpIssue,
} from './state';
import { gauge, packWarp, screwShift, type Warp, warpStepScale } from './warp';

const PLANE_COLORS: Record<PlaneName, number> = { start: 0x2fbf71, end: 0xe5484d, dest: 0x3b82f6 };
const VIEW_MODES = { colour: 0, parts: 1, slice: 2 } as const;

export interface Scene {
  readonly renderer: THREE.WebGLRenderer;
  readonly camera: THREE.PerspectiveCamera;
  readonly controls: OrbitControls;
  readonly planeGroup: THREE.Group;
  readonly planeMeshes: Readonly<Record<PlaneName, THREE.Mesh>>;
  readonly handleMeshes: Readonly<Record<PlaneName, THREE.Mesh>>;
  /** Largest grid per axis this GPU can hold as a 3D texture. */
  readonly maxTextureSize: number;
  /** Smoothed and last frame time (ms; GPU-synchronised with the capture option, else the time
   *  to submit the frame), frames drawn so far. */
  readonly perf: Readonly<{ frameTimeMs: number; lastFrameMs: number; frames: number }>;
  /** A frame is requested and not drawn yet. */
  readonly renderQueued: boolean;
  /** Upload the object's distances and colours (grid.ts Volume) and part indices (or null). */
  setObject(s: ServerState, volume: Volume, parts: Int16Array | null): void;
  fitCamera(): void;
  requestRender(): void;
  renderNow(): void;
  /** Screen position (CSS pixels) of a plane's handle. */
  handleScreen(name: PlaneName): { x: number; y: number };
  /** The shader's toSource() on points (N, 3) through zones (applied in order). */
  evalRemap(zones: Zone[], points: number[][]): number[][];
  /** The shader's warpSource() on points (N, 3) for packed warp uniforms: (N, 4). */
  evalWarp(kind: number, data: number[], points: number[][]): number[][];
  /** What draws the shaped zone (rings, planes, the step's arrow). */
  readonly warpGroup: THREE.Group;
  /** Show or hide the guides (the zone's planes, the shaped zone, the box and the axes): tests
   *  compare the object alone. */
  setGuides(visible: boolean): void;
  /** Render n frames orbiting the object; mean and median GPU-synchronised frame time in ms. */
  benchmark(n?: number): { mean: number; median: number; n: number };
  /** Tests: look as `view` says (the user's orbit goes on from there). */
  setCamera(view: CameraView): void;
  /** Tests: draw the colours as sampled, without the lights (true), or lit as users see them. */
  setUnlit(unlit: boolean): void;
}

/** A camera for tests (tests/test_browser.py places it as partscale.render's): at `position`,
 *  looking at `target` with `up` the screen's up (world units), `fov` the vertical field of view
 *  in degrees, clipping at `near` and `far` from the camera. */
export interface CameraView {
  position: [number, number, number];
  target: [number, number, number];
  up: [number, number, number];
  fov: number;
  near: number;
  far: number;
}

/** How the scene draws. fixedSize: canvas pixels, or null to fill its element. capture (tests
 *  and benchmarks, the page's `?capture=1`): keep each frame's pixels readable (the canvas's
 *  toDataURL) and wait for the GPU at every frame, so the frame time is the raymarch's; the
 *  editor itself does neither (a browser may then drop the drawing buffer once it is shown, and
 *  a frame never stalls on a read back). */
export interface SceneOptions {
  fixedSize: [number, number] | null;
  capture: boolean;
}

function createRenderer(store: Store, capture: boolean): THREE.WebGLRenderer {
  try {
    return new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: capture });
  } catch (e) {
    store.dispatch({
      type: 'set-status',
      message: 'This browser cannot draw the object: it needs WebGL2 (enable hardware acceleration).',
      error: true,
    });
    throw e;
  }
}

/** Vec4 arrays of the zones, as the shader's uniforms hold them. */
function packed(zs: Zone[]) {
  const a = Array.from({ length: MAX_ZONES }, () => new THREE.Vector4());
  const b = Array.from({ length: MAX_ZONES }, () => new THREE.Vector4());
  zs.forEach((z, i) => {
    const [pa, pb] = packZone(z);
    a[i].set(pa[0], pa[1], pa[2], pa[3]);
    b[i].set(pb[0], pb[1], pb[2], pb[3]);
  });
  return { a, b };
}

/** The scene in `view`, drawn from the store's state (see SceneOptions). */
export function createScene(store: Store, view: HTMLElement, { fixedSize, capture }: SceneOptions): Scene {
  const renderer = createRenderer(store, capture);
  renderer.setPixelRatio(fixedSize ? 1 : Math.min(window.devicePixelRatio, 2));
  renderer.setClearColor(0x1d2126, 1);
  view.appendChild(renderer.domElement);
  const gl = renderer.getContext() as WebGL2RenderingContext; // three.js r187 is WebGL2-only

  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(35, 1, 0.001, 1000);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;

  const material = createRaymarchMaterial();
  const u = material.uniforms;
  const volumeMesh = new THREE.Mesh(new THREE.BoxGeometry(1, 1, 1), material);
  volumeMesh.frustumCulled = false;
  scene.add(volumeMesh);
  const boxHelper = new THREE.Box3Helper(new THREE.Box3(), 0x8a94a6);
  scene.add(boxHelper);
  const axesHelper = new THREE.AxesHelper(1);
  scene.add(axesHelper);

  const planeGroup = new THREE.Group();
  scene.add(planeGroup);
  const planeMeshes = {} as Record<PlaneName, THREE.Mesh>;
  const handleMeshes = {} as Record<PlaneName, THREE.Mesh>;
  for (const name of PLANES) {
    const plane = new THREE.Mesh(
      new THREE.PlaneGeometry(1, 1),
      new THREE.MeshBasicMaterial({
        color: PLANE_COLORS[name],
        transparent: true,
        opacity: 0.18,
        side: THREE.DoubleSide,
        depthWrite: false,
      }),
    );
    plane.userData.plane = name;
    plane.renderOrder = 2;
    const edge = new THREE.LineSegments(
      new THREE.EdgesGeometry(new THREE.PlaneGeometry(1, 1)),
      new THREE.LineBasicMaterial({ color: PLANE_COLORS[name] }),
    );
    plane.add(edge);
    const handle = new THREE.Mesh(
      new THREE.SphereGeometry(1, 20, 12),
      new THREE.MeshBasicMaterial({ color: PLANE_COLORS[name] }),
    );
    handle.userData.plane = name;
    planeMeshes[name] = plane;
    handleMeshes[name] = handle;
    planeGroup.add(plane, handle);
  }

  // GPU resources and frame bookkeeping: the renderer's own, not the editor's state
  const textures: {
    distance: THREE.Data3DTexture | null;
    colour: THREE.Data3DTexture | null;
    parts: THREE.Data3DTexture | null;
  } = { distance: null, colour: null, parts: null };
  const partsPlaceholder = new THREE.Data3DTexture(new Uint8Array([128, 128, 128, 255]), 1, 1, 1);
  partsPlaceholder.colorSpace = THREE.SRGBColorSpace;
  partsPlaceholder.needsUpdate = true;
  u.uParts.value = partsPlaceholder;
  const perf = { frameTimeMs: 0, lastFrameMs: 0, frames: 0 };
  const guides = { visible: true };
  const frame = { queued: false };
  const pixel = new Uint8Array(4);

  function outputBox(s: AppState): THREE.Box3 {
    const [lo, hi] = outputBounds(s);
    return new THREE.Box3(new THREE.Vector3(...lo), new THREE.Vector3(...hi));
  }

  function requestRender() {
    if (frame.queued) return;
    frame.queued = true;
    requestAnimationFrame(renderNow);
  }

  /** Draw now; sync: wait for the GPU to finish (one pixel read back) before taking the time. */
  function draw(sync: boolean) {
    const t0 = performance.now();
    // handles keep one size on screen, however far the camera is
    for (const h of Object.values(handleMeshes)) {
      h.scale.setScalar(
        0.04 * camera.position.distanceTo(h.position) * Math.tan(THREE.MathUtils.degToRad(camera.fov / 2)),
      );
    }
    renderer.render(scene, camera);
    // reading one pixel waits for the GPU, so the time covers the raymarch, not just its submission
    if (sync) gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    const ms = performance.now() - t0;
    perf.lastFrameMs = ms;
    perf.frameTimeMs = perf.frames === 0 ? ms : 0.8 * perf.frameTimeMs + 0.2 * ms;
    perf.frames += 1;
    updateOverlay();
  }

  function renderNow() {
    frame.queued = false;
    draw(capture);
  }

  function updateOverlay() {
    const server = store.get().server;
    const s = server ? server.shape.join('×') : '–';
    const size = new THREE.Vector2();
    renderer.getSize(size);
    const overlay = document.getElementById('overlay');
    if (overlay) overlay.textContent = `frame ${perf.lastFrameMs.toFixed(1)} ms · grid ${s} · ${size.x}×${size.y} px`;
  }

  function resize() {
    const w = fixedSize ? fixedSize[0] : view.clientWidth;
    const h = fixedSize ? fixedSize[1] : view.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    requestRender();
  }
  window.addEventListener('resize', resize);
  controls.addEventListener('change', requestRender);

  function updateScene(s: AppState) {
    // a shaped zone is previewed alone, instead of the planar zones
    const warp = s.warp && warpIssue(s) === null ? s.warp : null;
    const zs = s.warp ? [] : validZones(s);
    u.uZoneCount.value = zs.length;
    let jac = warp ? warpStepScale(warp) : 1;
    if (warp) {
      const { kind, data } = packWarp(warp, voxel(s));
      u.uWarpKind.value = kind;
      (u.uWarp.value as THREE.Vector4[]).forEach((v, i) => v.set(data[4 * i], data[4 * i + 1], data[4 * i + 2], data[4 * i + 3]));
    } else u.uWarpKind.value = 0;
    zs.forEach((z, i) => {
      const [a, b] = packZone(z);
      (u.uZoneA.value as THREE.Vector4[])[i].set(a[0], a[1], a[2], a[3]);
      (u.uZoneB.value as THREE.Vector4[])[i].set(b[0], b[1], b[2], b[3]);
      jac *= minJacobian(z);
    });
    u.uStepScale.value = Math.min(1, jac);
    const box = outputBox(s);
    u.uBoxMin.value.copy(box.min);
    u.uBoxMax.value.copy(box.max);
    const size = box.getSize(new THREE.Vector3());
    const centre = box.getCenter(new THREE.Vector3());
    volumeMesh.position.copy(centre);
    volumeMesh.scale.copy(size);
    boxHelper.box.copy(box);
    const [smin] = solidBounds(s);
    axesHelper.position.set(smin[0], smin[1], smin[2]);
    axesHelper.scale.setScalar(0.35 * Math.max(size.x, size.y, size.z));
    layoutPlanes(s, box);
    drawWarp(s.warp, box);
    updateView(s, box);
    boxHelper.visible = axesHelper.visible = guides.visible;
    if (!guides.visible) planeGroup.visible = warpGroup.visible = false;
  }

  function layoutPlanes(s: AppState, box: THREE.Box3) {
    const z = s.zones[s.active];
    planeGroup.visible = !!z && !s.warp;
    if (!z) return;
    const a = AXES.indexOf(z.axis);
    const size = box.getSize(new THREE.Vector3());
    const centre = box.getCenter(new THREE.Vector3());
    const others = [0, 1, 2].filter((i) => i !== a);
    const offset = 0.05 * size.length(); // handles sit just outside the box
    for (const name of PLANES) {
      const plane = planeMeshes[name];
      const pos = centre.clone();
      pos.setComponent(a, previewPlane(s, name));
      plane.position.copy(pos);
      // PlaneGeometry lies in xy with normal +z: turn its normal onto the axis
      plane.rotation.set(0, 0, 0);
      if (a === 0) plane.rotation.y = Math.PI / 2;
      if (a === 1) plane.rotation.x = -Math.PI / 2;
      const sz = [size.x, size.y, size.z].map((v) => v * 1.08);
      if (a === 0) plane.scale.set(sz[2], sz[1], 1);
      else if (a === 1) plane.scale.set(sz[0], sz[2], 1);
      else plane.scale.set(sz[0], sz[1], 1);
      const handle = handleMeshes[name];
      const hp = pos.clone();
      hp.setComponent(others[0], box.max.getComponent(others[0]) + offset);
      // dest's handle on the opposite edge, so it stays apart from end's when they coincide
      const side =
        name === 'dest' ? box.min.getComponent(others[1]) - offset : box.max.getComponent(others[1]) + offset;
      hp.setComponent(others[1], side);
      handle.position.copy(hp);
    }
  }

  const warpGroup = new THREE.Group();
  scene.add(warpGroup);

  /** Lines (world points, pairs) in a colour. */
  function lines(points: number[][], color: number): THREE.LineSegments {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(points.flat(), 3));
    const l = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color, depthTest: false, transparent: true }));
    l.renderOrder = 3;
    return l;
  }

  /** A transparent plane square to n through the point on it nearest the box centre. */
  function tiltedPlane(n: THREE.Vector3, at: number, box: THREE.Box3, color: number): THREE.Mesh {
    const size = box.getSize(new THREE.Vector3()).length();
    const centre = box.getCenter(new THREE.Vector3());
    const plane = new THREE.Mesh(
      new THREE.PlaneGeometry(size, size),
      new THREE.MeshBasicMaterial({ color, transparent: true, opacity: 0.18, side: THREE.DoubleSide, depthWrite: false }),
    );
    plane.add(new THREE.LineSegments(new THREE.EdgesGeometry(plane.geometry), new THREE.LineBasicMaterial({ color })));
    plane.position.copy(centre).addScaledVector(n, at - centre.dot(n));
    plane.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
    plane.renderOrder = 2;
    return plane;
  }

  /** A radial zone's ring at gauge radius r, as a cylinder over lo..hi along its axis: a polygon
   *  (its outline) or a circle. */
  function ring(w: Extract<Warp, { kind: 'radial' }>, r: number, lo: number, hi: number, color: number) {
    const a = AXES.indexOf(w.axis);
    const [u, v] = [0, 1, 2].filter((i) => i !== a);
    const n = w.sides || 96;
    const pts: number[][] = [];
    for (let k = 0; k < n; k++) {
      const t = w.sides ? ((w.phase + 180 / w.sides + (360 * k) / w.sides) * Math.PI) / 180 : (2 * Math.PI * k) / n;
      const d = [Math.cos(t), Math.sin(t)];
      const g = gauge(d, w.sides, w.phase);
      const p = [0, 0, 0];
      p[u] = w.center[0] + (r * d[0]) / g;
      p[v] = w.center[1] + (r * d[1]) / g;
      pts.push(p);
    }
    const segs: number[][] = [];
    for (const level of [lo, hi]) {
      pts.forEach((p, k) => {
        const q = pts[(k + 1) % n];
        const a0 = [...p];
        const b0 = [...q];
        a0[a] = level;
        b0[a] = level;
        segs.push(a0, b0);
      });
    }
    const every = w.sides ? 1 : 12;
    pts.forEach((p, k) => {
      if (k % every) return;
      const a0 = [...p];
      const b0 = [...p];
      a0[a] = lo;
      b0[a] = hi;
      segs.push(a0, b0);
    });
    return lines(segs, color);
  }

  /** The shaped zone drawn: a radial zone as cylinders at R0 (green), R1 (red) and the target
   *  (blue) about its axis; an oblique zone as its two tilted planes and the destination's; a
   *  flight's or a spiral's step as its cut and an arrow from a point on the cut to where the
   *  copied step puts it; elements about the vertical as the axis, the hub's circle (green), the
   *  elements' outer circle (red) and spokes at their directions now (red) and after (blue), with
   *  an arrow from the last element to the last one's new place. */
  function drawWarp(w: Warp | null, box: THREE.Box3) {
    for (const c of [...warpGroup.children]) {
      warpGroup.remove(c);
      c.traverse((o) => {
        const m = o as THREE.Mesh;
        m.geometry?.dispose();
        (m.material as THREE.Material | undefined)?.dispose();
      });
    }
    warpGroup.visible = !!w;
    if (!w) return;
    const lo = box.min.toArray();
    const hi = box.max.toArray();
    const centre = box.getCenter(new THREE.Vector3());
    if (w.kind === 'radial') {
      const a = AXES.indexOf(w.axis);
      const [l0, l1] = w.span ?? [lo[a], hi[a]];
      warpGroup.add(ring(w, w.r0, l0, l1, PLANE_COLORS.start), ring(w, w.r1, l0, l1, PLANE_COLORS.end));
      if (w.to !== w.r1) warpGroup.add(ring(w, w.to, l0, l1, PLANE_COLORS.dest));
    } else if (w.kind === 'rotation') {
      drawRotation(w);
    } else if (w.kind === 'oblique') {
      const n = new THREE.Vector3(...w.normal).normalize();
      warpGroup.add(tiltedPlane(n, w.s0, box, PLANE_COLORS.start), tiltedPlane(n, w.s1, box, PLANE_COLORS.end));
      if (w.to !== w.s1) warpGroup.add(tiltedPlane(n, w.to, box, PLANE_COLORS.dest));
    } else {
      // the cut, and an arrow from its middle (a spiral's: on its outer edge) along the step
      const h = voxel(store.get());
      let from: THREE.Vector3;
      let to: THREE.Vector3;
      if (w.kind === 'screw') {
        const a = AXES.indexOf(w.axis);
        const n = new THREE.Vector3().setComponent(a, 1);
        warpGroup.add(tiltedPlane(n, w.cut, box, PLANE_COLORS.end));
        from = centre.clone().setComponent(a, w.cut);
        from.y = lo[1] + 0.5 * (hi[1] - lo[1]);
        const step = screwShift({ ...w, copies: Math.sign(w.copies) || 1 }, h);
        to = from.clone().add(new THREE.Vector3(...step));
      } else {
        warpGroup.add(tiltedPlane(new THREE.Vector3(0, 1, 0), w.cut, box, PLANE_COLORS.end));
        const r = 0.45 * Math.min(hi[0] - lo[0], hi[2] - lo[2]);
        from = new THREE.Vector3(w.center[0] + r, w.cut, w.center[1]);
        const t = (w.angle * Math.PI) / 180;
        to = new THREE.Vector3(w.center[0] + r * Math.cos(t), w.cut + w.rise, w.center[1] + r * Math.sin(t));
        warpGroup.add(lines([[w.center[0], lo[1], w.center[1]], [w.center[0], hi[1], w.center[1]]], PLANE_COLORS.start));
      }
      warpGroup.add(arrow(from, to));
    }
  }

  /** An arrow (over everything) from one point to another. */
  function arrow(from: THREE.Vector3, to: THREE.Vector3): THREE.ArrowHelper {
    const dir = to.clone().sub(from);
    const len = dir.length();
    const a = new THREE.ArrowHelper(dir.normalize(), from, len, PLANE_COLORS.dest, 0.3 * len, 0.15 * len);
    a.traverse((o) => {
      o.renderOrder = 3;
      const m = (o as THREE.Mesh).material as THREE.Material | undefined;
      if (m) m.depthTest = false;
    });
    return a;
  }

  /** Elements about the vertical: the axis, the hub's and the outer circle at the span's ends,
   *  spokes at the elements' directions now and after the edit, an arrow to the last one's new
   *  place. */
  function drawRotation(w: Extract<Warp, { kind: 'rotation' }>) {
    const [cx, cz] = w.center;
    const [y0, y1] = w.span;
    const ym = (y0 + y1) / 2;
    const at = (r: number, degrees: number, y: number) => {
      const t = (degrees * Math.PI) / 180;
      return [cx + r * Math.cos(t), y, cz + r * Math.sin(t)];
    };
    const circle = (r: number, color: number) => {
      const segs: number[][] = [];
      for (const y of [y0, y1]) {
        for (let k = 0; k < 96; k++) segs.push(at(r, (360 * k) / 96, y), at(r, (360 * (k + 1)) / 96, y));
      }
      return lines(segs, color);
    };
    const spokes = (dirs: number[], color: number) => lines(dirs.flatMap((d) => [at(w.hub, d, ym), at(w.radius, d, ym)]), color);
    const sign = w.angle > 0 ? 1 : -1;
    const k = w.count + w.copies;
    const now = Array.from({ length: w.count }, (_, m) => w.phase + m * w.angle);
    const after = Array.from({ length: Math.max(k, 0) }, (_, m) => w.phase + sign * m * (w.closed ? 360 / k : Math.abs(w.angle)));
    warpGroup.add(
      lines([[cx, y0 - 0.5 * (y1 - y0), cz], [cx, y1 + 0.5 * (y1 - y0), cz]], PLANE_COLORS.start),
      circle(Math.max(w.hub, 1e-6), PLANE_COLORS.start),
      circle(w.radius, PLANE_COLORS.end),
      spokes(now, PLANE_COLORS.end),
      spokes(after, PLANE_COLORS.dest),
    );
    if (k >= 1) {
      const r = 0.9 * w.radius;
      warpGroup.add(arrow(new THREE.Vector3(...at(r, now[now.length - 1], y1)), new THREE.Vector3(...at(r, after[after.length - 1], y1))));
    }
  }

  /** View mode and the distance slice's plane (a fraction of the output box). */
  function updateView(s: AppState, box: THREE.Box3) {
    u.uView.value = VIEW_MODES[s.view.mode];
    const axis = AXES.indexOf(s.view.sliceAxis);
    const f = s.view.slicePos / 100;
    u.uSliceAxis.value = axis;
    u.uSlicePos.value = box.min.getComponent(axis) + f * (box.max.getComponent(axis) - box.min.getComponent(axis));
  }

  function fitCamera() {
    const box = outputBox(store.get());
    const centre = box.getCenter(new THREE.Vector3());
    const radius = 0.5 * box.getSize(new THREE.Vector3()).length();
    const dist = (radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2))) * 0.95;
    const dir = new THREE.Vector3(1.0, 0.75, 1.35).normalize();
    camera.position.copy(centre).addScaledVector(dir, dist);
    camera.near = dist / 100;
    camera.far = dist * 10;
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    controls.update();
  }

  /** A 3D texture of the grid; filter: linear (distances, colours) or nearest (parts); colours
   *  are sRGB bytes, uploaded as SRGB8_ALPHA8 so the GPU decodes each texel to linear before
   *  it filters (blending sRGB values would darken every blend of two colours). */
  function volumeTexture(
    data: Uint16Array | Uint8Array,
    shape: readonly number[],
    format: THREE.PixelFormat,
    type: THREE.TextureDataType,
    { srgb = false, filter = THREE.LinearFilter }: { srgb?: boolean; filter?: THREE.MagnificationTextureFilter } = {},
  ) {
    const [X, Y, Z] = shape;
    // C order (z fastest): the texture's width runs along z (see raymarch.ts)
    const tex = new THREE.Data3DTexture(data, Z, Y, X);
    tex.format = format;
    tex.type = type;
    tex.colorSpace = srgb ? THREE.SRGBColorSpace : THREE.NoColorSpace;
    tex.minFilter = filter;
    tex.magFilter = filter;
    tex.unpackAlignment = 1;
    tex.needsUpdate = true;
    return tex;
  }

  /** The parts as RGBA sRGB bytes: each voxel its part's colour (grey: no part). */
  function partColours(s: ServerState, parts: Int16Array): Uint8Array {
    const palette = Array.from({ length: s.n_parts }, (_, i) => partColour(s.parts_info[i]?.color, i));
    const rgba = new Uint8Array(parts.length * 4);
    for (let i = 0; i < parts.length; i++) {
      const p = parts[i];
      const c = p >= 0 && p < palette.length ? palette[p] : [110, 110, 110];
      rgba[i * 4] = c[0];
      rgba[i * 4 + 1] = c[1];
      rgba[i * 4 + 2] = c[2];
      rgba[i * 4 + 3] = 255;
    }
    return rgba;
  }

  function setObject(s: ServerState, volume: Volume, parts: Int16Array | null) {
    textures.distance?.dispose();
    textures.colour?.dispose();
    textures.distance = volumeTexture(volume.distance, s.shape, THREE.RedFormat, THREE.HalfFloatType);
    textures.colour = volumeTexture(volume.rgba, s.shape, THREE.RGBAFormat, THREE.UnsignedByteType, { srgb: true });
    textures.parts?.dispose();
    textures.parts = null;
    if (parts && s.n_parts > 0) {
      const rgba = partColours(s, parts);
      textures.parts = volumeTexture(rgba, s.shape, THREE.RGBAFormat, THREE.UnsignedByteType, { srgb: true, filter: THREE.NearestFilter });
    }
    u.uDistance.value = textures.distance;
    u.uColour.value = textures.colour;
    u.uParts.value = textures.parts ?? partsPlaceholder;
    const [gmin, gmax] = s.grid_bounds;
    u.uGridMin.value.set(gmin[0], gmin[1], gmin[2]);
    u.uGridSize.value.set(gmax[0] - gmin[0], gmax[1] - gmin[1], gmax[2] - gmin[2]);
    u.uVoxel.value = s.voxel_size;
  }

  store.subscribe((s, prev) => {
    // the first object: frame it (later ones keep the user's camera)
    if (s.server && !prev.server) fitCamera();
    if (s.server !== prev.server || s.zones !== prev.zones || s.active !== prev.active || s.warp !== prev.warp) {
      updateScene(s);
      requestRender();
    } else if (s.view !== prev.view) {
      updateView(s, outputBox(s));
      requestRender();
    }
  });

  function handleScreen(name: PlaneName): { x: number; y: number } {
    const p = handleMeshes[name].getWorldPosition(new THREE.Vector3()).project(camera);
    const rect = renderer.domElement.getBoundingClientRect();
    return { x: rect.left + ((p.x + 1) / 2) * rect.width, y: rect.top + ((1 - p.y) / 2) * rect.height };
  }

  function benchmark(n = 30) {
    const times: number[] = [];
    const target = controls.target.clone();
    const offset = camera.position.clone().sub(target);
    for (let i = 0; i < n; i++) {
      offset.applyAxisAngle(new THREE.Vector3(0, 1, 0), (2 * Math.PI) / n);
      camera.position.copy(target).add(offset);
      camera.lookAt(target);
      draw(true);
      times.push(perf.lastFrameMs);
    }
    times.sort((x, y) => x - y);
    return { mean: times.reduce((acc, t) => acc + t, 0) / n, median: times[Math.floor(n / 2)], n };
  }

  function setCamera({ position, target, up, fov, near, far }: CameraView) {
    camera.up.set(...up);
    camera.position.set(...position);
    camera.lookAt(...target);
    camera.fov = fov;
    camera.near = near;
    camera.far = far;
    camera.updateProjectionMatrix();
    controls.target.set(...target);
    requestRender();
  }

  updateScene(store.get());
  resize();

  return {
    renderer,
    camera,
    controls,
    planeGroup,
    planeMeshes,
    handleMeshes,
    maxTextureSize: gl.getParameter(gl.MAX_3D_TEXTURE_SIZE) as number,
    perf,
    get renderQueued() {
      return frame.queued;
    },
    setObject,
    fitCamera,
    requestRender,
    renderNow,
    handleScreen,
    warpGroup,
    setGuides(visible: boolean) {
      guides.visible = visible;
      updateScene(store.get());
      requestRender();
    },
    evalWarp: (kind, data, points) => evalWarpOnGPU(renderer, kind, data, points),
    evalRemap: (zones, points) => {
      const { a, b } = packed(zones);
      return evalRemapOnGPU(renderer, a, b, zones.length, points);
    },
    benchmark,
    setCamera,
    setUnlit(unlit: boolean) {
      u.uUnlit.value = unlit;
      requestRender();
    },
  };
}
