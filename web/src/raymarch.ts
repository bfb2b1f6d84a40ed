// The raymarching material: sphere-traces the CSDF's 3D texture through the pending zones' maps.
// The box it is drawn on is the edited object's bounding box (output space); every sample is taken
// back to source space with toSource() (remap.ts), so a drag never needs the server.
import * as THREE from 'three';
import { MAX_ZONES, REMAP_GLSL } from './remap';
import { WARP_GLSL } from './warp';

const vertex = /* glsl */ `
precision highp float;
uniform mat4 modelMatrix;
uniform mat4 viewMatrix;
uniform mat4 projectionMatrix;
in vec3 position;
out vec3 vWorld;
void main() {
  vec4 w = modelMatrix * vec4(position, 1.0);
  vWorld = w.xyz;
  gl_Position = projectionMatrix * viewMatrix * w;
}
`;

const fragment = /* glsl */ `
precision highp float;
precision highp sampler3D;
uniform mat4 viewMatrix;
uniform mat4 projectionMatrix;
uniform vec3 cameraPosition;
// Both textures hold the grid in its own C order (z fastest): texel (s, t, r) = voxel (k, j, i),
// so they are sampled at uvw.zyx.
uniform sampler3D uDistance; // r = signed distance in voxels (float16)
// The colour textures hold sRGB bytes as SRGB8_ALPHA8: the GPU decodes each texel to linear
// before it filters, so a sample is already linear (no decode here).
uniform sampler3D uColour;   // rgb = colour, linear (sRGB bytes, trilinear in linear light)
uniform sampler3D uParts;    // rgb = part colour, linear (sRGB bytes), nearest filtering
uniform vec3 uGridMin;       // world corner of the texture (origin - voxel/2)
uniform vec3 uGridSize;      // world extent of the texture
uniform vec3 uBoxMin;        // output-space box being marched
uniform vec3 uBoxMax;
uniform float uVoxel;
uniform float uStepScale;    // smallest Jacobian of the zone maps: keeps steps safe when compressed
uniform int uView;           // 0 colour, 1 parts, 2 distance slice
uniform bool uUnlit;         // tests only (setUnlit): the colour as sampled, no light
uniform int uSliceAxis;
uniform float uSlicePos;
in vec3 vWorld;
out vec4 fragColor;
${REMAP_GLSL}
${WARP_GLSL}

float distanceAt(vec3 src) {
  vec3 uvw = (src - uGridMin) / uGridSize;
  float d = texture(uDistance, uvw.zyx).r * uVoxel;
  // outside the grid the clamped texture repeats the border: never report less than the way back
  vec3 q = abs(src - (uGridMin + 0.5 * uGridSize)) - 0.5 * uGridSize;
  float outside = length(max(q, 0.0));
  return max(d, outside);
}

// A flight kept on its floor (warp.screw_ground; apply_screw's _ground): lifted, the rows from
// the floor up by the rise take the flight shifted along it only where that is nearer; lowered,
// what goes below the floor is cut off half a voxel below it. alongWins: set where the first wins.
float grounded(vec3 p, float after, out bool alongWins) {
  alongWins = false;
  if (uWarpKind != 3 || uWarp[1].w < 0.5) return after;
  float h = uWarp[1].z, floorY = uWarp[2].x, rise = uWarp[0].y;
  if (rise > 0.5 * h && p.y >= floorY - 0.5 * h && p.y <= floorY + rise + 0.5 * h) {
    float along = distanceAt(p - vec3(uWarp[0].x, 0.0, uWarp[0].z));
    alongWins = along < after;
    return min(after, along);
  }
  if (rise < -0.5 * h && p.y < floorY - 0.5 * h) return max(after, floorY - 0.5 * h - p.y);
  return after;
}

// The point whose colour (and part) an output point shows: through the zones, then the warp's
// side of its cut.
vec3 colourPoint(vec3 pOut) {
  vec3 p = toSource(pOut);
  if (uWarpKind == 0) return p;
  float w;
  vec3 s = warpSource(p, w);
  if (w < 0.5) return p;
  bool alongWins;
  grounded(p, distanceAt(s), alongWins);
  return alongWins ? p - vec3(uWarp[0].x, 0.0, uWarp[0].z) : s;
}

vec4 sampleSource(vec3 pOut) {
  vec3 uvw = (colourPoint(pOut) - uGridMin) / uGridSize;
  return texture(uColour, uvw.zyx);
}

float sdf(vec3 pOut) {
  vec3 p = toSource(pOut);
  if (uWarpKind == 0) return distanceAt(p);
  float w;
  vec3 s = warpSource(p, w);
  bool alongWins;
  float after = w > 0.0 ? grounded(p, distanceAt(s), alongWins) : 0.0;
  if (w >= 1.0) return min(after, warpGap(p));
  return mix(distanceAt(p), after, w);
}

vec3 normalAt(vec3 p) {
  float h = uVoxel;
  vec2 e = vec2(h, 0.0);
  vec3 n = vec3(sdf(p + e.xyy) - sdf(p - e.xyy), sdf(p + e.yxy) - sdf(p - e.yxy),
                sdf(p + e.yyx) - sdf(p - e.yyx));
  float l = length(n);
  return l > 1e-12 ? n / l : vec3(0.0, 1.0, 0.0);
}

vec3 toSRGB(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}

vec2 boxHit(vec3 ro, vec3 rd, vec3 bmin, vec3 bmax) {
  vec3 inv = 1.0 / rd;
  vec3 t0 = (bmin - ro) * inv, t1 = (bmax - ro) * inv;
  vec3 tmin = min(t0, t1), tmax = max(t0, t1);
  return vec2(max(max(tmin.x, tmin.y), tmin.z), min(min(tmax.x, tmax.y), tmax.z));
}

float depthOf(vec3 p) {
  vec4 clip = projectionMatrix * viewMatrix * vec4(p, 1.0);
  return clamp(0.5 * (clip.z / clip.w) + 0.5, 0.0, 1.0);
}

vec3 sliceColor(float dVox) {
  // blue inside, orange outside, a line every 4 voxels, black at the surface
  vec3 c = dVox < 0.0 ? vec3(0.25, 0.45, 0.9) : vec3(0.95, 0.6, 0.25);
  c *= 0.55 + 0.45 * exp(-abs(dVox) / 24.0);
  float band = abs(fract(dVox / 4.0 + 0.5) - 0.5) * 4.0;
  c *= mix(0.75, 1.0, smoothstep(0.0, 0.35, band));
  return mix(vec3(0.0), c, smoothstep(0.05, 0.3, abs(dVox)));
}

void main() {
  vec3 ro = cameraPosition;
  vec3 rd = normalize(vWorld - cameraPosition);
  vec3 bmin = uBoxMin, bmax = uBoxMax;
  vec2 seg = boxHit(ro, rd, bmin, bmax);
  float tNear = max(seg.x, 0.0), tFar = seg.y;
  if (tFar <= tNear) discard;

  if (uView == 2) {
    // cut away the half on the camera's side of the slice plane; the plane shows the distances
    float side = cameraPosition[uSliceAxis] >= uSlicePos ? -1.0 : 1.0;
    float o = (ro[uSliceAxis] - uSlicePos) * side;  // <= 0: the camera is in the cut-away half
    float dir = rd[uSliceAxis] * side;
    if (dir <= 1e-9) discard;  // heading away from the half that is kept
    float tp = -o / dir;
    if (tp >= tFar) discard;
    if (tp > tNear) {
      vec3 p = ro + rd * tp;
      fragColor = vec4(sliceColor(sdf(p) / uVoxel), 1.0);
      gl_FragDepth = depthOf(p);
      return;
    }
  }

  float eps = 0.05 * uVoxel;
  float minStep = 0.02 * uVoxel;
  float t = tNear, tPrev = tNear;
  float d = sdf(ro + rd * t);
  bool hit = false;
  for (int i = 0; i < 768; ++i) {
    if (d < eps) { hit = true; break; }
    tPrev = t;
    t += max(d * uStepScale, minStep);
    if (t > tFar) break;
    d = sdf(ro + rd * t);
  }
  if (!hit) discard;
  if (d < 0.0 && t > tPrev) {
    // overshot (minimum step): bisect back to the zero crossing
    float a = tPrev, b = t;
    for (int i = 0; i < 6; ++i) {
      float m = 0.5 * (a + b);
      if (sdf(ro + rd * m) < 0.0) b = m; else a = m;
    }
    t = 0.5 * (a + b);
  }
  vec3 p = ro + rd * t;
  vec3 n = normalAt(p);
  vec3 albedo = uView == 1 ? texture(uParts, ((colourPoint(p) - uGridMin) / uGridSize).zyx).rgb
                           : sampleSource(p).rgb;
  if (uUnlit) {
    // tests compare the sampled colours alone with partscale.render's (whose lights differ)
    fragColor = vec4(toSRGB(albedo), 1.0);
    gl_FragDepth = depthOf(p);
    return;
  }
  vec3 l1 = normalize(vec3(0.45, 0.8, 0.55));
  vec3 l2 = normalize(vec3(-0.6, 0.25, -0.4));
  vec3 h = normalize(l1 - rd);
  float diff = max(dot(n, l1), 0.0);
  float fill = max(dot(n, l2), 0.0);
  float spec = pow(max(dot(n, h), 0.0), 48.0) * 0.15;
  vec3 lit = albedo * (0.28 + 0.75 * diff + 0.25 * fill) + vec3(spec);
  fragColor = vec4(toSRGB(lit), 1.0);
  gl_FragDepth = depthOf(p);
}
`;

