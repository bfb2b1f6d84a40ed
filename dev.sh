#!/usr/bin/env bash
# partscale's two commands:
#   ./dev.sh setup   create .venv (Python 3.11), install partscale, compile its kernels ahead
#                    (python -m partscale.warmup), run the demo on the table the
#                    package ships (partscale.data.table(); PARTSCALE_DEMO_OBJECT: another object)
#   ./dev.sh test    lint, format check, type checks (mypy, the page's tsc), the documentation site
#                    (mkdocs build --strict), the package build and the whole test suite (installs
#                    what it needs first, the optional Ray and docs extras included)
#   ./dev.sh addon   build the Blender add-on's zip (dist/partscale_blender.zip)
# Optional heavy parts (Node tools for glTF validation and browser tests, Debian's chromium,
# usd-core, Blender: the bpy wheel and Debian's blender) are installed when possible; tests that
# need them skip with a printed reason otherwise.
set -euo pipefail
cd "$(dirname "$0")"
ROOT=$PWD
VENV=$ROOT/.venv
PY=$VENV/bin/python

say() { printf '\033[1m==> %s\033[0m\n' "$*" >&2; }

find_python() {
  for c in python3.11 python3 python; do
    if command -v "$c" >/dev/null 2>&1 && "$c" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
      echo "$c"; return 0
    fi
  done
  echo "partscale needs Python 3.11 or newer on PATH" >&2; exit 2
}

ensure_venv() {
  local stamp=$VENV/.partscale-installed
  if [ ! -x "$PY" ]; then
    say "creating .venv with $(find_python)"
    "$(find_python)" -m venv "$VENV"
  fi
  if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
    say "installing partscale and its dependencies into .venv"
    "$PY" -m pip install -q --upgrade pip
    "$PY" -m pip install -q -e ".[test]"
    "$PY" -m partscale.warmup
    touch "$stamp"
  fi
}

ensure_extra() {
  # an optional extra of pyproject.toml (NAME), installed once per change of pyproject.toml; the
  # tests that need it skip with their reason when it cannot be installed
  local name=$1 what=$2 skipped=$3
  local stamp=$VENV/.partscale-$name-installed
  if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
    say "installing $what (partscale[$name])"
    if "$PY" -m pip install -q -e ".[test,$name]"; then touch "$stamp"
    else echo "note: could not install partscale[$name]; $skipped will be skipped" >&2; fi
  fi
}

