#!/usr/bin/env bash
# Times fixtures/batch_bench20.toml (20 small jobs) three ways, 3 runs each, and prints medians:
# the local pool (--jobs 2), one after the other (--jobs 1), and the single-node Slurm
# (tools/slurm_local.sh; submit to the array leaving the queue). The per-job overhead of batch
# itself is (wall of --jobs 1 - the sum of the jobs' own command times from their reports) / 20.
# Usage: tools/bench_batch.sh [DRAPEKIT]   (default: target/release/drapekit)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
exe=${1:-$here/target/release/drapekit}
plan=$here/fixtures/batch_bench20.toml
work=$(mktemp -d)
trap 'tools_stop; rm -rf "$work"' EXIT
tools_stop() { [[ -d "$work/slurm" ]] && "$here/tools/slurm_local.sh" stop "$work/slurm" || true; }
now() { date +%s.%N; }
median() { python3 -c 'import sys,statistics; print("%.2f" % statistics.median(float(x) for x in sys.argv[1:]))' "$@"; }
own() { # the sum of the jobs' own command times (their reports), s
    python3 -c 'import json,glob,sys; print(sum(json.load(open(f))["command_seconds"] for f in glob.glob(sys.argv[1]+"/jobs/*/report.json")))' "$1"
}
declare -a pool seq over slurm
for r in 1 2 3; do
    t0=$(now); "$exe" --jobs 2 batch run "$plan" -o "$work/p$r" >/dev/null; t1=$(now)
    pool+=("$(echo "$t1 - $t0" | bc)")
    t0=$(now); "$exe" --jobs 1 batch run "$plan" -o "$work/s$r" >/dev/null; t1=$(now)
    w=$(echo "$t1 - $t0" | bc)
    seq+=("$w")
    over+=("$(echo "($w - $(own "$work/s$r")) / 20 * 1000" | bc -l)")
done
if "$here/tools/slurm_local.sh" start "$work/slurm" 2>/dev/null; then
    export SLURM_CONF=$work/slurm/slurm.conf
    for r in 1 2 3; do
        "$exe" batch slurm "$plan" -o "$work/u$r" >/dev/null
        t0=$(now)
        id=$(sbatch --parsable "$work/u$r/batch.sbatch")
        while [[ -n "$(squeue -h -j "$id")" ]]; do sleep 0.1; done
        t1=$(now)
        slurm+=("$(echo "$t1 - $t0" | bc)")
        "$exe" batch collect "$work/u$r" >/dev/null
        grep -c ',done,' "$work/u$r/results.csv" | grep -qx 20 || { echo "slurm run $r: not all done" >&2; exit 1; }
    done
fi
echo "local pool --jobs 2:      median $(median "${pool[@]}") s  (${pool[*]})"
echo "one after other --jobs 1: median $(median "${seq[@]}") s  (${seq[*]})"
echo "batch overhead per job:   median $(median "${over[@]}") ms"
[[ ${#slurm[@]} -gt 0 ]] && echo "single-node Slurm:        median $(median "${slurm[@]}") s  (${slurm[*]})"
