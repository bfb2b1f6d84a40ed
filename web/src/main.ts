// partscale's browser editor: raymarched CSDF, draggable zone planes, live preview, apply/undo.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { ApiError, getGrid, getParts, getState, post, type State } from './api';
import { createRaymarchMaterial, evalRemapOnGPU } from './raymarch';
import {
  AXES,
  type Axis,
  forwardCoordinate,
  MAX_ZONES,
  MODES,
  type Mode,
  minJacobian,
  packZone,
  snapDest,
  sourceCoordinate,
  tileCount,
  type Zone,
  zoneProblem,
} from './remap';
import './style.css';

type PlaneName = 'start' | 'end' | 'dest';
const PLANES: PlaneName[] = ['start', 'end', 'dest'];
const PLANE_COLORS: Record<PlaneName, number> = { start: 0x2fbf71, end: 0xe5484d, dest: 0x3b82f6 };

interface EditZone {
  axis: Axis;
  mode: Mode;
  start: number;
  end: number;
  dest: number;
}

const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;

// -- renderer, scene, camera ------------------------------------------------------------------
const params = new URLSearchParams(location.search);
const fixedSize = params.get('canvas')?.match(/^(\d+)x(\d+)$/);
const view = $('view');
function createRenderer(): THREE.WebGLRenderer {
  try {
    return new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  } catch (e) {
    const el = document.getElementById('status');
    if (el) {
      el.textContent = 'This browser cannot draw the object: it needs WebGL2 (enable hardware acceleration).';
      el.classList.add('error');
    }
    throw e;
  }
}
const renderer = createRenderer();
renderer.setPixelRatio(fixedSize ? 1 : Math.min(window.devicePixelRatio, 2));
renderer.setClearColor(0x1d2126, 1);
view.appendChild(renderer.domElement);
const gl = renderer.getContext() as WebGL2RenderingContext; // three.js r187 is WebGL2-only

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(35, 1, 0.001, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;

const material = createRaymarchMaterial();
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

// -- state ------------------------------------------------------------------------------------
let state: State | null = null;
let zones: EditZone[] = [];
let active = 0;
let units: 'units' | '%' = 'units';
let busy = false;
let firstLoad = true;
let volumeTex: THREE.Data3DTexture | null = null;
let partsTex: THREE.Data3DTexture | null = null;
const partsPlaceholder = new THREE.Data3DTexture(new Uint8Array([128, 128, 128, 255]), 1, 1, 1);
partsPlaceholder.needsUpdate = true;
material.uniforms.uParts.value = partsPlaceholder;

const perf = { frameTimeMs: 0, lastFrameMs: 0, frames: 0 };

function solidBounds(): [number[], number[]] {
  if (!state) return [[0, 0, 0], [1, 1, 1]];
  return state.solid_bounds ?? state.grid_bounds;
}

/** The zones in world units with lo/hi: the solid's extent before each one (forward-mapped). */
function resolvedZones(): Zone[] {
  const [smin, smax] = solidBounds();
  const lo = [...smin];
  const hi = [...smax];
  const out: Zone[] = [];
  const h = voxel();
  for (const z of zones) {
    const a = AXES.indexOf(z.axis);
    const zone: Zone = { ...z, lo: lo[a], hi: hi[a] };
    // preview what the server will make: the end moves by whole voxels
    zone.dest = snapDest(zone, h);
    out.push(zone);
    if (zoneProblem(zone, h) === null) {
      lo[a] = forwardCoordinate(lo[a], zone);
      hi[a] = forwardCoordinate(hi[a], zone);
    }
  }
  return out;
}

function voxel(): number {
  return state ? state.voxel_size : 1e-3;
}

function validZones(): Zone[] {
  return resolvedZones().filter((z) => zoneProblem(z, voxel()) === null);
}

function outputBox(): THREE.Box3 {
  const [gmin, gmax] = state ? state.grid_bounds : [[0, 0, 0], [1, 1, 1]];
  const lo = [...gmin];
  const hi = [...gmax];
  for (const z of validZones()) {
    const a = AXES.indexOf(z.axis);
    lo[a] = forwardCoordinate(lo[a], z);
    hi[a] = forwardCoordinate(hi[a], z);
  }
  return new THREE.Box3(new THREE.Vector3(...lo), new THREE.Vector3(...hi));
}

function defaultZone(axis: Axis = 'x'): EditZone {
  const [smin, smax] = solidBounds();
  const a = AXES.indexOf(axis);
  const lo = smin[a];
  const len = smax[a] - lo;
  return { axis, mode: 'stretch', start: lo + 0.35 * len, end: lo + 0.65 * len, dest: lo + 0.65 * len };
}

/** The recipe (partscale.edit.JSON_SCHEMA) of the valid zones, with the destinations as given. */
function recipe() {
  const h = voxel();
  const edits = resolvedZones().flatMap((z, i) =>
    zoneProblem(z, h) === null
      ? [{ axis: z.axis, zone: [z.start, z.end], to: zones[i].dest, mode: z.mode }]
      : [],
  );
  return { version: 1, edits };
}

// -- rendering on demand ----------------------------------------------------------------------
let renderQueued = false;
const pixel = new Uint8Array(4);

function requestRender() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(renderNow);
}

