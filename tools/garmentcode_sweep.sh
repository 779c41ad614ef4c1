#!/bin/bash
# Drapes every GarmentCode specification in a folder on the body it was made for, one line of
# result per pattern (tools/garmentcode_sample.py names each file after its body: _ma_ mean_all,
# _mf_ mean_female, _mm_ mean_male).
#   tools/garmentcode_sweep.sh PATTERNS_DIR RESULTS_DIR [drapekit garment flags...]
# e.g. --sew-max 0.001 --settle-max 0.001 checks assembly and placement only (a second each);
# --spacing 0.02 a whole run at 2 cm. Needs ../shared/realdata/bodies and a release build.
set -u
in=$1; out=$2; shift 2
here=$(cd "$(dirname "$0")/.." && pwd)
bodies=$here/../shared/realdata/bodies
bin=$here/target/release/drapekit
mkdir -p "$out"
: > "$out/summary.txt"
for f in "$in"/*_specification.json; do
  n=$(basename "$f" _specification.json)
  body=mean_all
  case $n in *_mf_*) body=mean_female;; *_mm_*) body=mean_male;; esac
  start=$(date +%s.%N)
  "$bin" garment "$f" --body "$bodies/$body.obj" -o "$out/$n" --report "$out/$n.json" "$@" \
    > "$out/$n.log" 2>&1
  rc=$?
  verdict=$(grep -m1 "verdict:" "$out/$n.log" | sed 's/^ *//')
  error=$(grep -m1 "^error\|panicked" "$out/$n.log")
  printf "%s %s exit %s %.1f s %s%s\n" "$n" "$body" "$rc" \
    "$(echo "$(date +%s.%N) - $start" | bc)" "$verdict" "$error" >> "$out/summary.txt"
done
cat "$out/summary.txt"
