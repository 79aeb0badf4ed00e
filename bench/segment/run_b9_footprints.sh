#!/bin/bash
# Building footprints on the demo's aerial b9 tile, scored on its training strokes
# (b9_footprint_score.py: roof strokes inside the footprints, ground and vegetation strokes
# inside), and the picture docs/render/b9_footprints_strokes.png. Footprints: RANSAC planes
# (`segment --method ransac --types plane`, defaults), their outlines (`boundary`, defaults), the
# planes at least 2.5 m above the ground plane. Appends a row to bench/results/segment_b9_footprints.csv.
#   bench/segment/run_b9_footprints.sh [BUILD_DIR]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$ROOT/build}
PY=/usr/bin/python3
WORK=$(mktemp -d /tmp/pointsurf_b9_footprints.XXXX)
tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$WORK" data/points_3/b9_training.ply
"$BUILD/pointsurf" segment "$WORK/data/points_3/b9_training.ply" "$WORK/b9_segments.ply" --method ransac --types plane > /dev/null 2>&1
"$BUILD/pointsurf" boundary "$WORK/b9_segments.ply" "$WORK/b9_boundary.ply" --outlines "$WORK/b9_outlines.geojson" > /dev/null 2>&1
score=$($PY "$ROOT/bench/segment/b9_footprint_score.py" "$WORK/b9_segments.ply" "$WORK/b9_outlines.geojson" "$WORK/picture.ply" 2.5)
echo "$score"
"$BUILD/pointsurf" render "$WORK/picture.ply" "$ROOT/docs/render/b9_footprints_strokes.png" --view top --point-size 5 \
    --title "b9: footprints (black) over the training strokes: roof red, ground sand, vegetation green" > /dev/null 2>&1
CSV="$ROOT/bench/results/segment_b9_footprints.csv"
[ -f "$CSV" ] || echo "commit,date,machine,building_segments,roof_strokes,ground_strokes,vegetation_strokes,roof_recall,ground_inside,vegetation_inside,precision,iou_strokes" > "$CSV"
$PY - "$(git -C "$ROOT" rev-parse --short HEAD)" "$(date -u +%Y-%m-%dT%H:%M:%SZ)" "$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)" "$score" >> "$CSV" <<'PYEOF'
import json, sys
c, d, m, s = sys.argv[1:]
j = json.loads(s)
print(f'{c},{d},"{m}",{len(j["building_segments"])},{j["strokes"]["roof"]},{j["strokes"]["ground"]},{j["strokes"]["vegetation"]},'
      f'{j["roof_recall"]},{j["ground_inside"]},{j["vegetation_inside"]},{j["precision"]},{j["iou_strokes"]}')
PYEOF
rm -rf "$WORK"
