"""Keyword options of the public functions: an unknown one fails naming those that exist."""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from typing import TypeVar

F = TypeVar("F", bound=Callable)


def keyword_options(func: F) -> F:
    """Make an unknown keyword option fail with the list of the ones that exist.

    Python's own message ("unexpected keyword argument") does not say what is allowed.
    """
    sig = inspect.signature(func)
    known = [
        n
        for n, p in sig.parameters.items()
        if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and not n.startswith("_")
    ]

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        unknown = [k for k in kwargs if k not in sig.parameters]
        if unknown:
            raise TypeError(
                f"{func.__name__}() got unknown option(s) {', '.join(map(repr, unknown))}; "
                f"options are: {', '.join(known)}"
            )
        return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]  # wraps() keeps func's signature; mypy cannot see it
