"""Export a CSDF: a coloured mesh for every tool, 3D textures for engines and volume viewers.

Formats (chosen by the output's suffix, one module per format)
--------------------------------------------------------------
Meshes (:func:`export_mesh`, :data:`MESH_WRITERS`): marching cubes of the zero level
(:func:`partscale.surface.to_mesh`), faces outward, world units, per-vertex colours.

- ``.glb`` (``glb``): linear ``COLOR_0`` as glTF requires (on a primitive without a material,
  the layout trimesh reads too), normals from the SDF gradient; with an atlas, ``TEXCOORD_0`` and
  an embedded ``baseColorTexture`` instead.
- ``.usd``, ``.usda``, ``.usdc``, ``.usdz`` (``usd``, with the optional usd-core): a
  ``UsdPreviewSurface`` whose base colour is the atlas or the ``displayColor`` primvar, Y up,
  ``metersPerUnit`` from the units; ``.usdz`` packaged for AR Quick Look. :func:`save_usd`
  writes a whole scene (the mesh route's).
- ``.ply``, ``.obj`` (``mesh``): sRGB vertex colours; PLY also a ``parts`` vertex property; OBJ
  with an atlas: ``NAME.mtl`` + ``NAME.png`` beside it. :func:`save_obj` is partscale's one OBJ
  writer (the mesh route's too): companions named after the output, all written atomically.

Budgets (``simplify``): ``faces=N`` or ``error=E`` voxels decimate the surface with
meshoptimizer. Atlases (``atlas``): xatlas charts, the CSDF's colour baked per texel and padded.

3D textures (:func:`export_texture`, :data:`TEXTURE_WRITERS`; :func:`read_texture` decodes them):

- ``.raw``, ``.png`` (``textures``): RGBA with sRGB colour in RGB and signed distance in A, x
  fastest, each with a JSON sidecar ``NAME.EXT.json``.
- ``.nrrd`` (``nrrd``): the SDF alone for ParaView and 3D Slicer.

:func:`resize_grid` (``resize``) resamples the whole grid to a preset size first (``--size``).
"""

from .atlas import ATLAS_SIZES, DEFAULT_ATLAS, bake, check_atlas, unwrap
from .mesh import save_obj
from .resize import PRESET_SIZES, check_size, resize_grid
from .simplify import check_budget, simplify
from .textures import (
    DISTANCE_BAND_VOXELS,
    ISO_LEVEL_8BIT,
    TEXTURE_FORMAT,
    decode_distance_8bit,
    encode_distance_8bit,
    flipbook_layout,
)
from .usd import USD_EXTRA, USD_SUFFIXES, require_usd, save_usd, usd_faces
from .write import (
    MESH_SUFFIXES,
    MESH_WRITERS,
    TEXTURE_READERS,
    TEXTURE_SUFFIXES,
    TEXTURE_WRITERS,
    export_mesh,
    export_texture,
    read_texture,
)

__all__ = [
    "ATLAS_SIZES",
    "DEFAULT_ATLAS",
    "DISTANCE_BAND_VOXELS",
    "ISO_LEVEL_8BIT",
    "MESH_SUFFIXES",
    "MESH_WRITERS",
    "PRESET_SIZES",
    "TEXTURE_FORMAT",
    "TEXTURE_READERS",
    "TEXTURE_SUFFIXES",
    "TEXTURE_WRITERS",
    "USD_EXTRA",
    "USD_SUFFIXES",
    "bake",
    "check_atlas",
    "check_budget",
    "check_size",
    "decode_distance_8bit",
    "encode_distance_8bit",
    "export_mesh",
    "export_texture",
    "flipbook_layout",
    "read_texture",
    "require_usd",
    "resize_grid",
    "save_obj",
    "save_usd",
    "simplify",
    "unwrap",
    "usd_faces",
]
