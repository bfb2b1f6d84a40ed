"""The editing session behind the web editor: one CSDF, its undo/redo stacks, save and export.

The session is the only state the server holds. It knows the one file it was started with and
derives every path it writes from that file (never from a request).
"""

from __future__ import annotations

import tempfile
import threading
from pathlib import Path
from typing import Any

import numpy as np

from .. import csdf as csdf_mod
from ..csdf import CSDF
from ..errors import InputError
from ..progress import ProgressCallback

#: Most undo steps kept; a 128³ CSDF is ~20 MiB, so this bounds memory at ~1 GiB.
MAX_UNDO = 48


def edited_path(path: Path) -> Path:
    """``NAME.csdf.npz`` -> ``NAME.edited.csdf.npz`` (beside it): where Save writes by default."""
    name = path.name
    stem = name[: -len(csdf_mod.SUFFIX)] if name.endswith(csdf_mod.SUFFIX) else path.stem
    return path.with_name(f"{stem}.edited{csdf_mod.SUFFIX}")


def encode_grid(c: CSDF) -> bytes:
    """The grid as the page's 3D texture: ``(Z, Y, X, 4)`` float16 little-endian, x fastest.

    Channels: r, g, b = sRGB / 255 (the stored 8-bit colour, not linearised); a = sdf /
    voxel_size, i.e. signed distance in voxels (negative inside), which keeps float16's relative
    precision near the surface whatever the object's units.
    """
    x, y, z = c.shape
    out = np.empty((z, y, x, 4), dtype="<f2")
    out[..., :3] = c.rgb.transpose(2, 1, 0, 3)
    out[..., :3] *= np.float16(1.0 / 255.0)
    out[..., 3] = c.sdf.T * np.float32(1.0 / c.voxel_size)
    return out.tobytes()


def encode_parts(c: CSDF) -> bytes:
    """``(Z, Y, X)`` int16 little-endian part indices, x fastest, -1 where none."""
    return np.ascontiguousarray(c.parts.T, dtype="<i2").tobytes()


def header(c: CSDF) -> dict[str, Any]:
    """JSON description of ``c`` for the page: grid geometry, solid bounds, parts, history."""
    try:
        solid = c.surface_bounds().tolist()
    except InputError:
        solid = None
    parts_info = c.meta.get("parts_info")
    return {
        "shape": list(c.shape),
        "origin": c.origin.tolist(),
        "voxel_size": c.voxel_size,
        "grid_bounds": c.grid_bounds.tolist(),
        "solid_bounds": solid,
        "units": c.meta.get("units", "m"),
        "n_parts": c.n_parts,
        "parts_info": parts_info if isinstance(parts_info, list) else [],
        "history": c.meta.get("history", []),
        "encoding": {
            "grid": "RGBA float16 little-endian, x fastest; rgb = sRGB/255, a = sdf/voxel_size",
            "parts": "int16 little-endian, x fastest; -1 = none",
        },
    }


