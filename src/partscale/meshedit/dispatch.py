"""Which route an edit takes, and what the mesh route reports: the choices ``scale`` and ``fit``
share, whatever calls them (the CLI, a script).

A mesh in and a mesh out take the mesh route (:func:`is_mesh_route`): the recipe is applied to the
source mesh itself (:func:`~partscale.meshedit.edit_mesh_file`). Its options resolve against the
mesh's frame, or its CSDF where zones must be found (:func:`edit_target`), and what it did is said
in a few lines (:func:`report_lines`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InputError
from ..ingest import MESH_SUFFIXES
from .route import OUTPUT_SUFFIXES, MeshEditResult, MeshFrame, mesh_frame

if TYPE_CHECKING:
    from ..csdf import CSDF


def is_mesh_route(src: str | os.PathLike, dst: str | os.PathLike) -> bool:
    """Whether editing ``src`` into ``dst`` takes the mesh route.

    It does for a mesh in (:data:`MESH_SUFFIXES`) and a mesh out (:data:`OUTPUT_SUFFIXES`).

    Parameters
    ----------
    src, dst : str or os.PathLike
        The input and the output file (suffixes compared in lower case).

    Returns
    -------
    bool
        True for the mesh route; False where either is a CSDF (or anything else).

    Examples
    --------
    >>> from partscale.meshedit import is_mesh_route
    >>> is_mesh_route("sofa.glb", "wider.OBJ"), is_mesh_route("sofa.glb", "wider.csdf.npz")
    (True, False)
    """
    return Path(src).suffix.lower() in MESH_SUFFIXES and Path(dst).suffix.lower() in OUTPUT_SUFFIXES


def check_route(src: str | os.PathLike, dst: str | os.PathLike) -> bool:
    """:func:`is_mesh_route`, refusing a mesh in with anything but a mesh out.

    An edit of a mesh writes a mesh (the mesh route); a CSDF is made from a mesh by importing it
    first, at a resolution the user chooses, so a mesh in and a CSDF out is refused (one line
    naming ``partscale import``) rather than read as a CSDF.

    Parameters
    ----------
    src, dst : str or os.PathLike
        The input and the output file.

    Returns
    -------
    bool
        True for the mesh route, False for a CSDF in.

    Raises
    ------
    InputError
        ``src`` is a mesh and ``dst`` is no mesh.

    Examples
    --------
    >>> from partscale.meshedit import check_route
    >>> check_route("sofa.glb", "wider.obj"), check_route("sofa.csdf.npz", "wider.csdf.npz")
    (True, False)
    >>> check_route("sofa.glb", "wider.csdf.npz")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: sofa.glb is a mesh: expected a mesh OUT (.glb, .obj, .ply, .usd, .usda, .usdc, .usdz), got wider.csdf.npz; for a CSDF, import it first (partscale import sofa.glb -o sofa.csdf.npz)
    """
    if is_mesh_route(src, dst):
        return True
    src = Path(src)
    if src.suffix.lower() in MESH_SUFFIXES:
        raise InputError(
            f"{src.name} is a mesh: expected a mesh OUT ({', '.join(OUTPUT_SUFFIXES)}), got "
            f"{Path(dst).name}; for a CSDF, import it first (partscale import {src.name} -o "
            f"{src.stem}.csdf.npz)"
        )
    return False


def check_square(square: bool, mesh_route: bool, src: Path, dst: Path) -> None:
    """Refuse ``square`` off the mesh route: a CSDF was squared (or not) when it was imported.

    Parameters
    ----------
    square : bool
        Whether the edit was asked to be made square (``--square``).
    mesh_route : bool
        Whether the edit takes the mesh route (:func:`is_mesh_route`).
    src, dst : Path
        The input and the output, named in the refusal.

    Returns
    -------
    None
        Nothing; it raises :class:`~partscale.errors.InputError` instead (``square`` with a
        CSDF in or out), naming the files and the cure.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale.meshedit import check_square
    >>> check_square(True, True, Path("a.glb"), Path("b.glb"))  # the mesh route: fine
    """
    if square and not mesh_route:
        raise InputError(
            "--square: expected a mesh IN and a mesh output (the mesh route; a CSDF is squared "
            f"at import: partscale import --square), got {src.name} -> {dst.name}"
        )


def edit_target(src: str | os.PathLike, *, zones: bool, square: bool = False) -> CSDF | MeshFrame:
    """What a mesh-route edit's options resolve against.

    Parameters
    ----------
    src : str or os.PathLike
        The source mesh.
    zones : bool
        Whether zones must be found (``--snap``, counts of elements, ``fit``): then the mesh's
        CSDF at the default resolution (zones work on profiles); else its frame
        (:func:`~partscale.meshedit.mesh_frame`: bounds and units, enough for lengths and
        ``%``), which reads no more than the file.
    square : bool
        Turned square, as :func:`~partscale.meshedit.edit_mesh_file` edits it.

    Returns
    -------
    CSDF or MeshFrame

    Examples
    --------
    >>> from partscale import data
    >>> from partscale.meshedit import edit_target
    >>> edit_target(data.table(), zones=False).meta
    {'units': 'm'}
    """
    if zones:
        from ..ingest import load as import_file

        return import_file(src, square=square)
    return mesh_frame(src, square=square)


def report_lines(result: MeshEditResult) -> tuple[list[tuple[str, str]], str]:
    """What a mesh-route edit says, line by line.

    Parameters
    ----------
    result : MeshEditResult
        What :func:`~partscale.meshedit.edit_mesh_file` did.

    Returns
    -------
    (list of (str, str), str)
        ``(kind, line)`` pairs in order, ``kind`` ``"warning"`` for a seam that could not be
        welded and for a source whose walls run off x and z, ``"note"`` for the turn ``square``
        made; and the closing line naming the files written.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale.meshedit import MeshEditResult, report_lines
    >>> report_lines(MeshEditResult([Path("out.glb")], 120, 210, []))
    ([], 'wrote out.glb (mesh route: 120 -> 210 triangles)')
    """
    lines = [("warning", seam.message()) for seam in result.seams if not seam.ok]
    if result.turned_deg is not None:
        from ..orient import square_note

        lines.append(("note", square_note(result.turned_deg, edit=True)))
    if result.off_square_deg is not None:
        from ..orient import off_square_message

        lines.append(("warning", off_square_message(result.off_square_deg, mesh_route=True)))
    done = (
        f"wrote {', '.join(map(str, result.written))} (mesh route: {result.faces_in} -> "
        f"{result.faces_out} triangles)"
    )
    return lines, done
