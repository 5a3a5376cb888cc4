#!/usr/bin/env bash
# Builds the test suite with AddressSanitizer and UBSan (g++, -O1) into build-asan/ and runs it: every
# unit, conformance and corpus-replay test and the command-line checks. The regression suite (the whole
# comparison, ~10 min in Release) and the install check run in the plain build only (scripts/test.sh).
# Any sanitizer report fails its test: UBSan stops at the first report, ASan reports leaks at exit.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-asan"
jobs="${MSD_JOBS:-$(nproc)}"
bash "$root/scripts/setup.sh"

flags="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g1"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DMSD_BUILD_PYTHON=OFF -DMSD_BUILD_BENCH=OFF -DMSD_INSTALL=OFF >/dev/null
targets=(test_core test_decomposition test_detail test_deformation test_reconstruction test_analysis
         test_conformance test_compare test_view msdeform replay_off replay_obj replay_ply replay_stl replay_sel replay_dmat replay_def)
start=$SECONDS
cmake --build "$build" -j "$jobs" --target "${targets[@]}"
echo "sanitize: build $((SECONDS - start)) s"
start=$SECONDS
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
ctest --test-dir "$build" --output-on-failure -j "$jobs" -E "^(test_regression|catch2_case_count)$"
echo "sanitize: tests $((SECONDS - start)) s"