export function createRaymarchMaterial(): THREE.RawShaderMaterial {
  const zeros = () => Array.from({ length: MAX_ZONES }, () => new THREE.Vector4());
  return new THREE.RawShaderMaterial({
    glslVersion: THREE.GLSL3,
    vertexShader: vertex,
    fragmentShader: fragment,
    side: THREE.BackSide,
    uniforms: {
      uDistance: { value: null },
      uColour: { value: null },
      uParts: { value: null },
      uGridMin: { value: new THREE.Vector3() },
      uGridSize: { value: new THREE.Vector3(1, 1, 1) },
      uBoxMin: { value: new THREE.Vector3() },
      uBoxMax: { value: new THREE.Vector3(1, 1, 1) },
      uVoxel: { value: 1 },
      uStepScale: { value: 1 },
      uView: { value: 0 },
      uUnlit: { value: false },
      uSliceAxis: { value: 0 },
      uSlicePos: { value: 0 },
      uZoneCount: { value: 0 },
      uZoneA: { value: zeros() },
      uZoneB: { value: zeros() },
      uWarpKind: { value: 0 },
      uWarp: { value: Array.from({ length: 4 }, () => new THREE.Vector4()) },
    },
  });
}

// A one-row float render: evaluates the shader's own functions (GLSL, their source) on given
// points p (uInput), writing fragColor as the statements `result` say, so tests compare the GLSL
// (not a copy of it) with the Python maps.
function evalFragmentOf(glsl: string, result: string): string {
  return /* glsl */ `
precision highp float;
uniform highp sampler2D uInput;
${glsl}
out vec4 fragColor;
void main() {
  ivec2 ij = ivec2(gl_FragCoord.xy);
  vec4 p = texelFetch(uInput, ij, 0);
  ${result}
}
`;
}
// The remap's toSource: the source point of each output point.
const evalFragment = evalFragmentOf(REMAP_GLSL, 'fragColor = vec4(toSource(p.xyz), 1.0);');
const evalVertex = /* glsl */ `
in vec3 position;
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }
`;

