"""``python -m partscale.data NAME``: print the path of a shipped sample (no NAME: list them)."""

from __future__ import annotations

import sys

from . import NAMES


def main(argv: list[str]) -> int:
    if not argv:
        for name, fn in NAMES.items():
            print(f"{name}\t{fn()}")
        return 0
    if len(argv) != 1 or argv[0] not in NAMES:
        print(
            f"python -m partscale.data: expected one of {', '.join(NAMES)}, got {' '.join(argv)!r}",
            file=sys.stderr,
        )
        return 2
    print(NAMES[argv[0]]())
    return 0


sys.exit(main(sys.argv[1:]))
