#!/usr/bin/env bash
# `cmake --install` and `find_package(sidc)` as a user meets them: the build tree installed into a
# fresh temporary prefix, examples/library configured and built against that prefix alone, and
# run on the thesis' section 4-1 model, whose estimates it must print (tests/install/CMakeLists.txt).
#
#   install_test.sh build=DIR source=DIR cmake=PATH generator=NAME make=PATH cxx=PATH
#                   build_type=TYPE cxx_flags=FLAGS sanitize=ON|OFF [prefix_path=LIST]
#
# prefix_path: the build's own CMAKE_PREFIX_PATH, searched after the fresh prefix, so that the
# package's dependencies (Eigen, fmt, Boost, nlohmann_json) are found where sidc's build found them.
#
# Everything it makes lies in one temporary folder, removed when it ends.
set -euo pipefail

declare -A arg
for a in "$@"; do arg[${a%%=*}]=${a#*=}; done
build=${arg[build]} source=${arg[source]} cmake=${arg[cmake]}

# The physical path, as CMake stores it (no `//` from a TMPDIR ending in `/`, no symlink).
work=$(cd "$(mktemp -d "${TMPDIR:-/tmp}/sidc-install-test.XXXXXX")" && pwd -P)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
fail() { echo "FAIL: $*" >&2; exit 1; }
step() { echo "== $*"; }

# What is installed is what the sources say now (a no-op when the build is up to date).
step "building the installed targets in $build"
"$cmake" --build "$build" --target sidc sidc_diagnostics sidc_ir sidc_grammar sidc_compiler sidc_runtime sidc_report sidc_driver \
  > "$work/build.log" 2>&1 || { cat "$work/build.log"; fail "cannot build sidc in $build"; }

step "cmake --install $build --prefix $prefix"
"$cmake" --install "$build" --prefix "$prefix" > "$work/install.log" 2>&1 || { cat "$work/install.log"; fail "cmake --install failed"; }

package=$(dirname "$(find "$prefix" -path '*/cmake/sidc/sidcConfig.cmake' -print -quit)")
[[ $package != . ]] || fail "no sidcConfig.cmake installed under $prefix"
for f in bin/sidc include/sidc/runtime/solve/fit.hpp include/sidc/compiler/pipeline.hpp include/sidc/diagnostics/diagnostic.hpp include/sidc/driver/fit_run.hpp; do
  [[ -e $prefix/$f ]] || fail "$f not installed"
done
for f in sidcConfig.cmake sidcConfigVersion.cmake sidcTargets.cmake; do
  [[ -e $package/$f ]] || fail "$package/$f not installed"
done
for lib in diagnostics ir grammar compiler runtime report driver; do
  [[ -n $(find "$prefix" -name "libsidc_$lib.*" -print -quit) ]] || fail "libsidc_$lib not installed"
done
# Only sidc's own build may see its warnings, -Werror, sanitizers and SIDC_VERSION; and an
# installed package must not point back into the source or build tree.
if grep -nE -e '-W[a-z]|sanitize|SIDC_VERSION|sidc_build_flags' "$package"/*.cmake || grep -nF -e "$source" -e "$build" "$package"/*.cmake; then
  fail "the installed package leaks build settings or paths (above)"
fi
"$prefix/bin/sidc" --version > /dev/null || fail "the installed sidc does not run"

step "configuring examples/library against $prefix"
linker_flags=""
cxx_flags=${arg[cxx_flags]:-}
# A sanitized sidc's libraries need the sanitizers' runtime, which the package does not impose, and
# the consumer compiled alike: Eigen's inline allocation code differs with and without ASan, and two
# versions of it in one program free what the other allocated.
if [[ ${arg[sanitize]:-OFF} == ON ]]; then
  linker_flags="-fsanitize=address,undefined"
  cxx_flags="$cxx_flags -fsanitize=address,undefined -fno-omit-frame-pointer"
fi
"$cmake" -S "$source/examples/library" -B "$work/build" -G "${arg[generator]}" \
  -DCMAKE_MAKE_PROGRAM="${arg[make]}" -DCMAKE_CXX_COMPILER="${arg[cxx]}" \
  -DCMAKE_BUILD_TYPE="${arg[build_type]:-}" -DCMAKE_CXX_FLAGS="$cxx_flags" \
  -DCMAKE_EXE_LINKER_FLAGS="$linker_flags" \
  -DCMAKE_PREFIX_PATH="$prefix${arg[prefix_path]:+;${arg[prefix_path]}}" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  > "$work/configure.log" 2>&1 || { cat "$work/configure.log"; fail "configuring examples/library failed"; }
found=$(sed -n 's/^sidc_DIR:PATH=//p' "$work/build/CMakeCache.txt")
[[ $found == "$package" ]] || fail "find_package(sidc) found $found, not the package just installed in $package"

step "building examples/library"
"$cmake" --build "$work/build" > "$work/example-build.log" 2>&1 || { cat "$work/example-build.log"; fail "building examples/library failed"; }

step "sidc_library_example quasi_linear.sid appendix_a.csv"
thesis=$source/examples/thesis-4-1
output=$("$work/build/sidc_library_example" "$thesis/quasi_linear.sid" "$thesis/appendix_a.csv") \
  || { echo "$output"; fail "sidc_library_example failed"; }
echo "$output"
# The estimates `sidc fit examples/thesis-4-1/quasi_linear.sid` prints (thesis section 4-1).
grep -Eq '^m +=  *0\.0514791 ' <<< "$output" || fail "the output does not hold m = 0.0514791"
grep -Fq 'G(a) = 0.00858495 ' <<< "$output" || fail "the output does not hold G(a) = 0.00858495"
echo "PASS: installed, found by find_package(sidc), built, and printed the section 4-1 estimates"
