"""Make the documentation's before/after pictures (docs/gallery/*.png) with partscale itself.

Run from the repository root with the installed partscale::

    python docs/gallery.py            # test objects from PARTSCALE_DATA (or ../shared/data) if present
    python docs/gallery.py --only table_fit

Every picture is made by the commands it prints (``partscale import``, ``scale``, ``fit``,
``segment``, ``batch``), then rendered with :func:`partscale.render.render`, the before and after
panels in one frame so sizes compare. Objects come from the table shipped with partscale
(:func:`partscale.data.table`) and, where the folder of test objects is present, from it (Kenney's
CC0 furniture); without it those pictures are made from the analytic stand-ins the README's
command blocks build, and say so in their caption line.
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "gallery"
DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))
PIXELS = 300


def ps(*args: str | Path) -> None:
    """Run one partscale command (printed as a user would type it)."""
    words = [str(a) for a in args]
    print("  partscale " + " ".join(shlex.quote(w) for w in words), flush=True)
    subprocess.run([sys.executable, "-m", "partscale", *words], check=True)


def panels(
    paths: list[Path],
    labels: list[str],
    out: Path,
    *,
    parts: list[bool] | None = None,
    view: str = "iso",
) -> None:
    """Render CSDF files side by side in one frame (the union of their solids), labelled."""
    from partscale import load
    from partscale.render import render

    objs = [load(p) for p in paths]
    bounds = np.array([o.surface_bounds() for o in objs])
    frame = np.array([bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)])
    parts = parts or [False] * len(objs)
    images = [
        render(o, view=view, size=PIXELS, frame=frame, parts=p)
        for o, p in zip(objs, parts, strict=True)
    ]
    font = ImageFont.load_default(size=15)
    band = 26
    sheet = Image.new("RGB", (PIXELS * len(images), PIXELS + band), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (img, label) in enumerate(zip(images, labels, strict=True)):
        sheet.paste(Image.fromarray(img), (k * PIXELS, band))
        draw.text((k * PIXELS + PIXELS // 2, 4), label, fill=(40, 40, 40), font=font, anchor="mt")
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out, optimize=True)
    print(f"wrote {out.relative_to(ROOT)} ({out.stat().st_size // 1024} KB)", flush=True)


def real(rel: str) -> Path | None:
    """A test object's path, or None where the folder of test objects is absent."""
    p = DATA / rel
    return p if p.is_file() else None


def stand_in(name: str, tmp: Path) -> Path:
    """One of the README's analytic objects (the code its command blocks run)."""
    code = {
        "bookcase": """
from partscale import save, shapes
boards = [((0, 0, 0), (0.02, 1.2, 0.3)), ((0.78, 0, 0), (0.8, 1.2, 0.3)), ((0.02, 0, 0), (0.78, 1.2, 0.02))]
boards += [((0.02, y, 0.02), (0.78, y + 0.02, 0.3)) for y in (0.0, 0.295, 0.59, 0.885, 1.18)]
save(shapes.grid(lambda p: shapes.boxes_sdf(p, boards), [(0, 0, 0), (0.8, 1.2, 0.3)], voxel_size=0.01), "bookcase.csdf.npz")
""",
        "round": """
import numpy as np
from partscale import save, shapes
def cylinder(p, r, y0, y1):
    d = np.stack([np.hypot(p[:, 0], p[:, 2]) - r, np.abs(p[:, 1] - (y0 + y1) / 2) - (y1 - y0) / 2], -1)
    return np.minimum(d.max(-1), 0) + np.linalg.norm(np.maximum(d, 0), axis=-1)
def round_table(p):
    return np.minimum.reduce([cylinder(p, 0.5, 0.70, 0.74), cylinder(p, 0.05, 0.03, 0.70), cylinder(p, 0.25, 0.0, 0.03)])
save(shapes.grid(round_table, [(-0.5, 0, -0.5), (0.5, 0.74, 0.5)], voxel_size=0.01), "round.csdf.npz")
""",
        "stairs": """
from partscale import save, shapes
steps = [((0.25 * i, 0, 0), (0.25 * (i + 1), 0.18 * (i + 1), 1.0)) for i in range(5)]
save(shapes.grid(lambda p: shapes.boxes_sdf(p, steps), [(0, 0, 0), (1.25, 0.9, 1.0)], voxel_size=0.01), "stairs.csdf.npz")
""",
    }[name]
    subprocess.run([sys.executable, "-c", code], cwd=tmp, check=True)
    return tmp / f"{name}.csdf.npz"


