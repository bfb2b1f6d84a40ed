// Builds the editor page into the Python package (src/partscale/serve/static), so users need no
// Node. build.json records a hash of the sources; tests/test_serve.py recomputes it to check that
// the committed build is current (same file list and hashing as source_hash in that test).
import { createHash } from 'node:crypto';
import { readdirSync, readFileSync, statSync, writeFileSync } from 'node:fs';
import { join, relative, resolve, sep } from 'node:path';
import { defineConfig, type Plugin } from 'vite';

const here = resolve(import.meta.dirname);
const outDir = resolve(here, '../src/partscale/serve/static');

function sourceFiles(): string[] {
  const files = ['index.html', 'vite.config.ts', 'tsconfig.json'];
  const walk = (dir: string) => {
    for (const name of readdirSync(dir)) {
      const p = join(dir, name);
      if (statSync(p).isDirectory()) walk(p);
      else files.push(relative(here, p).split(sep).join('/'));
    }
  };
  walk(join(here, 'src'));
  return files.sort();
}

export function sourceHash(): string {
  const h = createHash('sha256');
  for (const f of sourceFiles()) {
    h.update(f + '\0');
    h.update(readFileSync(join(here, f)));
    h.update('\0');
  }
  return h.digest('hex');
}

function recordSourceHash(): Plugin {
  return {
    name: 'partscale-source-hash',
    apply: 'build',
    closeBundle() {
      const info = { source_hash: sourceHash(), files: sourceFiles() };
      writeFileSync(join(outDir, 'build.json'), JSON.stringify(info, null, 2) + '\n');
    },
  };
}

export default defineConfig({
  root: here,
  base: '/',
  plugins: [recordSourceHash()],
  build: {
    outDir,
    emptyOutDir: true,
    target: 'es2022',
    sourcemap: false,
    chunkSizeWarningLimit: 1200,
    rollupOptions: {
      output: {
        // stable names: the server's asset table and git diffs stay small
        entryFileNames: 'assets/editor.js',
        chunkFileNames: 'assets/[name].js',
        assetFileNames: 'assets/[name][extname]',
      },
    },
  },
  server: {
    proxy: { '/api': 'http://127.0.0.1:8765' },
  },
});