class EditSession:
    """One object being edited: current CSDF, undo and redo stacks, where to save.

    All mutating methods take the session lock, so concurrent requests apply one at a time and
    never interleave an apply with an undo.
    """

    def __init__(self, path: Path, csdf: CSDF):
        self.path = Path(path)
        self.current = csdf
        self.undo_stack: list[CSDF] = []
        self.redo_stack: list[CSDF] = []
        self.revision = 0
        self.saved_revision = 0
        self.lock = threading.Lock()
        self._cache: dict[str, tuple[int, bytes]] = {}

    @classmethod
    def open(cls, path: str | Path) -> EditSession:
        path = Path(path)
        return cls(path, csdf_mod.load(path))

    # -- state ----------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """Header of the current object plus the session's own state."""
        h = header(self.current)
        h.update(
            revision=self.revision,
            can_undo=bool(self.undo_stack),
            can_redo=bool(self.redo_stack),
            unsaved=self.revision != self.saved_revision,
            name=self.path.name,
            save_as=edited_path(self.path).name,
        )
        return h

    def _encoded(self, kind: str) -> bytes:
        # Encoding a 128³ grid takes tens of ms; cache it per revision (the page fetches it once
        # after every change, a test or second tab may fetch it again).
        with self.lock:
            rev, c = self.revision, self.current
            hit = self._cache.get(kind)
        if hit is not None and hit[0] == rev:
            return hit[1]
        data = encode_grid(c) if kind == "grid" else encode_parts(c)
        with self.lock:
            if self.revision == rev:
                self._cache[kind] = (rev, data)
        return data

    def grid_bytes(self) -> bytes:
        return self._encoded("grid")

    def parts_bytes(self) -> bytes:
        return self._encoded("parts")

    def _push(self, new: CSDF) -> None:
        self.undo_stack.append(self.current)
        del self.undo_stack[:-MAX_UNDO]
        self.redo_stack.clear()
        self.current = new
        self.revision += 1

    # -- edits ----------------------------------------------------------------------------
    def apply(self, recipe: Any, *, progress: ProgressCallback | None = None) -> CSDF:
        """Bake ``recipe`` (a Recipe or its JSON dict) into the current object (undoable)."""
        from ..edit import Recipe, apply_recipe

        parsed = Recipe.parse(recipe) if not isinstance(recipe, Recipe) else recipe
        with self.lock:
            new = apply_recipe(self.current, parsed, progress=progress)
            self._push(new)
            return new

    def undo(self) -> bool:
        """Restore the object before the last apply exactly (the same arrays); False if none."""
        with self.lock:
            if not self.undo_stack:
                return False
            self.redo_stack.append(self.current)
            self.current = self.undo_stack.pop()
            self.revision += 1
            return True

    def redo(self) -> bool:
        with self.lock:
            if not self.redo_stack:
                return False
            self.undo_stack.append(self.current)
            self.current = self.redo_stack.pop()
            self.revision += 1
            return True

    # -- output ---------------------------------------------------------------------------
    def save(self, *, overwrite: bool = False) -> Path:
        """Write the current object to ``NAME.edited.csdf.npz``, or over the input file."""
        with self.lock:
            c, rev = self.current, self.revision
        target = self.path if overwrite else edited_path(self.path)
        csdf_mod.save(c, target)
        with self.lock:
            self.saved_revision = rev
        return target

    def export(self, kind: str) -> tuple[bytes, str, str]:
        """Export the current object; returns ``(data, filename, media type)``.

        ``kind`` is ``'mesh'`` (binary glTF with vertex colours) or ``'texture'`` (the 3D
        texture file written by :func:`partscale.export.export_texture`).
        """
        from .. import export as export_mod

        with self.lock:
            c = self.current
        stem = edited_path(self.path).name[: -len(csdf_mod.SUFFIX)]
        if kind == "mesh":
            name, media = f"{stem}.glb", "model/gltf-binary"
            writer = export_mod.export_mesh
        elif kind == "texture":
            name, media = f"{stem}{TEXTURE_SUFFIX}", "application/octet-stream"
            writer = export_mod.export_texture
        else:
            raise InputError(f"export: expected 'mesh' or 'texture', got {kind!r}")
        with tempfile.TemporaryDirectory(prefix="partscale-export-") as tmp:
            out = Path(tmp) / name
            writer(c, out)
            files = sorted(p for p in Path(tmp).iterdir() if p.is_file())
            if len(files) == 1:
                return files[0].read_bytes(), files[0].name, media
            return _zip(files), f"{stem}.texture.zip", "application/zip"
        raise AssertionError("unreachable")  # pragma: no cover


#: Suffix asked of export_texture; it writes the format its suffix names.
TEXTURE_SUFFIX = ".nrrd"


def _zip(files: list[Path]) -> bytes:
    # export_texture may write a sidecar (e.g. a JSON header next to raw data): ship them together.
    import io
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for f in files:
            z.write(f, f.name)
    return buf.getvalue()