function renderNow() {
  renderQueued = false;
  const t0 = performance.now();
  // handles keep one size on screen, however far the camera is
  for (const h of Object.values(handleMeshes)) {
    h.scale.setScalar(0.04 * camera.position.distanceTo(h.position) * Math.tan(THREE.MathUtils.degToRad(camera.fov / 2)));
  }
  renderer.render(scene, camera);
  // reading one pixel waits for the GPU, so the time covers the raymarch, not just its submission
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
  const ms = performance.now() - t0;
  perf.lastFrameMs = ms;
  perf.frameTimeMs = perf.frames === 0 ? ms : 0.8 * perf.frameTimeMs + 0.2 * ms;
  perf.frames += 1;
  updateOverlay();
}

function resize() {
  const w = fixedSize ? Number(fixedSize[1]) : view.clientWidth;
  const h = fixedSize ? Number(fixedSize[2]) : view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  requestRender();
}
window.addEventListener('resize', resize);
controls.addEventListener('change', requestRender);

function updateOverlay() {
  const s = state ? state.shape.join('×') : '–';
  const size = new THREE.Vector2();
  renderer.getSize(size);
  $('overlay').textContent =
    `frame ${perf.lastFrameMs.toFixed(1)} ms · grid ${s} · ${size.x}×${size.y} px`;
}

// -- scene updates ----------------------------------------------------------------------------
function updateScene() {
  const zs = validZones();
  const u = material.uniforms;
  u.uZoneCount.value = zs.length;
  let jac = 1;
  zs.forEach((z, i) => {
    const [a, b] = packZone(z);
    (u.uZoneA.value as THREE.Vector4[])[i].set(a[0], a[1], a[2], a[3]);
    (u.uZoneB.value as THREE.Vector4[])[i].set(b[0], b[1], b[2], b[3]);
    jac *= minJacobian(z);
  });
  u.uStepScale.value = Math.min(1, jac);
  const box = outputBox();
  u.uBoxMin.value.copy(box.min);
  u.uBoxMax.value.copy(box.max);
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  volumeMesh.position.copy(centre);
  volumeMesh.scale.copy(size);
  boxHelper.box.copy(box);
  const [smin] = solidBounds();
  axesHelper.position.set(smin[0], smin[1], smin[2]);
  axesHelper.scale.setScalar(0.35 * Math.max(size.x, size.y, size.z));
  layoutPlanes(box);
  updateSliceUniforms(box);
  requestRender();
}

/** The valid zones after the active one on its axis: they move its planes in the preview. */
function laterOnAxis(): Zone[] {
  const axis = zones[active]?.axis;
  const h = voxel();
  return resolvedZones()
    .slice(active + 1)
    .filter((z) => z.axis === axis && zoneProblem(z, h) === null);
}

/** Active zone's coordinate -> where the preview shows it (through the later zones). */
function toPreview(v: number): number {
  for (const z of laterOnAxis()) v = forwardCoordinate(v, z);
  return v;
}

/** Preview coordinate -> the active zone's coordinate (the later zones' maps, last first). */
function fromPreview(v: number): number {
  const later = laterOnAxis();
  for (let i = later.length - 1; i >= 0; i--) v = sourceCoordinate(v, later[i]);
  return v;
}

