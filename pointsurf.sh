#!/usr/bin/env bash
# pointsurf set-up and entry point on Debian 12 (bookworm).
#   ./pointsurf.sh demo    install missing packages, build the CLI (Release), run the demo pipeline
#   ./pointsurf.sh test    install missing packages, build everything (Release), run the test suite
#   ./pointsurf.sh test-sanitize  build in build-asan/ with AddressSanitizer and
#                          UndefinedBehaviorSanitizer (RelWithDebInfo), run the test suite under them
#   ./pointsurf.sh build   install missing packages and build everything only
#   ./pointsurf.sh bench   build, then run bench/run_bench.sh (needs python3-open3d, pcl-tools)
# demo, test, build and bench share one configuration of build/ (tests and the Python module on), so
# `test` after `demo` compiles only the tests and the module, and `pip install ./python` reuses it.
# A second call rebuilds only what changed. Set BUILD_DIR to build elsewhere (default: build/).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
JOBS="$(nproc 2>/dev/null || echo 2)"

BUILD_PACKAGES=(
  cmake ninja-build g++ make
  libeigen3-dev libnanoflann-dev libtbb-dev libcli11-dev nlohmann-json3-dev liblzf-dev libfmt-dev
  libgtest-dev libgmock-dev
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libpng-dev libfreetype-dev fonts-dejavu-core libjs-three libjs-chart.js
  libpugixml-dev
  libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev libocct-foundation-dev
)
# The browser test of the HTML report (tests/report): headless Chromium, driven from Python.
TEST_PACKAGES=(chromium python3)
# The sanitizer runtimes of Debian's GCC 12 (g++ pulls them in; named so a slimmed machine gets them).
SANITIZE_PACKAGES=(libasan8 libubsan1)
# Node.js (Debian nodejs, npm; installed by the tests when the commands are missing) runs laz-perf and
# web-e57 (npm, installed into $BUILD_DIR/npm) to cross-check pointsurf's LAZ and E57.
# The Python module (python/): pybind11 and Debian's Python headers to configure and build it (every
# configuration of build/ has it, demo's too); numpy, pytest, setuptools and venv to test it and for pip.
PYTHON_BUILD_PACKAGES=(pybind11-dev python3-dev)
PYTHON_PACKAGES=(python3-numpy python3-pytest python3-setuptools python3-venv)
BENCH_PACKAGES=(libbenchmark-dev python3-open3d python3-numpy pcl-tools libcgal-demo libosmesa6-dev libpcl-dev)

log() { printf '\033[1mpointsurf.sh:\033[0m %s\n' "$*" >&2; }

