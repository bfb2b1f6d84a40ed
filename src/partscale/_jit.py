"""Where numba keeps partscale's compiled kernels, and the note a first compile prints.

Every kernel is ``@numba.njit(cache=True)``: the first run on a machine compiles the kernels a
command needs (tens of seconds on two cores) and stores them; later runs load them (well under a
second). numba stores them beside the source (``__pycache__``) where that folder is writable,
else in the user's cache (``~/.cache/numba``), else nowhere: it then refuses to import a module
with a cached kernel. :func:`ensure_cache` prevents that last case (a read-only install run by a
user without a writable home, as in some containers) by pointing numba at a per-user folder in
the temporary directory. ``NUMBA_CACHE_DIR``, where set, always wins.

``python -m partscale.warmup`` compiles the kernels ahead (``./dev.sh setup`` runs it).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _writable(folder: Path) -> bool:
    """Whether a file can be made in ``folder`` (made if missing), as numba checks it."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def ensure_cache() -> Path | None:
    """Make sure numba has a writable place for partscale's kernels; returns the folder set
    (None: numba's own choice works, or ``NUMBA_CACHE_DIR`` is set).

    Call before the first module with a cached kernel is imported (``partscale/__init__`` does).
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    if _writable(HERE / "__pycache__"):
        return None
    from numba.misc.appdirs import AppDirs

    if _writable(Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)):
        return None
    uid = os.getuid() if hasattr(os, "getuid") else 0
    folder = Path(tempfile.gettempdir()) / f"partscale-numba-{uid}"
    if not _writable(folder):
        return None  # nothing is writable: numba will say so
    import numba

    os.environ["NUMBA_CACHE_DIR"] = str(folder)  # worker processes inherit it
    numba.config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]
    return folder


#: Seconds a command's first compile takes on this project's reference machine (2 cores, numba
#: 0.68, nothing compiled yet; ``bench/bench_first_run.py`` measures ``import``): what the note
#: of :func:`on_first_compile` says to expect.
FIRST_COMPILE_SECONDS = {
    "import": 45,
    "complete": 45,
    "batch": 60,
    "eval": 90,
    "fit": 30,
    "scale": 20,
    "editor": 20,
    "render": 15,
    "segment": 10,
    "export": 10,
    "suggest": 10,
    "info": 10,
}


def first_compile_note(command: str | None) -> str:
    """The one line said while a first compile runs (``command``: the subcommand, for its
    estimate)."""
    seconds = FIRST_COMPILE_SECONDS.get(command or "")
    about = f"about {seconds} s for {command} on 2 cores" if seconds else "tens of seconds"
    return (
        f"first run on this machine: compiling partscale's kernels ({about}; once, then "
        "cached; python -m partscale.warmup compiles them all ahead)"
    )


def on_first_compile(callback) -> None:
    """Call ``callback()`` once, when numba starts compiling the first of partscale's kernels
    in this process (not when it loads one from the cache)."""
    from numba.core import event

    class _First(event.Listener):
        done = False

        def on_start(self, ev) -> None:
            if self.done:
                return
            dispatcher = (ev.data or {}).get("dispatcher")
            module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
            if module.startswith("partscale."):
                self.done = True
                callback()

        def on_end(self, ev) -> None:
            pass

    event.register("numba:compile", _First())


#: The folder :func:`ensure_cache` set when this module was first imported (None: not needed).
CACHE_SET = ensure_cache()