function layoutPlanes(box: THREE.Box3) {
  const z = zones[active];
  planeGroup.visible = !!z;
  if (!z) return;
  const a = AXES.indexOf(z.axis);
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  const others = [0, 1, 2].filter((i) => i !== a);
  const offset = 0.05 * size.length(); // handles sit just outside the box
  for (const name of PLANES) {
    const plane = planeMeshes[name];
    const pos = centre.clone();
    pos.setComponent(a, toPreview(name === 'dest' ? resolvedZones()[active].dest : z[name]));
    plane.position.copy(pos);
    // PlaneGeometry lies in xy with normal +z: turn its normal onto the axis
    plane.rotation.set(0, 0, 0);
    if (a === 0) plane.rotation.y = Math.PI / 2;
    if (a === 1) plane.rotation.x = -Math.PI / 2;
    const s = [size.x, size.y, size.z].map((v) => v * 1.08);
    if (a === 0) plane.scale.set(s[2], s[1], 1);
    else if (a === 1) plane.scale.set(s[0], s[2], 1);
    else plane.scale.set(s[0], s[1], 1);
    const handle = handleMeshes[name];
    const hp = pos.clone();
    hp.setComponent(others[0], box.max.getComponent(others[0]) + offset);
    // dest's handle on the opposite edge, so it stays apart from end's when they coincide
    const side = name === 'dest' ? box.min.getComponent(others[1]) - offset : box.max.getComponent(others[1]) + offset;
    hp.setComponent(others[1], side);
    handle.position.copy(hp);
  }
}

function updateSliceUniforms(box: THREE.Box3) {
  const u = material.uniforms;
  const axis = AXES.indexOf(($('slice-axis') as HTMLSelectElement).value as Axis);
  const f = Number(($('slice-pos') as HTMLInputElement).value) / 100;
  u.uSliceAxis.value = axis;
  u.uSlicePos.value = box.min.getComponent(axis) + f * (box.max.getComponent(axis) - box.min.getComponent(axis));
}

function fitCamera() {
  const box = outputBox();
  const centre = box.getCenter(new THREE.Vector3());
  const radius = 0.5 * box.getSize(new THREE.Vector3()).length();
  const dist = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 0.95;
  const dir = new THREE.Vector3(1.0, 0.75, 1.35).normalize();
  camera.position.copy(centre).addScaledVector(dir, dist);
  camera.near = dist / 100;
  camera.far = dist * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
}

// -- loading the object -----------------------------------------------------------------------
function srgbFloat(c: number[] | string | undefined, i: number): [number, number, number] {
  if (typeof c === 'string' && /^#?[0-9a-f]{6}$/i.test(c)) {
    const v = parseInt(c.replace('#', ''), 16);
    return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
  }
  if (Array.isArray(c) && c.length >= 3) {
    // partscale writes sRGB bytes ([r, g, b] integers); fractions in [0, 1] are accepted too
    const scale = !c.every(Number.isInteger) && c.every((v) => v <= 1) ? 255 : 1;
    return [c[0] * scale, c[1] * scale, c[2] * scale].map((v) => Math.round(v)) as [number, number, number];
  }
  const col = new THREE.Color().setHSL(((i * 0.618034) % 1 + 1) % 1, 0.65, 0.55, THREE.SRGBColorSpace);
  const hex = col.getHex(THREE.SRGBColorSpace);
  return [(hex >> 16) & 255, (hex >> 8) & 255, hex & 255];
}

