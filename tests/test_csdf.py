"""The CSDF type and its file: validation, exact round trips, atomic saves, clear errors."""

from __future__ import annotations

import errno
import json
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_bad_input

import partscale
from partscale import shapes
from partscale.csdf import load, make, save
from partscale.edit import Edit, resolve_edit
from partscale.errors import InputError, MemoryLimitError
from partscale.export import resize_grid


@pytest.fixture
def ball():
    return shapes.sphere((0.1, -0.2, 0.3), 0.25, voxel_size=0.02)


def test_sphere_grid_holds_known_distances():
    # a voxel lies on the centre; distances to voxels at whole-voxel offsets along Pythagorean
    # quadruples are known by hand: |(2, 3, 6)| = 7, |(1, 2, 2)| = 3, |(0, 3, 4)| = 5
    h = 0.05
    c = shapes.sphere((0.0, 0.0, 0.0), 0.25, voxel_size=h)
    centre = np.rint(-c.origin / h).astype(int)
    assert np.abs(c.index_to_world(centre[None])[0]).max() < 1e-12
    known = {(0, 0, 0): -0.25, (1, 2, 2): -0.1, (0, 3, 4): 0.0, (5, 0, 0): 0.0, (2, 3, 6): 0.1}
    for offset, d in known.items():
        for sign in (1, -1):
            i, j, k = centre + sign * np.array(offset)
            assert abs(c.sdf[i, j, k] - d) < 1e-6, (offset, sign)


def test_sphere_grid_is_a_distance_field(ball):
    # a distance has unit gradient (away from the centre, its kink) and the solid the volume of
    # the ball
    g = np.stack(np.gradient(ball.sdf.astype(np.float64), ball.voxel_size), axis=-1)[
        1:-1, 1:-1, 1:-1
    ]
    inner = ball.sdf[1:-1, 1:-1, 1:-1]  # central differences only
    far = inner + 0.25 > 0.1  # 5 voxels from the centre
    norm = np.linalg.norm(g, axis=-1)[far]
    # central differences across the curved level sets err by up to (h / rho)^2 / 2: 2% here
    assert np.abs(norm - 1).max() < 0.02
    volume = (ball.sdf < 0).sum() * ball.voxel_size**3
    assert abs(volume / (4 / 3 * np.pi * 0.25**3) - 1) < 0.02


def test_arrays_are_read_only_and_caller_array_untouched():
    sdf = np.ones((4, 5, 6), np.float32)
    sdf[1:3, 1:4, 1:5] = -1
    c = make(sdf)
    assert sdf.flags.writeable  # the caller's array is not frozen behind their back
    sdf[0, 0, 0] = 7
    assert c.sdf[0, 0, 0] == 1
    with pytest.raises(ValueError):
        c.sdf[0, 0, 0] = 2


def test_every_public_update_validates_the_values(ball):
    # make, replace and with_history have no path that skips the value checks
    nan = ball.sdf.copy()
    nan[1, 2, 3] = np.nan
    far = np.full(ball.shape, 1e30, np.float32)  # beyond 1e9 voxel sizes
    parts = np.full(ball.shape, -2)
    for update in (
        lambda **kw: make(**{"sdf": ball.sdf, **kw}),
        ball.replace,
        lambda **kw: ball.with_history({"op": "test"}, **kw),
    ):
        with pytest.raises(InputError, match="1 NaN/inf voxel"):
            update(sdf=nan)
        with pytest.raises(InputError, match=r"\|values\| <="):
            update(sdf=far)
        with pytest.raises(InputError, match=r"got \[-2, -2\]"):
            update(parts=parts)
    with pytest.raises(TypeError):
        make(nan, trusted=True)  # no trusted path in the public constructor


def test_trusted_history_checks_all_but_the_values(ball):
    # a stage's own arrays: the same CSDF as with_history, shapes and dtypes still checked
    parts = np.where(ball.sdf < 0, 2, -1).astype(np.int16)
    a = ball.with_trusted_history({"op": "test"}, parts=parts)
    b = ball.with_history({"op": "test"}, parts=parts)
    assert np.array_equal(a.parts, b.parts) and a.meta == b.meta
    assert ball.meta.get("history", []) == list(a.meta["history"])[:-1]
    with pytest.raises(InputError, match="rgb: expected shape"):
        ball.with_trusted_history({"op": "test"}, rgb=np.zeros((2, 2, 2, 3), np.uint8))
    with pytest.raises(InputError, match="parts: expected integer"):
        ball.with_trusted_history({"op": "test"}, parts=ball.sdf)


