#!/usr/bin/env bash
# Builds the readers' libFuzzer targets (tests/fuzz) with clang, AddressSanitizer and UBSan into
# build-fuzz/, then fuzzes each reader for MSD_FUZZ_SECONDS seconds (default 60), two at a time.
# A crash, a sanitizer report, a leak, a failed property, an input taking over 10 s or an allocation
# over 1 GB stops with exit 1; the input is kept in build-fuzz/crashes/<reader>/ (add it to
# tests/fuzz/corpus/<reader>/ with the fix, so it is replayed by every build from then on).
#   bash scripts/fuzz.sh            build and fuzz every reader
#   MSD_FUZZ_SECONDS=600 bash scripts/fuzz.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"
seconds="${MSD_FUZZ_SECONDS:-60}"
jobs="${MSD_JOBS:-$(nproc)}"
bash "$root/scripts/setup.sh" clang-14 libclang-rt-14-dev

# Only msd::core and the fuzzers are built; the library is instrumented for coverage too.
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -gline-tables-only"
CXX=clang++-14 cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="$flags" \
  -DMSD_FUZZ=ON -DMSD_SHARED=OFF -DMSD_BUILD_TESTS=OFF -DMSD_BUILD_APPS=OFF -DMSD_BUILD_PYTHON=OFF \
  -DMSD_BUILD_BENCH=OFF -DMSD_INSTALL=OFF >/dev/null
readers=(off obj ply stl sel dmat def)
cmake --build "$build" -j "$jobs" --target "${readers[@]/#/fuzz_}"

# reader:corpus pairs; the PLY fuzzer runs once from the ASCII seeds and once from the binary ones.
runs=(off:off obj:obj ply:ply_ascii ply:ply_binary stl:stl sel:sel dmat:dmat def:def)
fuzz_one() {
  local reader="${1%%:*}" corpus="${1##*:}"
  local work="$build/corpus/$corpus" crashes="$build/crashes/$reader"
  mkdir -p "$work" "$crashes"
  # The first folder receives the new inputs; the seeds in the source tree are only read.
  if "$build/tests/fuzz/fuzz_$reader" "$work" "$root/tests/fuzz/corpus/$corpus" -max_total_time="$seconds" \
      -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
      -artifact_prefix="$crashes/" >"$build/fuzz-$corpus.log" 2>&1; then
    echo "fuzz $corpus: $(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$build/fuzz-$corpus.log" | grep -o '[0-9]*$') runs, clean"
  else
    echo "fuzz $corpus: FAILED (log: $build/fuzz-$corpus.log, input kept in $crashes/)"
    tail -n 40 "$build/fuzz-$corpus.log"
    return 1
  fi
}
export -f fuzz_one
export build root seconds
start=$SECONDS
printf '%s\n' "${runs[@]}" | xargs -P "$jobs" -I{} bash -c 'fuzz_one {}'
echo "fuzz: ${#runs[@]} runs of ${seconds} s, $((SECONDS - start)) s"
