// The side panel (index.html): shows the state, and turns the user's input into store actions
// and commands. Nothing here holds state of its own.
import type { Commands } from './commands';
import { AXES, type Axis, type Mode, MODES, tileCount, type Zone } from './recipe';
import { MAX_ZONES } from './remap';
import {
  type AppState,
  canApply,
  firstProblem,
  isNoop,
  PLANES,
  resolvedZones,
  type Store,
  type Units,
  type ViewMode,
} from './state';

const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;

export function fmt(v: number): string {
  return Number.isFinite(v) ? String(Number(v.toPrecision(6))) : '';
}

function toDisplay(v: number, z: Zone, units: Units): number {
  return units === '%' ? ((v - z.lo) / (z.hi - z.lo)) * 100 : v;
}

function fromDisplay(v: number, z: Zone, units: Units): number {
  return units === '%' ? z.lo + (v / 100) * (z.hi - z.lo) : v;
}

function zoneSummary(z: Zone, units: string): string {
  const length = z.end - z.start;
  const target = z.dest - z.start;
  const delta = `${z.dest >= z.end ? '+' : '−'}${fmt(Math.abs(z.dest - z.end))} ${units}`;
  if (z.mode === 'global') return `whole object ×${fmt((z.hi - z.lo + z.dest - z.end) / (z.hi - z.lo))} (${delta})`;
  if (z.mode === 'tile') {
    const n = tileCount(length, target);
    return `${n} cop${n === 1 ? 'y' : 'ies'} of ${fmt(length)} ${units}, each ×${fmt(target / (n * length))} (${delta})`;
  }
  return `zone ×${fmt(target / length)} (${delta})`;
}

function renderStatus(s: AppState) {
  const status = $('status');
  status.textContent = s.status.message;
  status.classList.toggle('error', s.status.error);
}

function render(s: AppState) {
  renderStatus(s);
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
    for (const name of PLANES) {
      const input = $(`pos-${name}`) as HTMLInputElement;
      if (document.activeElement !== input) input.value = fmt(toDisplay(z[name], z, s.units));
    }
    const problem = firstProblem(s);
    $('zone-info').textContent = problem
      ? `invalid: ${problem.message}`
      : isNoop(s)
        ? 'no change yet: move the destination plane'
        : zoneSummary(z, server?.units ?? '');
    $('zone-info').classList.toggle('error', problem !== null);
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
      const z = resolvedZones(s)[s.active];
      if (z) dispatch({ type: 'set-zone', patch: { [name]: fromDisplay(v, z, s.units) } });
    };
    input.addEventListener('input', commit);
    input.addEventListener('change', () => {
      commit();
      const s = store.get();
      const z = resolvedZones(s)[s.active];
      if (z) input.value = fmt(toDisplay(s.zones[s.active][name], z, s.units));
    });
  }
  $('reset-zone').addEventListener('click', () => dispatch({ type: 'reset-zone' }));
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
