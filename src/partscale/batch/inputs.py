"""What a batch works on: inputs found in files, folders and manifests, named and hashed.

An input is one object: a main file (what :func:`partscale.ingest.load` reads) and the files it
needs beside it (a glTF's ``.bin`` buffers and textures, an OBJ's ``.mtl`` and its texture maps),
which travel with it and count in its content hash. Each input gets an output name, unique in
the batch and independent of discovery order.
"""

from __future__ import annotations

import csv
import hashlib
import os
import re
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import unquote

from .. import _schema
from .._files import parse_json
from ..csdf import SUFFIX as CSDF_SUFFIX
from ..errors import InputError, shown
from .status import LOCK_NAME, LOG_NAME, STATUS_NAME

INPUT_SUFFIXES = (".glb", ".gltf", ".obj", ".ply", ".npy", ".npz", ".h5", ".hdf5")
"""Suffixes a folder is searched for (lower case); ``.csdf.npz`` files are read as CSDFs."""
MANIFEST_SUFFIXES = (".csv", ".jsonl")
OPTION_KEYS = ("res", "square", "segment", "recipe", "size", "allow_deform", "export", "render")
"""Per-object options a manifest row may set (columns or keys besides ``path`` and ``name``),
named as ``partscale batch``'s options."""
MAX_NAME = 255
"""Longest output folder name (the file systems' limit)."""
OLD_KEYS = {"fit": "size"}
"""Old manifest keys still read, with a note, for one release: old -> new."""


@dataclass(frozen=True)
class Input:
    """One object of a batch.

    Attributes
    ----------
    path : Path
        The main file, absolute.
    files : tuple of Path
        Every file the object is made of, the main file first, then its companions sorted.
    name : str
        Output folder name under OUTDIR (unique in the batch).
    options : dict
        Per-object options from a manifest (override the batch's own), else empty.

    Examples
    --------
    >>> from partscale import batch, data
    >>> item = batch.discover([data.table()])[0]
    >>> item.name, item.path.name, len(item.content_hash())
    ('table', 'table.glb', 64)
    """

    path: Path
    files: tuple[Path, ...]
    name: str = ""
    options: dict[str, Any] = field(default_factory=dict)

    def content_hash(self) -> str:
        """SHA-256 (hex) over every file's name relative to the main file's folder and bytes."""
        h = hashlib.sha256()
        base = self.path.parent
        for f in self.files:
            try:
                rel = f.relative_to(base).as_posix()
            except ValueError:
                rel = f.as_posix()
            h.update(rel.encode() + b"\0")
            try:
                with open(f, "rb") as fh:
                    while chunk := fh.read(1 << 20):
                        h.update(chunk)
            except OSError:
                h.update(b"<missing>")  # the job will report it; the hash must not fail
            h.update(b"\0")
        return h.hexdigest()


def companions(path: Path) -> list[Path]:
    """Files ``path`` refers to that exist: glTF buffers and images, OBJ material libraries and
    their texture maps. Unreadable or corrupt files have none (the reader reports them).
    """
    suffix = path.suffix.lower()
    found: list[Path] = []
    try:
        if suffix == ".gltf":
            doc = parse_json(path.read_bytes(), what=str(path), max_bytes=None)
            for key in ("buffers", "images"):
                for item in doc.get(key, []) or []:
                    uri = item.get("uri") if isinstance(item, dict) else None
                    if isinstance(uri, str) and not uri.startswith("data:"):
                        found.append(path.parent / unquote(uri))
        elif suffix == ".obj":
            for lib in _obj_mtllibs(path):
                found.append(lib)
                found += _mtl_maps(lib)
    except (OSError, ValueError, UnicodeDecodeError, AttributeError):  # InputError too
        return []
    return sorted({p.resolve() for p in found if p.is_file()} - {path.resolve()})


def _obj_mtllibs(path: Path) -> list[Path]:
    libs = []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if line.startswith("mtllib"):
                libs += [path.parent / n for n in line.split()[1:]]
    return [p for p in libs if p.is_file()]


