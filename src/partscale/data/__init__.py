"""Sample objects shipped inside the package, for examples, documentation and the demo.

In the spirit of :mod:`skimage.data`: each function returns the path of a small file installed
with partscale, so that examples run without downloading anything. Provenance and licence of each
file are in this folder's ``README.md`` and ``LICENSE_*.txt``.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["NAMES", "table", "table_scan"]

_HERE = Path(__file__).resolve().parent


def table() -> Path:
    """Path of a small table: a coloured glTF binary mesh (7.5 kB) to try partscale on.

    A top on four legs joined by rails, about 2.4 m long (x), 0.95 m tall (y, up) and 1.3 m
    deep (z), in flat material colours. From Kenney's Furniture Kit (www.kenney.nl), CC0 1.0 (public domain), unmodified.

    Returns
    -------
    pathlib.Path
        Absolute path of ``table.glb`` inside the installed package (read it, do not write it).

    Examples
    --------
    >>> from partscale import data, ingest
    >>> c = ingest.load(data.table(), res=64)
    >>> c.shape[0] > c.shape[1]  # longer along x than it is tall
    True

    From the shell, ``python -m partscale.data table`` prints the same path::

        partscale import "$(python -m partscale.data table)" -o table.csdf.npz
    """
    return _HERE / "table.glb"


def table_scan() -> Path:
    """Folder of one RGB-D frame of the :func:`table`, as a depth camera held at a corner sees it.

    ``depth.png`` (320 x 240, 16-bit, 1/5000 m: the TUM convention and ``complete``'s default
    ``--depth-scale``), ``color.jpg`` (the same pixels) and ``intrinsics.json`` (``fx``, ``fy``,
    ``cx``, ``cy``, ``width``, ``height``). Made by partscale's virtual sensor
    (:func:`partscale.evaluate.virtual_scan` of the table at yaw 30 degrees, 25 degrees down,
    seed 0: its depth noise and holes, the floor in view), so the table's true shape is known.

    Returns
    -------
    pathlib.Path
        Absolute path of the folder inside the installed package (read it, do not write it).

    Examples
    --------
    >>> from partscale import data
    >>> from partscale.complete import read_frame
    >>> s = data.table_scan()
    >>> frame = read_frame(s / "depth.png", s / "color.jpg", s / "intrinsics.json")
    >>> frame.depth.shape
    (240, 320)

    From the shell::

        S="$(python -m partscale.data table-scan)"
        partscale complete --depth "$S/depth.png" --color "$S/color.jpg" --intrinsics "$S/intrinsics.json" -o table_scan.csdf.npz
    """
    return _HERE / "table_scan"


NAMES = {"table": table, "table-scan": table_scan}
"""Each sample's name (what ``python -m partscale.data NAME`` takes) and its function."""
