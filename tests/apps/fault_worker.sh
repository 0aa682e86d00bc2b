#!/bin/bash
# A worker for PeerWorker's tests (tests/apps/test_peer_worker.cpp): it speaks the worker
# protocol of apps/cli/peer_worker.hpp ("ready" first) and fails on demand, so that every failure kind is
# exercised without depending on a peer library's defects. Called as
#   fault_worker.sh batch --backend B --worker
# For each "q" line it answers {"op":"echo","n":N}, N counting the q lines this process has
# read (so a test sees whether state lines were replayed into a new worker), tagged "+" when the
# line contains STATE (a state change to replay) and "=" otherwise. A q line containing
#   ABORT  prints an assertion message on stderr and kills this process with SIGABRT;
#   SEGV   kills it with SIGSEGV;
#   HANG   never answers (the process becomes `sleep`, so killing its pid ends it);
#   EXIT   exits with status 3.
# Every q line is appended to $FAULT_WORKER_LOG when that is set.
echo ready
n=0
while IFS= read -r line; do
  case "$line" in
    r*|s*) echo ok; continue ;;
  esac
  n=$((n + 1))
  [[ -n ${FAULT_WORKER_LOG:-} ]] && printf '%s\n' "$line" >> "$FAULT_WORKER_LOG"
  case "$line" in
    *ABORT*) echo "fault_worker: peer.cpp:42: check: Assertion \`isOutsidePolytopeFace' failed." >&2; kill -s ABRT $$ ;;
    *SEGV*) kill -s SEGV $$ ;;
    *HANG*) exec sleep 600 ;;
    *EXIT*) exit 3 ;;
    *STATE*) echo "+{\"op\":\"echo\",\"n\":$n}" ;;
    *) echo "={\"op\":\"echo\",\"n\":$n}" ;;
  esac
done
