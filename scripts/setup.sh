#!/usr/bin/env bash
# Installs the Debian packages sidc needs (only those missing), then configures and builds.
#
# Usage: bash scripts/setup.sh [BUILD_DIR [EXTRA_CMAKE_ARGS...]]
#   BUILD_DIR defaults to build (relative to the repository root); EXTRA_CMAKE_ARGS come after the
#   defaults (-G Ninja -DCMAKE_BUILD_TYPE=Release), so a later -DCMAKE_BUILD_TYPE=Debug wins.
# Relies on: a Debian machine (dpkg-query, apt-get), root or sudo only when a package is missing.
# Guarantees: works from any current directory; does no apt work at all when every package is
# present; passes -DSIDC_WERROR=ON when CI is set (and OFF otherwise, so a cached value from an
# earlier CI-style run does not linger); stops at the first failure with a one-line reason.
set -euo pipefail

fail() { echo "setup.sh: error: $*" >&2; exit 1; }
trap 'fail "command failed (exit $?) at line $LINENO: $BASH_COMMAND"' ERR

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo_root"

build_dir=${1:-build}
shift || true

required_packages=(g++ cmake ninja-build libeigen3-dev libboost-dev libfmt-dev libcli11-dev
                   libceres-dev nlohmann-json3-dev libgtest-dev libbenchmark-dev gnuplot-nox python3-minimal
                   clang libclang-rt-dev   # Clang and libFuzzer: the sanitizer and fuzz build (scripts/test.sh)
                   pybind11-dev python3-pybind11 python3-numpy python3-dev  # the Python module (docs/python.md)
                   libopenmpi-dev openmpi-bin)  # mpirun -np N sidc fit (docs/distributed.md)

# One dpkg-query call for all packages: it exits 1 when some are unknown, which is expected here,
# so its status is ignored and only the packages reported as fully installed count as present.
installed=$(dpkg-query -W -f='${Package} ${Status}\n' "${required_packages[@]}" 2>/dev/null |
            awk '$2 == "install" && $4 == "installed" { print $1 }' || true)
missing=()
for package in "${required_packages[@]}"; do
  grep -qxF "$package" <<<"$installed" || missing+=("$package")
done

if ((${#missing[@]} > 0)); then
  echo "setup.sh: installing missing Debian packages: ${missing[*]}"
  if [[ $(id -u) -eq 0 ]]; then
    as_root=()
  elif command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
  else
    fail "missing Debian packages and no root or sudo to install them; as root run: apt-get install ${missing[*]}"
  fi
  "${as_root[@]}" apt-get update -qq
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

werror=OFF
[[ -n "${CI:-}" ]] && werror=ON

echo "setup.sh: configuring $build_dir"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSIDC_WERROR="$werror" "$@"
echo "setup.sh: building $build_dir with $(nproc) jobs"
cmake --build "$build_dir" -j"$(nproc)"
