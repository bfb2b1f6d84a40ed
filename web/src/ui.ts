// The side panel (index.html): shows the state, and turns the user's input into store actions
// and commands. Nothing here holds state of its own.
import type { Candidate } from './api';
import type { Commands } from './commands';
import { AXES, type Axis, type Mode, MODES, tileCount, type Zone } from './recipe';
import { MAX_ZONES } from './remap';
import {
  type AppState,
  canApply,
  extents,
  firstProblem,
  isNoop,
  PLANES,
  resolvedZones,
  solidBounds,
  type Store,
  targetExtents,
  type Units,
  type ViewMode,
  voxel,
} from './state';
import { type Warp, type WarpKind, warpFromEdit } from './warp';

const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;

export function fmt(v: number): string {
  return Number.isFinite(v) ? String(Number(v.toPrecision(6))) : '';
}

/** The loaded solid's extent along the axis: % positions are of it, as in a recipe. */
function extent(s: AppState, axis: Axis): [number, number] {
  const [lo, hi] = solidBounds(s);
  const a = AXES.indexOf(axis);
  return [lo[a], hi[a]];
}

/** A length for people: in an object in metres, metres from 1 m up and centimetres below (to the
 *  millimetre); in other units, the number and the unit's name (nothing converted). */
export function formatLength(v: number, units: string): string {
  if (units !== 'm') return `${fmt(v)} ${units}`.trim();
  return Math.abs(v) >= 1 ? `${v.toFixed(3)} m` : `${(100 * v).toFixed(1)} cm`;
}

function toDisplay(v: number, [lo, hi]: [number, number], units: Units): number {
  return units === '%' ? ((v - lo) / (hi - lo)) * 100 : v;
}

function fromDisplay(v: number, [lo, hi]: [number, number], units: Units): number {
  return units === '%' ? lo + (v / 100) * (hi - lo) : v;
}

function candidateLabel(c: Candidate, units: string): string {
  const span = `${fmt(c.zone[0])}–${fmt(c.zone[1])} ${units}`;
  return c.kind === 'tile' ? `tile ${span}, period ${fmt(c.period ?? 0)} ×${c.count}` : `stretch ${span}`;
}

/** A "−1" or "+1" button: n whole elements along the axis (POST /api/add), previewed. */
function countButton(axis: Axis, n: number): HTMLButtonElement {
  const b = document.createElement('button');
  b.id = `count-${axis}-${n > 0 ? 'plus' : 'minus'}`;
  b.className = 'count';
  b.dataset.axis = axis;
  b.dataset.n = String(n);
  b.textContent = n > 0 ? `+${n}` : `−${-n}`;
  return b;
}

/** Per axis, a ruler over the solid's extent with one clickable band per candidate, and the
 *  count buttons (one element fewer or more). */
function renderSuggestions(s: AppState) {
  const box = $('suggestions');
  box.innerHTML = '';
  if (!s.server) return;
  const units = s.server.units;
  for (const axis of AXES) {
    const row = document.createElement('div');
    row.className = 'axis-row';
    const name = document.createElement('span');
    name.className = 'ruler-axis';
    name.textContent = axis;
    const ruler = document.createElement('div');
    ruler.className = 'ruler';
    row.append(name, ruler, countButton(axis, -1), countButton(axis, 1));
    box.appendChild(row);
    if (s.suggestions === null) {
      ruler.textContent = 'looking…';
      continue;
    }
    const found = s.suggestions.filter((c) => c.axis === axis);
    if (!found.length) ruler.textContent = 'no zone found';
    const [lo, hi] = extent(s, axis);
    found.forEach((c, i) => {
      const band = document.createElement('button');
      band.id = `suggest-${axis}-${i}`;
      band.className = `band ${c.kind}`;
      band.dataset.axis = axis;
      band.dataset.index = String(i);
      band.style.left = `${(100 * (c.zone[0] - lo)) / (hi - lo)}%`;
      band.style.width = `${(100 * (c.zone[1] - c.zone[0])) / (hi - lo)}%`;
      band.title = `${candidateLabel(c, units)} (score ${fmt(c.score)}): ${c.reason}`;
      band.textContent = c.kind;
      ruler.appendChild(band);
    });
  }
}

