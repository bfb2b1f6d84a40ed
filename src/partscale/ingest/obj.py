"""Wavefront OBJ + MTL reader: geometry and UVs through trimesh, materials read here.

MTL ``Kd`` and vertex colours are display (sRGB) values; ``map_Kd`` multiplies ``Kd``. OBJ and
MTL carry no encoding: UTF-8 when it decodes, else Latin-1.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np

from ..color import srgb_to_linear
from ..errors import InputError, one_line
from .mesh import ColoredMesh, Material, image_linear, read_scene, scene_to_mesh

# MTL texture options and how many arguments each takes (-o/-s/-t: u and optional v, w)
_MTL_OPTION_ARGS = {
    "-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1, "-imfchan": 1,
    "-mm": 2, "-texres": 1, "-type": 1, "-o": 3, "-s": 3, "-t": 3,
}  # fmt: skip


def _decode_text(data: bytes) -> str:
    # OBJ/MTL carry no encoding: UTF-8 when it decodes, else Latin-1 (every byte is a character)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _float_or_none(tok: str) -> float | None:
    try:
        return float(tok)
    except ValueError:
        return None


def _is_number(tok: str) -> bool:
    """Whether ``tok`` is a finite number (nan, inf and overflowing ones are not)."""
    x = _float_or_none(tok)
    return x is not None and bool(np.isfinite(x))


def _map_kd(line: str) -> tuple[str, np.ndarray | None]:
    """File name and (2, 3) UV affine (``-o``/``-s``) of an MTL ``map_Kd`` line.

    Options come before the file name; the rest of the line (spaces kept) is the name.
    """
    toks = [(m.start(), m.group()) for m in re.finditer(r"\S+", line)][1:]
    scale, offset = [1.0, 1.0], [0.0, 0.0]
    i = 0
    while i < len(toks) and toks[i][1].lower() in _MTL_OPTION_ARGS:
        opt = toks[i][1].lower()
        n = _MTL_OPTION_ARGS[opt]
        args: list[str] = []
        i += 1
        while len(args) < n and i < len(toks) - 1:
            if opt in ("-o", "-s", "-t") and not _is_number(toks[i][1]):
                break  # v and w are optional
            args.append(toks[i][1])
            i += 1
        if opt in ("-o", "-s") and args:
            vals = [float(a) for a in args[:2]]
            target = offset if opt == "-o" else scale
            target[: len(vals)] = vals
    name = line[toks[i][0] :].strip() if i < len(toks) else ""
    if scale == [1.0, 1.0] and offset == [0.0, 0.0]:
        return name, None
    return name, np.array([[scale[0], 0.0, offset[0]], [0.0, scale[1], offset[1]]])


def _read_texture(obj: Path, mtl: Path, name: str) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    tex = mtl.parent / name
    if not tex.is_file() and "\\" in name:  # written on Windows
        tex = mtl.parent / name.replace("\\", "/")
    if not tex.is_file():
        raise InputError(f"{obj}: expected the texture {tex} named by {mtl}, got no such file")
    try:
        with Image.open(tex) as img:
            return image_linear(img)
    except (OSError, ValueError, UnidentifiedImageError) as exc:
        raise InputError(
            f"{obj}: expected a readable texture image {tex}, got {one_line(exc)}"
        ) from None


class _Utf8Resolver:
    """trimesh file resolver that hands text files (MTL) over as UTF-8.

    It keeps the text of each MTL it serves (``mtl``: name -> text), so the materials are read
    from exactly the files trimesh followed (only an OBJ's first ``mtllib``).
    """

    def __init__(self, source: str):
        import trimesh

        self._inner = trimesh.resolvers.FilePathResolver(source)
        self.mtl: dict[str, str] = {}

    def get(self, name: str) -> bytes:
        data = self._inner.get(name)
        if name.lower().endswith(".mtl"):
            text = _decode_text(data)
            self.mtl[name] = text
            data = text.encode("utf-8")
        return data

    def __getitem__(self, name: str) -> bytes:
        return self.get(name)

    def __getattr__(self, name: str):
        return getattr(self._inner, name)


# MTL Kd when a material gives none: trimesh's diffuse for an untextured material (kept so its
# colour does not change); a texture alone is shown as it is.
_KD_PLAIN = 0.4
_KD_TEXTURED = 1.0


def _obj_materials(obj: Path, mtl_texts: dict[str, str]) -> dict[str, Material]:
    """Materials of an OBJ's MTL files (name -> text, relative to the OBJ), by material name.

    They are read here rather than taken from trimesh, which takes the rest of a ``map_Kd``
    line as the file name (options break it), resolves it against the OBJ's folder rather than
    the MTL's, turns a missing texture into plain white and gives a textured material without
    ``Kd`` a diffuse of 0.4. Here options are parsed (``-o``/``-s`` become a UV affine), names
    resolve against the MTL's folder, a missing texture is an :class:`InputError` and a texture
    without ``Kd`` is unscaled (:data:`_KD_TEXTURED`); no ``Kd`` and no texture is
    :data:`_KD_PLAIN` grey.
    """
    out: dict[str, Material] = {}
    for lib, text in mtl_texts.items():
        mtl = obj.parent / lib
        entries: dict[str, dict] = {}
        cur: dict | None = None
        for mline in text.splitlines():
            mt = mline.split()
            if len(mt) < 2:
                continue
            key = mt[0].lower()
            if key == "newmtl":
                cur_name = " ".join(mt[1:])
                cur = entries.setdefault(cur_name, {})
            elif cur is None:
                continue
            elif key == "kd":
                kd_or_none = [_float_or_none(t) for t in mt[1:4]]
                if None in kd_or_none:
                    continue  # "Kd spectral file" / "Kd xyz x y z": not read, the default
                kd = [x for x in kd_or_none if x is not None]
                if not np.isfinite(kd).all():
                    raise InputError(
                        f"{obj}: expected Kd of material {cur_name!r} in {mtl.name} to be "
                        f"finite numbers, got {' '.join(mt[1:4])}"
                    )
                cur["kd"] = kd * 3 if len(kd) == 1 else kd
            elif key == "map_kd":
                cur["map"] = _map_kd(mline.strip())
        for name, e in entries.items():
            tex = uv_tf = None
            if "map" in e and e["map"][0]:
                tex = _read_texture(obj, mtl, e["map"][0])
                uv_tf = e["map"][1]
            default = _KD_TEXTURED if "map" in e else _KD_PLAIN
            diffuse = np.clip(np.asarray(e.get("kd", [default] * 3), np.float32), 0, 1)
            out.setdefault(name, Material(srgb_to_linear(diffuse), tex, uv_tf))
    return out


def _check_mtllib(obj: Path, text: str) -> None:
    """Refuse an OBJ whose material library (its first ``mtllib``, the one read) is missing.

    trimesh would import it all white with no word; a missing texture is refused too.
    """
    for line in text.splitlines():
        if line.startswith("mtllib"):
            name = line[len("mtllib") :].strip()
            if not name:
                return
            mtl = obj.parent / name
            candidates = {name, name.replace("\\", "/"), name.split()[0]}
            if not any((obj.parent / c).is_file() for c in candidates):
                raise InputError(
                    f"{obj}: expected the material library {mtl.name} it names beside it, "
                    f"got {'a directory' if mtl.is_dir() else 'no such file'}"
                )
            return


def load_obj(path: Path) -> ColoredMesh:
    """Read an ``.obj`` (an existing, non-empty file) and its MTL as a :class:`ColoredMesh`."""
    import trimesh

    resolver: _Utf8Resolver | None = None

    def read():
        nonlocal resolver
        # trimesh needs charset_normalizer for text that is not UTF-8: hand it UTF-8
        text = _decode_text(path.read_bytes())
        _check_mtllib(path, text)
        resolver = _Utf8Resolver(str(path))
        return trimesh.load_scene(
            io.BytesIO(text.encode("utf-8")),
            file_type="obj",
            # trimesh annotates Resolver | Mapping but only calls get()/[]; subclassing its
            # Resolver ABC would import trimesh with this module
            resolver=resolver,  # type: ignore[arg-type]
            process=False,
        )

    scene = read_scene(path, read)
    assert resolver is not None
    # outside read_scene: a failure here is ours (or an InputError), not an unreadable OBJ
    materials = _obj_materials(path, resolver.mtl)
    return scene_to_mesh(scene, path, linear_colors=False, materials=materials)
