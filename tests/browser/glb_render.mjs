// Renders GLB files with three.js's GLTFLoader in headless Chromium (playwright-core) for
// tests/test_export_assets.py. Usage: node glb_render.mjs '<json args>'; prints one JSON line.
//
// args: { chromium, web (folder with node_modules), files: [glb paths], size: [w, h] }
// Each file is drawn twice from the same camera: as loaded (its own materials, two lights) and
// unlit (MeshBasicMaterial keeping the loaded map and vertexColors), so colour alone can be
// compared between a textured and a vertex-coloured export. Returns per file the unlit RGBA
// pixels as base64 and the lit render's mean colour over the object.
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { pathToFileURL } from 'node:url';

const args = JSON.parse(process.argv[2]);
const require = createRequire(join(args.web, 'package.json'));
const load = async (name) => import(pathToFileURL(require.resolve(name)).href);
const pick = (mod, name) => mod[name] ?? mod.default?.[name];
const chromium = pick(await load('playwright-core'), 'chromium');
const threeDir = dirname(dirname(require.resolve('three')));
const [W, H] = args.size ?? [256, 256];

const browser = await chromium.launch({
  executablePath: args.chromium,
  headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--ignore-gpu-blocklist', '--force-color-profile=srgb'],
});
const result = { errors: [], renders: [] };
try {
  const page = await browser.newPage({ viewport: { width: W, height: H } });
  page.on('pageerror', (e) => result.errors.push(String(e)));
  await page.route('http://assets.test/**', async (route) => {
    const url = new URL(route.request().url());
    if (url.pathname === '/') {
      const html = `<!doctype html><html><body style="margin:0"><script type="importmap">
        {"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}
        </script><script type="module">
        import * as THREE from 'three';
        import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
        window.renderGlb = async (url, unlit) => {
          const gltf = await new GLTFLoader().loadAsync(url);
          const scene = new THREE.Scene();
          scene.background = new THREE.Color(0, 0, 0);
          scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 2.0));
          const sun = new THREE.DirectionalLight(0xffffff, 2.0);
          sun.position.set(1, 2, 3);
          scene.add(sun);
          gltf.scene.traverse((o) => {
            if (o.isMesh && unlit) {
              o.material = new THREE.MeshBasicMaterial({ map: o.material.map, vertexColors: o.material.vertexColors });
            }
          });
          scene.add(gltf.scene);
          const box = new THREE.Box3().setFromObject(gltf.scene);
          const c = box.getCenter(new THREE.Vector3()), s = box.getSize(new THREE.Vector3()).length();
          const cam = new THREE.PerspectiveCamera(35, ${W} / ${H}, s / 100, s * 10);
          cam.position.set(c.x + s * 0.8, c.y + s * 0.5, c.z + s * 1.2);
          cam.lookAt(c);
          const r = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
          r.setSize(${W}, ${H});
          r.render(scene, cam);
          const gl = r.getContext();
          const px = new Uint8Array(${W} * ${H} * 4);
          gl.readPixels(0, 0, ${W}, ${H}, gl.RGBA, gl.UNSIGNED_BYTE, px);
          r.dispose();
          let b = ''; for (let i = 0; i < px.length; i += 8192) b += String.fromCharCode(...px.subarray(i, i + 8192));
          return btoa(b);
        };
        window.ready = true;
        </script></body></html>`;
      return route.fulfill({ contentType: 'text/html', body: html });
    }
    if (url.pathname.startsWith('/three/')) {
      return route.fulfill({ path: join(threeDir, url.pathname.slice('/three/'.length)) });
    }
    if (url.pathname.startsWith('/file/')) {
      const i = Number(url.pathname.slice('/file/'.length).split('.')[0]);
      return route.fulfill({ contentType: 'model/gltf-binary', body: readFileSync(args.files[i]) });
    }
    return route.fulfill({ status: 404, body: 'not found' });
  });
  await page.goto('http://assets.test/');
  await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
  for (let i = 0; i < args.files.length; i++) {
    const unlit = await page.evaluate((u) => window.renderGlb(u, true), `/file/${i}.glb`);
    const lit = await page.evaluate((u) => window.renderGlb(u, false), `/file/${i}.glb`);
    result.renders.push({ file: args.files[i], unlit, lit });
  }
} catch (e) {
  result.errors.push(String(e && e.stack || e));
} finally {
  await browser.close();
}
process.stdout.write(JSON.stringify(result) + '\n');
