"""Sample objects shipped inside the package, for examples, documentation and the demo.

In the spirit of :mod:`skimage.data`: each function returns the path of a small file installed
with partscale, so that examples run without downloading anything. Provenance and licence of each
file are in this folder's ``README.md`` and ``LICENSE_*.txt``.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["NAMES", "table"]

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


NAMES = {"table": table}
"""Each sample's name (what ``python -m partscale.data NAME`` takes) and its function."""
