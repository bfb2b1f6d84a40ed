// Drives the editor page in headless Chromium (playwright-core) for tests/test_browser.py and
// bench/bench_editor.py. Usage: node editor.mjs '<json args>'; prints one JSON result line.
//
// args (the JSON, or @FILE): { url, chromium, web (folder with node_modules), out (folder), reference (png path or
//         null), updateReference, canvas: [w, h], remapCases, zone: {axis, start, end, dest},
//         benchmark: n frames (only load + benchmark when set), features: {snapZone, fitSize}
//         (suggestion click, snap toggle, fit preview/apply/undo),
//         limits: true (only load, an apply beyond the GPU's 3D texture size, and a page of
//         another name, evil.example, resolved to this server: DNS rebinding),
//         count: {axis, other} (only load, then +1 element along axis: preview, apply, undo;
//         then -1 previewed; other: an axis with no repeat, its buttons read),
//         refusal: {size} (only load, a fit refused, then allowed to deform: previewed),
//         shaped: {button | kind, fields, to, warpCases} (only load; the warp GLSL on warpCases
//         [{edit, points, h}]; a click on the shaped-zone button (#warp-radial, #warp-step-0),
//         or the kind chosen, draws it; fields {selector: value} are typed, then `to` (radial)
//         sets its target; previewed, applied, undone; fitSize: then a fit previewed),
//         plain: true (the page as users get it, without ?capture=1: load, drag the end plane,
//         orbit; the drawing buffer's attribute, frames drawn, pixels read back, zone
//         resolutions per pointer move),
//         picture: {camera, unlit} (only load, then the object alone, without the guides, from
//         camera (the hooks' setCamera: position, target, up, fov, near, far), unlit if asked:
//         picture.png, to compare with partscale.render's) }
// Every other run loads the page with ?capture=1 (its canvas readable, frames GPU-timed).
import { createRequire } from 'node:module';
import { existsSync, readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { pathToFileURL } from 'node:url';

// the JSON, or @FILE holding it (a long one: one argument holds at most 128 KiB)
const args = JSON.parse(process.argv[2].startsWith('@') ? readFileSync(process.argv[2].slice(1), 'utf8') : process.argv[2]);
const require = createRequire(join(args.web, 'package.json'));
const load = async (name) => import(pathToFileURL(require.resolve(name)).href);
const pick = (mod, name) => mod[name] ?? mod.default?.[name];
const chromium = pick(await load('playwright-core'), 'chromium');
const pixelmatch = (await load('pixelmatch')).default;
const PNG = pick(await load('pngjs'), 'PNG');

const result = { errors: [], steps: [] };
const [W, H] = args.canvas ?? [480, 360];
const browser = await chromium.launch({
  executablePath: args.chromium,
  headless: true,
  args: [
    '--no-sandbox',
    '--use-angle=swiftshader',
    '--enable-unsafe-swiftshader',
    '--ignore-gpu-blocklist',
    '--disable-gpu-vsync',
    '--force-color-profile=srgb',
    // a foreign name resolving to this machine, as DNS rebinding makes it (for args.limits)
    '--host-resolver-rules=MAP evil.example 127.0.0.1',
  ],
});

function diffPixels(a, b) {
  const pa = PNG.sync.read(a);
  const pb = PNG.sync.read(b);
  if (pa.width !== pb.width || pa.height !== pb.height) return { count: -1, total: pa.width * pa.height };
  const diff = new PNG({ width: pa.width, height: pa.height });
  const count = pixelmatch(pa.data, pb.data, diff.data, pa.width, pa.height, { threshold: 0.1 });
  return { count, total: pa.width * pa.height, diff: PNG.sync.write(diff) };
}

try {
  const context = await browser.newContext({
    viewport: { width: W + 260, height: H },
    deviceScaleFactor: 1,
    acceptDownloads: true,
  });
  const page = await context.newPage();
  page.on('console', (m) => {
    if (m.type() === 'error') result.errors.push(m.text());
  });
  page.on('pageerror', (e) => result.errors.push(String(e)));
  const idle = async () => {
    await page.waitForFunction(() => window.__partscale?.idle === true, null, { timeout: 60000 });
    // one more frame so the canvas holds the latest state
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  };
  const shot = async (name) => {
    // the canvas's own pixels (kept by ?capture=1), without the HTML overlay on top of it
    const url = await page.evaluate(() => document.querySelector('#view canvas').toDataURL('image/png'));
    const png = Buffer.from(url.slice(url.indexOf(',') + 1), 'base64');
    writeFileSync(join(args.out, name), png);
    return png;
  };

  if (args.plain) {
    // count every pixel read back from WebGL, from the first frame on
    await page.addInitScript(() => {
      window.__readPixels = 0;
      for (const C of [WebGLRenderingContext, WebGL2RenderingContext]) {
        const read = C.prototype.readPixels;
        C.prototype.readPixels = function (...a) {
          window.__readPixels += 1;
          return read.apply(this, a);
        };
      }
    });
  }
  const t0 = Date.now();
  await page.goto(`${args.url}?canvas=${W}x${H}${args.plain ? '' : '&capture=1'}`);
  await idle();
  result.loadMs = Date.now() - t0;
  result.state0 = await page.evaluate(() => window.__partscale.state());
  result.zone0 = await page.evaluate(() => window.__partscale.zones()[0]);

  const text = (sel) => page.textContent(sel);
  const sizesText = async () => {
    const out = {};
    for (const a of ['x', 'y', 'z']) out[a] = { extent: await text(`#extent-${a}`), target: await text(`#target-${a}`) };
    return out;
  };
  const revisionAbove = (r) =>
    page.waitForFunction((rr) => window.__partscale.state()?.revision > rr, r, { timeout: 60000 });

  if (args.shaped) {
    // a shaped zone (radial, steps): drawn, previewed (nothing applied), applied, undone
    const { button, kind, fields, to, warpCases } = args.shaped;
    const sh = {};
    const hooks = (fn, arg) => page.evaluate(fn, arg);
    const bare = async (name) => {
      // the object alone, without the guides drawn over it (planes, rings, arrows, box)
      await hooks(() => window.__partscale.setGuides(false));
      await idle();
      const png = await shot(name);
      await hooks(() => window.__partscale.setGuides(true));
      await idle();
      return png;
    };
    sh.warps = await hooks(() => window.__partscale.warps());
    if (warpCases) {
      sh.remap = await hooks((cases) => cases.map((c) => ({
        glsl: window.__partscale.evalWarp(c.edit, c.points, c.h),
        ts: window.__partscale.evalWarpTS(c.edit, c.points, c.h),
      })), warpCases);
    }
    const initial = await shot('shaped-initial.png');
    const initialBare = await bare('shaped-initial-bare.png');
    if (button) await page.click(button);
    else await page.selectOption('#warp-kind', kind);
    await idle();
    sh.drawn = await hooks(() => window.__partscale.warp());
    for (const [sel, v] of Object.entries(fields ?? {})) await page.fill(sel, String(v));
    const drawn = await shot('shaped-drawn.png');
    sh.drawnDiff = diffPixels(initial, drawn).count;
    sh.drawnBareDiff = diffPixels(initialBare, await bare('shaped-drawn-bare.png')).count;
    if (to !== undefined && to !== null) {
      await page.fill('#warp-to', String(to));
      await idle();
    }
    sh.preview = await hooks(() => window.__partscale.warp());
    sh.recipe = await hooks(() => window.__partscale.recipe());
    sh.sizes = await hooks(() => window.__partscale.sizes());
    sh.info = await text('#warp-info');
    sh.revisionPreview = (await hooks(() => window.__partscale.state())).revision;
    const preview = await shot('shaped-preview.png');
    const previewBare = await bare('shaped-preview-bare.png');
    sh.previewDiff = diffPixels(initialBare, previewBare).count;
    await page.screenshot({ path: join(args.out, 'shaped-page-preview.png') });
    await page.click('#warp-apply');
    await revisionAbove(sh.revisionPreview);
    await idle();
    sh.applied = await hooks(() => window.__partscale.state());
    sh.status = await text('#status');
    sh.warpAfterApply = await hooks(() => window.__partscale.warp());
    const appliedBare = await bare('shaped-applied-bare.png');
    sh.appliedVsPreview = diffPixels(previewBare, appliedBare).count;
    sh.appliedVsInitial = diffPixels(initialBare, appliedBare).count;
    await page.screenshot({ path: join(args.out, 'shaped-page-applied.png') });
    await page.click('#undo');
    await revisionAbove(sh.applied.revision);
    await idle();
    sh.undone = await hooks(() => window.__partscale.state());
    sh.warpAfterUndo = await hooks(() => window.__partscale.warp());
    sh.undoneVsPreview = diffPixels(preview, await shot('shaped-undone.png')).count;
    if (args.shaped.fitSize) {
      // a fit whose recipe is one shaped zone: previewed as it
      for (const [i, axis] of ['x', 'y', 'z'].entries()) await page.fill(`#size-${axis}`, args.shaped.fitSize[i]);
      await page.click('#size-preview');
      await page.waitForFunction(() => window.__partscale.fitWhy().length > 0, null, { timeout: 60000 });
      await idle();
      sh.fit = {
        warp: await hooks(() => window.__partscale.warp()),
        recipe: await hooks(() => window.__partscale.recipe()),
        why: await hooks(() => window.__partscale.fitWhy()),
        status: await text('#status'),
        revision: (await hooks(() => window.__partscale.state())).revision,
      };
    }
    result.shaped = sh;
  } else if (args.count) {
    // one element more along an axis: previewed (nothing applied), applied, undone; one fewer
    const { axis, other } = args.count;
    const c = {};
    c.suggestions = await page.evaluate(() => window.__partscale.suggestions());
    c.zone0 = await page.evaluate(() => window.__partscale.zoneInputs()[0]);
    c.elements = await page.evaluate(() => window.__partscale.elements());
    c.sizes0 = await sizesText();
    c.buttons = await page.evaluate((axes) =>
      Object.fromEntries(axes.flatMap((a) => ['plus', 'minus'].map((k) => {
        const b = document.querySelector(`#count-${a}-${k}`);
        return [`${a}-${k}`, { disabled: b.disabled, title: b.title }];
      }))), [axis, other]);
    const initial = await shot('count-initial.png');
    await page.click(`#count-${axis}-plus`);
    await page.waitForFunction(() => window.__partscale.fitWhy().length > 0, null, { timeout: 60000 });
    await idle();
    c.recipe = await page.evaluate(() => window.__partscale.recipe());
    c.why = await page.evaluate(() => window.__partscale.fitWhy());
    c.status = await text('#status');
    c.preview = { sizes: await page.evaluate(() => window.__partscale.sizes()), text: await sizesText() };
    c.revisionPreview = (await page.evaluate(() => window.__partscale.state())).revision;
    const preview = await shot('count-preview.png');
    c.previewDiff = diffPixels(initial, preview).count;
    await page.screenshot({ path: join(args.out, 'count-page-preview.png') });
    await page.click('#apply');
    await revisionAbove(c.revisionPreview);
    await idle();
    c.applied = await page.evaluate(() => window.__partscale.state());
    c.appliedText = await sizesText();
    c.appliedVsPreview = diffPixels(preview, await shot('count-applied.png')).count;
    await page.screenshot({ path: join(args.out, 'count-page-applied.png') });
    await page.click('#undo');
    await revisionAbove(c.applied.revision);
    await idle();
    c.undone = await page.evaluate(() => window.__partscale.state());
    c.undoneText = await sizesText();
    // one fewer: previewed only
    await page.click(`#count-${axis}-minus`);
    await page.waitForFunction(() => window.__partscale.fitWhy().length > 0, null, { timeout: 60000 });
    await idle();
    c.minus = {
      recipe: await page.evaluate(() => window.__partscale.recipe()),
      sizes: await page.evaluate(() => window.__partscale.sizes()),
      text: await sizesText(),
      revision: (await page.evaluate(() => window.__partscale.state())).revision,
    };
    result.count = c;
  } else if (args.refusal) {
    // a fit only a deformation reaches: refused in the status line; allowed: previewed
    const f = {};
    f.zone0 = await page.evaluate(() => window.__partscale.zoneInputs());
    for (const [i, axis] of ['x', 'y', 'z'].entries()) await page.fill(`#size-${axis}`, args.refusal.size[i]);
    await page.click('#size-preview');
    await page.waitForFunction(() => document.querySelector('#status').textContent.includes('failed'), null, { timeout: 60000 });
    await idle();
    f.status = await text('#status');
    f.statusIsError = await page.evaluate(() => document.querySelector('#status').classList.contains('error'));
    f.zones = await page.evaluate(() => window.__partscale.zoneInputs());
    f.why = await page.evaluate(() => window.__partscale.fitWhy());
    f.panel = await page.evaluate(() => document.querySelector('#size-refused')?.textContent ?? null);
    await page.screenshot({ path: join(args.out, 'refusal-page.png') });
    await page.check('#allow-deform');
    await page.waitForFunction(() => window.__partscale.fitWhy().length > 0, null, { timeout: 60000 });
    await idle();
    f.allowed = {
      status: await text('#status'),
      why: await page.evaluate(() => window.__partscale.fitWhy()),
      recipe: await page.evaluate(() => window.__partscale.recipe()),
      sizes: await page.evaluate(() => window.__partscale.sizes()),
      text: await sizesText(),
      revision: (await page.evaluate(() => window.__partscale.state())).revision,
      panel: await page.evaluate(() => document.querySelector('#size-refused')?.textContent ?? null),
    };
    await page.screenshot({ path: join(args.out, 'refusal-allowed-page.png') });
    result.refusal = f;
  } else if (args.limits) {
    // an apply whose result this GPU could not show: refused by the server before computing
    result.maxTexture = await page.evaluate(() =>
      document.createElement('canvas').getContext('webgl2').getParameter(WebGL2RenderingContext.MAX_3D_TEXTURE_SIZE));
    const s0 = result.state0;
    const z = result.zone0;
    const dest = z.end + (result.maxTexture - s0.shape[0] + 10) * s0.voxel_size;
    await page.selectOption('#units', 'units');
    for (const [id, v] of [['#pos-start', z.start], ['#pos-end', z.end], ['#pos-dest', dest]]) {
      await page.fill(id, String(v));
      await page.dispatchEvent(id, 'change');
    }
    result.tooBigRecipe = await page.evaluate(() => window.__partscale.recipe());
    await idle();
    await page.click('#apply');
    await page.waitForFunction(() => document.querySelector('#status').textContent.includes('failed'), null, { timeout: 60000 });
    await idle();
    result.statusTooBig = await page.textContent('#status');
    result.stateTooBig = await page.evaluate(() => window.__partscale.state());
    result.undoDisabledTooBig = await page.isDisabled('#undo');
    // DNS rebinding: evil.example resolves here; neither its page nor its requests are answered
    const port = new URL(args.url).port;
    const evil = await context.newPage();
    const resp = await evil.goto(`http://evil.example:${port}/`);
    result.rebind = { status: resp.status(), body: await resp.text() };
    result.rebindSave = await evil.evaluate(async () => {
      const r = await fetch('/api/save', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: '{"overwrite": true}' });
      return { status: r.status, body: await r.text() };
    });
  } else if (args.plain) {
    const counters = () => page.evaluate(() => ({
      frames: window.__partscale.frames,
      resolutions: window.__partscale.zoneResolutions,
      zone: window.__partscale.zoneInputs()[0],
    }));
    const p = {};
    p.preserveDrawingBuffer = await page.evaluate(() =>
      document.querySelector('#view canvas').getContext('webgl2').getContextAttributes().preserveDrawingBuffer);
    const c0 = await counters();
    const h = await page.evaluate(() => window.__partscale.handleScreen('end'));
    p.moves = 8;
    await page.mouse.move(h.x, h.y);
    await page.mouse.down();
    for (let i = 1; i <= p.moves; i++) await page.mouse.move(h.x + 6 * i, h.y + 2 * i);
    await page.mouse.up();
    await idle();
    const c1 = await counters();
    // orbit from a corner of the canvas, away from the planes
    const box = await page.evaluate(() => {
      const r = document.querySelector('#view canvas').getBoundingClientRect();
      return { x: r.left + 15, y: r.top + 15 };
    });
    await page.mouse.move(box.x, box.y);
    await page.mouse.down();
    for (let i = 1; i <= 4; i++) await page.mouse.move(box.x + 12 * i, box.y + 4 * i);
    await page.mouse.up();
    await idle();
    const c2 = await counters();
    p.zoneChanged = c1.zone.end !== c0.zone.end;
    p.resolutions = c1.resolutions - c0.resolutions;
    p.framesDrag = c1.frames - c0.frames;
    p.framesOrbit = c2.frames - c1.frames;
    p.readPixels = await page.evaluate(() => window.__readPixels);
    result.plain = p;
  } else if (args.picture) {
    await page.evaluate(({ camera, unlit }) => {
      const h = window.__partscale;
      h.setGuides(false);
      h.setUnlit(unlit);
      h.setCamera(camera);
    }, args.picture);
    await idle();
    await shot('picture.png');
    result.picture = join(args.out, 'picture.png');
  } else if (args.benchmark) {
    result.benchmark = await page.evaluate((n) => window.__partscale.benchmark(n), args.benchmark);
    result.renderer = await page.evaluate(() => {
      const gl = document.createElement('canvas').getContext('webgl2');
      const ext = gl.getExtension('WEBGL_debug_renderer_info');
      return ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
    });
  } else {
    // 1. the object is drawn, like the reference
    const initial = await shot('initial.png');
    if (args.reference) {
      if (args.updateReference) {
        writeFileSync(args.reference, initial);
        result.referenceWritten = true;
      }
    }
    if (args.reference && existsSync(args.reference)) {
      const d = diffPixels(readFileSync(args.reference), initial);
      if (d.diff) writeFileSync(join(args.out, 'reference-diff.png'), d.diff);
      result.reference = { count: d.count, total: d.total };
    }
    const blank = PNG.sync.read(initial);
    const bg = [blank.data[0], blank.data[1], blank.data[2]];
    let fg = 0;
    for (let i = 0; i < blank.data.length; i += 4) {
      if (Math.abs(blank.data[i] - bg[0]) + Math.abs(blank.data[i + 1] - bg[1]) + Math.abs(blank.data[i + 2] - bg[2]) > 30) fg++;
    }
    result.foregroundPixels = fg;

    // 2. the shader's own remap on sample points
    if (args.remapCases) {
      result.remap = await page.evaluate((cases) =>
        cases.map((c) => ({
          glsl: window.__partscale.evalRemap(c.zones, c.points),
          ts: window.__partscale.evalRemapTS(c.zones, c.points),
        })), args.remapCases);
    }

    // view modes: parts (segmented objects) and a distance slice, then back to colour
    result.views = {};
    for (const mode of ['parts', 'slice', 'colour']) {
      await page.selectOption('#view-mode', mode);
      await idle();
      result.views[mode] = diffPixels(initial, await shot(`view-${mode}.png`)).count;
    }
    // positions in % of the solid's extent
    await page.selectOption('#units', '%');
    result.percent = await page.inputValue('#pos-start');
    await page.selectOption('#units', 'units');

    // 3. drag the end plane's handle: the zone and the preview change, the server does not
    // rendering is on demand: nothing is drawn while nothing changes
    const framesIdle0 = await page.evaluate(() => window.__partscale.frames);
    await page.waitForTimeout(600);
    result.framesWhileIdle = (await page.evaluate(() => window.__partscale.frames)) - framesIdle0;

    const h = await page.evaluate(() => window.__partscale.handleScreen('end'));
    result.handle = h;
    const apiDuringDrag = [];
    const onRequest = (req) => {
      if (new URL(req.url()).pathname.startsWith('/api/')) apiDuringDrag.push(req.url());
    };
    page.on('request', onRequest);
    const framesDrag0 = await page.evaluate(() => window.__partscale.frames);
    await page.mouse.move(h.x, h.y);
    await page.mouse.down();
    for (let i = 1; i <= 6; i++) await page.mouse.move(h.x + 10 * i, h.y + 3 * i);
    await page.mouse.up();
    await idle();
    page.off('request', onRequest);
    result.apiDuringDrag = apiDuringDrag;
    result.framesDuringDrag = (await page.evaluate(() => window.__partscale.frames)) - framesDrag0;
    result.zoneDragged = await page.evaluate(() => window.__partscale.zones()[0]);
    const dragged = await shot('dragged.png');
    result.dragDiff = diffPixels(initial, dragged).count;
    result.revisionAfterDrag = (await page.evaluate(() => window.__partscale.state())).revision;

    // 4. type an exact zone and apply it on the server
    if (args.zone) {
      const z = args.zone;
      await page.selectOption('#units', 'units');
      await page.selectOption('#axis', z.axis);
      await page.selectOption('#mode', z.mode ?? 'stretch');
      for (const [id, v] of [['#pos-start', z.start], ['#pos-end', z.end], ['#pos-dest', z.dest]]) {
        await page.fill(id, String(v));
        await page.dispatchEvent(id, 'change');
      }
      result.recipe = await page.evaluate(() => window.__partscale.recipe());
      await idle();
      await shot('preview.png');
      await page.click('#apply');
      await page.waitForFunction((r) => window.__partscale.state()?.revision > r, result.revisionAfterDrag, { timeout: 60000 });
      await idle();
      result.applied = await page.evaluate(() => window.__partscale.state());
      result.zonesAfterApply = await page.evaluate(() => window.__partscale.zoneInputs());
      await shot('applied.png');
      result.statusAfterApply = await page.textContent('#status');

      // 5. undo
      await page.click('#undo');
      await page.waitForFunction((r) => window.__partscale.state()?.revision > r, result.applied.revision, { timeout: 60000 });
      await idle();
      result.undone = await page.evaluate(() => window.__partscale.state());
      result.zonesAfterUndo = await page.evaluate(() => window.__partscale.zoneInputs());
      const undoneShot = await shot('undone.png');
      // the original object again, previewed with the zones of the undone edit
      result.undoneDiff = diffPixels(readFileSync(join(args.out, 'preview.png')), undoneShot).count;

      // 6. two zones in one recipe: the same x zone, then one along y
      if (args.zone2) {
        const setZone = async (zz) => {
          await page.selectOption('#axis', zz.axis);
          await page.selectOption('#mode', zz.mode ?? 'stretch');
          for (const [id, v] of [['#pos-start', zz.start], ['#pos-end', zz.end], ['#pos-dest', zz.dest]]) {
            await page.fill(id, String(v));
            await page.dispatchEvent(id, 'change');
          }
        };
        await setZone(z);
        await page.click('#add-zone');
        await setZone(args.zone2);
        await idle();
        result.recipe2 = await page.evaluate(() => window.__partscale.recipe());
        const two = await shot('two-zones.png');
        result.twoZoneDiff = diffPixels(initial, two).count;
        await page.click('#apply');
        await page.waitForFunction((r) => window.__partscale.state()?.revision > r, result.undone.revision, { timeout: 60000 });
        await idle();
        result.applied2 = await page.evaluate(() => window.__partscale.state());
        await page.click('#undo');
        await page.waitForFunction((r) => window.__partscale.state()?.revision > r, result.applied2.revision, { timeout: 60000 });
        await idle();
      }
    }

    // 8. suggestions, snapping, fit to size
    if (args.features) {
      const f = args.features;
      const revision = async () => (await page.evaluate(() => window.__partscale.state())).revision;
      result.suggestions = await page.evaluate(() => window.__partscale.suggestions());
      // a click on the first x band sets the active zone's planes and mode
      await page.selectOption('#zone', '0');
      await page.click('#suggest-x-0');
      await idle();
      result.afterBand = await page.evaluate(() => ({
        input: window.__partscale.zoneInputs()[0],
        start: Number(document.querySelector('#pos-start').value),
        end: Number(document.querySelector('#pos-end').value),
        mode: document.querySelector('#mode').value,
        axis: document.querySelector('#axis').value,
      }));
      // snap toggle: the server snaps the zone as `scale --snap` does
      const sz = f.snapZone;
      await page.selectOption('#axis', sz.axis);
      await page.selectOption('#mode', sz.mode);
      for (const [id, v] of [['#pos-start', sz.start], ['#pos-end', sz.end], ['#pos-dest', sz.dest]]) {
        await page.fill(id, String(v));
        await page.dispatchEvent(id, 'change');
      }
      await page.check('#snap');
      await page.waitForFunction((z) => window.__partscale.zoneInputs()[0].start !== z.start, sz, { timeout: 30000 });
      await idle();
      result.snapped = await page.evaluate(() => window.__partscale.zoneInputs()[0]);
      result.snapStatus = await page.textContent('#status');
      await page.uncheck('#snap');
      // fit to size: preview (nothing applied), apply, undo
      const rev0 = await revision();
      for (const [i, axis] of ['x', 'y', 'z'].entries()) await page.fill(`#size-${axis}`, f.fitSize[i]);
      await page.click('#size-preview');
      await page.waitForFunction(() => window.__partscale.fitWhy().length > 0, null, { timeout: 60000 });
      await idle();
      result.fitWhy = await page.evaluate(() => window.__partscale.fitWhy());
      result.fitRecipe = await page.evaluate(() => window.__partscale.recipe());
      result.fitRevision = await revision();
      result.fitPreviewDiff = diffPixels(initial, await shot('fit-preview.png')).count;
      await page.click('#apply');
      await page.waitForFunction((r) => window.__partscale.state()?.revision > r, rev0, { timeout: 60000 });
      await idle();
      result.fitApplied = await page.evaluate(() => window.__partscale.state());
      result.fitZonesAfterApply = await page.evaluate(() => window.__partscale.zoneInputs());
      const fitShot = await shot('fit-applied.png');
      result.fitAppliedVsPreview = diffPixels(readFileSync(join(args.out, 'fit-preview.png')), fitShot).count;
      await page.click('#undo');
      await page.waitForFunction((r) => window.__partscale.state()?.revision > r, result.fitApplied.revision, { timeout: 60000 });
      await idle();
      result.fitUndone = await page.evaluate(() => window.__partscale.state());
      result.fitZonesAfterUndo = await page.evaluate(() => window.__partscale.zoneInputs());
    }

    // 7. export the mesh: a browser download
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-mesh')]);
    const glb = join(args.out, 'export.glb');
    await download.saveAs(glb);
    result.download = { path: glb, suggested: download.suggestedFilename() };
    result.status = await page.textContent('#status');
  }
  await context.close();
} catch (e) {
  result.fatal = String(e && e.stack ? e.stack : e);
} finally {
  await browser.close();
}
process.stdout.write(JSON.stringify(result) + '\n');
