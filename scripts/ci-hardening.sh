#!/usr/bin/env bash
# CI hardening (docs/reliability.md): (a) the whole test suite built with
# AddressSanitizer + UndefinedBehaviorSanitizer (g++), (b) the libFuzzer
# targets in fuzz/ (clang++), each run for a bounded time from its generated
# seed corpus, (c) the detector's tests under ThreadSanitizer (a Detector
# shared by two threads refuses the overlapping call instead of racing). Non-zero exit on any build failure, test failure, sanitizer
# report or fuzzer finding.
#   FUZZ_RUNS      inputs per fuzz target (default 60000; fixed seed 1, so a
#                  run is reproducible: same binary, same inputs, same verdict)
#   JOBS           build/test parallelism (default 2)
# Sanitizer builds use -O1 -g1 (fast enough to build in CI). The two slowest
# end-to-end groups (SyntheticCli, SyntheticDefaults: 45-85 s each under ASan)
# are left to the normal build; every other test runs sanitized.
set -euo pipefail
cd "$(dirname "$0")/.."

fuzz_runs=${FUZZ_RUNS:-60000}
jobs=${JOBS:-2}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

echo "ci-hardening: (a) ASan+UBSan test suite in build-asan"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  -DLSGD_SANITIZE=address,undefined -DLSGD_BUILD_TESTS=ON -DLSGD_BUILD_TOOLS=ON -DLSGD_BUILD_BENCH=OFF \
  -DLSGD_BUILD_PYTHON=OFF -DLSGD_BUILD_EXAMPLES=OFF
cmake --build build-asan -j"$jobs"
ctest --test-dir build-asan --output-on-failure -j"$jobs" -E "SyntheticCli|SyntheticDefaults"

echo "ci-hardening: (c) ThreadSanitizer: detector_test in build-tsan"
cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  -DLSGD_SANITIZE=thread -DLSGD_BUILD_TESTS=ON -DLSGD_BUILD_TOOLS=OFF -DLSGD_BUILD_BENCH=OFF \
  -DLSGD_BUILD_PYTHON=OFF -DLSGD_BUILD_EXAMPLES=OFF
cmake --build build-tsan -j"$jobs" --target detector_test
TSAN_OPTIONS=halt_on_error=1 build-tsan/tests/detector_test --gtest_filter='Detector.*'

echo "ci-hardening: (b) libFuzzer targets in build-fuzz"
cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  -DLSGD_SANITIZE=address,undefined -DLSGD_BUILD_FUZZERS=ON \
  -DLSGD_BUILD_TESTS=OFF -DLSGD_BUILD_TOOLS=OFF -DLSGD_BUILD_BENCH=OFF -DLSGD_BUILD_PYTHON=OFF -DLSGD_BUILD_EXAMPLES=OFF
cmake --build build-fuzz -j"$jobs"

status=0
for target in config pairs gt db description; do
  corpus=build-fuzz/fuzz/corpus/$target
  artifacts=build-fuzz/fuzz/artifacts/$target/
  mkdir -p "$corpus" "$artifacts"
  log=build-fuzz/fuzz/fuzz_$target.log
  # Databases are bigger (seeds 40-100 KB) and slower to open: longer inputs, fewer runs.
  max_len=8192 runs=$fuzz_runs
  if [ "$target" = db ]; then max_len=131072 runs=$((fuzz_runs / 3)); fi
  # A description carries ~500 ORB keypoints (~20 KB; the seeds are 22-30 KB).
  if [ "$target" = description ]; then max_len=65536; fi
  echo "ci-hardening: fuzz_$target, $runs inputs"
  # New inputs go to corpus/ (kept between runs of the same build dir); seeds are read only.
  # matio (Debian 1.5.23) allocates what a corrupt .mat header claims before
  # reading it; lsgd now checks the headers it knows of (docs/reliability.md),
  # but matio is C and trusts sizes. So, as outside ASan: an impossible
  # calloc returns NULL, which matio handles (allocator_may_return_null=1; a
  # NULL dereference would still fail the run), and a request above 4 GB that
  # succeeds fails the run (-malloc_limit_mb=4096).
  if ! ASAN_OPTIONS="$ASAN_OPTIONS:allocator_may_return_null=1" "build-fuzz/fuzz/fuzz_$target" -seed=1 -runs="$runs" -rss_limit_mb=2048 -malloc_limit_mb=4096 \
      -max_len="$max_len" -timeout=10 -print_final_stats=1 -artifact_prefix="$artifacts" \
      "$corpus" "build-fuzz/fuzz/seeds/$target" >"$log" 2>&1; then
    echo "ci-hardening: fuzz_$target FAILED; reproducer in $artifacts, log:" >&2
    tail -n 60 "$log" >&2
    status=1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  echo "ci-hardening: fuzz_$target: ${runs:-?} executions"
done
exit $status