# Installs the Debian packages of "$@" that are not installed yet, with apt-get.
install_missing() {
  local missing=()
  for pkg in "$@"; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$pkg")
    fi
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then sudo=(sudo); else
      log "missing packages: ${missing[*]}; run as root or install sudo"; exit 1
    fi
  fi
  log "installing: ${missing[*]}"
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# The one configuration of build/ for demo, test, build and bench: the library, the CLI, the tests
# and the Python module (for Debian's /usr/bin/python3). The library is always built -fPIC
# (CMakeLists.txt), so its objects do not depend on which of these targets are built.
CONFIG_OPTIONS=(-DCMAKE_BUILD_TYPE=Release -DPOINTSURF_BUILD_TESTS=ON -DPOINTSURF_BUILD_PYTHON=ON
                -DPython3_EXECUTABLE=/usr/bin/python3)

# True when $BUILD_DIR's CMake cache holds every -DNAME=VALUE of "$@".
configured_with() {
  local cache="$BUILD_DIR/CMakeCache.txt" opt name line
  [ -f "$cache" ] || return 1
  for opt in "$@"; do
    opt="${opt#-D}"; name="${opt%%=*}"
    line="$(grep -m1 "^${name}:" "$cache")" || return 1
    [ "${line#*=}" = "${opt#*=}" ] || return 1
  done
}

# configure [-DNAME=VALUE...]: installs the build packages and configures $BUILD_DIR with the
# options given, unless its cache holds them already (then CMake is not rerun here; the build
# reruns it when a CMakeLists.txt changed).
configure() {
  install_missing "${BUILD_PACKAGES[@]}" "${PYTHON_BUILD_PACKAGES[@]}"
  configured_with "$@" && return 0
  local generator=()
  if [ ! -f "$BUILD_DIR/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
  cmake -S "$ROOT" -B "$BUILD_DIR" "${generator[@]}" "$@"
}

# build [-DNAME=VALUE...]: configures build/ (CONFIG_OPTIONS, then the options given) and builds
# every target.
build() {
  configure "${CONFIG_OPTIONS[@]}" "$@"
  cmake --build "$BUILD_DIR" --parallel "$JOBS"
}

# Node.js (Debian nodejs and npm, only where the commands are missing: a machine may carry another
# Node.js build, and NodeSource's nodejs bundles npm and conflicts with Debian's npm package) and
# the npm packages "$@" in $BUILD_DIR/npm, for the cross-checks of the tests.
install_npm_tools() {
  local node_packages=() pkg
  command -v node >/dev/null 2>&1 || node_packages+=(nodejs)
  command -v npm >/dev/null 2>&1 || node_packages+=(npm)
  install_missing "${node_packages[@]}"
  for pkg in "$@"; do
    [ -d "$BUILD_DIR/npm/node_modules/${pkg%@*}" ] || npm install --prefix "$BUILD_DIR/npm" --no-audit --no-fund "$pkg" >/dev/null 2>&1 ||
      log "could not install ${pkg%@*} from npm (no network or no npm): its cross-check will skip"
  done
}

demo() {
  configure "${CONFIG_OPTIONS[@]}"
  cmake --build "$BUILD_DIR" --parallel "$JOBS" --target pointsurf_cli  # the CLI only
  local cli="$BUILD_DIR/pointsurf" out="$ROOT/out"
  mkdir -p "$out"
  cd "$ROOT"  # the example pipelines name data/ and out/ relative to the repository
  log "demo: aerial LiDAR tile data/b9_training.ply (22,300 points at x ~ 596,648 m)"
  "$cli" info data/b9_training.ply --report out/b9_info.json
  "$cli" run examples/b9_mesh.json --report out/b9_run.json
  "$cli" run examples/b9_poisson.json --report out/b9_poisson_run.json  # screened Poisson, trimmed at density depth 6
  log "demo: kitten scan data/kitten.xyz"
  "$cli" info data/kitten.xyz --report out/kitten_info.json
  "$cli" run examples/kitten_mesh.json --report out/kitten_run.json --html out/kitten_report.html
  "$cli" reconstruct data/kitten.xyz out/kitten_poisson.ply --method poisson --report out/kitten_poisson.json
  log "demo: pictures (pointsurf render) and the HTML report of the b9 run"
  "$cli" render out/kitten_deviation.ply out/kitten_deviation.png --field deviation --view front --quiet
  "$cli" render out/kitten_mesh.ply out/kitten_mesh.png --view front --quiet
  "$cli" render out/kitten_poisson.ply out/kitten_poisson.png --view front --quiet
  "$cli" report out/b9_run.json out/b9_report.html
  log "demo done. Results in $out/:"
  ls -1 "$out" | sed "s|^|  $out/|" >&2
  log "open the report: $out/kitten_report.html (offline, one file; also $out/b9_report.html)"
}

run_tests() {
  install_missing "${TEST_PACKAGES[@]}" "${PYTHON_PACKAGES[@]}"
  build
  # laz-perf decodes pointsurf's LAZ (tests/io/lazperf_check.sh), web-e57 reads its E57
  # (tests/io/e57_test.cpp); each check skips without its package.
  install_npm_tools laz-perf@0.0.7 web-e57@1.2.0
  cd "$BUILD_DIR"
  ctest --output-on-failure --parallel "$JOBS" --timeout 900
  # The Python module from this build; pytest exits 5 (failing the script) when it collects nothing.
  PYTHONPATH="$BUILD_DIR/python" /usr/bin/python3 -m pytest -q -p no:cacheprovider "$ROOT/python/tests"
}

# Sanitizer run: the whole suite built with -fsanitize=address,undefined in its own build folder.
# Any finding aborts the test that made it (no recovery), so ctest reports it as a failure.
SANITIZE_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
# Tests left out of the sanitizer run, each because its input is large enough that the 2-5x
# slowdown of ASan would push CI past its budget; the code they exercise is covered under the
# sanitizers by the smaller tests of the same module. A ctest regular expression.
SANITIZE_EXCLUDE=(
)
run_sanitized_tests() {
  install_missing "${SANITIZE_PACKAGES[@]}"
  BUILD_DIR="${SANITIZE_BUILD_DIR:-$ROOT/build-asan}"
  # Without the Python module: an ASan-built extension cannot load into Debian's python3.
  configure -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPOINTSURF_BUILD_TESTS=ON -DPOINTSURF_BUILD_PYTHON=OFF \
    "-DCMAKE_CXX_FLAGS=$SANITIZE_FLAGS" \
    "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" \
    "-DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined"
  cmake --build "$BUILD_DIR" --parallel "$JOBS"
  install_npm_tools laz-perf@0.0.7
  cd "$BUILD_DIR"
  local exclude=()
  if [ ${#SANITIZE_EXCLUDE[@]} -gt 0 ]; then
    local IFS='|'
    exclude=(-E "${SANITIZE_EXCLUDE[*]}")
  fi
  # Suppressions: a file per sanitizer, each entry with its reason (see the files).
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
  LSAN_OPTIONS="suppressions=$ROOT/.ci/lsan.supp:print_suppressions=0" \
    ctest --output-on-failure --parallel "$JOBS" --timeout 1800 "${exclude[@]}"
}

case "${1:-}" in
  demo) demo ;;
  test) run_tests ;;
  test-sanitize) run_sanitized_tests ;;
  build) shift; build "$@" ;;
  bench)
    install_missing "${BENCH_PACKAGES[@]}"
    build -DPOINTSURF_BUILD_BENCHMARKS=ON
    shift; BUILD_DIR="$BUILD_DIR" bash "$ROOT/bench/run_bench.sh" "$@" ;;
  *)
    sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'
    exit 1 ;;
esac
