"""Interruptions that no library can swallow.

The CLI turns SIGINT and SIGTERM into exceptions so that ``with`` blocks clean up. A library that
catches ``BaseException`` (trimesh's OBJ exporter does, around each material) would swallow
them and carry on with half its work. So the handlers also *note* the signal here, and every
writer checks the note (:func:`raise_if_interrupted`) after a library call and before it renames
anything into place: a swallowed signal still ends the command, with nothing written.
"""

from __future__ import annotations

import signal

_pending: list[int] = []


def note(signum: int) -> None:
    """Record that ``signum`` arrived (called by the CLI's signal handlers)."""
    _pending.append(int(signum))


def clear() -> None:
    """Forget the signals noted (a new command starts)."""
    _pending.clear()


def interrupted() -> int | None:
    """The first signal noted since :func:`clear`, or None."""
    return _pending[0] if _pending else None


def raise_if_interrupted() -> None:
    """Raise :class:`KeyboardInterrupt` if a signal was noted, even one a library swallowed."""
    if _pending:
        name = signal.Signals(_pending[0]).name if _pending[0] in _SIGNALS else str(_pending[0])
        raise KeyboardInterrupt(f"{name} (noted while a library held it)")


_SIGNALS = {int(s) for s in signal.Signals}
