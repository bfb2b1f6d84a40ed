"""Files: atomic writes and JSON reading, each failure an :class:`InputError` naming the file."""

from __future__ import annotations

import contextlib
import contextvars
import errno
import json
import math
import os
import re
import signal
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ._interrupt import raise_if_interrupted
from .errors import InputError, one_line, shown

JSON_MAX_BYTES = 64 << 20
"""Largest JSON text read (recipes, suites, ``.csdf.npz`` meta, editor request bodies)."""
JSON_MAX_DEPTH = 64
"""Deepest nesting of arrays and objects a JSON text may have (partscale's own use 6)."""
JSON_MAX_DIGITS = 30
"""Most digits of a JSON integer (int64 has 19; more is a mistake or an attack)."""


class _JsonRefused(ValueError):
    pass


def _no_constant(name: str):
    raise _JsonRefused(f"{name} (only finite numbers are valid JSON)")


def _int(text: str) -> int:
    if len(text.lstrip("-")) > JSON_MAX_DIGITS:
        raise _JsonRefused(
            f"an integer of {len(text.lstrip('-'))} digits (at most {JSON_MAX_DIGITS})"
        )
    return int(text)


def _float(text: str) -> float:
    x = float(text)
    if not math.isfinite(x):
        raise _JsonRefused(f"the number {shown(text, 40)} (beyond the float range)")
    return x


def _depth(obj: Any) -> int:
    # iterative: a recursive walk would itself hit the recursion limit on hostile input
    deepest, stack = 0, [(obj, 1)]
    while stack:
        o, d = stack.pop()
        if isinstance(o, dict | list):
            deepest = max(deepest, d)
            if d > JSON_MAX_DEPTH:
                return d
            stack.extend((v, d + 1) for v in (o.values() if isinstance(o, dict) else o))
    return deepest


def parse_json(text: str | bytes, *, what: str, max_bytes: int | None = JSON_MAX_BYTES) -> Any:
    """Parse JSON text strictly, or raise :class:`InputError` starting with ``what``.

    Strict: at most ``max_bytes`` long (:data:`JSON_MAX_BYTES`; None: a file read whole anyway,
    such as a glTF's JSON) and :data:`JSON_MAX_DEPTH` deep, integers of at most
    :data:`JSON_MAX_DIGITS` digits, finite numbers only (``NaN``, ``Infinity`` and ``1e400``
    are refused). The one JSON reader of partscale: files, meta, manifests, glTF documents and
    request bodies.
    """
    if max_bytes is not None and len(text) > max_bytes:
        raise InputError(
            f"{what}: expected JSON of at most {max_bytes >> 20} MiB, got {len(text)} bytes"
        )
    if isinstance(text, bytes | bytearray):
        try:
            text = bytes(text).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(f"{what}: expected UTF-8 JSON text, got {one_line(exc)}") from None
    try:
        obj = json.loads(text, parse_constant=_no_constant, parse_int=_int, parse_float=_float)
    except _JsonRefused as exc:
        raise InputError(f"{what}: expected strict JSON, got {exc}") from None
    except RecursionError:
        raise InputError(
            f"{what}: expected JSON nested at most {JSON_MAX_DEPTH} deep, got deeper"
        ) from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{what}: expected JSON, got {exc}") from None
    if _depth(obj) > JSON_MAX_DEPTH:
        raise InputError(f"{what}: expected JSON nested at most {JSON_MAX_DEPTH} deep, got deeper")
    return obj


def dumps_json(obj: Any, **kw: Any) -> str:
    """``json.dumps`` that refuses NaN and infinities (which are not JSON) with a ValueError."""
    return json.dumps(obj, allow_nan=False, **kw)