/** The count buttons: enabled where the axis has a repeat group, the tooltip says why not. */
function markCountButtons(s: AppState) {
  document.querySelectorAll<HTMLButtonElement>('#suggestions .count').forEach((b) => {
    const axis = b.dataset.axis as Axis;
    const n = Number(b.dataset.n);
    const found = s.elements?.find((e) => e.axis === axis);
    const group = found?.groups[0];
    const more = n > 0 ? `${n} more` : `${-n} fewer`;
    if (s.elements === null) b.title = `${more} along ${axis}: looking for elements…`;
    else if (!group) {
      b.title =
        `${more} along ${axis}: no repeated element along ${axis} (a seat, a door, a shelf row, ` +
        'a drawer); resize by length instead (a zone, or a size below)';
    } else b.title = `${more} element${Math.abs(n) === 1 ? '' : 's'} along ${axis} (${found.summary}): previewed, Apply makes it`;
    b.disabled = s.busy || !group;
  });
}

/** The solid's size per axis and, while zones preview a change, the size they make. */
function renderSizes(s: AppState) {
  const units = s.server?.units ?? '';
  const now = extents(s);
  const target = targetExtents(s);
  AXES.forEach((axis, a) => {
    $(`extent-${axis}`).textContent = s.server ? formatLength(now[a], units) : '';
    const changed = target !== null && Math.abs(target[a] - now[a]) > voxel(s) / 4;
    $(`target-${axis}`).textContent = changed ? `→ ${formatLength(target[a], units)}` : '';
  });
}

/** The band of the active zone's own candidate, if it is one. */
function markActiveBand(s: AppState) {
  const z = s.zones[s.active];
  document.querySelectorAll<HTMLButtonElement>('#suggestions .band').forEach((band) => {
    const c = s.suggestions?.filter((k) => k.axis === band.dataset.axis)[Number(band.dataset.index)];
    band.classList.toggle('active', !!z && !!c && c.axis === z.axis && c.kind === z.mode && c.zone[0] === z.start && c.zone[1] === z.end);
    band.disabled = s.busy;
  });
}

function zoneSummary(z: Zone, units: string): string {
  const length = z.end - z.start;
  const target = z.dest - z.start;
  const delta = `${z.dest >= z.end ? '+' : '−'}${fmt(Math.abs(z.dest - z.end))} ${units}`;
  if (z.mode === 'global') return `whole object ×${fmt((z.hi - z.lo + z.dest - z.end) / (z.hi - z.lo))} (${delta})`;
  if (z.mode === 'tile') {
    const n = tileCount(length, target);
    if (n === 0) return `tile 0 copies: zone of ${fmt(length)} ${units} removed (${delta})`;
    return `${n} cop${n === 1 ? 'y' : 'ies'} of ${fmt(length)} ${units}, each ×${fmt(target / (n * length))} (${delta})`;
  }
  return `zone ×${fmt(target / length)} (${delta})`;
}

function renderStatus(s: AppState) {
  const status = $('status');
  status.textContent = s.status.message;
  status.classList.toggle('error', s.status.error);
}

/** The object's warp zones as buttons: its radial plan, each flight and spiral (one more step),
 *  each ring or arc of elements about the vertical (one more element). */
function renderWarpFound(s: AppState) {
  const box = $('warp-found');
  box.innerHTML = '';
  if (!s.server) return;
  const found = s.warps;
  if (found === null) {
    box.textContent = 'looking…';
    return;
  }
  const units = s.server.units;
  const button = (id: string, text: string, title: string) => {
    const b = document.createElement('button');
    b.id = id;
    b.className = 'warp-candidate';
    b.textContent = text;
    b.title = title;
    box.appendChild(b);
  };
  const r = found.radial;
  if (r?.edit) {
    const shape = r.sides ? `${r.sides}-sided` : 'round';
    const [r0, r1] = r.annuli[0];
    button('warp-radial', `radial: ${shape} plan`, `about ${r.axis} through ${fmt(r.center[0])}, ${fmt(r.center[1])} ${units}; annulus ${fmt(r0)}–${fmt(r1)} ${units} (constant radial section): set its target radius`);
  }
  found.steps.forEach((k, i) =>
    button(`warp-step-${i}`, `steps along ${k.axis}: +1`, `${k.count} steps of ${fmt(k.going)} going and ${fmt(k.rise)} rise ${units} (${Math.round(100 * k.support)}% of the surface repeats)`),
  );
  found.helix.forEach((k, i) =>
    button(`warp-helix-${i}`, 'spiral steps: +1', `${k.count} steps each turning ${fmt(k.angle)}° and rising ${fmt(k.rise)} ${units} (${Math.round(100 * k.support)}% of the surface repeats)`),
  );
  found.rotation.forEach((k, i) =>
    button(
      `warp-rotation-${i}`,
      `${k.closed ? 'ring' : 'arc'} of ${k.count}: +1`,
      `${k.count} elements ${fmt(Math.abs(k.angle))}° apart about the vertical through ${fmt(k.center[0])}, ${fmt(k.center[1])} ${units}, ` +
        `${k.closed ? 'a closed ring (spaced evenly again)' : 'an open arc (continued)'}; the hub within ${fmt(k.hub)} ${units} stays (${Math.round(100 * k.support)}% of the surface repeats)`,
    ),
  );
  if (!box.children.length) box.textContent = 'no round plan, flight, spiral or ring found';
}

