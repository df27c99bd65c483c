#!/usr/bin/env bash
# Runs each libFuzzer target (tests/fuzz/) for a long time: an hour each by default, one after the
# other, in the sanitizer tree that scripts/test.sh --sanitize builds (build-asan/, Clang, ASan and
# UBSan). The corpus each target grows is kept in build-asan/tests/fuzz/<target>.work/corpus, so a
# later run starts where this one ended.
#
# Usage: bash scripts/fuzz.sh [SECONDS_EACH [TARGET...]]
#   SECONDS_EACH defaults to 3600; TARGETs default to all three: model_pipeline_fuzz,
#   compiled_model_fuzz, csv_fuzz.
# Relies on: scripts/setup.sh (Debian packages, clang and libFuzzer among them), CMake, Ninja.
# Guarantees: exits 0 only when every target ran its time and found nothing; a finding stops the
# script, naming the input (build-asan/tests/fuzz/<target>/findings/) and the command that
# reproduces it. Each target's last lines give its executions (`stat::number_of_executed_units`).
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
seconds=${1:-3600}
shift || true
targets=("$@")
((${#targets[@]} > 0)) || targets=(model_pipeline_fuzz compiled_model_fuzz csv_fuzz)
[[ $seconds =~ ^[0-9]+$ ]] || { echo "fuzz.sh: error: SECONDS_EACH must be a whole number, not '$seconds'" >&2; exit 2; }

build=$repo_root/build-asan
bash "$repo_root/scripts/test.sh" --sanitize --build-only
for target in "${targets[@]}"; do
  case $target in
    model_pipeline_fuzz) kind=model ;;
    compiled_model_fuzz) kind=compiled ;;
    csv_fuzz) kind=csv ;;
    *) echo "fuzz.sh: error: unknown target '$target' (model_pipeline_fuzz, compiled_model_fuzz or csv_fuzz)" >&2; exit 2 ;;
  esac
  echo "fuzz.sh: $target for $seconds s"
  bash "$repo_root/tests/fuzz/run_fuzz.sh" "$build/tests/fuzz/$target" "$kind" "$seconds" \
    "$build/tests/fuzz/$target.work" "$build/cli/sidc"
done
echo "fuzz.sh: ${#targets[@]} target(s), $seconds s each: nothing found"
