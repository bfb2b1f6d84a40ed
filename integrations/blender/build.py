"""Build the Blender add-on's zip: ``python integrations/blender/build.py [OUT.zip]``.

The zip holds the ``partscale_blender`` package, what Blender's Preferences > Add-ons >
Install... takes. Default output: ``dist/partscale_blender.zip`` in the repository.
"""

from __future__ import annotations

import sys
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
PACKAGE = HERE / "partscale_blender"


def build(out: Path) -> Path:
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted(PACKAGE.rglob("*.py")):
            z.write(f, f.relative_to(HERE).as_posix())
    tmp.replace(out)
    return out


if __name__ == "__main__":
    target = (
        Path(sys.argv[1])
        if len(sys.argv) > 1
        else HERE.parents[1] / "dist" / "partscale_blender.zip"
    )
    print(build(target))