/** The shaped zone's fields: those of its kind shown, each with its value. */
function renderWarp(s: AppState) {
  const w = s.warp;
  ($('warp-kind') as HTMLSelectElement).value = w?.kind ?? '';
  document.querySelectorAll<HTMLElement>('.warp-field').forEach((el) => {
    el.hidden = !w || !(el.dataset.kinds ?? '').split(' ').includes(w.kind);
  });
  const set = (id: string, v: string) => {
    const input = $(id) as HTMLInputElement;
    if (document.activeElement !== input) input.value = v;
  };
  if (w?.kind === 'radial') {
    $('warp-start-label').textContent = 'R0';
    $('warp-end-label').textContent = 'R1';
    set('warp-start', fmt(w.r0));
    set('warp-end', fmt(w.r1));
    set('warp-to', fmt(w.to));
  } else if (w?.kind === 'oblique') {
    $('warp-start-label').textContent = 'start';
    $('warp-end-label').textContent = 'end';
    set('warp-normal', w.normal.map(fmt).join(' '));
    set('warp-start', fmt(w.s0));
    set('warp-end', fmt(w.s1));
    set('warp-to', fmt(w.to));
  } else if (w) {
    $('warp-copies-label').textContent = w.kind === 'rotation' ? 'elements' : 'steps';
    set('warp-copies', String(w.copies));
  }
  const info = $('warp-info');
  const problem = firstProblem(s);
  info.textContent = !w ? '' : problem ? `invalid: ${problem.message}` : isNoop(s) ? 'no change yet: set the target' : warpSummary(w, s.server?.units ?? '');
  info.classList.toggle('error', !!w && problem !== null);
  ($('warp-apply') as HTMLButtonElement).disabled = !w || !canApply(s);
  document.querySelectorAll<HTMLButtonElement>('#warp-found button').forEach((b) => (b.disabled = s.busy));
}

function warpSummary(w: Warp, units: string): string {
  switch (w.kind) {
    case 'radial':
      return `annulus ${fmt(w.r0)}–${fmt(w.r1)} → ${fmt(w.r0)}–${fmt(w.to)} ${units} (outline ${w.to >= w.r1 ? '+' : '−'}${fmt(Math.abs(w.to - w.r1))})`;
    case 'oblique':
      return `slab ×${fmt((w.to - w.s0) / (w.s1 - w.s0))} along (${w.normal.map(fmt).join(', ')})`;
    case 'screw':
      return `${w.copies > 0 ? '+' : '−'}${Math.abs(w.copies)} step${Math.abs(w.copies) === 1 ? '' : 's'} of (${w.step.map(fmt).join(', ')}) ${units} beyond ${w.axis} = ${fmt(w.cut)}`;
    case 'helix':
      return `${w.copies > 0 ? '+' : '−'}${Math.abs(w.copies)} step${Math.abs(w.copies) === 1 ? '' : 's'} turning ${fmt(w.angle)}° and rising ${fmt(w.rise)} ${units} above ${fmt(w.cut)}`;
    case 'rotation': {
      const k = w.count + w.copies;
      const spacing = w.closed ? `spaced evenly every ${fmt(360 / k)}°` : `${fmt(Math.abs(w.angle))}° apart`;
      return `${w.copies > 0 ? '+' : '−'}${Math.abs(w.copies)} element${Math.abs(w.copies) === 1 ? '' : 's'}: ${k} of the ${w.closed ? 'ring' : 'arc'}, ${spacing}`;
    }
  }
}

