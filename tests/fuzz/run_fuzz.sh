#!/usr/bin/env bash
# Runs one libFuzzer target of this folder for a bounded time on a seed corpus taken from the
# repository: the examples and the bad-input catalogue. Used by CTest (tests/fuzz/CMakeLists.txt,
# about 30 s each) and by scripts/fuzz.sh (an hour each).
#
# Usage: run_fuzz.sh FUZZER KIND SECONDS WORK_DIR [SIDC_BINARY]
#   KIND: model (model files), compiled (compiled models: the seed models compiled by SIDC_BINARY)
#   or csv (records). WORK_DIR keeps the corpus the fuzzer grows (WORK_DIR/corpus, kept between
#   runs) and what it finds (WORK_DIR/findings/crash-*, timeout-*, oom-*).
# Relies on: bash, a fuzzer built with -fsanitize=fuzzer (SIDC_FUZZ=ON). Guarantees: exits 0 only
# when the fuzzer ran for SECONDS and found nothing; on a finding, prints the input's path, the
# command that reproduces it, and exits non-zero.
set -euo pipefail

if (($# < 4)); then
  echo "run_fuzz.sh: usage: run_fuzz.sh FUZZER KIND SECONDS WORK_DIR [SIDC_BINARY]" >&2
  exit 2
fi
fuzzer=$1 kind=$2 seconds=$3 work_dir=$4 sidc=${5:-}
repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

seeds=$work_dir/seeds
# Compiled seeds cost a compile each: made once per build tree (the stamp), the others every run.
[[ $kind == compiled && -e $seeds/.complete ]] || rm -rf "$seeds"
mkdir -p "$seeds" "$work_dir/corpus" "$work_dir/findings"

# One seed per file, named after its path so that collisions cannot hide one.
add_seed() { cp "$1" "$seeds/$(echo "${1#"$repo_root"/}" | tr '/' '_')"; }

case "$kind" in
  model|compiled)
    mapfile -t models < <(find "$repo_root/examples" "$repo_root/tests/golden" "$repo_root/tests/fidelity" \
                            -name '*.sid' -size -64k | sort)
    if [[ $kind == model ]]; then
      for m in "${models[@]}"; do add_seed "$m"; done
      max_len=8192
    elif [[ ! -e $seeds/.complete ]]; then
      [[ -x $sidc ]] || { echo "run_fuzz.sh: compiled seeds need the sidc binary as 5th argument" >&2; exit 2; }
      for m in "${models[@]}"; do  # the models that compile: the bad-input catalogue does not
        [[ $m == */bad*/* ]] && continue
        out=$seeds/$(echo "${m#"$repo_root"/}" | tr '/' '_').sidc.json
        "$sidc" compile "$m" -o "$out" >/dev/null 2>&1 || rm -f "$out"
      done
      # Damaged compiled models of the catalogue, the fuzzers' findings among them, replay each run.
      for f in "$repo_root"/tests/golden/*/*.files/*.sidc.json; do [[ -e $f ]] && add_seed "$f"; done
      touch "$seeds/.complete"
    fi
    if [[ $kind == compiled ]]; then max_len=65536; fi ;;
  csv)
    mapfile -t records < <(find "$repo_root/examples" "$repo_root/tests" \( -name '*.csv' -o -name '*.tsv' \) \
                             -size -16k | sort)
    # The target's first byte chooses the options: 0x00 = detect everything, one thread.
    for r in "${records[@]}"; do
      name=$(echo "${r#"$repo_root"/}" | tr '/' '_')
      { printf '\x00'; cat "$r"; } > "$seeds/$name"
      { printf '\x80'; cat "$r"; } > "$seeds/threads_$name"
    done
    max_len=16384 ;;
  *) echo "run_fuzz.sh: unknown kind '$kind' (model, compiled or csv)" >&2; exit 2 ;;
esac
echo "run_fuzz.sh: $(basename "$fuzzer"): $(find "$seeds" -type f -not -name .complete | wc -l) seeds, $seconds s"

# -timeout: one input taking 25 s is a hang (SIDC_FUZZ_TIMEOUT on a machine busy with other work,
# where a slow unit under ASan is not a hang); -rss_limit_mb: more than 2 GB is a finding too.
status=0
"$fuzzer" -max_total_time="$seconds" -timeout="${SIDC_FUZZ_TIMEOUT:-25}" -rss_limit_mb=2048 -max_len="$max_len" \
  -print_final_stats=1 -artifact_prefix="$work_dir/findings/" "$work_dir/corpus" "$seeds" || status=$?
if ((status != 0)); then
  echo "run_fuzz.sh: $(basename "$fuzzer") found a problem (exit $status); the input is in $work_dir/findings/" >&2
  ls -l "$work_dir/findings/" >&2
  echo "run_fuzz.sh: reproduce with: $fuzzer $work_dir/findings/<file>" >&2
  exit 1
fi