def test_save_load_is_exact(tmp_path, ball):
    c = ball.with_history({"op": "test", "n": 1}, parts=np.where(ball.sdf < 0, 3, -1))
    p = save(c, tmp_path / "ball.csdf.npz")
    d = load(p)
    for name in ("sdf", "rgb", "parts", "origin"):
        a, b = getattr(c, name), getattr(d, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert d.voxel_size == c.voxel_size
    assert d.meta == c.meta
    assert d.meta["history"][-1] == {"op": "test", "n": 1}
    assert d.n_parts == 4
    assert list(tmp_path.iterdir()) == [p]  # no temporary left beside it
    assert p.stat().st_mode & 0o044  # readable by others, like any file the user writes


def test_surface_bounds_subvoxel():
    c = shapes.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.25), voxel_size=0.05)
    sb = c.surface_bounds()
    assert np.allclose(sb, [[0, 0, 0], [1.0, 0.5, 0.25]], atol=0.05 * 0.05)


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"sdf": np.zeros((4, 4))}, "3D grid"),
        ({"sdf": np.full((4, 4, 4), np.nan)}, "NaN"),
        ({"sdf": np.zeros((4, 4, 4), int)}, "floating"),
        ({"sdf": np.zeros((4, 4, 4)), "rgb": np.zeros((4, 4, 4, 3), float)}, "uint8"),
        ({"sdf": np.zeros((4, 4, 4)), "parts": np.zeros((4, 4, 3), int)}, "shape"),
        ({"sdf": np.zeros((4, 4, 4)), "voxel_size": -1}, "voxel_size"),
        ({"sdf": np.zeros((4, 4, 4)), "origin": (0, 1)}, "origin"),
        ({"sdf": np.zeros((4, 4, 4)), "origin": ["1", "2", "3"]}, "origin: expected 3 finite"),
        ({"sdf": np.zeros((4, 4, 4)), "voxel_size": True}, "voxel_size: expected one number"),
        ({"sdf": np.zeros((4, 4, 4)), "meta": {"history": 5}}, "history: expected a list of"),
    ],
)
def test_make_rejects_bad_arrays(kwargs, fragment):
    with pytest.raises(InputError, match=fragment):
        make(**kwargs)


def test_load_rejects_bad_files(tmp_path, ball):
    good = save(ball, tmp_path / "good.csdf.npz")
    truncated = tmp_path / "trunc.csdf.npz"
    truncated.write_bytes(good.read_bytes()[:200])
    with pytest.raises(InputError, match=r"trunc\.csdf\.npz"):
        load(truncated)
    with pytest.raises(InputError, match="no such file"):
        load(tmp_path / "missing.csdf.npz")
    other = tmp_path / "other.npz"
    np.savez(other, sdf=np.zeros((3, 3, 3), np.float32))
    with pytest.raises(InputError, match="missing"):
        load(other)
    # a newer format version is refused, not misread
    bumped = tmp_path / "v9.csdf.npz"
    with zipfile.ZipFile(good) as z:
        arrays = {n[:-4]: np.load(z.open(n)) for n in z.namelist()}
    meta = json.loads(str(arrays["meta"]))
    meta["version"] = 9
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez(bumped, **arrays)
    with pytest.raises(InputError, match="version"):
        load(bumped)


def _arrays(path) -> dict:
    with zipfile.ZipFile(path) as z:
        return {n[:-4]: np.load(z.open(n)) for n in z.namelist()}


def _with_meta(arrays, **changes) -> dict:
    meta = json.loads(str(arrays["meta"]))
    meta.update(changes)
    return {**arrays, "meta": np.array(json.dumps(meta))}


