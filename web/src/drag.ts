// Dragging the active zone's planes (or their handles) along its axis with the pointer.
import * as THREE from 'three';
import { AXES } from './recipe';
import type { Commands } from './commands';
import type { Scene } from './scene';
import { appliedFromPreview, fromApplied, type PlaneName, resolvedZones, type Store, voxel } from './state';

interface Drag {
  name: PlaneName;
  origin: THREE.Vector3;
  axis: THREE.Vector3;
  value0: number;
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

/** Plane drags on the scene's canvas set the active zone's start, end or destination; with snap
 *  on, the server snaps the zone whenever the pointer rests and when it is released. */
export function bindDrag(store: Store, scene: Scene, commands: Commands): void {
  const { renderer, camera, controls, planeGroup, planeMeshes, handleMeshes } = scene;
  const canvas = renderer.domElement;
  const raycaster = new THREE.Raycaster();
  const current: { drag: Drag | null } = { drag: null };

  function pointerRay(e: PointerEvent): THREE.Ray {
    const rect = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(
      ((e.clientX - rect.left) / rect.width) * 2 - 1,
      -((e.clientY - rect.top) / rect.height) * 2 + 1,
    );
    raycaster.setFromCamera(ndc, camera);
    return raycaster.ray;
  }

  canvas.addEventListener('pointerdown', (e) => {
    const s = store.get();
    const z = s.zones[s.active];
    if (!z || !planeGroup.visible || s.busy || e.button !== 0) return;
    pointerRay(e);
    const handles = Object.values(handleMeshes);
    const hits = raycaster.intersectObjects([...handles, ...Object.values(planeMeshes)], false);
    if (!hits.length) return;
    // handles win over planes; among planes the nearest
    const hit = hits.find((h) => handles.includes(h.object as THREE.Mesh)) ?? hits[0];
    const name = hit.object.userData.plane as PlaneName;
    const a = AXES.indexOf(z.axis);
    const axis = new THREE.Vector3().setComponent(a, 1);
    // the drag runs in preview space; the plane's own coordinate comes back through fromPreview
    current.drag = { name, origin: hit.point.clone(), axis, value0: planeMeshes[name].position.getComponent(a) };
    controls.enabled = false;
    canvas.setPointerCapture(e.pointerId);
    e.preventDefault();
  });

  canvas.addEventListener('pointermove', (e) => {
    const drag = current.drag;
    if (!drag) return;
    const t = closestOnAxis(pointerRay(e), drag.origin, drag.axis);
    if (t === null) return;
    // keep the zone one apply_recipe accepts: inside the solid, two voxels thick, dest past start
    // (checked as it applies: in the frame the earlier zones on its axis leave)
    const s = store.get();
    const z = resolvedZones(s)[s.active];
    const h = voxel(s);
    let v = appliedFromPreview(s, drag.value0 + t);
    if (drag.name === 'start') v = Math.max(z.lo, Math.min(v, z.end - 2 * h, z.dest - h));
    else if (drag.name === 'end') v = Math.min(z.hi, Math.max(v, z.start + 2 * h));
    else v = Math.max(v, z.start + h);
    store.dispatch({ type: 'set-zone', patch: { [drag.name]: fromApplied(s, drag.name, v) } });
    if (s.snap) void commands.snapActive();
  });

  function endDrag(e: PointerEvent) {
    if (!current.drag) return;
    current.drag = null;
    controls.enabled = true;
    if (canvas.hasPointerCapture(e.pointerId)) canvas.releasePointerCapture(e.pointerId);
    if (store.get().snap) void commands.snapActive();
  }
  canvas.addEventListener('pointerup', endDrag);
  canvas.addEventListener('pointercancel', endDrag);
}