def check_input_file(path: str | os.PathLike, *, what: str) -> Path:
    """``path`` as a Path if it is an existing file, else an :class:`InputError` saying what it is."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: expected {what}, got a directory")
    if not path.is_file():
        got = "no such file" if not path.exists() else "not a regular file"
        raise InputError(f"{path}: expected {what}, got {got}")
    return path


def read_json(path: Path, *, what: str):
    """Parse a JSON file strictly (see :func:`parse_json`), or raise :class:`InputError` naming it."""
    path = check_input_file(path, what=what)
    try:
        if path.stat().st_size > JSON_MAX_BYTES:
            raise InputError(
                f"{path}: expected {what} of at most {JSON_MAX_BYTES >> 20} MiB, got "
                f"{path.stat().st_size} bytes"
            )
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(
            f"{path}: expected a readable file ({what}), got {exc.strerror or exc}"
        ) from None
    try:
        return parse_json(data, what=f"{path}")
    except InputError as exc:
        raise InputError(f"{exc} ({what})") from None


def check_writable(path: str | os.PathLike) -> Path:
    """``path`` as a Path if a file can be written there, else an :class:`InputError`.

    Checked by creating (and removing) a file beside it, so read-only folders and file systems
    are found before the caller does any work.
    """
    path = Path(path)
    if not path.parent.is_dir():
        what = "a file" if path.parent.exists() else "none"
        raise InputError(f"{path}: expected an existing output folder, got {what} at {path.parent}")
    if path.is_dir():
        raise InputError(f"{path}: expected a writable file, got a directory")
    try:
        fd, probe = tempfile.mkstemp(
            prefix=f".{path.name}.{os.getpid()}.", suffix=".probe", dir=path.parent
        )
    except OSError as exc:
        raise _unwritable(path, exc) from None
    os.close(fd)
    os.unlink(probe)
    return path


def _temp_prefix(path: Path) -> str:
    return f".{path.name}."


_TEMP_FILE = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[a-z0-9_]{8}\.(tmp|probe)")


#: Folders this process has swept of dead writers' temporaries, with the pid that swept them (a
#: forked worker sweeps again once).
_SWEPT: dict[str, int] = {}


def _remove_stale_temps(path: Path) -> None:
    """Remove temporary files of ours in ``path``'s folder whose writing process has gone.

    Our temporaries are named ``.<name>.<pid>.<random>.tmp<suffix>`` (or ``.probe``); a kill -9
    leaves them. One whose process still runs (another writer) is kept. Each folder is swept
    once per process, at its first write, so a batch writing thousands of files into one folder
    lists it once, not once per file; what a writer killed later leaves is swept by the next
    process that writes there.
    """
    folder = os.path.abspath(path.parent)
    if _SWEPT.get(folder) == os.getpid():
        return
    try:
        names = [n for n in os.listdir(folder) if n.startswith(".")]
    except OSError:
        return
    _SWEPT[folder] = os.getpid()
    for name in names:
        m = _TEMP_FILE.match(name)
        if m is None:
            continue
        pid = int(m["pid"])
        if pid == os.getpid() or _alive(pid):
            continue
        with contextlib.suppress(OSError):
            os.unlink(os.path.join(folder, name))


_TEMP_NAME = re.compile(r"^\.(?P<name>.+)\.\d+\.[a-z0-9_]{8}\.tmp")


def final_path(tmp: Path) -> Path:
    """The destination an :func:`atomic_path` temporary ``tmp`` will be renamed to.

    Writers that put companion files beside their output (an OBJ's ``.mtl`` and texture) name
    them after the destination, not after the temporary they are handed.
    """
    m = _TEMP_NAME.match(tmp.name)
    return tmp.with_name(m["name"]) if m else tmp


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True  # someone else's process: not ours to judge
    return True


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Nothing half-written is ever left: on any exception (and on SIGTERM, which the CLI turns into
    an exception) the temporary file is removed and the destination is untouched; temporaries a
    killed process left beside ``path`` are removed on the next write to it. The temporary keeps
    ``path``'s suffix (or ``suffix``) so writers that infer the format from the name still work.
    A destination the file system refuses (read-only folder, a directory in the way) and an
    ``OSError`` while writing (disk full...) are an :class:`InputError` naming ``path``; other
    errors raised inside the ``with`` block propagate unchanged.
    """
    path = Path(path)
    if not path.parent.exists():
        raise InputError(f"{path}: expected an existing output folder, got none at {path.parent}")
    if path.is_dir():  # refused before the caller does any work
        raise InputError(f"{path}: expected a writable file, got a directory")
    _remove_stale_temps(path)
    suf = suffix if suffix is not None else "".join(path.suffixes)
    try:
        fd, tmp = tempfile.mkstemp(
            prefix=f"{_temp_prefix(path)}{os.getpid()}.", suffix=f".tmp{suf}", dir=path.parent
        )
    except OSError as exc:
        raise _unwritable(path, exc) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        # mkstemp creates 0600; a written file should get the usual permissions (umask applied).
        os.chmod(tmp_path, 0o666 & ~_umask())
        yield tmp_path
    except OSError as exc:
        tmp_path.unlink(missing_ok=True)
        raise _unwritable(path, exc) from None
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise
    stage = _STAGE.get()
    if stage is not None:  # renamed with the rest of the set, by staged_writes
        stage.append((tmp_path, path))
    else:
        _commit([(tmp_path, path)])


_STAGE: contextvars.ContextVar[list[tuple[Path, Path]] | None] = contextvars.ContextVar(
    "partscale_staged_writes", default=None
)


@contextlib.contextmanager
def staged_writes() -> Iterator[None]:
    """Make every :func:`atomic_path` inside the block one set: all renamed at its end, or none.

    Each file is written to its temporary as usual, but renamed into place only when the whole
    block succeeds (an OBJ with its MTL and texture, an export's mesh and its 3D textures). On
    any exception, a signal (even one a library swallowed: :mod:`partscale._interrupt`) or a
    rename that fails, every temporary is removed and every destination keeps what it had.
    Nested blocks join the outermost.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale._files import atomic_path, staged_writes
    >>> with staged_writes():
    ...     with atomic_path("a.txt") as tmp:
    ...         _ = tmp.write_text("a")
    ...     Path("a.txt").exists()  # not yet: renamed with the rest of the set
    False
    >>> Path("a.txt").read_text()
    'a'
    """
    if _STAGE.get() is not None:
        yield
        return
    pending: list[tuple[Path, Path]] = []
    token = _STAGE.set(pending)
    try:
        yield
    except BaseException:
        _STAGE.reset(token)
        for tmp, _ in pending:
            tmp.unlink(missing_ok=True)
        raise
    _STAGE.reset(token)
    _commit(pending)


def _commit(pending: list[tuple[Path, Path]]) -> None:
    """Rename each ``(temporary, destination)`` into place, all or none.

    Nothing is renamed once a signal was noted. Signals are held off while the renames run (a
    few system calls), so they end the command after the set is complete, never half-way.
    Where a rename fails, those already done are undone: a destination that existed is put back
    from a hard link taken before (where the file system has them), a new one is removed.
    """
    try:
        raise_if_interrupted()
    except BaseException:
        for tmp, _ in pending:
            tmp.unlink(missing_ok=True)
        raise
    held = _hold_signals()
    done: list[tuple[Path, Path | None]] = []
    failed = pending[0][1] if pending else Path()
    try:
        for tmp, path in pending:
            failed = path
            backup = _link_aside(path) if len(pending) > 1 else None
            try:
                os.replace(tmp, path)
            except BaseException:
                if backup is not None:
                    backup.unlink(missing_ok=True)
                raise
            done.append((path, backup))
    except BaseException as exc:
        for tmp, _ in pending:
            tmp.unlink(missing_ok=True)
        for path, backup in reversed(done):
            with contextlib.suppress(OSError):
                if backup is not None:
                    os.replace(backup, path)
                else:
                    path.unlink()
        if isinstance(exc, OSError):
            raise _unwritable(failed, exc) from None
        raise
    finally:
        _release_signals(held)
    for _, backup in done:
        if backup is not None:
            backup.unlink(missing_ok=True)


def _link_aside(path: Path) -> Path | None:
    """A hard link to the existing ``path`` under a temporary name beside it, or None (no file
    there, or a file system without hard links)."""
    if not path.is_file():
        return None
    backup = path.with_name(f"{_temp_prefix(path)}{os.getpid()}.{os.urandom(4).hex()}.tmp.bak")
    try:
        os.link(path, backup)
    except OSError:
        return None
    return backup


_HELD = (signal.SIGINT, signal.SIGTERM)


def _hold_signals() -> set | None:
    """Block SIGINT and SIGTERM in this thread (they wait); returns the mask to restore."""
    try:
        return signal.pthread_sigmask(signal.SIG_BLOCK, _HELD)
    except (AttributeError, OSError, ValueError):  # no pthread_sigmask (Windows)
        return None


def _release_signals(previous: set | None) -> None:
    if previous is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _unwritable(path: Path, exc: OSError) -> InputError:
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return InputError(f"{path}: expected room to write it, got no space left on the device")
    return InputError(f"{path}: expected a writable file, got {exc.strerror or one_line(exc)}")


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
