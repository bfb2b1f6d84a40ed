// Runs web/src/remap.ts (the TypeScript mirror of recipe.source_coordinate) in node, without a
// browser: vite's own TypeScript transform, then import. Usage: node remap_node.mjs WEB_DIR CASES.json
// (JSON [{zones, points}]); prints JSON [[[x, y, z], ...], ...] (points through toSource order).
import { createRequire } from 'node:module';
import { readFileSync, writeFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

const web = resolve(process.argv[2]);
const require = createRequire(join(web, 'package.json'));
const { transformWithOxc } = await import(pathToFileURL(require.resolve('vite')).href);
const src = readFileSync(join(web, 'src', 'remap.ts'), 'utf8');
const { code } = await transformWithOxc(src, 'remap.ts', { lang: 'ts' });
const dir = mkdtempSync(join(tmpdir(), 'partscale-remap-'));
try {
  const file = join(dir, 'remap.mjs');
  writeFileSync(file, code);
  const remap = await import(pathToFileURL(file).href);
  const cases = JSON.parse(readFileSync(resolve(process.argv[3]), 'utf8'));
  const out = cases.map(({ zones, points }) =>
    points.map((p) => {
      const q = [...p];
      for (let i = zones.length - 1; i >= 0; i--) {
        const a = remap.AXES.indexOf(zones[i].axis);
        q[a] = remap.sourceCoordinate(q[a], zones[i]);
      }
      return q;
    }),
  );
  process.stdout.write(JSON.stringify(out) + '\n');
} finally {
  rmSync(dir, { recursive: true, force: true });
}
