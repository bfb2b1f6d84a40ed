"""Progress reporting shared by the library, the CLI and the web server.

Every long-running public function takes ``progress=None`` or a callable
``progress(fraction: float, message: str) -> None`` with ``fraction`` in [0, 1], non-decreasing.
The CLI turns it into a rich progress bar on stderr; the server streams it to the page.
"""

from __future__ import annotations

from collections.abc import Callable

ProgressCallback = Callable[[float, str], None]


def _silent(fraction: float, message: str) -> None:
    return None


def resolve(progress: ProgressCallback | None) -> ProgressCallback:
    """Return ``progress`` or a callback that does nothing."""
    return progress if progress is not None else _silent


def scaled(progress: ProgressCallback | None, start: float, stop: float) -> ProgressCallback:
    """A callback reporting into the sub-range ``[start, stop]`` of ``progress``.

    Lets a stage call another stage and keep one monotone bar.
    """
    outer = resolve(progress)

    def inner(fraction: float, message: str) -> None:
        f = min(max(fraction, 0.0), 1.0)
        outer(start + (stop - start) * f, message)

    return inner