def imported(src: Path | None, name: str, tmp: Path, fallback: str | None = None) -> Path:
    """``src`` imported at 128 voxels (or the stand-in ``fallback`` where src is None)."""
    if src is None:
        assert fallback is not None
        print(f"  (test object absent: the analytic {fallback} instead)", flush=True)
        return stand_in(fallback, tmp)
    out = tmp / f"{name}.csdf.npz"
    ps("import", src, "-o", out, "--res", "128")
    return out


def table_demo(tmp: Path) -> None:
    from partscale import data

    t = tmp / "table.csdf.npz"
    ps("import", data.table(), "-o", t, "--res", "128")
    ps("segment", t, "-o", t)
    longer = tmp / "table_longer.csdf.npz"
    ps("scale", t, "-o", longer, "--axis", "x", "--zone", "35%", "65%", "--to", "105%")
    panels(
        [t, t, longer],
        ["the shipped table", "its parts", "40% longer: the zone between the legs"],
        OUT / "table_demo.png",
        parts=[False, True, False],
    )


def table_fit(tmp: Path) -> None:
    from partscale import data

    t = tmp / "table.csdf.npz"
    ps("import", data.table(), "-o", t, "--res", "128")
    out = tmp / "table_fit.csdf.npz"
    ps("fit", t, "-o", out, "--size", "3m", "=", "120%")
    panels([t, out], ["table", "fit --size 3m = 120%"], OUT / "table_fit.png")


def table_zones(tmp: Path) -> None:
    from partscale import data

    t = tmp / "table.csdf.npz"
    ps("import", data.table(), "-o", t, "--res", "128")
    ps("suggest", t, "--axis", "x", "--png", OUT / "table_zones.png")


def table_mesh(tmp: Path) -> None:
    from partscale import data

    longer = tmp / "table_longer.glb"
    ps("scale", data.table(), "-o", longer, "--axis", "x", "--zone", "35%", "65%", "--by", "+60cm")
    a, b = tmp / "mesh_a.csdf.npz", tmp / "mesh_b.csdf.npz"
    ps("import", data.table(), "-o", a, "--res", "128")
    ps("import", longer, "-o", b, "--res", "128")
    panels(
        [a, b], ["table.glb", "table_longer.glb (the mesh itself edited)"], OUT / "table_mesh.png"
    )


def bookcase_add(tmp: Path) -> None:
    src = real("kenney/bookcaseOpen.glb")
    c = imported(src, "bookcase", tmp, "bookcase")
    more, less = tmp / "more.csdf.npz", tmp / "less.csdf.npz"
    ps("fit", c, "-o", more, "--add", "y", "1")
    ps("fit", c, "-o", less, "--add", "y", "-1")
    panels([less, c, more], ["--add y -1", "bookcase", "--add y 1"], OUT / "bookcase_add.png")


def round_radial(tmp: Path) -> None:
    c = imported(real("kenney/tableRound.glb"), "round", tmp, "round")
    wide = tmp / "wide.csdf.npz"
    ps("scale", c, "-o", wide, "--radial", "--zone", "20%", "90%", "--by", "+20cm")
    panels(
        [c, wide], ["round table", "--radial --zone 20% 90% --by +20cm"], OUT / "round_radial.png"
    )


def stairs_step(tmp: Path) -> None:
    c = imported(real("kenney/stairs.glb"), "stairs", tmp, "stairs")
    more = tmp / "more.csdf.npz"
    ps("fit", c, "-o", more, "--add", "y", "1")
    panels([c, more], ["stairs", "fit --add y 1: one more step"], OUT / "stairs_step.png")