async function loadObject() {
  setStatus('loading grid…');
  const s = await getState();
  const [X, Y, Z] = s.shape;
  const limit = gl.getParameter(gl.MAX_3D_TEXTURE_SIZE) as number;
  if (Math.max(X, Y, Z) > limit) {
    throw new ApiError(`grid: expected at most ${limit} voxels per axis on this GPU, got ${s.shape.join('×')}`);
  }
  const grid = await getGrid();
  if (grid.length !== X * Y * Z * 4) throw new ApiError(`grid: expected ${X * Y * Z * 4} values, got ${grid.length}`);
  volumeTex?.dispose();
  // C order (z fastest): the texture's width runs along z (see raymarch.ts)
  volumeTex = new THREE.Data3DTexture(grid, Z, Y, X);
  volumeTex.format = THREE.RGBAFormat;
  volumeTex.type = THREE.HalfFloatType;
  volumeTex.minFilter = THREE.LinearFilter;
  volumeTex.magFilter = THREE.LinearFilter;
  volumeTex.unpackAlignment = 1;
  volumeTex.needsUpdate = true;
  partsTex?.dispose();
  partsTex = null;
  if (s.n_parts > 0) {
    const parts = await getParts();
    const palette = Array.from({ length: s.n_parts }, (_, i) => srgbFloat(s.parts_info[i]?.color, i));
    const rgba = new Uint8Array(parts.length * 4);
    for (let i = 0; i < parts.length; i++) {
      const p = parts[i];
      const c = p >= 0 && p < palette.length ? palette[p] : [110, 110, 110];
      rgba[i * 4] = c[0];
      rgba[i * 4 + 1] = c[1];
      rgba[i * 4 + 2] = c[2];
      rgba[i * 4 + 3] = 255;
    }
    partsTex = new THREE.Data3DTexture(rgba, Z, Y, X);
    partsTex.unpackAlignment = 1;
    partsTex.needsUpdate = true;
  }
  state = s;
  const u = material.uniforms;
  u.uVolume.value = volumeTex;
  u.uParts.value = partsTex ?? partsPlaceholder;
  const [gmin, gmax] = s.grid_bounds;
  u.uGridMin.value.set(gmin[0], gmin[1], gmin[2]);
  u.uGridSize.value.set(gmax[0] - gmin[0], gmax[1] - gmin[1], gmax[2] - gmin[2]);
  u.uVoxel.value = s.voxel_size;
  const axis = zones[0]?.axis ?? 'x';
  zones = [defaultZone(axis)];
  active = 0;
  if (firstLoad) fitCamera();
  firstLoad = false;
  refreshUI();
  updateScene();
  setStatus(`${s.name}: ${s.history.length} operation(s) in history`);
}

// -- UI ---------------------------------------------------------------------------------------
function setStatus(msg: string, error = false) {
  const el = $('status');
  el.textContent = msg;
  el.classList.toggle('error', error);
}

function toDisplay(v: number, z: Zone): number {
  return units === '%' ? ((v - z.lo) / (z.hi - z.lo)) * 100 : v;
}

function fromDisplay(v: number, z: Zone): number {
  return units === '%' ? z.lo + (v / 100) * (z.hi - z.lo) : v;
}

function fmt(v: number): string {
  return Number.isFinite(v) ? String(Number(v.toPrecision(6))) : '';
}

function refreshUI() {
  const zoneSel = $('zone') as HTMLSelectElement;
  zoneSel.innerHTML = '';
  zones.forEach((_, i) => zoneSel.add(new Option(`zone ${i + 1}`, String(i))));
  zoneSel.value = String(active);
  const rz = resolvedZones();
  const z = rz[active];
  ($('axis') as HTMLSelectElement).value = z.axis;
  ($('mode') as HTMLSelectElement).value = z.mode;
  ($('units') as HTMLSelectElement).value = units;
  for (const name of PLANES) {
    const input = $(`pos-${name}`) as HTMLInputElement;
    if (document.activeElement !== input) input.value = fmt(toDisplay(z[name], z));
  }
  const unitLabel = units === '%' ? '%' : state?.units ?? '';
  document.querySelectorAll('.unit').forEach((el) => (el.textContent = unitLabel));
  const problems = rz.map((q) => zoneProblem(q, voxel())).filter((p) => p !== null);
  // dest == end leaves the object as it is in every mode: nothing to send
  const noop = rz.every((q) => q.dest === q.end);
  $('zone-info').textContent = problems.length
    ? `invalid: ${problems[0]}`
    : noop
      ? 'no change yet: move the destination plane'
      : zoneSummary(z);
  $('zone-info').classList.toggle('error', problems.length > 0);
  ($('apply') as HTMLButtonElement).disabled = busy || problems.length > 0 || noop || !state;
  ($('undo') as HTMLButtonElement).disabled = busy || !state?.can_undo;
  ($('redo') as HTMLButtonElement).disabled = busy || !state?.can_redo;
  ($('save') as HTMLButtonElement).disabled = busy || !state;
  ($('add-zone') as HTMLButtonElement).disabled = busy || zones.length >= MAX_ZONES;
  ($('remove-zone') as HTMLButtonElement).disabled = busy || zones.length <= 1;
  const partsOpt = ($('view-mode') as HTMLSelectElement).querySelector('option[value="parts"]') as HTMLOptionElement;
  partsOpt.disabled = !state || state.n_parts === 0;
  partsOpt.textContent = state && state.n_parts > 0 ? `parts (${state.n_parts})` : 'parts (not segmented)';
  $('grid-info').textContent = state
    ? `${state.shape.join(' × ')} voxels of ${fmt(state.voxel_size)} ${state.units}${state.unsaved ? ' · unsaved' : ''}`
    : '';
  ($('save-as') as HTMLElement).textContent = ($('overwrite') as HTMLInputElement).checked
    ? state?.name ?? ''
    : state?.save_as ?? '';
}