const drawn: {
  suggestions: AppState['suggestions'] | undefined;
  server: AppState['server'] | undefined;
  warps: AppState['warps'] | undefined;
} = {
  suggestions: undefined,
  server: undefined,
  warps: undefined,
};

function render(s: AppState) {
  renderStatus(s);
  const newServer = s.server !== drawn.server;
  if (s.suggestions !== drawn.suggestions || newServer) {
    renderSuggestions(s);
    drawn.suggestions = s.suggestions;
    drawn.server = s.server;
  }
  if (s.warps !== drawn.warps || newServer) {
    renderWarpFound(s);
    drawn.warps = s.warps;
  }
  renderWarp(s);
  markActiveBand(s);
  markCountButtons(s);
  renderSizes(s);
  ($('snap') as HTMLInputElement).checked = s.snap;
  ($('allow-deform') as HTMLInputElement).checked = s.fit.allowDeform;
  AXES.forEach((axis, i) => {
    const input = $(`size-${axis}`) as HTMLInputElement;
    if (document.activeElement !== input) input.value = s.fit.size[i];
  });
  const why = $('size-why');
  why.innerHTML = '';
  if (s.fit.refused) {
    const li = document.createElement('li');
    li.className = 'error';
    li.id = 'size-refused';
    li.textContent = s.fit.refused;
    why.appendChild(li);
  }
  for (const line of s.fit.why) {
    const li = document.createElement('li');
    li.textContent = line;
    why.appendChild(li);
  }
  ($('size-preview') as HTMLButtonElement).disabled = s.busy || !s.server;
  ($('size-apply') as HTMLButtonElement).disabled = s.busy || !s.server;
  const server = s.server;
  ($('units') as HTMLSelectElement).value = s.units;
  ($('view-mode') as HTMLSelectElement).value = s.view.mode;
  $('slice-controls').hidden = s.view.mode !== 'slice';
  ($('overwrite') as HTMLInputElement).checked = s.overwrite;
  const zoneSel = $('zone') as HTMLSelectElement;
  zoneSel.innerHTML = '';
  s.zones.forEach((_, i) => zoneSel.add(new Option(`zone ${i + 1}`, String(i))));
  zoneSel.value = String(s.active);
  const z = resolvedZones(s)[s.active];
  if (z) {
    ($('axis') as HTMLSelectElement).value = z.axis;
    ($('mode') as HTMLSelectElement).value = z.mode;
    const given = s.zones[s.active];
    for (const name of PLANES) {
      const input = $(`pos-${name}`) as HTMLInputElement;
      if (document.activeElement !== input) input.value = fmt(toDisplay(given[name], extent(s, z.axis), s.units));
    }
    const problem = firstProblem(s);
    $('zone-info').textContent = s.warp
      ? 'off: the shaped zone below is previewed instead'
      : problem
        ? `invalid: ${problem.message}`
        : isNoop(s)
          ? 'no change yet: move the destination plane'
          : zoneSummary(z, server?.units ?? '');
    $('zone-info').classList.toggle('error', !s.warp && problem !== null);
  }
  const unitLabel = s.units === '%' ? '%' : server?.units ?? '';
  document.querySelectorAll('.unit').forEach((el) => (el.textContent = unitLabel));
  ($('apply') as HTMLButtonElement).disabled = !canApply(s);
  ($('undo') as HTMLButtonElement).disabled = s.busy || !server?.can_undo;
  ($('redo') as HTMLButtonElement).disabled = s.busy || !server?.can_redo;
  ($('save') as HTMLButtonElement).disabled = s.busy || !server;
  ($('add-zone') as HTMLButtonElement).disabled = s.busy || s.zones.length >= MAX_ZONES;
  ($('remove-zone') as HTMLButtonElement).disabled = s.busy || s.zones.length <= 1;
  const partsOpt = ($('view-mode') as HTMLSelectElement).querySelector('option[value="parts"]') as HTMLOptionElement;
  partsOpt.disabled = !server || server.n_parts === 0;
  partsOpt.textContent = server && server.n_parts > 0 ? `parts (${server.n_parts})` : 'parts (not segmented)';
  $('grid-info').textContent = server
    ? `${server.shape.join(' × ')} voxels of ${fmt(server.voxel_size)} ${server.units}${server.unsaved ? ' · unsaved' : ''}`
    : '';
  $('save-as').textContent = s.overwrite ? server?.name ?? '' : server?.save_as ?? '';
}

