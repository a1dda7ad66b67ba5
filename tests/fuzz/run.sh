#!/usr/bin/env bash
# Builds the fuzz targets with clang -fsanitize=fuzzer,address,undefined in build-fuzz (core, proto and
# the server library instrumented too) and runs each for N seconds from its committed corpus.
#   tests/fuzz/run.sh [seconds-per-target=60] [target ...]     targets: off obj ply pcd xyz deserialize convert
# New interesting inputs go to tests/fuzz/corpus-run/<target>/ (git-ignored; merge the good ones into
# corpus/ by hand); a crash leaves its input in build-fuzz/crashes/<target>/ and fails the run.
# Needs clang and libclang-rt-14-dev (Debian). The first build costs ~12 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(off obj ply pcd xyz deserialize convert)
build=${GLIMPSE_FUZZ_BUILD_DIR:-build-fuzz}
jobs=${GLIMPSE_BUILD_JOBS:-2}

san="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS="$san -fsanitize=fuzzer-no-link" \
  -DCMAKE_EXE_LINKER_FLAGS="$san" -DGLIMPSE_FUZZ=ON -DGLIMPSE_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
failed=()
for t in "${targets[@]}"; do
  run_corpus="tests/fuzz/corpus-run/$t"
  crashes="$build/crashes/$t"
  mkdir -p "$run_corpus" "$crashes"
  echo "== fuzz_$t: $seconds s"
  # -rss_limit_mb: the readers refuse files they cannot hold, so 2 GB means a bug;
  # -max_len: big enough for the model seeds (up to ~60 KB).
  if ! "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
      -print_final_stats=1 -artifact_prefix="$crashes/" "$run_corpus" "tests/fuzz/corpus/$t" \
      2>"$build/fuzz_$t.log"; then
    failed+=("$t")
    grep -E "ERROR|runtime error|SUMMARY|Test unit written" "$build/fuzz_$t.log" | head -20
  fi
  grep -E "stat::number_of_executed_units|stat::new_units_added|cov:" "$build/fuzz_$t.log" | tail -3
done
if ((${#failed[@]})); then
  echo "fuzz: crashes in ${failed[*]} (inputs in $build/crashes/)" >&2
  exit 1
fi
echo "fuzz: ${#targets[@]} targets, $seconds s each, no crash"