function zoneSummary(z: Zone): string {
  const u = state?.units ?? '';
  const length = z.end - z.start;
  const target = z.dest - z.start;
  const delta = `${z.dest >= z.end ? '+' : '−'}${fmt(Math.abs(z.dest - z.end))} ${u}`;
  if (z.mode === 'global') return `whole object ×${fmt((z.hi - z.lo + z.dest - z.end) / (z.hi - z.lo))} (${delta})`;
  if (z.mode === 'tile') {
    const n = tileCount(length, target);
    return `${n} cop${n === 1 ? 'y' : 'ies'} of ${fmt(length)} ${u}, each ×${fmt(target / (n * length))} (${delta})`;
  }
  return `zone ×${fmt(target / length)} (${delta})`;
}

function setZone(patch: Partial<EditZone>) {
  zones[active] = { ...zones[active], ...patch };
  refreshUI();
  updateScene();
}

async function run(label: string, fn: () => Promise<void>) {
  if (busy) return;
  busy = true;
  refreshUI();
  setStatus(`${label}…`);
  try {
    await fn();
  } catch (e) {
    setStatus(`${label} failed: ${e instanceof Error ? e.message : String(e)}`, true);
  } finally {
    busy = false;
    refreshUI();
  }
}

function bindUI() {
  ($('zone') as HTMLSelectElement).addEventListener('change', (e) => {
    active = Number((e.target as HTMLSelectElement).value);
    refreshUI();
    updateScene();
  });
  $('add-zone').addEventListener('click', () => {
    zones.push(defaultZone(zones[active].axis));
    active = zones.length - 1;
    // the new zone's default sits on the solid as it is after the earlier zones
    const z = resolvedZones()[active];
    const len = z.hi - z.lo;
    zones[active] = { ...zones[active], start: z.lo + 0.35 * len, end: z.lo + 0.65 * len, dest: z.lo + 0.65 * len };
    refreshUI();
    updateScene();
  });
  $('remove-zone').addEventListener('click', () => {
    zones.splice(active, 1);
    active = Math.max(0, active - 1);
    refreshUI();
    updateScene();
  });
  ($('axis') as HTMLSelectElement).addEventListener('change', (e) => {
    const axis = (e.target as HTMLSelectElement).value as Axis;
    setZone({ ...defaultZone(axis), mode: zones[active].mode });
  });
  ($('mode') as HTMLSelectElement).addEventListener('change', (e) => {
    setZone({ mode: (e.target as HTMLSelectElement).value as Mode });
  });
  ($('units') as HTMLSelectElement).addEventListener('change', (e) => {
    units = (e.target as HTMLSelectElement).value as 'units' | '%';
    refreshUI();
  });
  for (const name of PLANES) {
    const input = $(`pos-${name}`) as HTMLInputElement;
    const commit = () => {
      const v = Number(input.value);
      if (input.value.trim() === '' || !Number.isFinite(v)) return;
      setZone({ [name]: fromDisplay(v, resolvedZones()[active]) });
    };
    input.addEventListener('input', commit);
    input.addEventListener('change', () => {
      commit();
      input.value = fmt(toDisplay(zones[active][name], resolvedZones()[active]));
    });
  }
  $('reset-zone').addEventListener('click', () => setZone(defaultZone(zones[active].axis)));
  $('fit').addEventListener('click', () => {
    fitCamera();
    requestRender();
  });
  ($('view-mode') as HTMLSelectElement).addEventListener('change', (e) => {
    const v = (e.target as HTMLSelectElement).value;
    material.uniforms.uView.value = v === 'parts' ? 1 : v === 'slice' ? 2 : 0;
    $('slice-controls').hidden = v !== 'slice';
    requestRender();
  });
  for (const id of ['slice-axis', 'slice-pos']) {
    $(id).addEventListener('input', () => {
      updateSliceUniforms(outputBox());
      requestRender();
    });
  }
  $('apply').addEventListener('click', () =>
    run('applying', async () => {
      const t0 = performance.now();
      const poll = setInterval(async () => {
        try {
          const p = await (await fetch('/api/progress', { cache: 'no-store' })).json();
          if (p.busy) setStatus(`applying… ${Math.round(100 * p.fraction)}% ${p.message}`);
        } catch {
          /* the apply's own result reports errors */
        }
      }, 250);
      let s: State;
      try {
        s = await post('/api/apply', recipe());
      } finally {
        clearInterval(poll);
      }
      await loadObject();
      setStatus(`applied in ${(performance.now() - t0).toFixed(0)} ms (server ${s.apply_ms?.toFixed(0)} ms)`);
    }),
  );
  const undo = () => run('undo', async () => { await post('/api/undo'); await loadObject(); setStatus('undone'); });
  const redo = () => run('redo', async () => { await post('/api/redo'); await loadObject(); setStatus('redone'); });
  $('undo').addEventListener('click', undo);
  $('redo').addEventListener('click', redo);
  $('overwrite').addEventListener('change', refreshUI);
  $('save').addEventListener('click', () =>
    run('saving', async () => {
      const s = await post('/api/save', { overwrite: ($('overwrite') as HTMLInputElement).checked });
      state = { ...(state as State), ...s };
      setStatus(`saved ${s.saved}`);
    }),
  );
  window.addEventListener('keydown', (e) => {
    if ((e.target as HTMLElement).tagName === 'INPUT') return;
    if (e.key === 'f' && !e.ctrlKey && !e.metaKey) {
      fitCamera();
      requestRender();
      return;
    }
    if (!(e.ctrlKey || e.metaKey)) return;
    if (e.key.toLowerCase() === 'z') {
      e.preventDefault();
      if (e.shiftKey) redo();
      else undo();
    } else if (e.key.toLowerCase() === 'y') {
      e.preventDefault();
      redo();
    }
  });
}

