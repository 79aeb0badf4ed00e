#!/bin/bash
# AddressSanitizer + UBSan build of the E57 tests alone (the io and core sources, none of the
# CGAL modules, so it builds in two minutes where ./pointsurf.sh test-sanitize builds everything),
# then runs them. The CLI tests among them use the release CLI in build/.
set -e
cd "$(dirname "$0")/../.."
export CCACHE_BASEDIR=/work CCACHE_DIR=/work/.ccache
FLAGS=(-std=c++20 -O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
DEFS=(-DPOINTSURF_VERSION=\"0.1.0\" "-DPOINTSURF_DATA_DIR=\"$PWD/data\"" "-DPOINTSURF_CLI_PATH=\"$PWD/build/pointsurf\"")
INC=(-Iinclude -Isrc -Itests -I/usr/include/eigen3 -I/usr/include/liblzf)
rm -rf build-asan-e57/obj
mkdir -p build-asan-e57/obj
n=0
for s in src/io/*.cpp src/io/detail/*.cpp src/core/*.cpp tests/support/files.cpp tests/support/shapes.cpp tests/support/cli_run.cpp tests/io/e57_test.cpp; do
  ccache g++ "${FLAGS[@]}" "${DEFS[@]}" "${INC[@]}" -c "$s" -o "build-asan-e57/obj/$(echo "$s" | tr / _).o" &
  n=$((n + 1)); if [ $((n % 2)) -eq 0 ]; then wait; fi
done
wait
g++ "${FLAGS[@]}" build-asan-e57/obj/*.o -o build-asan-e57/e57_tests -lgtest -lgtest_main -lfmt -ltbb -lpugixml -llzf -lpthread
ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1" \
UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" build-asan-e57/e57_tests --gtest_filter='E57*'