def test_a_mesh_read_as_a_csdf_is_refused_naming_the_import(tmp_path, cli):
    """info on a GLB (a new user's first try): one line naming what makes a CSDF of it; a
    damaged .csdf.npz is not told to import anything."""
    import trimesh

    mesh = tmp_path / "box.glb"
    trimesh.creation.box().export(mesh)
    assert_bad_input(cli("info", mesh), "expected a .csdf.npz", "partscale import makes one")
    damaged = tmp_path / "damaged.csdf.npz"
    damaged.write_bytes(b"not a zip")
    with pytest.raises(InputError, match=r"expected a \.csdf\.npz \(zip of \.npy arrays\), got"):
        load(damaged)


def test_load_refuses_damaged_compressed_data(tmp_path, ball):
    """Bytes flipped inside the compressed sdf member: an InputError wherever they land."""
    good = save(ball, tmp_path / "good.csdf.npz")
    src = good.read_bytes()
    with zipfile.ZipFile(good) as z:
        h = z.getinfo("sdf.npy").header_offset
    # member data follow the local header, its file name and its (local) extra field
    start = h + 30 + int.from_bytes(src[h + 26 : h + 28], "little")
    start += int.from_bytes(src[h + 28 : h + 30], "little")
    bad = tmp_path / "bad.csdf.npz"
    for k in range(0, 400, 7):
        b = bytearray(src)
        b[start + k : start + k + 16] = bytes(x ^ 0xFF for x in b[start + k : start + k + 16])
        bad.write_bytes(bytes(b))
        with pytest.raises(InputError, match=r"bad\.csdf\.npz: expected"):
            load(bad)


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        ({"meta": np.array(json.dumps([1, 2]))}, "meta to be a JSON object, got list"),
        ({"meta": np.array(b"{}")}, "meta to be one JSON string"),
        ({"history": 5}, "meta history: expected a list of objects, got 5"),
        ({"history": [1]}, "meta history: expected a list of objects"),
        ({"version": True}, "format version 1, got True"),
        (
            {"origin": np.array(["a", "b", "c"])},
            r"origin: expected 3 finite numbers, got \['a', 'b', 'c'\]",
        ),
        ({"origin": np.array([0.0, np.nan, 0.0])}, "origin: expected 3 finite numbers"),
        ({"origin": np.zeros(2)}, "origin: expected 3 finite numbers"),
        ({"voxel_size": np.array("x")}, "voxel_size: expected one number, got 'x'"),
        ({"voxel_size": np.float64(np.inf)}, "voxel_size: expected a finite number > 0"),
        ({"voxel_size": np.float64(0)}, "voxel_size: expected a finite number > 0"),
    ],
)
def test_load_refuses_bad_meta_origin_and_voxel_size(tmp_path, ball, change, fragment):
    arrays = _arrays(save(ball, tmp_path / "good.csdf.npz"))
    meta_keys = {k: v for k, v in change.items() if k in ("history", "version")}
    arrays = _with_meta(arrays, **meta_keys) if meta_keys else arrays
    arrays.update({k: v for k, v in change.items() if k not in meta_keys})
    bad = tmp_path / "bad.csdf.npz"
    np.savez(bad, **arrays)
    with pytest.raises(InputError, match=rf"bad\.csdf\.npz: .*{fragment}"):
        load(bad)


def test_load_refuses_extra_arrays_listing_the_expected_ones(tmp_path, ball):
    arrays = _arrays(save(ball, tmp_path / "good.csdf.npz"))
    bad = tmp_path / "bad.csdf.npz"
    np.savez(bad, **arrays, foo=np.zeros(3))
    with pytest.raises(
        InputError,
        match=r"bad\.csdf\.npz: expected exactly the arrays sdf, rgb, "
        r"parts, origin, voxel_size, meta, got extra foo",
    ):
        load(bad)


def test_disk_full_is_one_input_error_naming_the_file_and_leaves_nothing(
    tmp_path, ball, monkeypatch
):
    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np.lib.format, "write_array", full)
    target = tmp_path / "x.csdf.npz"
    with pytest.raises(InputError, match="no space left") as err:
        save(ball, target)
    assert str(target) in str(err.value)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("refuse", ["tempfile.mkstemp", "os.replace"])
