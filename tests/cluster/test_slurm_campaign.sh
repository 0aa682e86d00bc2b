#!/bin/bash
# CTest test cluster.slurm_campaign: a `crux diff` campaign through a real, single-node Slurm
# (tests/cluster/slurm_cluster.sh: munged, slurmctld and slurmd on 127.0.0.1, started here as
# root and stopped by pid, whatever happens). Checks that
#  1. an 8-shard campaign run by cluster/slurm/campaign.sh (sbatch --array, then a dependent
#     merge job) merges to the summary of the serial run of the same seed and case count, except
#     the times;
#  2. a shard cancelled with scancel is named by the merge job, which exits 3, and rerunning that
#     shard alone (campaign.sh --rerun) completes a summary equal to the serial one.
# Skips (exit 77) only when Slurm or munge is not installed (scripts/setup installs them).
# Usage: test_slurm_campaign.sh CRUX SOURCE_DIR
set -euo pipefail
crux=$1
src=$2
for tool in munged slurmctld slurmd sbatch scancel squeue sinfo scontrol; do
  if ! command -v "$tool" > /dev/null; then
    echo "SKIP: $tool is not installed (scripts/setup installs slurm-wlm and munge)"
    exit 77
  fi
done
if [[ $(id -u) -ne 0 ]]; then
  echo "FAIL: the test starts slurmd, which must run as root" >&2
  exit 1
fi
work=$(mktemp -d /tmp/crux-slurm-test-XXXXXX)
# shellcheck source=slurm_cluster.sh
source "$src/tests/cluster/slurm_cluster.sh"
finish() {
  local status=$?
  slurm_cluster_stop
  if ((status != 0)); then
    echo "--- logs (test failed with status $status) ---" >&2
    tail -n 15 "$work"/cluster/*.log "$work"/*/slurm-*.out "$work"/*/merged.txt 2>/dev/null >&2 || true
  fi
  rm -rf "$work"
}
trap finish EXIT

slurm_cluster_start "$work/cluster"

seed=2718 shards=8 per=5
export CRUX_DIFF_ARGS="--peer-timeout 10"
# the serial run the campaign must equal
"$crux" diff --seed "$seed" --cases $((shards * per)) --shard-dir "$work/serial" --quiet $CRUX_DIFF_ARGS || [[ $? -eq 1 ]]

# waits for job $1 to leave the queue (at most 300 s)
wait_job() {
  for _ in $(seq 1500); do
    [[ -z $(squeue -h -j "$1" 2> /dev/null) ]] && return 0
    sleep 0.2
  done
  echo "FAIL: job $1 still queued after 300 s: $(squeue -j "$1")" >&2
  return 1
}
# the job id printed by campaign.sh for "$2" (shards or merge) in output $1
job_of() { awk -v what="$2" '$1 == what { print $2 }' <<< "$1"; }

# prints nothing when the summaries $1 and $2 are equal except for times and the shard list
compare() {
  /usr/bin/python3 - "$1" "$2" << 'PY'
import json, sys
def comparable(path):
    s = json.load(open(path))
    for key in ("seconds", "shards", "missing_cases"):
        s.pop(key, None)
    return s
a, b = comparable(sys.argv[1]), comparable(sys.argv[2])
if a != b:
    for key in sorted(set(a) | set(b)):
        if a.get(key) != b.get(key):
            print(f"{key}: {json.dumps(a.get(key))[:300]} != {json.dumps(b.get(key))[:300]}")
PY
}

# 1. the whole campaign
out=$("$src/cluster/slurm/campaign.sh" --seed "$seed" --shards "$shards" --cases-per-shard "$per" \
  --out "$work/campaign" --crux "$crux")
wait_job "$(job_of "$out" merge)"
[[ -f $work/campaign/merged.json ]] || { echo "FAIL: the merge job wrote no merged.json" >&2; exit 1; }
diffs=$(compare "$work/campaign/merged.json" "$work/serial/summary.json")
[[ -z $diffs ]] || { echo "FAIL: merged campaign != serial run:" >&2; echo "$diffs" >&2; exit 1; }
ran=$(/usr/bin/python3 -c 'import json,sys; print(sum(s["status"] == "merged" for s in json.load(open(sys.argv[1]))["shards"]))' \
  "$work/campaign/merged.json")
[[ $ran == "$shards" ]] || { echo "FAIL: $ran of $shards shards merged" >&2; exit 1; }
echo "campaign: $shards shards through sbatch --array merged equal to the serial run"
/usr/bin/python3 - "$work/campaign/merged.json" << 'PY'
import json, sys
for s in json.load(open(sys.argv[1]))["shards"]:
    name = s["dir"].rsplit("/", 1)[1]
    print(f"  {name}: {s['cases']} cases, {s['cases_per_second']:.1f} cases/s")
PY

# 2. a shard cancelled with scancel, then rerun alone
out=$("$src/cluster/slurm/campaign.sh" --seed "$seed" --shards "$shards" --cases-per-shard "$per" \
  --out "$work/cancel" --crux "$crux" --hold)
array=$(job_of "$out" shards)
scancel "${array}_3"
scontrol release "$array"
wait_job "$(job_of "$out" merge)"
grep -q "shard missing: $work/cancel/shard-3 " "$work/cancel/merged.txt" \
  || { echo "FAIL: the merge did not name the cancelled shard 3:" >&2; cat "$work/cancel/merged.txt" >&2; exit 1; }
state=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["shards"][3]["status"])' "$work/cancel/merged.json")
[[ $state == missing ]] || { echo "FAIL: shard 3 is $state in merged.json" >&2; exit 1; }
[[ -n $(compare "$work/cancel/merged.json" "$work/serial/summary.json") ]] \
  || { echo "FAIL: a campaign without shard 3 equals the serial run" >&2; exit 1; }
echo "cancelled shard 3 named by merge"
out=$("$src/cluster/slurm/campaign.sh" --seed "$seed" --shards "$shards" --cases-per-shard "$per" \
  --out "$work/cancel" --crux "$crux" --rerun 3)
wait_job "$(job_of "$out" merge)"
diffs=$(compare "$work/cancel/merged.json" "$work/serial/summary.json")
[[ -z $diffs ]] || { echo "FAIL: campaign with shard 3 rerun != serial run:" >&2; echo "$diffs" >&2; exit 1; }
grep -q "shards merged: $shards of $shards" "$work/cancel/merged.txt" \
  || { echo "FAIL: not every shard merged after the rerun:" >&2; cat "$work/cancel/merged.txt" >&2; exit 1; }
echo "rerun of shard 3 completed the campaign equal to the serial run"