function fillSelect(id: string, values: readonly string[]) {
  const sel = $(id) as HTMLSelectElement;
  for (const v of values) sel.add(new Option(v, v));
}

/** Send the user's input to the store and to commands. */
export function bindPanel(store: Store, commands: Commands): void {
  fillSelect('axis', AXES);
  fillSelect('mode', MODES);
  fillSelect('slice-axis', AXES);
  const dispatch = store.dispatch;
  const selectValue = (e: Event) => (e.target as HTMLSelectElement).value;

  $('zone').addEventListener('change', (e) => dispatch({ type: 'select-zone', index: Number(selectValue(e)) }));
  $('add-zone').addEventListener('click', () => dispatch({ type: 'add-zone' }));
  $('remove-zone').addEventListener('click', () => dispatch({ type: 'remove-zone' }));
  $('axis').addEventListener('change', (e) => dispatch({ type: 'set-axis', axis: selectValue(e) as Axis }));
  $('mode').addEventListener('change', (e) => dispatch({ type: 'set-zone', patch: { mode: selectValue(e) as Mode } }));
  $('units').addEventListener('change', (e) => dispatch({ type: 'set-units', units: selectValue(e) as Units }));
  for (const name of PLANES) {
    const input = $(`pos-${name}`) as HTMLInputElement;
    const commit = () => {
      const v = Number(input.value);
      if (input.value.trim() === '' || !Number.isFinite(v)) return;
      const s = store.get();
      const z = s.zones[s.active];
      if (z) dispatch({ type: 'set-zone', patch: { [name]: fromDisplay(v, extent(s, z.axis), s.units) } });
    };
    input.addEventListener('input', commit);
    input.addEventListener('change', () => {
      commit();
      const s = store.get();
      const z = s.zones[s.active];
      if (z) input.value = fmt(toDisplay(z[name], extent(s, z.axis), s.units));
    });
  }
  $('reset-zone').addEventListener('click', () => dispatch({ type: 'reset-zone' }));
  $('snap').addEventListener('change', (e) => {
    const on = (e.target as HTMLInputElement).checked;
    dispatch({ type: 'set-snap', snap: on });
    if (on) void commands.snapActive();
  });
  $('suggestions').addEventListener('click', (e) => {
    const count = (e.target as HTMLElement).closest<HTMLButtonElement>('.count');
    if (count) {
      if (!count.disabled) void commands.previewCount(count.dataset.axis as Axis, Number(count.dataset.n));
      return;
    }
    const band = (e.target as HTMLElement).closest<HTMLButtonElement>('.band');
    const s = store.get();
    const c = band && s.suggestions?.filter((k) => k.axis === band.dataset.axis)[Number(band.dataset.index)];
    if (c && !s.busy) {
      dispatch({ type: 'use-candidate', candidate: c });
      dispatch({ type: 'set-status', message: `${c.kind} zone along ${c.axis}: ${c.reason}` });
    }
  });
  AXES.forEach((axis, i) => {
    $(`size-${axis}`).addEventListener('input', (e) =>
      dispatch({ type: 'set-fit-size', axis: i, value: (e.target as HTMLInputElement).value.trim() || '=' }),
    );
  });
  $('size-preview').addEventListener('click', () => void commands.previewFit());
  $('allow-deform').addEventListener('change', (e) => {
    dispatch({ type: 'set-allow-deform', allowDeform: (e.target as HTMLInputElement).checked });
    // a size asked: fit it again, allowed to deform or not
    if (store.get().fit.size.some((v) => v !== '=')) void commands.previewFit();
  });
  $('size-apply').addEventListener('click', async () => {
    if (await commands.previewFit()) await commands.apply();
  });
  $('fit').addEventListener('click', commands.fit);
  $('view-mode').addEventListener('change', (e) =>
    dispatch({ type: 'set-view', view: { mode: selectValue(e) as ViewMode } }),
  );
  $('slice-axis').addEventListener('input', (e) =>
    dispatch({ type: 'set-view', view: { sliceAxis: selectValue(e) as Axis } }),
  );
  $('slice-pos').addEventListener('input', (e) =>
    dispatch({ type: 'set-view', view: { slicePos: Number((e.target as HTMLInputElement).value) } }),
  );
  $('apply').addEventListener('click', () => void commands.apply());
  bindWarp(store, commands);
  $('undo').addEventListener('click', () => void commands.undo());
  $('redo').addEventListener('click', () => void commands.redo());
  $('overwrite').addEventListener('change', (e) =>
    dispatch({ type: 'set-overwrite', overwrite: (e.target as HTMLInputElement).checked }),
  );
  $('save').addEventListener('click', () => void commands.save());
  window.addEventListener('keydown', (e) => {
    if ((e.target as HTMLElement).tagName === 'INPUT') return;
    if (e.key === 'f' && !e.ctrlKey && !e.metaKey) {
      commands.fit();
      return;
    }
    if (!(e.ctrlKey || e.metaKey)) return;
    if (e.key.toLowerCase() === 'z') {
      e.preventDefault();
      void (e.shiftKey ? commands.redo() : commands.undo());
    } else if (e.key.toLowerCase() === 'y') {
      e.preventDefault();
      void commands.redo();
    }
  });
}

