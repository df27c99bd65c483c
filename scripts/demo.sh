#!/usr/bin/env bash
# The main job on the bundled example: sets up and builds (scripts/setup.sh), then compiles the
# thesis section 4-1 model and fits it to the thesis Appendix A record (examples/thesis-4-1/).
# Relies on: scripts/setup.sh producing build/cli/sidc. Guarantees: says which step it runs,
# works from any current directory, stops at the first failing step.
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$repo_root/scripts/setup.sh"

sidc="$repo_root/build/cli/sidc"
[[ -x "$sidc" ]] || { echo "demo.sh: error: $sidc was not built" >&2; exit 1; }

cd "$repo_root/examples/thesis-4-1"
echo "demo.sh: step 1 of 2: sidc compile quasi_linear.sid (in examples/thesis-4-1)"
../../build/cli/sidc compile quasi_linear.sid
echo "demo.sh: step 2 of 2: sidc fit (in examples/thesis-4-1)"
../../build/cli/sidc fit