def test_file_system_refusal_is_one_input_error_naming_the_file(
    tmp_path, ball, monkeypatch, refuse
):
    def denied(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(refuse, denied)
    target = tmp_path / "x.csdf.npz"
    with pytest.raises(InputError, match="expected a writable file, got Permission denied") as err:
        save(ball, target)
    assert str(target) in str(err.value)
    assert list(tmp_path.iterdir()) == []


def test_memory_guard_names_the_need(monkeypatch, ball):
    # resampling to 256: 256^3 voxels of 4 + 3 + 2 bytes, 144 MiB
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(100 << 20))
    with pytest.raises(MemoryLimitError, match=r"256x256x256 grid would need 144\.0 MiB"):
        resize_grid(ball, 256)
    assert resize_grid(ball, 64).shape == (64, 64, 64)


def test_memory_guard_message_stays_short_for_absurd_requests(ball):
    # a mistyped size (an edit to 1e300 m) must not print hundreds of digits
    with pytest.raises(MemoryLimitError) as err:
        resolve_edit(ball, Edit("x", "20%", "80%", 1e300))
    message = str(err.value)
    assert len(message) < 160, message
    assert "5.00e+301x32x32 grid" in message and "EiB" in message


def test_unknown_option_lists_the_known_ones(ball):
    assert resize_grid(ball, size=32).shape == (32, 32, 32)
    with pytest.raises(TypeError, match="options are: csdf, size, progress"):
        resize_grid(ball, 32, gamma=3)


def test_info_cli(tmp_path, ball, cli):
    p = save(ball, tmp_path / "ball.csdf.npz")
    proc = cli("info", p, "--json", check=True)
    s = json.loads(proc.stdout)
    assert s["shape"] == list(ball.shape)
    assert s["solid_bounds"]["size"] == pytest.approx([0.5, 0.5, 0.5], abs=0.02 * 0.1)
    assert_bad_input(cli("info", tmp_path / "nope.csdf.npz"), "nope.csdf.npz", "no such file")


def test_version_is_the_packages():
    # one version: what `import partscale` says is what the package is built and installed as
    with open(Path(__file__).resolve().parents[1] / "pyproject.toml", "rb") as f:
        declared = tomllib.load(f)["project"]["version"]
    assert partscale.__version__ == declared


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("info",), "missing argument"),
        (("no-such-command",), "no such command"),
        (("info", "x.csdf.npz", "--bogus"), "no such option"),
    ],
)
def test_cli_usage_errors_are_one_line(cli, args, fragment):
    assert_bad_input(cli(*args), fragment)


# -- history: shared, read-only, linear cost ---------------------------------------------------
class _Cost:
    """Counts what recording operations copies: objects deep-copied (the size of each copy's
    memo, which holds every container it copied) and bytes serialised to check JSON."""

    def __init__(self, monkeypatch):
        import copy

        self.copies = self.json_bytes = 0
        real_copy, real_dumps = copy.deepcopy, json.dumps

        def deepcopy(x, memo=None, _nil=None):
            memo = {} if memo is None else memo
            before = len(memo)
            out = real_copy(x, memo)
            self.copies += max(1, len(memo) - before)
            return out

        def dumps(obj, *a, **kw):
            text = real_dumps(obj, *a, **kw)
            self.json_bytes += len(text)
            return text

        monkeypatch.setattr(copy, "deepcopy", deepcopy)
        monkeypatch.setattr(json, "dumps", dumps)

    def take(self) -> tuple[int, int]:
        out = (self.copies, self.json_bytes)
        self.copies = self.json_bytes = 0
        return out


def test_850_operations_cost_linear_history_is_shared_not_copied(ball, monkeypatch):
    # the fuzz campaign's 850-edit session: each edit deep-copied and re-serialised the whole
    # history (several times), so an edit's cost grew with the history and the session's with
    # its square. Recording an operation must cost the same at entry 800 as at entry 1.
    cost = _Cost(monkeypatch)
    c, per_op = ball, []
    for i in range(850):
        op = {"op": "scale", "n": i, "edit": {"axis": "x", "zone": [0.1, 0.2], "to": 0.3}}
        c = c.with_history(op)
        per_op.append(cost.take())
    first = np.array(per_op[1:51]).sum(axis=0)
    last = np.array(per_op[-50:]).sum(axis=0)
    assert last[0] <= first[0], (first, last)  # deep copies: the same count at any length
    # bytes checked: only the new entry (its "n" has at most two more digits)
    assert last[1] <= first[1] + 2 * 50, (first, last)
    assert len(c.meta["history"]) == len(ball.meta["history"]) + 850
    assert c.meta["history"][-1]["n"] == 849