// -- dragging the planes ----------------------------------------------------------------------
const raycaster = new THREE.Raycaster();
let drag: { name: PlaneName; origin: THREE.Vector3; axis: THREE.Vector3; value0: number } | null = null;

function pointerRay(e: PointerEvent): THREE.Ray {
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(
    ((e.clientX - rect.left) / rect.width) * 2 - 1,
    -((e.clientY - rect.top) / rect.height) * 2 + 1,
  );
  raycaster.setFromCamera(ndc, camera);
  return raycaster.ray;
}

/** Parameter s of the point on line origin + s * axis closest to the ray. */
function closestOnAxis(ray: THREE.Ray, origin: THREE.Vector3, axis: THREE.Vector3): number | null {
  const w0 = origin.clone().sub(ray.origin);
  const b = axis.dot(ray.direction);
  const denom = 1 - b * b;
  if (denom < 1e-6) return null; // looking straight down the axis
  const d = axis.dot(w0);
  const e = ray.direction.dot(w0);
  return (b * e - d) / denom;
}

renderer.domElement.addEventListener('pointerdown', (e) => {
  if (!planeGroup.visible || busy || e.button !== 0) return;
  pointerRay(e);
  const hits = raycaster.intersectObjects([...Object.values(handleMeshes), ...Object.values(planeMeshes)], false);
  if (!hits.length) return;
  // handles win over planes; among planes the nearest
  const hit = hits.find((h) => h.object.userData.plane && handleMeshes[h.object.userData.plane as PlaneName] === h.object) ?? hits[0];
  const name = hit.object.userData.plane as PlaneName;
  const z = zones[active];
  const axis = new THREE.Vector3().setComponent(AXES.indexOf(z.axis), 1);
  const a = AXES.indexOf(z.axis);
  // the drag runs in preview space; the plane's own coordinate comes back through fromPreview
  drag = { name, origin: hit.point.clone(), axis, value0: planeMeshes[name].position.getComponent(a) };
  controls.enabled = false;
  renderer.domElement.setPointerCapture(e.pointerId);
  e.preventDefault();
});