/** Run ``fragmentShader`` (an eval fragment: uInput holds the points) on output points
 *  (N, 3) in a one-row float render; returns its (N, 4) RGBA floats, flat. */
function evalPointsOnGPU(
  renderer: THREE.WebGLRenderer,
  fragmentShader: string,
  uniforms: Record<string, THREE.IUniform>,
  points: number[][],
): Float32Array {
  const n = points.length;
  const data = new Float32Array(n * 4);
  points.forEach((p, i) => data.set([p[0], p[1], p[2], 1], i * 4));
  const input = new THREE.DataTexture(data, n, 1, THREE.RGBAFormat, THREE.FloatType);
  input.needsUpdate = true;
  const target = new THREE.WebGLRenderTarget(n, 1, { type: THREE.FloatType, depthBuffer: false });
  const mat = new THREE.RawShaderMaterial({
    glslVersion: THREE.GLSL3,
    vertexShader: evalVertex,
    fragmentShader,
    uniforms: { ...uniforms, uInput: { value: input } },
  });
  const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), mat);
  const scene = new THREE.Scene();
  scene.add(quad);
  const prev = renderer.getRenderTarget();
  renderer.setRenderTarget(target);
  renderer.render(scene, new THREE.Camera());
  const out = new Float32Array(n * 4);
  renderer.readRenderTargetPixels(target, 0, 0, n, 1, out);
  renderer.setRenderTarget(prev);
  target.dispose();
  input.dispose();
  mat.dispose();
  quad.geometry.dispose();
  return out;
}

/** Map output points (N, 3) through the zones with the GLSL; returns source points (N, 3). */
export function evalRemapOnGPU(
  renderer: THREE.WebGLRenderer,
  zonesA: THREE.Vector4[],
  zonesB: THREE.Vector4[],
  count: number,
  points: number[][],
): number[][] {
  const uniforms = {
    uZoneCount: { value: count },
    uZoneA: { value: zonesA },
    uZoneB: { value: zonesB },
  };
  const out = evalPointsOnGPU(renderer, evalFragment, uniforms, points);
  return points.map((_, i) => [out[i * 4], out[i * 4 + 1], out[i * 4 + 2]]);
}

// The warp's warpSource: (source point, weight) of each output point.
const evalWarpFragment = evalFragmentOf(
  WARP_GLSL,
  'float w;\n  vec3 s = warpSource(p.xyz, w);\n  fragColor = vec4(s, w);',
);

/** Map output points (N, 3) through a warp (its packWarp uniforms) with the GLSL; returns
 *  (N, 4): the source point and its weight. */
export function evalWarpOnGPU(renderer: THREE.WebGLRenderer, kind: number, data: number[], points: number[][]): number[][] {
  const uWarp = [0, 1, 2, 3].map((i) => new THREE.Vector4(...data.slice(4 * i, 4 * i + 4)));
  const uniforms = { uWarpKind: { value: kind }, uWarp: { value: uWarp } };
  const out = evalPointsOnGPU(renderer, evalWarpFragment, uniforms, points);
  return points.map((_, i) => [out[i * 4], out[i * 4 + 1], out[i * 4 + 2], out[i * 4 + 3]]);
}