def many(tmp: Path) -> None:
    from partscale import data

    srcs = [data.table()] + [
        p
        for p in (
            real("kenney/chair.glb"),
            real("kenney/bookcaseOpen.glb"),
            real("kenney/desk.glb"),
        )
        if p
    ]
    folder = tmp / "in"
    folder.mkdir()
    for s in srcs:
        shutil.copy(s, folder / s.name)
    ps("batch", folder, "-o", tmp / "out", "--res", "96", "--size", "=", "120%", "=", "--render")
    pngs = sorted((tmp / "out").glob("*/*.render-iso.png"))
    ims = [Image.open(p).convert("RGB").resize((220, 220)) for p in pngs]
    sheet = Image.new("RGB", (220 * len(ims), 220), "white")
    for k, im in enumerate(ims):
        sheet.paste(im, (220 * k, 0))
    sheet.save(OUT / "batch.png", optimize=True)
    print(f"wrote docs/gallery/batch.png ({len(ims)} objects)")


def copies(tmp: Path) -> None:
    """Pictures made elsewhere that the guide shows: the editor's view, the evaluation's sheet."""
    shutil.copy(ROOT / "tests" / "browser" / "table_480x360.png", OUT / "editor.png")
    sheet = Image.open(ROOT / "eval" / "results" / "contact_sheet.png").convert("RGB")
    sheet.thumbnail((800, 2000))
    sheet.quantize(256).save(OUT / "eval_contact_sheet.png", optimize=True)
    print("wrote docs/gallery/editor.png, docs/gallery/eval_contact_sheet.png")


def table_scan(tmp: Path) -> None:
    from partscale import data, load, save
    from partscale.complete import completion_colors

    s = data.table_scan()
    c = tmp / "table_scan.csdf.npz"
    ps(
        "complete", "--depth", s / "depth.png", "--color", s / "color.jpg",
        "--intrinsics", s / "intrinsics.json", "-o", c, "--upright",
    )  # fmt: skip
    kinds = tmp / "kinds.csdf.npz"
    done = load(c)
    save(done.replace(rgb=completion_colors(done)), kinds)
    longer = tmp / "table_scan_longer.csdf.npz"
    ps("fit", c, "-o", longer, "--size", "120%", "=", "=")
    frame = Image.open(s / "color.jpg").convert("RGB").resize((PIXELS, PIXELS * 3 // 4))
    panels(
        [c, kinds, longer],
        ["completed from one frame", "observed, mirrored, guessed", "fit --size 120% = ="],
        OUT / "table_scan.png",
    )
    sheet = Image.open(OUT / "table_scan.png")
    out = Image.new("RGB", (sheet.width + PIXELS, sheet.height), "white")
    out.paste(frame, (0, 26 + PIXELS // 8))
    ImageDraw.Draw(out).text(
        (PIXELS // 2, 4), "the depth frame (colour)", fill=(40, 40, 40),
        font=ImageFont.load_default(size=15), anchor="mt",
    )  # fmt: skip
    out.paste(sheet, (PIXELS, 0))
    out.save(OUT / "table_scan.png", optimize=True)
    print(
        f"wrote docs/gallery/table_scan.png ({(OUT / 'table_scan.png').stat().st_size // 1024} KB)"
    )


PICTURES: dict[str, Callable[[Path], None]] = {
    "table_demo": table_demo,
    "table_fit": table_fit,
    "table_zones": table_zones,
    "table_mesh": table_mesh,
    "bookcase_add": bookcase_add,
    "round_radial": round_radial,
    "stairs_step": stairs_step,
    "table_scan": table_scan,
    "batch": many,
    "copies": copies,
}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", choices=list(PICTURES), help="make only these")
    args = ap.parse_args()
    print(f"test objects: {DATA if DATA.is_dir() else 'absent (analytic stand-ins instead)'}")
    for name in args.only or PICTURES:
        print(f"{name}:", flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            PICTURES[name](Path(tmp))
    return 0


if __name__ == "__main__":
    sys.exit(main())
