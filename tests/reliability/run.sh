#!/usr/bin/env bash
# One command per part of the reliability and security checks:
#   tests/reliability/run.sh bad-input   the bad-input table over the real recogniser (~10 s)
#   tests/reliability/run.sh faults      kill -9 during Train, bad DB files, vanished clients, deadlines (~1 min)
#   tests/reliability/run.sh security    TLS, mutual TLS, bearer token with the real CLI (~30 s)
#   tests/reliability/run.sh load [glimpse-load flags]   the load test, report in build-rel/load-report.md
#   tests/reliability/run.sh fuzz [seconds-per-target]   libFuzzer, ASan+UBSan, in build-fuzz (default 60 s)
#   tests/reliability/run.sh sanitize [asan|tsan]        tests/sanitize.sh (both when no kind is given)
#   tests/reliability/run.sh all         every part above, in that order (fuzz 60 s per target)
# bad-input, faults, security and load use a Release build in build-rel (GLIMPSE_REL_BUILD_DIR).
set -euo pipefail
cd "$(dirname "$0")/../.."
part=${1:-}
shift || true
build=${GLIMPSE_REL_BUILD_DIR:-build-rel}
jobs=${GLIMPSE_BUILD_JOBS:-2}

release() {
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DGLIMPSE_BUILD_BENCH=OFF >/dev/null
  cmake --build "$build" -j "$jobs" --target glimpse-server glimpse reliability_test_bad_input glimpse-load
}

case "$part" in
  bad-input) release && (cd "$build" && ctest --output-on-failure -R "^BadInput\\." -V | grep -vE "^[0-9]+: (Test command|Working Directory|Environment)") ;;
  faults) release && (cd "$build" && ctest --output-on-failure -L faults) ;;
  security) release && (cd "$build" && ctest --output-on-failure -L security) ;;
  load)
    release
    "$build/tests/reliability/glimpse-load" --report="$build/load-report.md" "$@"
    ;;
  fuzz) bash tests/fuzz/run.sh "${1:-60}" ;;
  sanitize)
    if (($#)); then bash tests/sanitize.sh "$@"; else bash tests/sanitize.sh asan && bash tests/sanitize.sh tsan; fi
    ;;
  all)
    for p in bad-input faults security load; do bash "$0" "$p"; done
    bash "$0" fuzz 60
    bash "$0" sanitize
    ;;
  *)
    sed -n '2,10p' "$0" >&2
    exit 2
    ;;
esac
