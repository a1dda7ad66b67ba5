#!/usr/bin/env bash
# Sanitizer builds of the test suite (issue 10, item 3), each in its own build folder:
#   tests/sanitize.sh asan   ASan+UBSan (gcc), the whole test suite, in build-asan
#   tests/sanitize.sh tsan   TSan (gcc), the server tests (ctest -L server, and the reliability
#                            bad-input table), in build-tsan
# Extra arguments go to ctest (e.g. -R Store). Costs on 2 cores: see tests/reliability/README.md.
# Debian's gRPC, protobuf, PCL and libgomp are not instrumented: LeakSanitizer and ThreadSanitizer
# suppressions for them are in tests/reliability/sanitizers/, and the TSan run sets OMP_NUM_THREADS=1
# (libgomp's own synchronisation is invisible to TSan; core's results do not depend on the thread count).
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:-}
shift || true
jobs=${GLIMPSE_BUILD_JOBS:-2}
supp="$PWD/tests/reliability/sanitizers"
case "$kind" in
  asan)
    build=build-asan
    flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
    targets=()  # everything
    labels=()
    export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=1:strict_string_checks=1"
    export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
    ;;
  tsan)
    build=build-tsan
    flags="-fsanitize=thread -fno-omit-frame-pointer"
    targets=(glimpse-server glimpse reliability_test_bad_input)
    labels=(-L server)
    export TSAN_OPTIONS="suppressions=$supp/tsan.supp:halt_on_error=1:second_deadlock_stack=1:history_size=4"
    export OMP_NUM_THREADS=1
    ;;
  *)
    echo "usage: tests/sanitize.sh asan|tsan [ctest arguments]" >&2
    exit 2
    ;;
esac

start=$(date +%s)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags" \
  -DGLIMPSE_BUILD_BENCH=OFF >/dev/null
if [[ "$kind" == tsan ]]; then
  # The server tests: every target the "server" label runs, plus what they start.
  mapfile -t server_tests < <(cd tests/server && ls test_*.cpp | sed 's/^test_\(.*\)\.cpp$/server_test_\1/')
  cmake --build "$build" -j "$jobs" --target "${targets[@]}" "${server_tests[@]}"
else
  cmake --build "$build" -j "$jobs"
fi
built=$(date +%s)
echo "sanitize $kind: built in $(((built - start) / 60)) min $(((built - start) % 60)) s"
cd "$build"
status=0
ctest --output-on-failure -j "$jobs" --timeout 1800 "${labels[@]}" "$@" || status=$?
if [[ "$kind" == tsan ]]; then ctest --output-on-failure --timeout 1800 -R '^BadInput\.' "$@" || status=$?; fi
end=$(date +%s)
echo "sanitize $kind: tests ran in $(((end - built) / 60)) min $(((end - built) % 60)) s"
exit $status
