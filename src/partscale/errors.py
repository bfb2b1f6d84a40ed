"""Errors raised at the public boundary.

Every error a user can cause is an :class:`InputError`: its message is one line that names the
thing at fault and says what was expected and what arrived. The CLI prints it and exits with 2.
"""

from __future__ import annotations


class PartscaleError(Exception):
    """Base class of every error partscale raises on purpose.

    Made as :class:`Exception` is, the message first.

    Examples
    --------
    >>> from partscale import PartscaleError, load
    >>> try:
    ...     load("no such file.csdf.npz")
    ... except PartscaleError as exc:
    ...     print(type(exc).__name__)
    InputError
    """


class InputError(PartscaleError, ValueError):
    """Bad input: a file, a grid or an option that is not what was expected.

    Parameters
    ----------
    message : str
        One line: what is wrong, expected vs got. Parameters are named as the function takes
        them (``res``, ``world_size``), not as the command line spells them.
    params : tuple of str
        The parameters the message names within its text (``"expected res in [16, 16384]"``),
        so that the command line can say its own spelling (``--res``). One named at the head of
        the message (``"rank: expected ..."``) need not be listed.

    Examples
    --------
    >>> from partscale import InputError, load
    >>> try:
    ...     load("missing.csdf.npz")
    ... except InputError as exc:
    ...     print(exc)
    missing.csdf.npz: expected an existing .csdf.npz file, got no such file
    """

    def __init__(self, message: str = "", *, params: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.params = tuple(params)


class MemoryLimitError(InputError):
    """A request that would need more memory than this machine allows.

    Raised before the memory is asked for, so nothing is half done; an :class:`InputError`, so
    the CLI prints it as one line and exits with 2.

    Parameters
    ----------
    message : str
        What was asked, how much memory it would need and how much is available.
    params : tuple of str
        The parameters the message names (as in :class:`InputError`).

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.errors import MemoryLimitError
    >>> try:
    ...     ingest.load(data.table(), res=16384)
    ... except MemoryLimitError as exc:
    ...     print(exc.params, "would need" in str(exc))
    ('res',) True
    """


class PartscaleWarning(UserWarning):
    """A note for the user about something partscale did on its own.

    Raised through :func:`warnings.warn` (e.g. a damaged cache entry discarded); the CLI prints
    it as one line, ``note: ...``; made as :class:`UserWarning` is, the message first.

    Examples
    --------
    >>> import warnings
    >>> from partscale.errors import PartscaleWarning
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warnings.warn("a damaged cache entry was discarded", PartscaleWarning)
    >>> caught[0].category.__name__, str(caught[0].message)
    ('PartscaleWarning', 'a damaged cache entry was discarded')
    """


def one_line(exc: BaseException) -> str:
    r"""The exception's message on one line (whitespace runs become one space), or its type name.

    Parameters
    ----------
    exc : BaseException
        Any exception.

    Returns
    -------
    str
        Its message with every run of whitespace (newlines included) made one space; its type's
        name where the message is empty.

    Examples
    --------
    >>> from partscale.errors import one_line
    >>> one_line(ValueError("expected res in [16, 16384],\n   got 8"))
    'expected res in [16, 16384], got 8'
    >>> one_line(KeyError())
    'KeyError'
    """
    return " ".join(str(exc).split()) or type(exc).__name__


def shown(x: object, limit: int = 60) -> str:
    """Short text of a rejected value for a message: its repr cut to ``limit`` characters.

    Arrays of more than 6 elements are described by their shape; so a 10 MB string in a recipe
    is never echoed in full.

    Parameters
    ----------
    x : object
        The rejected value: anything, an array (anything with ``shape``, ``size`` and
        ``tolist``) included.
    limit : int
        Most characters of the text; a longer repr is cut and ends with ``...``.

    Returns
    -------
    str
        The value's repr (an array of up to 6 elements as its list), or ``"an array of shape
        (...)"`` for a larger array.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.errors import shown
    >>> shown(np.array([1.5, 2.0]))
    '[1.5, 2.0]'
    >>> shown(np.zeros((32, 32, 32)))
    'an array of shape (32, 32, 32)'
    >>> shown("x" * 100, limit=10)
    "'xxxxxx..."
    """
    shape, size = getattr(x, "shape", None), getattr(x, "size", None)
    if shape is not None and isinstance(size, int) and hasattr(x, "tolist"):
        if size > 6:
            return f"an array of shape {tuple(shape)}"
        x = x.tolist()
    text = repr(x)
    return text if len(text) <= limit else text[: limit - 3] + "..."