check_docs() {
  # the documentation site in strict mode (broken links, missing references and docstring
  # warnings fail it) and the package build (sdist and wheel), each skipped with the reason when
  # its tool is missing
  if [ -x "$VENV/bin/mkdocs" ]; then
    say "mkdocs build --strict (the documentation site)"
    local site; site=$(mktemp -d)
    NO_MKDOCS_2_WARNING=1 "$VENV/bin/mkdocs" build --strict --quiet --site-dir "$site"
    rm -rf "$site"
  else
    echo "note: mkdocs not installed; the documentation site build is skipped" >&2
  fi
  if "$PY" -c 'import build' 2>/dev/null; then
    say "python -m build (sdist and wheel)"
    local dist; dist=$(mktemp -d)
    "$PY" -m build --outdir "$dist" . >"$dist/build.log" 2>&1 || { cat "$dist/build.log" >&2; exit 1; }
    ls "$dist"/*.whl "$dist"/*.tar.gz >&2
    rm -rf "$dist"
  else
    echo "note: build not installed; the package build is skipped" >&2
  fi
}

ensure_blender() {
  # Blender for the add-on's tests: the bpy wheel (Blender 4.2 as a Python 3.11 module) in
  # .venv-bpy, and Debian's blender with xvfb for the test that needs a window (Undo, the
  # panel's picture); each test skips with the reason where its Blender is missing
  local bvenv=$ROOT/.venv-bpy
  if ! { [ -x "$bvenv/bin/python" ] && "$bvenv/bin/python" -c 'import bpy' >/dev/null 2>&1; }; then
    if command -v python3.11 >/dev/null 2>&1; then
      say "installing Blender as a Python module (bpy 4.2, large) into .venv-bpy for the add-on tests"
      { python3.11 -m venv "$bvenv" && "$bvenv/bin/python" -m pip install -q "bpy>=4.0,<4.3"; } \
        || echo "note: could not install the bpy wheel; the Blender add-on tests will be skipped" >&2
    else
      echo "note: the bpy wheel needs python3.11 on PATH; the Blender add-on tests will be skipped" >&2
    fi
  fi
  if command -v blender >/dev/null 2>&1 && command -v xvfb-run >/dev/null 2>&1; then return 0; fi
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    say "installing Debian's blender and xvfb for the add-on's Undo test"
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq blender xvfb python3-numpy >/dev/null) \
      || echo "note: could not install blender and xvfb; the add-on's Undo test will be skipped" >&2
  else
    echo "note: blender and xvfb-run not found and cannot be installed here (needs root and apt-get); the add-on's Undo test will be skipped" >&2
  fi
}

addon() {
  # the Blender add-on's zip (Edit > Preferences > Add-ons > Install...)
  "$(find_python)" integrations/blender/build.py "${1:-$ROOT/dist/partscale_blender.zip}"
}

ensure_node_tools() {
  # gltf-validator (Khronos) and playwright-core for browser tests; npm registry only.
  if ! command -v npm >/dev/null 2>&1; then
    echo "note: npm not found; glTF validation and browser tests will be skipped" >&2; return 0
  fi
  local stamp=web/node_modules/.partscale-installed
  if [ ! -f "$stamp" ] || [ web/package-lock.json -nt "$stamp" ]; then
    say "installing web tools (npm ci in web/)"
    (cd web && npm ci --no-audit --no-fund --loglevel=error && touch node_modules/.partscale-installed) || echo "note: npm ci failed; glTF validation and browser tests will be skipped" >&2
  fi
}

ensure_chromium() {
  if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1; then return 0; fi
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    say "installing Debian's chromium for browser tests"
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
      || echo "note: could not install chromium; browser tests will be skipped" >&2
  else
    echo "note: chromium not found and cannot be installed here (needs root and apt-get); browser tests will be skipped" >&2
  fi
}

demo() {
  # the demo's steps, with the installed partscale (PARTSCALE_PYTHON: the Python it is installed in,
  # default .venv's); on the table shipped in the package unless PARTSCALE_DEMO_OBJECT names another
  local py=${PARTSCALE_PYTHON:-$PY}
  local out=${PARTSCALE_DEMO_OUT:-$ROOT/out/demo}
  local obj=${PARTSCALE_DEMO_OBJECT:-}
  if [ -z "$obj" ]; then obj=$("$py" -m partscale.data table); fi
  mkdir -p "$out"
  if [ ! -f "$obj" ]; then echo "demo object $obj not found (set PARTSCALE_DEMO_OBJECT)" >&2; exit 2; fi
  run() { "$py" -m partscale "$@"; }
  say "demo: import $obj"
  run import "$obj" -o "$out/table.csdf.npz" --res 128
  say "demo: split it into nearly convex parts (top, legs, rails)"
  run segment "$out/table.csdf.npz" -o "$out/table.csdf.npz"
  run info "$out/table.csdf.npz"
  say "demo: make it 40% longer by stretching the zone between its legs (parts carried through)"
  run scale "$out/table.csdf.npz" -o "$out/table_longer.csdf.npz" --axis x --zone 35% 65% --to 105% --mode stretch
  run render "$out/table.csdf.npz" -o "$out/table.png" --view iso
  run render "$out/table.csdf.npz" -o "$out/table_parts.png" --view iso --parts
  run render "$out/table_longer.csdf.npz" -o "$out/table_longer.png" --view iso
  run export "$out/table_longer.csdf.npz" --mesh "$out/table_longer.glb"
  say "demo done: see $out (table.png, table_parts.png, table_longer.png, table_longer.glb)"
}

case "${1:-}" in
  setup)
    ensure_venv
    demo
    ;;
  test)
    ensure_venv
    ensure_extra ray "the optional Ray extra for the batch engine test" "the batch's Ray engine test"
    ensure_extra usd "the optional USD extra for USD and USDZ export" "the USD and USDZ export tests"
    ensure_extra docs "the documentation tools" "the site and package builds"
    ensure_node_tools
    ensure_chromium
    ensure_blender
    say "ruff"
    "$VENV/bin/ruff" check src tests bench integrations
    "$VENV/bin/ruff" format --check src tests bench integrations
    say "mypy (src/partscale, settings in pyproject.toml)"
    "$VENV/bin/mypy"
    if [ -x web/node_modules/.bin/tsc ]; then
      say "tsc --noEmit (web/)"
      web/node_modules/.bin/tsc --noEmit -p web
    else
      echo "note: web/node_modules not installed; the page's type check (tsc --noEmit) is skipped" >&2
    fi
    check_docs
    say "pytest"
    shift
    "$PY" -m pytest "$@"
    ;;
  demo)
    ensure_venv
    demo
    ;;
  addon)
    shift
    addon "$@"
    ;;
  demo-steps)
    # the demo alone, without installing anything (tests run it with their own Python)
    demo
    ;;
  *)
    echo "usage: ./dev.sh setup | test [pytest args] | demo | demo-steps | addon [OUT.zip]" >&2; exit 2
    ;;
esac
