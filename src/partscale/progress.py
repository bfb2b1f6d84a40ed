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
    """Return ``progress`` or a callback that does nothing.

    Parameters
    ----------
    progress : callable (fraction: float, message: str) -> None, or None
        A caller's progress callback, or None for none.

    Returns
    -------
    callable (fraction: float, message: str) -> None
        ``progress`` itself, or (for None) one that does nothing, so a function can report
        without testing for None.

    Examples
    --------
    >>> from partscale.progress import resolve
    >>> resolve(None)(0.5, "halfway")
    >>> resolve(lambda f, m: print(f"{f:.0%} {m}"))(0.5, "halfway")
    50% halfway
    """
    return progress if progress is not None else _silent


def scaled(progress: ProgressCallback | None, start: float, stop: float) -> ProgressCallback:
    """A callback reporting into the sub-range ``[start, stop]`` of ``progress``.

    Lets a stage call another stage and keep one monotone bar.

    Parameters
    ----------
    progress : callable (fraction: float, message: str) -> None, or None
        The outer callback (None: the result does nothing).
    start, stop : float
        The sub-range of the outer bar, within [0, 1], that the inner stage fills.

    Returns
    -------
    callable (fraction: float, message: str) -> None
        A callback that maps its ``fraction`` (clipped to [0, 1]) to
        ``start + (stop - start) * fraction`` of ``progress`` and passes the message on.

    Examples
    --------
    >>> from partscale.progress import scaled
    >>> inner = scaled(lambda f, m: print(f"{f:.2f} {m}"), 0.5, 0.75)
    >>> inner(0.0, "meshing")
    0.50 meshing
    >>> inner(1.0, "meshing")
    0.75 meshing
    """
    outer = resolve(progress)

    def inner(fraction: float, message: str) -> None:
        f = min(max(fraction, 0.0), 1.0)
        outer(start + (stop - start) * f, message)

    return inner
