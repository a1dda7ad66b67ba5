#!/usr/bin/env bash
# Sanitizer builds of the test suite, each in its own build folder:
#   tests/sanitize.sh asan   ASan+UBSan (gcc), the whole test suite, in build-asan
#   tests/sanitize.sh tsan   TSan (gcc), the server tests (ctest -L server) and the reliability
#                            bad-input table, in build-tsan
# Extra arguments go to ctest (e.g. -R Store). Costs on 2 cores: see tests/reliability/README.md.
#
# Every sanitizer report, including those of glimpse-server processes that the script tests start
# and whose stderr they throw away, is written to <build>/sanitizer-logs/<kind>.<program>.<pid>; the
# run fails when there is one, even if every test passed, and prints one example of each distinct
# report (grouped by its SUMMARY line) at the end.
#
# Debian's PCL, FLANN, gRPC, protobuf, abseil and libgomp are not instrumented. Hence:
#   - ASan: -DEIGEN_MALLOC_ALREADY_ALIGNED=1. Eigen 3.4 stops trusting glibc's malloc alignment when
#     __SANITIZE_ADDRESS__ is defined and switches to its "handmade" aligned allocator (an offset
#     byte before the block). Debian's libpcl_* were compiled without ASan and use plain malloc, so
#     a pcl::PointCloud allocated inside PCL and freed by our (instrumented) inline code read 8 bytes
#     before the block: heap-buffer-overflow in Eigen::internal::handmade_aligned_free, from every
#     PCL-backed feature (VFH, ESF, ...). The define restores the one allocator both sides agree on;
#     ASan's malloc is 16-byte aligned like glibc's, which is all Eigen needs here (no AVX).
#   - LeakSanitizer and ThreadSanitizer suppressions for those libraries: tests/reliability/sanitizers/.
#   - TSan: OMP_NUM_THREADS=1 (libgomp's barriers are invisible to TSan; core's results do not depend
#     on the thread count, tests/core checks that).
# The build takes the working tree as it is, including other people's uncommitted edits.
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
    defines="-DEIGEN_MALLOC_ALREADY_ALIGNED=1 -D_GLIBCXX_ASSERTIONS"
    targets=()  # everything
    labels=()
    logs="$PWD/$build/sanitizer-logs"
    export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=1:strict_string_checks=1:log_path=$logs/asan:log_exe_name=1"
    export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:log_path=$logs/ubsan:log_exe_name=1"
    ;;
  tsan)
    build=build-tsan
    flags="-fsanitize=thread -fno-omit-frame-pointer"
    defines=""
    targets=(glimpse-server glimpse reliability_test_bad_input)
    labels=(-L server)
    logs="$PWD/$build/sanitizer-logs"
    export TSAN_OPTIONS="suppressions=$supp/tsan.supp:halt_on_error=0:second_deadlock_stack=1:history_size=4:log_path=$logs/tsan:log_exe_name=1"
    export OMP_NUM_THREADS=1
    ;;
  *)
    echo "usage: tests/sanitize.sh asan|tsan [ctest arguments]" >&2
    exit 2
    ;;
esac

minutes() { echo "$(($1 / 60)) min $(($1 % 60)) s"; }
start=$(date +%s)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_CXX_FLAGS="$flags $defines" -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags" \
  -DGLIMPSE_BUILD_BENCH=OFF >/dev/null
rm -rf "$logs"
mkdir -p "$logs"
if [[ "$kind" == tsan ]]; then
  # The server tests: every target the "server" label runs, plus what they start.
  mapfile -t server_tests < <(cd tests/server && ls test_*.cpp | sed 's/^test_\(.*\)\.cpp$/server_test_\1/')
  nice -n 10 cmake --build "$build" -j "$jobs" --target "${targets[@]}" "${server_tests[@]}"
else
  nice -n 10 cmake --build "$build" -j "$jobs"
fi
built=$(date +%s)
echo "sanitize $kind: built in $(minutes $((built - start)))"
cd "$build"
status=0
ctest --output-on-failure -j "$jobs" --timeout 1800 "${labels[@]}" "$@" || status=$?
if [[ "$kind" == tsan ]]; then ctest --output-on-failure --timeout 1800 -R '^BadInput\.' "$@" || status=$?; fi
end=$(date +%s)
echo "sanitize $kind: tests ran in $(minutes $((end - built)))"

# Reports, grouped by their SUMMARY line (a report without one, e.g. a LeakSanitizer "all leaks
# suppressed" footer, is grouped by its first line).
mapfile -t reports < <(find "$logs" -type f -size +0 | sort)
if ((${#reports[@]})); then
  status=1
  echo "sanitize $kind: ${#reports[@]} sanitizer report file(s) in $logs"
  declare -A example count
  for f in "${reports[@]}"; do
    key=$(grep -m1 '^SUMMARY:' "$f" || head -n1 "$f")
    count[$key]=$((${count[$key]:-0} + 1))
    [[ -n "${example[$key]:-}" ]] || example[$key]=$f
  done
  for key in "${!count[@]}"; do
    echo "---- ${count[$key]} x $key"
    echo "     e.g. ${example[$key]}:"
    grep -v -E '^ *0x[0-9a-f]+: |^Shadow byte|^  [A-Z][a-z].*: *[0-9a-f]{2}' "${example[$key]}" | head -n 60
  done
else
  echo "sanitize $kind: no sanitizer reports"
fi
exit $status