def test_history_is_read_only_and_behaves_as_a_list_of_dicts(ball, tmp_path):
    import pickle

    op = {"op": "test", "zone": [1.0, 2.0], "nested": {"k": [1, 2]}}
    c = ball.with_history(op)
    op["zone"].append(3.0)  # the caller's dict stays theirs
    h = c.meta["history"]
    assert h[-1] == {"op": "test", "zone": [1.0, 2.0], "nested": {"k": [1, 2]}}
    assert h == [*ball.meta["history"], h[-1]] and isinstance(h, list)
    for change in (
        lambda: h.append({}),
        lambda: h.__setitem__(0, {}),
        lambda: h[-1].__setitem__("op", "x"),
        lambda: h[-1]["zone"].append(1),
        lambda: h[-1]["nested"].update(k=0),
    ):
        with pytest.raises(TypeError, match="read-only"):
            change()
    d = c.with_history({"op": "more"})
    assert d.meta["history"][-2] is h[-1]  # shared, not copied
    assert c.meta["history"] == h and len(d.meta["history"]) == len(h) + 1
    assert load(save(d, tmp_path / "h.csdf.npz")).meta == d.meta
    assert pickle.loads(pickle.dumps(d.meta)) == d.meta
    # a plain list given to make is checked and frozen like any history
    with pytest.raises(InputError, match="history"):
        make(ball.sdf, meta={"history": [{"x": object()}]})
    with pytest.raises(InputError, match="history"):
        make(ball.sdf, meta={"history": [1]})


def test_save_deflates_only_what_shrinks(tmp_path, ball):
    """Exact distances with full float noise do not deflate (a real object's sdf shrinks ~10 %
    for a second and more at 256^3): stored; an analytic ball's smooth field and the colours
    and parts shrink: deflated. Either way the file reads back exact and the bytes repeat."""
    rng = np.random.default_rng(0)
    noisy = ball.replace(sdf=ball.sdf + rng.normal(0, 1e-3, ball.shape).astype(np.float32))
    for c, sdf_method in ((ball, zipfile.ZIP_DEFLATED), (noisy, zipfile.ZIP_STORED)):
        p = save(c, tmp_path / "c.csdf.npz")
        with zipfile.ZipFile(p) as z:
            method = {i.filename: i.compress_type for i in z.infolist()}
        assert method["sdf.npy"] == sdf_method
        assert method["rgb.npy"] == method["parts.npy"] == zipfile.ZIP_DEFLATED
        assert np.array_equal(load(p).sdf, c.sdf)
        first = p.read_bytes()
        assert save(c, p).read_bytes() == first
    assert save(noisy, tmp_path / "s.csdf.npz", compress=False).stat().st_size >= noisy.sdf.nbytes


# -- the compact layout -----------------------------------------------------------------------


@pytest.fixture
def painted():
    """A sphere 60 voxels across with a colour and a part per voxel that vary everywhere."""
    c = shapes.sphere((0.0, 0.0, 0.0), 0.6, voxel_size=0.02)
    rng = np.random.default_rng(1)
    rgb = rng.integers(0, 256, c.rgb.shape, dtype=np.uint8)
    parts = rng.integers(-1, 5, c.shape, dtype=np.int16)
    return c.with_history({"op": "paint"}, rgb=rgb, parts=parts)


