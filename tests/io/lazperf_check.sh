#!/usr/bin/env bash
# Cross-check of pointsurf's LAZ with an independent decoder: laz-perf (npm, WASM) decodes LAZ
# files pointsurf wrote (point formats 0-3, extra bytes, several chunks), and the points it
# gives must read back identically to pointsurf's own decoding (every field, as XYZ text).
# Then the same for files of point formats `convert` does not write (0-3, 8, and 6-8 with four
# scanner channels), made by laz_records_tool: laz-perf's records must equal the records encoded.
#   lazperf_check.sh POINTSURF_CLI BUILD_DIR SOURCE_DIR LAZ_RECORDS_TOOL
# laz-perf is installed by pointsurf.sh into BUILD_DIR/npm; when it is absent the check installs
# it there. Node.js missing is a failure (pointsurf.sh installs it). Only when the npm registry
# cannot be reached to install laz-perf does the check skip (exit 77, ctest's SKIP_RETURN_CODE),
# saying so.
set -euo pipefail
cli="$1"; build="$2"; src="$3"; tool="$4"
module="$build/npm/node_modules/laz-perf"
command -v node >/dev/null || { echo "FAIL: node (Debian nodejs) is not installed; run ./pointsurf.sh build"; exit 1; }
if [ ! -d "$module" ]; then
  command -v npm >/dev/null || { echo "FAIL: npm (Debian npm) is not installed; run ./pointsurf.sh build"; exit 1; }
  if ! timeout 120 npm install --prefix "$build/npm" --no-audit --no-fund laz-perf@0.0.7 >/dev/null 2>&1; then
    echo "SKIP: laz-perf is not installed in $build/npm and npm could not fetch it (no network?)"
    exit 77
  fi
fi
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
python3 - "$work/lines.xyz" <<'PY'
import random, sys
random.seed(7)
with open(sys.argv[1], "w") as f:  # scan lines: x y z intensity, 120,000 points (3 chunks)
    f.write("# x y z intensity\n")
    for i in range(120000):
        f.write(f"{i*0.01:.4f} {random.random()*5:.4f} {random.gauss(10, 0.5):.4f} {random.randrange(4096)}\n")
PY
inputs=("$src/data/b9_training.ply" "$src/data/kitten.xyz" "$src/tests/data/simple.las" "$work/lines.xyz")
status=0
for input in "${inputs[@]}"; do
  name="$(basename "$input")"
  "$cli" convert "$input" "$work/$name.laz" >/dev/null 2>&1
  node "$src/tests/io/lazperf_decode.js" "$module" "$work/$name.laz" "$work/$name.lazperf.las" >/dev/null
  "$cli" convert "$work/$name.lazperf.las" "$work/a.xyz" >/dev/null 2>&1
  "$cli" convert "$work/$name.laz" "$work/b.xyz" >/dev/null 2>&1
  if cmp -s "$work/a.xyz" "$work/b.xyz"; then
    echo "ok: $name: laz-perf decodes pointsurf's LAZ to the same $(($(wc -l < "$work/a.xyz") - 1)) points"
  else
    echo "FAIL: $name: laz-perf's points differ from pointsurf's"; status=1
  fi
done
for spec in "0 1" "1 1" "2 1" "3 1" "6 4" "7 4" "8 1" "8 4"; do
  set -- $spec
  "$tool" "$1" 120000 "$2" "$work/f$1.laz" "$work/f$1.las"
  node "$src/tests/io/lazperf_decode.js" "$module" "$work/f$1.laz" "$work/f$1.lazperf.las" >/dev/null
  if python3 - "$work/f$1.las" "$work/f$1.lazperf.las" <<'PY'
import struct, sys
a, b = (open(f, "rb").read() for f in sys.argv[1:3])
size = struct.unpack_from("<Q", a, 247)[0] * struct.unpack_from("<H", a, 105)[0]
sys.exit(0 if size and a[-size:] == b[-size:] and len(b) == struct.unpack_from("<I", b, 96)[0] + size else 1)
PY
  then
    echo "ok: point format $1, $2 scanner channel(s): laz-perf decodes pointsurf's LAZ to the records encoded"
  else
    echo "FAIL: point format $1, $2 scanner channel(s): laz-perf's records differ from those encoded"; status=1
  fi
done
exit $status
