"""The status table ``OUTDIR/status.csv``: one row per object, rewritten atomically as it goes.

Several processes may share one OUTDIR (shards of a Slurm array): every write takes a lock on
``OUTDIR/.status.lock``, re-reads the table and replaces only the rows this process owns, so no
shard's rows are lost and a reader never sees a half-written table.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path

from .. import _schema
from .._files import atomic_path
from ..errors import InputError

STATUS_NAME = "status.csv"
LOCK_NAME = ".status.lock"
"""The lock file beside :data:`STATUS_NAME` (``flock``: one writer of the table at a time)."""
LOG_NAME = "workers.log"
"""The batch's log of its workers' output, beside :data:`STATUS_NAME`."""
COLUMNS = (
    "name",
    "input",
    "state",
    "seconds",
    "error",
    "input_hash",
    "options_hash",
    "outputs",
    "peak_memory_mib",
    "started",
    "finished",
    "attempts",
)
"""Columns of ``status.csv``; ``outputs`` are paths relative to OUTDIR joined by ``;``."""
MAX_FIELD = 65536
"""Longest field of a status row (csv reads at most 131,072 characters); longer ones written
are cut to it, so the table always reads back."""
MAX_ATTEMPTS = 1_000_000
"""Most attempts a row may count."""
STATES = ("done", "failed", "running", "interrupted")
"""``running``: started and not finished (a crashed or killed batch leaves it; rerun redoes it);
``interrupted``: stopped by Ctrl-C or SIGTERM (redone on the next run, like ``running``)."""


def now() -> str:
    """UTC time stamp, ISO 8601 with milliseconds."""
    return datetime.now(UTC).isoformat(timespec="milliseconds")


def read(path: Path) -> dict[str, dict[str, str]]:
    """Rows of a status table by object name.

    Parameters
    ----------
    path : Path
        A batch's ``status.csv`` (:data:`STATUS_NAME` in its output folder).

    Returns
    -------
    dict of str to dict
        Name -> row (every column of :data:`COLUMNS`, as text); empty when there is no table
        yet.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale import batch
    >>> batch.read_status(Path("out/status.csv"))
    {}
    >>> with open("status.csv", "w") as f:
    ...     print("name,state,input_hash,options_hash", file=f)
    ...     print("table,done,1f,2e", file=f)
    >>> batch.read_status(Path("status.csv"))["table"]["state"]
    'done'
    """
    if not path.exists():
        return {}
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: expected a readable status table, got {exc}") from None
    reader = csv.DictReader(io.StringIO(text))
    try:
        if reader.fieldnames is None:
            return {}
        missing = [
            c for c in ("name", "state", "input_hash", "options_hash") if c not in reader.fieldnames
        ]
        if missing:
            raise InputError(
                f"{path}: expected a status table with columns {COLUMNS}, missing {missing}"
            )
        rows = {}
        for row in reader:
            checked = check_row({c: row.get(c) or "" for c in COLUMNS}, f"{path}:{reader.line_num}")
            rows[checked["name"]] = checked
        return rows
    except csv.Error as exc:
        raise InputError(
            f"{path}: expected a status table (CSV), got {exc} on line {reader.line_num}"
        ) from None


def check_row(row: dict[str, str], where: str) -> dict[str, str]:
    """A status row (every column as text) checked against the table's schema, or an
    :class:`InputError` naming the cell: a name, a known state, counts and figures that read
    as numbers, no field over :data:`MAX_FIELD` characters.
    """
    for c in COLUMNS:
        if len(row[c]) > MAX_FIELD:
            raise InputError(
                f"{where}: {c}: expected at most {MAX_FIELD} characters, got {len(row[c])}"
            )
    _schema.string(row["name"], f"{where}: name", max_len=MAX_FIELD)
    if row["state"]:
        _schema.string(row["state"], f"{where}: state", choices=STATES)
    if row["attempts"]:
        _schema.integer(row["attempts"], f"{where}: attempts", lo=0, hi=MAX_ATTEMPTS, text=True)
    for c in ("seconds", "peak_memory_mib"):
        if row[c]:
            _schema.number(row[c], f"{where}: {c}", lo=0, text=True)
    return row


def _render(
    rows: dict[str, dict[str, str]], lines: dict[str, tuple[tuple[str, ...], str]] | None = None
) -> str:
    """The table's CSV text, rows sorted by name. ``lines`` keeps each row's line by name with
    the values it was made from, so a row that has not changed is not formatted again.
    """
    lines = {} if lines is None else lines
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    out = [buf.getvalue()]
    for name in sorted(rows):
        values = tuple(rows[name].get(c, "") for c in COLUMNS)
        kept = lines.get(name)
        if kept is None or kept[0] != values:
            buf.seek(0)
            buf.truncate()
            w.writerow(values)
            kept = lines[name] = (values, buf.getvalue())
        out.append(kept[1])
    return "".join(out)


@contextlib.contextmanager
def _locked(outdir: Path) -> Iterator[None]:
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: one writer per OUTDIR
        yield
        return
    fd = os.open(outdir / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing releases the lock


class StatusTable:
    """The rows this process owns, merged into ``OUTDIR/status.csv`` on every :meth:`write`.

    Parameters
    ----------
    outdir : Path
        The batch's output folder (must exist).
    """

    def __init__(self, outdir: Path):
        self.outdir = Path(outdir)
        self.path = self.outdir / STATUS_NAME
        self.previous = read(self.path)
        self.rows: dict[str, dict[str, str]] = {}
        # the table as this process last wrote it, and the file's stamp then: while the stamp
        # holds, no other process wrote, and the table need not be read again
        self._written: dict[str, dict[str, str]] = {}
        self._stamp: tuple[int, int, int] | None = None
        self._lines: dict[str, tuple[tuple[str, ...], str]] = {}

    def update(self, name: str, **fields: object) -> dict[str, str]:
        """Set fields of ``name``'s row (starting from its previous row) and write the table."""
        row = self.rows.get(name) or dict(self.previous.get(name) or dict.fromkeys(COLUMNS, ""))
        row["name"] = name
        for k, v in fields.items():
            if k not in COLUMNS:
                raise KeyError(k)
            row[k] = ("" if v is None else str(v))[:MAX_FIELD]
        self.rows[name] = row
        self.write()
        return row

    def write(self) -> None:
        """Merge this process's rows into the table on disk, atomically, under the lock.

        The table is read again only when another process wrote it since this one did (its
        file's inode, size or modification time changed), and only changed rows are formatted
        again: a batch's own write costs about its changed rows, not a read, a check and a
        formatting of every row.
        """
        with _locked(self.outdir):
            fresh = self._stamp is not None and self._stamp == _stamp(self.path)
            merged = self._written if fresh else read(self.path)
            merged.update(self.rows)
            text = _render(merged, self._lines)
            with atomic_path(self.path) as tmp:
                tmp.write_text(text, encoding="utf-8")
            self._written, self._stamp = merged, _stamp(self.path)


def _stamp(path: Path) -> tuple[int, int, int] | None:
    """What tells one version of a file from another: its inode, size and modification time."""
    try:
        st = path.stat()
    except OSError:
        return None
    return st.st_ino, st.st_size, st.st_mtime_ns
