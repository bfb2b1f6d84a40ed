"""Designer lengths for ``fit``: re-exported from their one home, :mod:`partscale.edit`."""

from ..edit import parse_length, parse_size

__all__ = ["parse_length", "parse_size"]