renderer.domElement.addEventListener('pointermove', (e) => {
  if (!drag) return;
  const s = closestOnAxis(pointerRay(e), drag.origin, drag.axis);
  if (s === null) return;
  // keep the zone one apply_recipe accepts: inside the solid, two voxels thick, dest past start
  const z = resolvedZones()[active];
  const h = voxel();
  let v = fromPreview(drag.value0 + s);
  if (drag.name === 'start') v = Math.max(z.lo, Math.min(v, z.end - 2 * h, z.dest - h));
  else if (drag.name === 'end') v = Math.min(z.hi, Math.max(v, z.start + 2 * h));
  else v = Math.max(v, z.start + h);
  setZone({ [drag.name]: v });
});

function endDrag(e: PointerEvent) {
  if (!drag) return;
  drag = null;
  controls.enabled = true;
  if (renderer.domElement.hasPointerCapture(e.pointerId)) renderer.domElement.releasePointerCapture(e.pointerId);
}
renderer.domElement.addEventListener('pointerup', endDrag);
renderer.domElement.addEventListener('pointercancel', endDrag);

// -- hooks for scripts (tests, benchmarks) ----------------------------------------------------
function handleScreen(name: PlaneName): { x: number; y: number } {
  const p = handleMeshes[name].getWorldPosition(new THREE.Vector3()).project(camera);
  const rect = renderer.domElement.getBoundingClientRect();
  return { x: rect.left + ((p.x + 1) / 2) * rect.width, y: rect.top + ((1 - p.y) / 2) * rect.height };
}

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

const api = {
  ready: false,
  get busy() {
    return busy;
  },
  get frameTimeMs() {
    return perf.frameTimeMs;
  },
  get lastFrameMs() {
    return perf.lastFrameMs;
  },
  get frames() {
    return perf.frames;
  },
  /** Loaded, nothing in flight, and the last change has been drawn. */
  get idle() {
    return api.ready && !busy && !renderQueued;
  },
  state: () => state,
  zones: () => resolvedZones(),
  recipe,
  handleScreen,
  /** GLSL toSource() of the shader on points (N, 3) through zones (applied in order). */
  evalRemap: (zs: Zone[], points: number[][]) => {
    const { a, b } = packed(zs);
    return evalRemapOnGPU(renderer, a, b, zs.length, points);
  },
  /** The TypeScript mirror, for comparison. */
  evalRemapTS: (zs: Zone[], points: number[][]) =>
    points.map((p) => {
      const q = [...p];
      for (let i = zs.length - 1; i >= 0; i--) {
        const a = AXES.indexOf(zs[i].axis);
        q[a] = sourceCoordinate(q[a], zs[i]);
      }
      return q;
    }),
  /** Render n frames orbiting the object; mean and median GPU-synchronised frame time in ms. */
  benchmark: (n = 30) => {
    const times: number[] = [];
    const target = controls.target.clone();
    const offset = camera.position.clone().sub(target);
    for (let i = 0; i < n; i++) {
      offset.applyAxisAngle(new THREE.Vector3(0, 1, 0), (2 * Math.PI) / n);
      camera.position.copy(target).add(offset);
      camera.lookAt(target);
      renderNow();
      times.push(perf.lastFrameMs);
    }
    times.sort((x, y) => x - y);
    return { mean: times.reduce((s, t) => s + t, 0) / n, median: times[Math.floor(n / 2)], n };
  },
};
(window as unknown as { __partscale: typeof api }).__partscale = api;

// -- start ------------------------------------------------------------------------------------
function fillSelect(id: string, values: string[]) {
  const sel = $(id) as HTMLSelectElement;
  for (const v of values) sel.add(new Option(v, v));
}
fillSelect('axis', AXES);
fillSelect('mode', MODES);
fillSelect('slice-axis', AXES);
bindUI();
resize();
loadObject()
  .then(() => {
    api.ready = true;
  })
  .catch((e) => setStatus(`loading failed: ${e instanceof Error ? e.message : String(e)}`, true));