def test_compact_file_is_exact_in_the_band_and_bounds_beyond_it(tmp_path, painted):
    from partscale.csdf import FILE_BAND_VOXELS

    c = painted
    p = save(c, tmp_path / "c.csdf.npz", compact=True)
    d = load(p)
    h = c.voxel_size
    band = np.abs(c.sdf) <= FILE_BAND_VOXELS * h
    assert band.any() and (~band).any()
    for name in ("sdf", "rgb", "parts"):  # every band voxel exactly as saved
        a, b = getattr(c, name), getattr(d, name)
        assert a.dtype == b.dtype and np.array_equal(a[band], b[band]), name
    assert d.meta == c.meta and d.voxel_size == c.voxel_size
    assert np.array_equal(d.origin, c.origin)
    far = ~band
    # beyond the band: the sign kept, a distance no larger than the saved one (and no larger
    # than the analytic distance to the sphere), still beyond the band
    assert np.array_equal(d.sdf[far] < 0, c.sdf[far] < 0)
    assert (np.abs(d.sdf[far]) <= np.abs(c.sdf[far])).all()
    centres = c.index_to_world(np.argwhere(far))
    truth = np.abs(np.linalg.norm(centres, axis=1) - 0.6)
    assert (np.abs(d.sdf[far]) <= truth + 1e-6).all()
    assert (np.abs(d.sdf[far]) > FILE_BAND_VOXELS * h).all()
    # at most one block's diagonal (4 voxels a side) below the saved distance
    assert (np.abs(c.sdf[far]) - np.abs(d.sdf[far]) <= 4 * np.sqrt(3) * h + 1e-6).all()
    # the band's colours and parts come back; beyond it a colour and part of the block
    assert set(np.unique(d.parts[far])) <= set(np.unique(c.parts[far]))
    # smaller than the whole file, and the same bytes each time
    whole = save(c, tmp_path / "w.csdf.npz", compact=False)
    assert p.stat().st_size < whole.stat().st_size
    first = p.read_bytes()
    assert save(c, p, compact=True).read_bytes() == first
    assert save(d, tmp_path / "again.csdf.npz", compact=True).stat().st_size > 0


def test_large_grids_are_written_compact_small_ones_whole(tmp_path, painted, monkeypatch):
    import partscale.csdf as csdf_mod

    small = save(painted, tmp_path / "small.csdf.npz")
    with zipfile.ZipFile(small) as z:
        assert "far.npy" not in z.namelist()
    monkeypatch.setattr(csdf_mod, "COMPACT_VOXELS", painted.sdf.size - 1)
    large = save(painted, tmp_path / "large.csdf.npz")
    with zipfile.ZipFile(large) as z:
        assert "far.npy" in z.namelist()
        assert json.loads(str(np.load(z.open("meta.npy"))))["version"] == 2
    assert np.array_equal(load(large).sdf < 0, painted.sdf < 0)


def test_compact_file_with_inconsistent_arrays_is_refused(tmp_path, painted):
    arrays = _arrays(save(painted, tmp_path / "c.csdf.npz", compact=True))
    bad = tmp_path / "bad.csdf.npz"
    np.savez(bad, **{**arrays, "sdf": arrays["sdf"][:-1]})
    with pytest.raises(InputError, match=r"bad\.csdf\.npz: expected sdf of dtype float32 shape"):
        load(bad)
    np.savez(bad, **{**arrays, "far": arrays["far"][:, :-1]})
    with pytest.raises(InputError, match=r"bad\.csdf\.npz: expected far of dtype float32"):
        load(bad)
    arrays.pop("far_rgb")
    np.savez(bad, **arrays)
    with pytest.raises(InputError, match=r"bad\.csdf\.npz: expected exactly the arrays .*far_rgb"):
        load(bad)


def test_deflated_members_are_plain_npy_any_zip_reader_opens(tmp_path):
    """Members deflated in parallel pieces are one valid deflate stream each: zipfile's own
    check passes, and every member reads back as what ``np.save`` writes."""
    import io

    c = shapes.sphere((0.0, 0.0, 0.0), 0.6, voxel_size=0.01)  # colours: 5.3 MB, 2 pieces
    for compact in (False, True):
        p = save(c, tmp_path / f"{compact}.csdf.npz", compact=compact)
        with zipfile.ZipFile(p) as z:
            assert z.testzip() is None
            deflated = [i for i in z.infolist() if i.compress_type == zipfile.ZIP_DEFLATED]
            assert deflated
            for info in deflated:
                a = np.load(z.open(info))
                buf = io.BytesIO()
                np.lib.format.write_array(buf, a, allow_pickle=False)
                assert z.read(info) == buf.getvalue()
