#!/usr/bin/env bash
# The whole test suite: sets up and builds (scripts/setup.sh), then runs every CTest test.
#
# Usage: bash scripts/test.sh              # Release build in build/
#        bash scripts/test.sh --sanitize   # Debug build with ASan+UBSan in build-asan/
# Relies on: scripts/setup.sh. Guarantees: works from any current directory; exits non-zero when
# a test fails or when no test was found (a suite that runs nothing must not look green).
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

case "${1:-}" in
  "")         build_dir=build;      cmake_args=() ;;
  --sanitize) build_dir=build-asan; cmake_args=(-DSIDC_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug) ;;
  *) echo "test.sh: error: unknown option '$1' (usage: scripts/test.sh [--sanitize])" >&2; exit 2 ;;
esac

bash "$repo_root/scripts/setup.sh" "$build_dir" "${cmake_args[@]}"

echo "test.sh: running ctest in $build_dir"
ctest --test-dir "$repo_root/$build_dir" --output-on-failure --no-tests=error -j2
