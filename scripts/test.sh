#!/usr/bin/env bash
# The test command (CI runs it): the whole suite in a Release build, then a sanitizer pass: the
# same code built by Clang with AddressSanitizer and UndefinedBehaviorSanitizer (float-cast-overflow
# included, which GCC's UBSan does not check), running the unit tests, the golden tests of the sidc
# binary and a short run of each libFuzzer target (tests/fuzz/).
#
# Usage: bash scripts/test.sh                 # Release build in build/, then the sanitizer pass in build-asan/
#        bash scripts/test.sh --release       # the Release build and its tests only
#        bash scripts/test.sh --sanitize      # the sanitizer pass only
#        bash scripts/test.sh --sanitize --build-only   # build build-asan/, run nothing (scripts/fuzz.sh)
#   SIDC_FUZZ_SECONDS (default 15) sets how long each fuzz target runs in the sanitizer pass.
#
# The sanitizer pass, and why it is a subset. CI is a fresh clone on a 2-core machine and the
# whole command should stay under 15 minutes; the Release build and suite take about 8 of them
# with a cold compiler cache (about 16 in all: README, section Tests). The sanitizer tree is one build serving both the sanitizers and the
# fuzz targets (Clang, -O1 -gline-tables-only: -O0 code runs the tests about 3 times slower, -g
# costs link time and disk; but the report, driver and command line at -O0, as their tests here
# are small and their build is not), and it builds and runs what finds memory and undefined-behaviour
# errors where hostile input arrives: every layer's library, the sidc binary, the unit tests of
# the code that reads what users hand over (label `input`: grammar, compiler and compiled-model
# reader, records, output files), every golden case (label `golden`: the whole bad-input
# catalogue and the CLI transcripts, which run every command through every layer) and the fuzz
# targets (label `fuzz`). Left out: the other unit tests (numerics on well-formed data, a third
# of the tree's build time), the `fit` and `install` labels (long fits of the same code paths the
# golden fits take, 3 to 10 times slower under ASan, and a second install build). Figures: README,
# section Tests.
#
# A sanitizer report fails its test: the code is built with -fno-sanitize-recover=all, and ASan
# and UBSan stop at the first error (halt_on_error) with a non-zero exit.
#
# Relies on: scripts/setup.sh (Debian packages, among them clang and libclang-rt-14-dev for
# libFuzzer). Guarantees: works from any current directory; exits non-zero when a test fails or
# when no test was found (a suite that runs nothing must not look green).
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
release=true sanitize=true build_only=false
for argument in "$@"; do
  case "$argument" in
    --release)    sanitize=false ;;
    --sanitize)   release=false ;;
    --build-only) build_only=true ;;
    *) echo "test.sh: error: unknown option '$argument' (usage: scripts/test.sh [--release | --sanitize [--build-only]])" >&2; exit 2 ;;
  esac
done

if $release; then
  bash "$repo_root/scripts/setup.sh" build
  echo "test.sh: running ctest in build"
  ctest --test-dir "$repo_root/build" --output-on-failure --no-tests=error -j2 -LE '^input$'
fi
$sanitize || exit 0

# The Release step has installed the packages; alone, this pass needs Clang and libFuzzer first.
if ! command -v clang++ >/dev/null 2>&1 || ! compgen -G '/usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a' >/dev/null; then
  bash "$repo_root/scripts/setup.sh" build
fi
werror=OFF
[[ -n "${CI:-}" ]] && werror=ON
echo "test.sh: configuring build-asan (Clang, ASan + UBSan, fuzz targets)"
# The report, driver and command line at -O0: Clang with ASan builds them about twice as fast as at
# -O1 and their tests here barely run them. Not the runtime: at -O0 its golden fits ran 3 to 4
# times slower, and form_from_data reached the golden harness's 15-second limit (a failed run).
cmake -S "$repo_root" -B "$repo_root/build-asan" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug \
  "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -gline-tables-only" -DSIDC_FUZZ=ON -DSIDC_WERROR="$werror" \
  "-DSIDC_UNOPTIMIZED_LAYERS=report;driver;cli" \
  -DSIDC_FUZZ_SECONDS="${SIDC_FUZZ_SECONDS:-15}"
# The unit-test executables of label `input`: sidc_input_tests(TARGET) in tests/*/CMakeLists.txt.
input_targets=$(grep -ho 'sidc_input_tests([a-z_0-9]*' "$repo_root"/tests/*/CMakeLists.txt | sed -E 's/sidc_input_tests\(//' | sort -u)
echo "test.sh: building build-asan with $(nproc) jobs"
# shellcheck disable=SC2086  # the target names are words
cmake --build "$repo_root/build-asan" -j"$(nproc)" --target sidc model_pipeline_fuzz compiled_model_fuzz csv_fuzz $input_targets
$build_only && exit 0

echo "test.sh: running ctest in build-asan (labels input, golden, fuzz)"
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
ctest --test-dir "$repo_root/build-asan" --output-on-failure --no-tests=error -j2 -L '^(input|golden|fuzz)$'