/** Draw the panel from the store's state from now on (a status change redraws only the status). */
export function showPanel(store: Store): void {
  store.subscribe((s, prev) => {
    const { status, ...rest } = s;
    const { status: prevStatus, ...prevRest } = prev;
    const others = (Object.keys(rest) as (keyof typeof rest)[]).some((k) => rest[k] !== prevRest[k]);
    if (others) render(s);
    else if (status !== prevStatus) renderStatus(s);
  });
  render(store.get());
}

/** The shaped zone's panel: the kind, its fields, the object's own warp zones, Apply. */
function bindWarp(store: Store, commands: Commands) {
  const dispatch = store.dispatch;
  $('warp-kind').addEventListener('change', (e) => {
    const kind = (e.target as HTMLSelectElement).value;
    dispatch({ type: 'set-warp-kind', kind: kind === '' ? null : (kind as WarpKind) });
  });
  const numberField = (id: string, key: (w: Warp) => string | null, integer = false) => {
    const input = $(id) as HTMLInputElement;
    input.addEventListener('input', () => {
      const w = store.get().warp;
      const v = Number(input.value);
      const k = w && key(w);
      if (!k || input.value.trim() === '' || !Number.isFinite(v) || (integer && !Number.isInteger(v))) return;
      dispatch({ type: 'patch-warp', patch: { [k]: v } });
    });
  };
  numberField('warp-start', (w) => (w.kind === 'radial' ? 'r0' : w.kind === 'oblique' ? 's0' : null));
  numberField('warp-end', (w) => (w.kind === 'radial' ? 'r1' : w.kind === 'oblique' ? 's1' : null));
  numberField('warp-to', (w) => (w.kind === 'radial' || w.kind === 'oblique' ? 'to' : null));
  numberField('warp-copies', (w) => (w.kind === 'screw' || w.kind === 'helix' || w.kind === 'rotation' ? 'copies' : null), true);
  $('warp-normal').addEventListener('input', (e) => {
    const v = (e.target as HTMLInputElement).value.trim().split(/[\s,]+/).map(Number);
    if (v.length === 3 && v.every(Number.isFinite) && store.get().warp?.kind === 'oblique') {
      dispatch({ type: 'patch-warp', patch: { normal: v } });
    }
  });
  $('warp-found').addEventListener('click', (e) => {
    const b = (e.target as HTMLElement).closest<HTMLButtonElement>('button');
    const s = store.get();
    if (!b || s.busy || !s.warps) return;
    const [, kind, index] = b.id.split('-');
    const w =
      kind === 'radial' && s.warps.radial?.edit
        ? warpFromEdit(s.warps.radial.edit)
        : kind === 'step'
          ? warpFromEdit(s.warps.steps[Number(index)].edit, s.warps.steps[Number(index)].ground)
          : kind === 'helix'
            ? warpFromEdit(s.warps.helix[Number(index)].edit)
            : kind === 'rotation'
              ? warpFromEdit(s.warps.rotation[Number(index)].edit)
              : null;
    if (w) {
      dispatch({ type: 'set-warp', warp: w });
      dispatch({ type: 'set-status', message: `${b.textContent}: ${b.title}` });
    }
  });
  $('warp-apply').addEventListener('click', () => void commands.apply());
}
