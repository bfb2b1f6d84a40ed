#!/usr/bin/env bash
# The README's pictures of real TUM scans completed (docs/complete_tum_*.png): each row is
# the scan | the completion | the completion coloured by kind (observed blue, mirrored and
# rotated copies amber, guessed red), all rendered --view iso --pixels 320.
# A derived range mesh's scan panel is `partscale import SCAN --up=-y`; the raw frame's is
# the colour image cropped to the --box (it has no mesh to import).
# Run from the repository root: bash docs/complete_tum.sh [../shared/data]
set -euo pipefail
DATA=${1:-../shared/data}/scans
OUT=$(mktemp -d)
ps() { PYTHONPATH=src .venv/bin/python -m partscale "$@"; }

row() { # name, scan panel png, completion
    ps render "$3" -o "$OUT/$1_done.png" --view iso --pixels 320
    ps render "$3" -o "$OUT/$1_kind.png" --view iso --pixels 320 --completion
    .venv/bin/python - "$2" "$OUT/$1_done.png" "$OUT/$1_kind.png" "docs/complete_tum_$1.png" <<'EOF'
import sys
from PIL import Image
ims = [Image.open(p).convert("RGB") for p in sys.argv[1:4]]
ims[0].thumbnail((320, 320))
row = Image.new("RGB", (960, 320), "white")
for i, im in enumerate(ims):
    row.paste(im, (320 * i + (320 - im.width) // 2, (320 - im.height) // 2))
row.save(sys.argv[4])
EOF
}

for name in yellow purple; do
    scan=$DATA/derived/tum_${name}_office_chair_partial.ply
    ps import "$scan" -o "$OUT/$name.scan.csdf.npz" --up=-y
    ps render "$OUT/$name.scan.csdf.npz" -o "$OUT/${name}_scan.png" --view iso --pixels 320
    ps complete "$scan" -o "$OUT/$name.csdf.npz" --upright
    row "$name" "$OUT/${name}_scan.png" "$OUT/$name.csdf.npz"
done

F=$DATA/tum_rgbd_frame
for spec in "frame_yellow 365,225,540,440" "frame_purple 0,255,245,480"; do
    set -- $spec
    ps complete --depth "$F/TUM_depth.png" --color "$F/TUM_color.png" \
        --intrinsics "$F/camera_primesense.json" --box "$2" -o "$OUT/$1.csdf.npz" --upright
    .venv/bin/python -c "import sys; from PIL import Image; b=[int(x) for x in sys.argv[2].split(',')]; Image.open(sys.argv[1]).crop(b).save(sys.argv[3])" \
        "$F/TUM_color.png" "$2" "$OUT/$1_scan.png"
    row "$1" "$OUT/$1_scan.png" "$OUT/$1.csdf.npz"
done

# docs/complete_tum_parts.png: the four completions segmented at the defaults (the scan's relief
# measured, see the README's segment section), each rendered --parts --view iso --pixels 320
for name in yellow frame_yellow purple frame_purple; do
    ps segment "$OUT/$name.csdf.npz" -o "$OUT/${name}_parts.csdf.npz" --no-cache
    ps render "$OUT/${name}_parts.csdf.npz" -o "$OUT/${name}_parts.png" --view iso --pixels 320 --parts
done
.venv/bin/python - "$OUT" <<'EOF'
import sys
from PIL import Image
names = ["yellow", "frame_yellow", "purple", "frame_purple"]
row = Image.new("RGB", (320 * len(names), 320), "white")
for i, n in enumerate(names):
    row.paste(Image.open(f"{sys.argv[1]}/{n}_parts.png").convert("RGB"), (320 * i, 0))
row.save("docs/complete_tum_parts.png")
EOF
rm -r "$OUT"
