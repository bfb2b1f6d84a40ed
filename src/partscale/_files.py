"""Files: atomic writes and JSON reading, each failure an :class:`InputError` naming the file."""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import InputError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Nothing half-written is ever left: on any exception the temporary file is removed and the
    destination is untouched. The temporary keeps ``path``'s suffix (or ``suffix``) so writers
    that infer the format from the name still work. A destination the file system refuses
    (read-only folder, a directory in the way) is an :class:`InputError` naming ``path``;
    errors raised inside the ``with`` block propagate unchanged.
    """
    path = Path(path)
    if not path.parent.exists():
        raise InputError(f"{path}: expected an existing output folder, got none at {path.parent}")
    if path.is_dir():  # refused before the caller does any work
        raise InputError(f"{path}: expected a writable file, got a directory")
    suf = suffix if suffix is not None else "".join(path.suffixes)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suf}", dir=path.parent)
    except OSError as exc:
        raise _unwritable(path, exc) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        # mkstemp creates 0600; a written file should get the usual permissions (umask applied).
        os.chmod(tmp_path, 0o666 & ~_umask())
        yield tmp_path
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise
    try:
        os.replace(tmp_path, path)
    except OSError as exc:
        tmp_path.unlink(missing_ok=True)
        raise _unwritable(path, exc) from None


def _unwritable(path: Path, exc: OSError) -> InputError:
    return InputError(f"{path}: expected a writable file, got {exc.strerror or exc}")


def _umask() -> int:
    """The process umask, read without changing it where possible.

    Setting and restoring it (the portable way) would briefly give files created by other threads
    (the editor's server saves from a worker thread) world-writable permissions.
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def read_json(path: Path, *, what: str):
    """Parse a JSON file, or raise :class:`InputError` naming the file (missing, not JSON)."""
    if not path.is_file():
        raise InputError(f"{path}: expected {what}, got no such file")
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: expected JSON ({what}), got {exc}") from None
