"""``partscale complete``: a partial scan (range mesh, point cloud, RGB-D frame, views) -> CSDF."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer

from .. import _schema
from . import _common


def _numbers(text: str | None, n: int, what: str, limit: float) -> list[float] | None:
    if text is None:
        return None
    return _schema.numbers_text(text, n, what, lo=-limit, hi=limit)


def _checked(n: int, what: str, limit: str) -> Callable[[str | None], str | None]:
    """A callback checking an option of ``n`` numbers as it is read (``limit``: the name of
    their bound in :mod:`partscale.complete`): typed with spaces, the option ends at its first
    number and the rest would be refused as stray arguments, not as the option."""

    def check(text: str | None) -> str | None:
        from .. import complete as complete_mod

        _numbers(text, n, what, getattr(complete_mod, limit))
        return text

    return check


def complete(
    scan: Annotated[
        Path | None,
        typer.Argument(
            metavar="SCAN",
            help="Partial range mesh or point cloud (PLY, camera frame, metres), cropped to the "
            "object and the floor at its foot: all else in it counts as object.",
        ),
    ] = None,
    output: _common.CsdfOut = Path("completed.csdf.npz"),
    res: _common.Res = 128,
    depth: Annotated[
        Path | None,
        typer.Option("--depth", metavar="FILE", help="16-bit depth PNG of an RGB-D frame."),
    ] = None,
    color: Annotated[
        Path | None,
        typer.Option("--color", metavar="FILE", help="Colour: the image of the --depth frame."),
    ] = None,
    intrinsics: Annotated[
        Path | None,
        typer.Option(
            "--intrinsics", metavar="FILE", help="Intrinsics JSON (Open3D or fx/fy/cx/cy)."
        ),
    ] = None,
    depth_scale: Annotated[
        float,
        typer.Option("--depth-scale", metavar="UNITS", help="Depth units per metre (TUM: 5000)."),
    ] = 5000.0,
    views: Annotated[
        Path | None,
        typer.Option(
            "--views",
            metavar="FILE",
            help="JSON list of registered views (depth+pose or points+pose).",
        ),
    ] = None,
    camera: Annotated[
        str | None,
        typer.Option(
            "--camera",
            metavar="POSE",
            help="Camera-to-world pose: 16 numbers, row major.",
            callback=_checked(16, "--camera", "MAX_COORDINATE"),
        ),
    ] = None,
    box: Annotated[
        str | None,
        typer.Option(
            "--box",
            metavar="X0,Y0,X1,Y1",
            help="Pixel box of the object in the (first) frame.",
            callback=_checked(4, "--box", "MAX_PIXEL"),
        ),
    ] = None,
    upright: Annotated[
        bool,
        typer.Option(
            "--upright", help="Write it floor down, y up (without it: in the scan's frame)."
        ),
    ] = False,
    no_symmetry: Annotated[
        bool, typer.Option("--no-symmetry", help="Do not look for mirror planes or rotations.")
    ] = False,
    scale: Annotated[
        float | None,
        typer.Option(
            "--scale",
            metavar="FACTOR",
            help="Multiply the mesh's coordinates by this; the scan's metres per unit (without "
            "it, a scan that is not plausible furniture in metres gets a warning).",
        ),
    ] = None,
    force_completion: Annotated[
        bool,
        typer.Option(
            "--force-completion",
            help="Keep the completion even where the scan speaks against it (without it: the "
            "scan as observed, closed, and a note saying why).",
        ),
    ] = False,
) -> None:
    """Complete a partial scan into a watertight coloured SDF (.csdf.npz).

    Free space seen by the camera stays empty, the observed surface is kept, the floor gives up,
    symmetries consistent with the free space are applied and the rest is closed thinly.
    """
    _common.check_output(output, suffixes=(".csdf.npz",), what="a CSDF file")
    from ..complete import MAX_COORDINATE, MAX_PIXEL, complete_file

    pose = _numbers(camera, 16, "--camera", MAX_COORDINATE)
    b = _numbers(box, 4, "--box", MAX_PIXEL)
    from ..csdf import save

    with _common.progress_bar("complete") as progress:
        c = complete_file(
            scan,
            depth=depth,
            color=color,
            intrinsics=intrinsics,
            depth_scale=depth_scale,
            camera=pose,
            views=views,
            res=res,
            box=tuple(int(v) for v in b) if b else None,
            upright=upright,
            symmetry=not no_symmetry,
            force_completion=force_completion,
            scale=scale,
            progress=progress,
        )
    save(c, output)
    m = c.meta["completion"]
    _common.done(
        f"wrote {output}: {' x '.join(map(str, c.shape))} voxels of {c.voxel_size:.4g} m; surface "
        f"{m['observed']:.0%} observed, {m['mirrored']:.0%} mirrored, {m['guessed']:.0%} guessed"
        + ("" if m["guard"]["kept"] == "completion" else " (the scan as observed, closed)")
        + ("; most of it guessed: scan more of it" if m["guard"]["mostly_guessed"] else "")
    )
