#!/usr/bin/env bash
# Rewrites the expected transcripts of the golden cases from the current sidc binary.
#
# Usage: bash scripts/update-golden.sh [PATTERN]
#   PATTERN is an extended regular expression matched against the test name
#   golden/<topic>/<name>, as `ctest -R` would; without it every case is rewritten.
# Relies on: scripts/setup.sh (builds build/cli/sidc first, so "current" means the working tree)
# and tests/golden/run_case.sh (the same runner the tests use, in --update mode).
# Guarantees: touches only <name>.expected files; ends with `git diff --stat tests/golden` and
# the list of new, untracked expected files, for review before committing.
set -euo pipefail

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
pattern=${1:-}

bash "$repo_root/scripts/setup.sh"
cd "$repo_root"
sidc=build/cli/sidc
[[ -x "$sidc" ]] || { echo "update-golden.sh: error: $sidc was not built" >&2; exit 1; }

updated=0
while IFS= read -r -d '' case_file; do
  case_id=${case_file#tests/golden/}
  case_id=${case_id%.sid}
  [[ "$case_id" == *.files/* ]] && continue   # inputs of another case, not a case
  if [[ -n "$pattern" ]] && ! grep -qE -- "$pattern" <<<"golden/$case_id"; then continue; fi
  bash tests/golden/run_case.sh --update "$sidc" "$case_file"
  updated=$((updated + 1))
done < <(find tests/golden -name '*.sid' -type f -print0 | sort -z)

if ((updated == 0)); then
  echo "update-golden.sh: no golden case matches '${pattern}'" >&2
  exit 1
fi
echo "update-golden.sh: rewrote $updated expected file(s)."
git diff --stat -- tests/golden
new_files=$(git ls-files --others --exclude-standard -- 'tests/golden/*.expected')
if [[ -n "$new_files" ]]; then
  echo "New (untracked) expected files:"
  echo "$new_files"
fi
echo "Review the changes (git diff tests/golden) before committing: every changed line is a change users see."
