// Runs the page's own TypeScript (web/src) in node, without a browser, for tests/test_browser.py:
// vite's module runner transforms and imports the modules. Usage:
//   node page_node.mjs WEB_DIR CASES.json
// CASES.json: {remap: [{zones, points}], tiles: [[length, target]], rules: [{server, zones}],
//              palette: N}, each key optional. Prints one JSON object with the same keys:
//   remap:   points through the zones back to the source (remap.ts toSource)
//   tiles:   recipe.ts tileCount
//   rules:   the page's resolved zones of a state holding that object header and those zones
//            (state.ts resolvedZones: as applied, lo, hi, snapped dest, problem), the recipe it
//            would send, and (when the case has points) the preview's map of the points back to
//            the loaded object (remap.ts toSource through the valid zones)
//   palette: color.ts paletteColour of 0..N-1
//   lengths: ui.ts formatLength of [[value, units]], as the page shows sizes
//   warps:   warp.ts warpSource on [{edit, points, h}] (a warp's recipe edit): per point the
//            source point and its weight, [x, y, z, w]
//   splice:  grid.ts spliceLayers on [{base, baseShape, shape, channels, delta, body}] (Uint16
//            values), the spliced array
//   memo:    {server, zones, patch}: how many times state.ts resolved the zones while every
//            derived value the page reads is read twice, on that state (first), on one with only
//            the view changed (view), after a set-zone with patch (moved) and with the same
//            object header as a new object (reloaded); and whether the view's resolved zones are
//            the very same array as the first's
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

const web = resolve(process.argv[2]);
const require = createRequire(join(web, 'package.json'));
const { runnerImport } = await import(pathToFileURL(require.resolve('vite')).href);
const load = async (name) =>
  (await runnerImport(join(web, 'src', name), { configFile: false, root: web, logLevel: 'silent' })).module;

const cases = JSON.parse(readFileSync(resolve(process.argv[3]), 'utf8'));
const out = {};
if (cases.remap) {
  const remap = await load('remap.ts');
  out.remap = cases.remap.map(({ zones, points }) => points.map((p) => remap.toSource(zones, p)));
}
if (cases.tiles) {
  const recipe = await load('recipe.ts');
  out.tiles = cases.tiles.map(([length, target]) => recipe.tileCount(length, target));
}
if (cases.rules) {
  const state = await load('state.ts');
  const remap = await load('remap.ts');
  out.rules = cases.rules.map(({ server, zones, points }) => {
    const s = { ...state.initialState, server, zones };
    const valid = state.validZones(s);
    const sources = (points ?? []).map((p) => remap.toSource(valid, p));
    return { zones: state.resolvedZones(s), recipe: state.recipe(s), sources };
  });
}
if (cases.palette) {
  const color = await load('color.ts');
  out.palette = Array.from({ length: cases.palette }, (_, i) => color.paletteColour(i));
}
if (cases.lengths) {
  const ui = await load('ui.ts');
  out.lengths = cases.lengths.map(([v, units]) => ui.formatLength(v, units));
}
if (cases.warps) {
  const warp = await load('warp.ts');
  out.warps = cases.warps.map(({ edit, points, h }) => {
    const w = warp.warpFromEdit(edit);
    return points.map((p) => {
      const [src, weight] = warp.warpSource(w, p, h);
      return [...src, weight];
    });
  });
}
if (cases.splice) {
  const grid = await load('grid.ts');
  out.splice = cases.splice.map((c) =>
    Array.from(grid.spliceLayers(Uint16Array.from(c.base), c.baseShape, c.shape, c.channels, c.delta, Uint16Array.from(c.body))));
}
if (cases.memo) {
  const state = await load('state.ts');
  const { server, zones, patch } = cases.memo;
  const readAll = (s) => {
    const before = state.zoneResolutions();
    for (let k = 0; k < 2; k++) {
      state.resolvedZones(s);
      state.validZones(s);
      state.recipe(s);
      state.isNoop(s);
      state.firstProblem(s);
      state.canApply(s);
      state.outputBounds(s);
      state.targetExtents(s);
      for (const name of state.PLANES) state.previewPlane(s, name);
    }
    return state.zoneResolutions() - before;
  };
  const first = { ...state.initialState, server, zones };
  const view = { ...first, view: { ...first.view, mode: 'parts' } };
  const moved = state.reduce(first, { type: 'set-zone', patch });
  const reloaded = { ...first, server: { ...server } };
  out.memo = {
    first: readAll(first),
    view: readAll(view),
    moved: readAll(moved),
    reloaded: readAll(reloaded),
    sameArray: state.resolvedZones(first) === state.resolvedZones(view),
    movedEnd: state.resolvedZones(moved)[0].end,
    firstEnd: state.resolvedZones(first)[0].end,
  };
}
process.stdout.write(JSON.stringify(out) + '\n');
