"""Errors raised at the public boundary.

Every error a user can cause is an :class:`InputError`: its message is one line that names the
thing at fault and says what was expected and what arrived. The CLI prints it and exits with 2.
"""

from __future__ import annotations


class PartscaleError(Exception):
    """Base class of every error partscale raises on purpose."""


class InputError(PartscaleError, ValueError):
    """Bad input: a file, a grid or an option that is not what was expected.

    Parameters
    ----------
    message : str
        One line: what is wrong, expected vs got.
    """


class MemoryLimitError(InputError):
    """A request that would need more memory than this machine allows."""


def one_line(exc: BaseException) -> str:
    """The exception's message on one line (whitespace runs become one space), or its type name."""
    return " ".join(str(exc).split()) or type(exc).__name__
