// Validate a glTF/GLB file with the Khronos glTF validator and print its report as JSON.
// Usage: node tests/tools/validate_gltf.mjs FILE.glb
// The module is resolved from web/ (where `npm ci` installs it), not from this folder.
import { createRequire } from "node:module";
import { readFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import path from "node:path";

const here = path.dirname(fileURLToPath(import.meta.url));
const require = createRequire(path.join(here, "..", "..", "web", "package.json"));
const validator = require("gltf-validator");

const file = process.argv[2];
const bytes = new Uint8Array(readFileSync(file));
const report = await validator.validateBytes(bytes, { maxIssues: 100 });
process.stdout.write(JSON.stringify(report));