_MAP = re.compile(r"^\s*(map_\w+|bump|disp|decal|refl)\s+(.+)$")


def _mtl_maps(lib: Path) -> list[Path]:
    maps = []
    with open(lib, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            m = _MAP.match(line)
            if m:
                # options (-bm 1.0 ...) come before the file name, which is the last word
                maps.append(lib.parent / m.group(2).split()[-1])
    return maps


def is_input_file(path: Path) -> bool:
    """Whether a folder search takes ``path`` as an input: an input suffix, not a hidden file."""
    name = path.name.lower()
    return not name.startswith(".") and (
        name.endswith(CSDF_SUFFIX) or path.suffix.lower() in INPUT_SUFFIXES
    )


def _stem(path: Path) -> str:
    name = path.name
    if name.lower().endswith(CSDF_SUFFIX):
        return name[: -len(CSDF_SUFFIX)]
    return path.stem


def discover(sources: Sequence[str | os.PathLike], *, exclude: Path | None = None) -> list[Input]:
    """The inputs named by files, folders and manifests.

    Folders are searched recursively by suffix (:data:`INPUT_SUFFIXES`); manifests are ``.csv``
    with a ``path`` column, or ``.jsonl`` with a ``path`` key per line (other columns: ``name``
    and :data:`OPTION_KEYS`, :func:`read_manifest`). A file that is some other input's
    companion (a glTF's ``.bin``, an OBJ's ``.mtl``) is not an input of its own.

    Parameters
    ----------
    sources : sequence of str or os.PathLike
        Files, folders and manifests.
    exclude : Path, optional
        Files under this folder (the output folder) are skipped when searching folders.

    Returns
    -------
    list of Input
        Sorted by path, each path once (or once per manifest ``name``), and named by
        :func:`assign_names` (unique output folder names).

    Raises
    ------
    partscale.errors.InputError
        For a missing source, a folder without inputs, a bad manifest.

    Examples
    --------
    >>> import shutil
    >>> from pathlib import Path
    >>> from partscale import batch, data
    >>> for folder in ("a", "b"):
    ...     Path(folder).mkdir()
    ...     _ = shutil.copy(data.table(), Path(folder) / "table.glb")
    >>> [item.name for item in batch.discover(["a", "b"])]
    ['a__table', 'b__table']
    """
    if not sources:
        raise InputError("batch: expected at least one input (file, folder or manifest), got none")
    found: dict[tuple[Path, str], Input] = {}
    ex = exclude.resolve() if exclude is not None else None
    for src in sources:
        p = Path(src)
        if p.is_dir():
            files = [
                f
                for f in sorted(p.rglob("*"))
                if f.is_file() and is_input_file(f) and not _under(f.resolve(), ex)
            ]
            if not files:
                raise InputError(
                    f"{p}: expected a folder with inputs ({', '.join(INPUT_SUFFIXES)}, "
                    f"{CSDF_SUFFIX}), got none"
                )
            items = [_make(f, {}) for f in files]
            used = {c for it in items for c in it.files[1:]}
            items = [it for it in items if it.path not in used]
        elif p.suffix.lower() in MANIFEST_SUFFIXES:
            items = read_manifest(p)
        elif p.is_file():
            items = [_make(p, {})]
        else:
            raise InputError(f"{p}: expected an input file, folder or manifest, got no such path")
        for it in items:
            # a manifest may list one file twice under two names (two resolutions, say)
            found.setdefault((it.path, it.name), it)
    return assign_names(sorted(found.values(), key=lambda it: (str(it.path), it.name)))


def _under(path: Path, folder: Path | None) -> bool:
    return folder is not None and (path == folder or folder in path.parents)


def _make(path: Path, options: dict[str, Any], name: str = "") -> Input:
    path = path.resolve()
    return Input(path=path, files=(path, *companions(path)), name=name, options=options)


def read_manifest(path: Path) -> list[Input]:
    """Inputs listed in a CSV (header with ``path``) or JSONL (one object per line) manifest.

    Parameters
    ----------
    path : Path
        The manifest. Its paths are relative to its folder; other columns are ``name`` and
        :data:`OPTION_KEYS`, and an empty cell means "the batch's option".

    Returns
    -------
    list of Input
        One per row, in order, with its options.

    Raises
    ------
    partscale.errors.InputError
        For a missing or unreadable manifest, a row without ``path``, or an unknown key.

    Examples
    --------
    The shipped table twice, at two resolutions:

    >>> from pathlib import Path
    >>> from partscale import batch, data
    >>> with open("objects.csv", "w") as f:
    ...     print("path,name,res", file=f)
    ...     print(f"{data.table()},small,32", file=f)
    ...     print(f"{data.table()},large,", file=f)
    >>> [(item.name, item.options) for item in batch.read_manifest(Path("objects.csv"))]
    [('small', {'res': '32'}), ('large', {})]
    """
    if not path.is_file():
        raise InputError(f"{path}: expected a manifest file, got no such file")
    rows: list[tuple[int, dict[str, Any]]] = []
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: expected a UTF-8 manifest, got {exc}") from None
    if path.suffix.lower() == ".csv":
        rows = _csv_rows(text, path)
    else:
        for i, line in enumerate(text.splitlines(), start=1):
            if not line.strip():
                continue
            obj = parse_json(line, what=f"{path}:{i}")  # strict: depth, digits, finite numbers
            if not isinstance(obj, dict):
                raise InputError(f"{path}:{i}: expected a JSON object, got {type(obj).__name__}")
            rows.append((i, obj))
    out = []
    rows = _renamed(rows, path)
    for lineno, row in rows:
        where = f"{path}:{lineno}"
        unknown = sorted(set(row) - {"path", "name", *OPTION_KEYS})
        if unknown:
            raise InputError(
                f"{where}: unknown key(s) {unknown}; keys are path, name, {', '.join(OPTION_KEYS)}"
            )
        if not isinstance(row.get("path"), str) or not row["path"]:
            raise InputError(f"{where}: expected a 'path', got {shown(row.get('path'))}")
        check_row(row, where)
        f = Path(row["path"])
        f = f if f.is_absolute() else path.parent / f
        opts = {k: row[k] for k in OPTION_KEYS if k in row}
        if "size" in opts:
            opts["fit"] = opts.pop("size")  # the fit step's target (the job's key)
        if isinstance(opts.get("recipe"), str) and not Path(opts["recipe"]).is_absolute():
            opts["recipe"] = str(path.parent / opts["recipe"])
        name = row.get("name", "")
        if not isinstance(name, str) or "/" in name or name in (".", ".."):
            raise InputError(f"{where}: expected a folder name for 'name', got {shown(name)}")
        out.append(_make(f, opts, name))
    if not out:
        raise InputError(f"{path}: expected at least one row, got none")
    return out


ROW_TYPES: dict[str, tuple[tuple[type, ...], str]] = {
    "path": ((str,), "a file's path"),
    "name": ((str,), "a folder name"),
    "res": ((int, str), "a whole number"),
    "square": ((bool, str), "true or false"),
    "allow_deform": ((bool, str), "true or false"),
    "segment": ((bool, str, type(None)), "a method or true/false"),
    "recipe": ((str, dict, type(None)), "a recipe file's path or a recipe object"),
    "size": ((str, list), "three sizes (X Y Z)"),
    "export": ((str, list), "formats (a list or comma-separated)"),
    "render": ((bool, str, type(None)), "a view or true/false"),
}
"""The JSON types each manifest key may hold (a CSV cell is always a string)."""


def check_row(row: dict[str, Any], where: str) -> None:
    """A manifest row's values checked for type and size before anything reads them, or an
    :class:`InputError` naming the key: strings without control characters, paths and names
    of bounded length, lists of at most a few strings or numbers.
    """
    for key, value in row.items():
        types, expected = ROW_TYPES.get(key, ((), ""))
        if not types:
            continue
        if not isinstance(value, types) or (
            int not in types and isinstance(value, bool) and bool not in types
        ):
            raise InputError(f"{where}: {key}: expected {expected}, got {shown(value)}")
        if isinstance(value, str):
            _schema.string(value, f"{where}: {key}", empty=True)
        elif isinstance(value, list):
            for i, item in enumerate(_schema.sequence(value, f"{where}: {key}", hi=16)):
                if isinstance(item, str):
                    _schema.string(item, f"{where}: {key}[{i}]", max_len=256)
                elif key == "size":
                    _schema.number(item, f"{where}: {key}[{i}]")
                else:
                    raise InputError(f"{where}: {key}[{i}]: expected a string, got {shown(item)}")
    name = row.get("name")
    if isinstance(name, str) and len(name) > MAX_NAME:
        raise InputError(f"{where}: name: expected at most {MAX_NAME} characters, got {len(name)}")


def _csv_rows(text: str, path: Path) -> list[tuple[int, dict[str, Any]]]:
    """(line, row) of a CSV manifest; empty cells left out (the batch's option)."""
    reader = csv.DictReader(text.splitlines())
    rows = []
    try:
        if not reader.fieldnames or "path" not in reader.fieldnames:
            raise InputError(
                f"{path}: expected a CSV header with a 'path' column, got "
                f"{shown(reader.fieldnames)}"
            )
        for row in reader:
            rows.append(
                (reader.line_num, {k: v for k, v in row.items() if k and v not in (None, "")})
            )
    except csv.Error as exc:
        raise InputError(f"{path}:{reader.line_num}: expected a CSV row, got {exc}") from None
    return rows


def _renamed(rows: list[tuple[int, dict]], path: Path) -> list[tuple[int, dict]]:
    """Rows with old keys (:data:`OLD_KEYS`) under their new names; one note per manifest."""
    import warnings

    from ..errors import PartscaleWarning

    out, seen = [], set()
    for lineno, row in rows:
        for old, new in OLD_KEYS.items():
            if old not in row:
                continue
            if new in row:
                raise InputError(
                    f"{path}:{lineno}: expected {new} ({old} is its old name), got both"
                )
            row = {(new if k == old else k): v for k, v in row.items()}
            seen.add(old)
        out.append((lineno, row))
    for old in sorted(seen):
        warnings.warn(
            f"{path}: manifest key {old!r} is now {OLD_KEYS[old]!r}; the old name goes in the "
            "next release",
            PartscaleWarning,
            stacklevel=3,
        )
    return out


def assign_names(items: Iterable[Input]) -> list[Input]:
    """Give every input a unique, safe output name, the same whatever order they were found in.

    A manifest's ``name`` wins; otherwise the file name without its extension. Where several
    inputs would share a name, each gets the shortest tail of its folder path that tells them
    apart, joined with ``__`` (``kenney/chair.glb`` and ``sweethome3d/chair.obj`` become
    ``kenney__chair`` and ``sweethome3d__chair``). Two manifest names that clash are an error.
    Every name is then made safe (:func:`safe_name`) and unique (:func:`unique_names`), each
    change said in a note.

    Parameters
    ----------
    items : iterable of Input
        The inputs (their ``name``: a manifest's, or empty).

    Returns
    -------
    list of Input
        The same inputs in the same order, each with its output folder name.

    Raises
    ------
    partscale.errors.InputError
        For two equal manifest names, or a manifest name that is no safe folder name.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale.batch.inputs import Input, assign_names
    >>> found = [Input(Path(p), (Path(p),)) for p in ("/in/a/x.glb", "/in/b/x.glb", "/in/a__x.glb")]
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as notes:
    ...     warnings.simplefilter("always")
    ...     named = assign_names(found)
    >>> [it.name for it in named]
    ['a__x', 'b__x', 'a__x~2']
    >>> print(notes[0].message)
    /in/a__x.glb: output folder 'a__x' is /in/a/x.glb's already; this one writes to 'a__x~2'
    """
    items = list(items)
    explicit = [it.name for it in items if it.name]
    dup = sorted({n for n in explicit if explicit.count(n) > 1})
    if dup:
        raise InputError(f"batch: expected unique manifest names, got {dup[0]!r} more than once")
    for it in items:
        if it.name and safe_name(it.name)[1] is not None:
            raise InputError(
                f"{it.path}: expected a folder name for 'name', got {shown(it.name)} "
                f"({safe_name(it.name)[1]})"
            )
    wanted = [it.name or _stem(it.path) for it in items]
    names = _told_apart(items, wanted, explicit)
    for i, it in enumerate(items):
        if not it.name:
            names[i], why = safe_name(names[i])
            if why is not None:
                _note(f"{it.path}: output folder named {names[i]!r} ({why})")
    names = unique_names(
        [(str(it.path), n, bool(it.name)) for it, n in zip(items, names, strict=True)]
    )
    return [
        Input(path=it.path, files=it.files, name=n, options=it.options)
        for it, n in zip(items, names, strict=True)
    ]


def _told_apart(items: list[Input], wanted: list[str], explicit: list[str]) -> list[str]:
    """``wanted`` with the inputs that share one told apart by their folders' tails, then by
    their suffixes (same folder and stem).
    """
    names = list(wanted)
    groups: dict[str, list[int]] = {}
    for i, (it, n) in enumerate(zip(items, wanted, strict=True)):
        if not it.name:
            groups.setdefault(n, []).append(i)
    for n, idx in groups.items():
        if len(idx) < 2 and n not in explicit:
            continue
        for i in idx:
            mine = items[i].path.parent
            others = [items[j].path.parent.parts for j in idx if items[j].path.parent != mine]
            p, d = mine.parts, 1
            while d < len(p) and any(o[-d:] == p[-d:] for o in others):
                d += 1
            names[i] = "__".join([*p[-d:], n])
    # same folder and stem, different suffixes (other clashes: unique_names)
    same: Counter = Counter(
        (n, it.path.parent, _stem(it.path)) for n, it in zip(names, items, strict=True)
    )
    return [
        f"{n}.{it.path.suffix.lstrip('.').lower()}"
        if same[n, it.path.parent, _stem(it.path)] > 1
        else n
        for n, it in zip(names, items, strict=True)
    ]


RESERVED_NAMES = (STATUS_NAME, LOCK_NAME, LOG_NAME)
"""Names in OUTDIR that are the batch's own files, never an object's folder."""
#: Longest output name, in UTF-8 bytes (file systems allow 255; room for ``~N`` and temporaries)
MAX_NAME_BYTES = 200
_UNSAFE_CHARS = re.compile(r"[\x00-\x1f\x7f/\\]")


def safe_name(name: str) -> tuple[str, str | None]:
    r"""``name`` made a safe output folder name, and why it changed (None where it did not).

    Safe: no NUL, control character, ``/`` or ``\`` (each becomes ``_``); not hidden (a
    leading ``.`` becomes ``_``), not empty, ``.`` or ``..``; not one of the batch's own files
    (:data:`RESERVED_NAMES`, in any case: ``_`` is appended); at most :data:`MAX_NAME_BYTES`
    bytes of UTF-8 (cut, with a hash of the whole name appended).

    Parameters
    ----------
    name : str
        The wanted name.

    Returns
    -------
    str
        The safe name.
    str or None
        What was changed, for a note (None: nothing).

    Examples
    --------
    >>> from partscale.batch.inputs import safe_name
    >>> safe_name("chair")
    ('chair', None)
    >>> safe_name("status.csv")
    ('status.csv_', "'status.csv' is the batch's own file")
    >>> safe_name("a\x00b")[0]
    'a_b'
    """
    why = []
    new = _UNSAFE_CHARS.sub("_", name)
    if new != name:
        why.append("NUL, control characters and slashes replaced")
    if new.startswith("."):
        new = "_" + new[1:]
        why.append("a hidden name made visible")
    if not new.strip("._ "):
        new = f"_{new}" if new else "_"
        why.append("an empty name")
    if new.casefold() in {r.casefold() for r in RESERVED_NAMES}:
        why.append(f"{new!r} is the batch's own file")
        new += "_"
    raw = new.encode("utf-8")
    if len(raw) > MAX_NAME_BYTES:
        digest = hashlib.sha256(raw).hexdigest()[:8]
        new = raw[: MAX_NAME_BYTES - 9].decode("utf-8", "ignore") + "-" + digest
        why.append(f"cut to {MAX_NAME_BYTES} bytes")
    return new, ("; ".join(why) if why else None)


def unique_names(entries: Sequence[tuple[str, str, bool]]) -> list[str]:
    """The names of ``entries`` made unique (case aside), each change said in a note.

    Parameters
    ----------
    entries : sequence of (key, name, kept)
        Per input: a key ordering it (its path), the name it wants, and whether the name must be
        kept (a manifest's: those are unique already).

    Returns
    -------
    list of str
        One name per entry, in order; where several want one name (in any case: a file system
        may not tell ``Chair`` from ``chair``), a kept name keeps it, then the first by key, and
        the others get ``NAME~2``, ``NAME~3``...

    Examples
    --------
    >>> from partscale.batch.inputs import unique_names
    >>> import warnings
    >>> with warnings.catch_warnings(record=True):
    ...     warnings.simplefilter("always")
    ...     names = unique_names([("in/a/x.glb", "a__x", False), ("in/a__x.glb", "a__x", False)])
    >>> names
    ['a__x', 'a__x~2']
    """
    order = sorted(range(len(entries)), key=lambda i: (not entries[i][2], entries[i][0], i))
    taken = {entries[i][1].casefold() for i in order if entries[i][2]}
    out = [e[1] for e in entries]
    for i in order:
        key, name, kept = entries[i]
        if kept:
            continue
        if name.casefold() not in taken:
            taken.add(name.casefold())
            continue
        k = 2
        while f"{name}~{k}".casefold() in taken or any(
            f"{name}~{k}".casefold() == e[1].casefold() for e in entries
        ):
            k += 1
        out[i] = f"{name}~{k}"
        taken.add(out[i].casefold())
        first = next(
            e[0] for j, e in enumerate(entries) if j != i and e[1].casefold() == name.casefold()
        )
        _note(f"{key}: output folder {name!r} is {first}'s already; this one writes to {out[i]!r}")
    return out


def _note(message: str) -> None:
    import warnings

    from ..errors import PartscaleWarning

    warnings.warn(message, PartscaleWarning, stacklevel=3)


def shard(items: Sequence[Input], rank: int, world_size: int) -> list[Input]:
    """The inputs of shard ``rank`` of ``world_size``: every ``world_size``-th from ``rank``.

    Parameters
    ----------
    items : sequence of Input
        Every input, named (:func:`discover`).
    rank : int
        This shard, ``0 .. world_size - 1``.
    world_size : int
        How many shards.

    Returns
    -------
    list of Input
        The shard's inputs. The shards of 0..world_size-1 partition ``items`` exactly (each
        once, none missing), and names were assigned before sharding, so they agree.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale import batch
    >>> items = [batch.Input(Path(f"{n}.glb"), (Path(f"{n}.glb"),), n) for n in "abcde"]
    >>> [[item.name for item in batch.shard(items, rank, 2)] for rank in (0, 1)]
    [['a', 'c', 'e'], ['b', 'd']]
    """
    if isinstance(world_size, bool) or not isinstance(world_size, int) or world_size < 1:
        raise InputError(f"world_size: expected an integer >= 1, got {world_size!r}")
    if isinstance(rank, bool) or not isinstance(rank, int) or not 0 <= rank < world_size:
        raise InputError(f"rank: expected an integer in [0, {world_size - 1}], got {rank!r}")
    return list(items[rank::world_size])
