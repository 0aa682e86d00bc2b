#!/bin/bash
# Runs a `crux diff` campaign on Slurm: an array job of SHARDS shards, then a merge job that
# depends on it (docs/fuzzing.md "Campaigns on a cluster").
#
#   cluster/slurm/campaign.sh --seed S --shards N --cases-per-shard K --out DIR [--crux PATH]
#                             [--rerun LIST] [--hold] [-- SBATCH_OPTIONS...]
#
# Shard i answers cases i*K .. (i+1)*K-1 of the sequence seed S defines; the merged summary of all
# N shards equals `crux diff --seed S --cases N*K` run serially (except times). DIR must be on a
# file system every node sees. --rerun LIST (sbatch's array syntax, e.g. 3 or 2,5-6) submits only
# those shards again, and a new merge job. --hold submits the array held (release it with
# `scontrol release JOBID`). CRUX_DIFF_ARGS passes more `crux diff` options to every shard.
# Prints "shards JOBID" and "merge JOBID".
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
seed="" shards="" per="" out="" crux=$(command -v crux || true) rerun="" hold=()
while (($#)); do
  case "$1" in
    --seed) seed=$2; shift 2 ;;
    --shards) shards=$2; shift 2 ;;
    --cases-per-shard) per=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --crux) crux=$2; shift 2 ;;
    --rerun) rerun=$2; shift 2 ;;
    --hold) hold=(--hold); shift ;;
    --) shift; break ;;
    *) echo "campaign.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
if [[ -z $seed || -z $shards || -z $per || -z $out || -z $crux ]]; then
  echo "usage: campaign.sh --seed S --shards N --cases-per-shard K --out DIR [--crux PATH] [--rerun LIST] [--hold]" >&2
  exit 2
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
export CRUX=$crux CRUX_SEED=$seed CRUX_SHARD_CASES=$per CRUX_OUT=$out CRUX_SHARDS=$shards
array=${rerun:-0-$((shards - 1))}
job=$(sbatch --parsable --export=ALL --array="$array" "${hold[@]}" --output="$out/slurm-%A_%a.out" "$@" \
  "$here/shard.sbatch")
job=${job%%;*}
merge=$(sbatch --parsable --export=ALL --dependency="afterany:$job" --output="$out/slurm-merge-%j.out" "$@" \
  "$here/merge.sbatch")
merge=${merge%%;*}
echo "shards $job"
echo "merge $merge"
