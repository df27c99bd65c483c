#!/usr/bin/env bash
# `cmake --install` places the Python module where the interpreter finds it: installs this build
# into a temporary prefix, then imports sidc from PREFIX/SIDC_PYTHON_INSTALL_DIR (the folder
# docs/python.md names) with only that on PYTHONPATH, and fits thesis section 4-1 with it.
#   install_test.sh CMAKE BUILD_DIR PYTHON INSTALL_DIR SOURCE_DIR
set -euo pipefail
cmake=$1 build=$2 python=$3 install_dir=$4 source=$5
prefix=$(mktemp -d /tmp/sidc-python-install.XXXXXX)
trap 'rm -rf "$prefix"' EXIT
"$cmake" --install "$build" --prefix "$prefix" >/dev/null
test -f "$prefix/$install_dir/sidc/__init__.py" || { echo "no $prefix/$install_dir/sidc/__init__.py"; exit 1; }
cd "$source/examples/thesis-4-1"
PYTHONPATH="$prefix/$install_dir" PYTHONDONTWRITEBYTECODE=1 "$python" - "$prefix" <<'PY'
import sys
import sidc
assert sidc.__file__.startswith(sys.argv[1]), sidc.__file__
estimates = sidc.compile("quasi_linear.sid").fit(no_validate=True).estimates
assert abs(estimates["m"] - 0.0514790862275414) < 1e-12, estimates["m"]
print("imported", sidc.__file__, "m =", estimates["m"])
PY
