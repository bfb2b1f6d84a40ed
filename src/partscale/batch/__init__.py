"""Batch: the pipeline over many objects, resumable, on all cores or on a Ray cluster.

Public API
----------
- :func:`run` ``(inputs, outdir, *, res, segment, recipe, fit, export, render, engine, workers,
  timeout, memory, address, retries, rank, world_size, retry_failed, progress) -> BatchResult``.
- :func:`discover` ``(sources, *, exclude=None) -> list[Input]``: files, folders and manifests
  as named inputs (multi-file assets as one); :func:`shard` ``(inputs, rank, world_size)``.
- :func:`read_status` ``(path) -> {name: row}``: the status table; :data:`STATUS_COLUMNS`.

Modules: ``inputs`` (discovery, manifests, names, content hashes, shards), ``status`` (the
table), ``job`` (the per-object function every engine runs), ``local`` (process pool),
``ray_engine`` (Ray tasks), ``api`` (:func:`run`).
"""

from .api import ENGINES, BatchResult, parse_memory, run
from .inputs import INPUT_SUFFIXES, OPTION_KEYS, Input, discover, read_manifest, shard
from .job import EXPORT_FORMATS
from .status import COLUMNS as STATUS_COLUMNS
from .status import STATES, STATUS_NAME
from .status import read as read_status

__all__ = [
    "ENGINES",
    "EXPORT_FORMATS",
    "INPUT_SUFFIXES",
    "OPTION_KEYS",
    "STATES",
    "STATUS_COLUMNS",
    "STATUS_NAME",
    "BatchResult",
    "Input",
    "discover",
    "parse_memory",
    "read_manifest",
    "read_status",
    "run",
    "shard",
]
