"""Serve stage: the browser editor (a local web server over one CSDF file).

``create_app(path)`` builds the ASGI app (testable with starlette's ``TestClient``);
``serve(path, ...)`` runs it with uvicorn. The page itself is built from ``web/`` with Vite and
shipped, built, in ``static/`` so users need no Node (rebuild with ``npx vite build`` in ``web/``;
``tests/test_serve.py`` checks ``static/build.json`` against a hash of the sources).

For scripts, the page exposes ``window.__partscale``: ``frameTimeMs`` (smoothed),
``lastFrameMs``, ``frames``, ``idle``, ``state()``, ``zones()``, ``zoneResolutions`` (how often the
zones were resolved: once per change), ``recipe()``, ``elements()``, ``sizes()`` (the solid's size
per axis and the size the previewed zones make), ``benchmark(n)`` (n orbiting frames, each waited
for on the GPU; mean and median ms), ``evalRemap(zones, points)`` (the shader's own GLSL map) and
``handleScreen(name)``. ``?canvas=WxH`` fixes the canvas size; ``?capture=1`` (tests and
benchmarks) keeps the canvas's pixels readable and times every frame to the GPU's end, which the
editor otherwise never waits for.
"""

from .app import MAX_BODY, create_app
from .hosts import allowed_hosts, canonical_host, is_loopback
from .server import serve
from .session import (
    GRID_BYTES_PER_VOXEL,
    EditSession,
    Encoding,
    GridDelta,
    PageLimits,
    edited_path,
    encode_grid,
    encode_parts,
    encode_slab,
    grid_delta,
)

__all__ = [
    "GRID_BYTES_PER_VOXEL",
    "MAX_BODY",
    "EditSession",
    "Encoding",
    "GridDelta",
    "PageLimits",
    "allowed_hosts",
    "canonical_host",
    "create_app",
    "edited_path",
    "encode_grid",
    "encode_parts",
    "encode_slab",
    "grid_delta",
    "is_loopback",
    "serve",
]
