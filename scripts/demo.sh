#!/usr/bin/env bash
# The main job on the bundled examples: sets up and builds (scripts/setup.sh), then compiles the
# thesis section 4-1 model and fits it to the thesis Appendix A record (examples/thesis-4-1/),
# then does the same for the section 4-2 process (its input smooth, then held between samples), the
# Silverbox record, a noisy Duffing record, a drifting stiffness fitted locally along its record
# (thesis chapter V) and a pendulum with a parameter inside sin(), each with its pictures.
# Relies on: scripts/setup.sh producing build/cli/sidc. Guarantees: says which step it runs,
# works from any current directory, stops at the first failing step.
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$repo_root/scripts/setup.sh"

sidc="$repo_root/build/cli/sidc"
[[ -x "$sidc" ]] || { echo "demo.sh: error: $sidc was not built" >&2; exit 1; }

# Each example: `sidc compile MODEL && sidc fit MODEL.sidc.json --plots DIR --report DIR/report.html`, pictures
# (SVG and PNG, drawn by gnuplot) into build/pictures/<example>/.
pictures="$repo_root/build/pictures"
run_example() {  # folder, model, step number, [pictures folder: the example's folder by default]
  local folder=$1 model=$2 step=$3 name=${4:-$1}
  local out="$pictures/$name"
  cd "$repo_root/examples/$folder"
  # The compiled model is named: a folder with two examples holds two (plain `sidc fit` refuses).
  local compiled=${model%.sid}.sidc.json
  echo "demo.sh: step $step of 7: sidc compile $model && sidc fit $compiled --plots $out (in examples/$folder)"
  "$sidc" compile "$model"
  rm -rf "$out"
  "$sidc" fit "$compiled" --plots "$out" --report "$out/report.html"
}
run_example thesis-4-1 quasi_linear.sid 1
run_example thesis-4-2 process.sid 2
run_example thesis-4-2 process_held.sid 3 thesis-4-2-held
run_example silverbox derivative_form.sid 4
run_example noisy-duffing duffing.sid 5
run_example time-varying drift.sid 6
run_example pendulum-length pendulum.sid 7
echo "demo.sh: pictures and one-page reports in $pictures/{thesis-4-1,thesis-4-2,thesis-4-2-held,silverbox,noisy-duffing,time-varying,pendulum-length}/"
