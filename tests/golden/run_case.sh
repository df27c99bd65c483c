#!/usr/bin/env bash
# Runs one golden case: the sidc binary on one model file, its transcript compared byte for byte
# with the checked-in <name>.expected beside the model file (format: tests/golden/README.md).
#
# Usage: run_case.sh [--update] SIDC_BINARY CASE.sid
#   --update writes the transcript to <name>.expected instead of comparing (scripts/update-golden.sh).
# Relies on: bash, mktemp, diff. The arguments come from the first `# sidc-args:` line of the model
# file (split on white space, no quoting; default `compile`), with the model file name appended.
# Guarantees: sidc runs in a fresh temporary directory holding only a copy of the model file (and
# the contents of <name>.files/ if that folder exists), with standard input from /dev/null and the
# C locale, so the transcript does not depend on where the repository is or who runs it. Exit 0
# when the transcript matches (or was written), 1 with a unified diff when it does not.
set -euo pipefail

update=false
if [[ "${1:-}" == --update ]]; then update=true; shift; fi
if (($# != 2)); then
  echo "usage: run_case.sh [--update] SIDC_BINARY CASE.sid" >&2
  exit 2
fi
sidc=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")  # absolute: sidc runs elsewhere
case_file=$2
case_dir=$(cd "$(dirname "$case_file")" && pwd)
model=$(basename "$case_file")
stem=${model%.sid}
expected="$case_dir/$stem.expected"

[[ -x "$sidc" ]] || { echo "run_case.sh: sidc binary not found or not executable: $1" >&2; exit 1; }

args_line=$(grep -m1 -E '^[[:space:]]*#[[:space:]]*sidc-args:' "$case_dir/$model" || true)
if [[ -n "$args_line" ]]; then
  read -r -a args <<<"${args_line#*sidc-args:}"
else
  args=(compile)
fi
args+=("$model")

# The captured streams live beside the working directory, not in it, so sidc never sees them.
scratch=$(mktemp -d "${TMPDIR:-/tmp}/sidc-golden.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
work="$scratch/work"
mkdir "$work"
cp "$case_dir/$model" "$work/"
if [[ -d "$case_dir/$stem.files" ]]; then cp -R "$case_dir/$stem.files/." "$work/"; fi

# The harness's own time limit sits below CTest's TIMEOUT (20 s, CMakeLists.txt), so that a hang
# is reported as one and the scratch folder is still removed.
time_limit=15
status=0
(cd "$work" && LC_ALL=C exec timeout --kill-after=2 "$time_limit" "$sidc" "${args[@]}" \
   </dev/null >"$scratch/stdout" 2>"$scratch/stderr") || status=$?
if ((status == 124 || status == 137)); then
  echo "golden: sidc did not finish within $time_limit s: sidc ${args[*]}" >&2
  exit 1
fi

# One section per stream. A stream that does not end in a newline gets one, followed by a marker
# line, so that "no final newline" is visible in the file and in a diff.
print_stream() {
  cat "$1"
  if [[ -n $(tail -c1 "$1") ]]; then  # $(...) drops a final newline, so non-empty means none
    printf '\n\\ No newline at end of %s\n' "$2"
  fi
}
{
  printf '$ sidc %s\n' "${args[*]}"
  echo '--- stdout'
  print_stream "$scratch/stdout" stdout
  echo '--- stderr'
  print_stream "$scratch/stderr" stderr
  echo "--- exit code: $status"
} >"$scratch/transcript"

pattern="$(basename "$case_dir")/$stem"
if $update; then
  cp "$scratch/transcript" "$expected"
  echo "updated ${expected#"$PWD/"}"
  exit 0
fi

if [[ ! -f "$expected" ]]; then
  echo "golden: $expected is missing; create it with scripts/update-golden.sh '$pattern' and review it." >&2
  echo "The transcript it would hold:" >&2
  cat "$scratch/transcript" >&2
  exit 1
fi

if ! diff -u --label "$stem.expected" --label "$stem (actual)" "$expected" "$scratch/transcript"; then
  echo "golden: transcript differs from $expected; if the change is intended, run" \
       "scripts/update-golden.sh '$pattern' and review git diff." >&2
  exit 1
fi
