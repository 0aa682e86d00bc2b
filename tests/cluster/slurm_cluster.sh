#!/bin/bash
# A single-node Slurm cluster for tests, on 127.0.0.1 only, without systemd: munged (on a private
# socket and key), slurmctld and slurmd, each started by this script as root and stopped by its
# pid. Source it, then:
#   slurm_cluster_start DIR   writes DIR/slurm.conf, starts the three daemons, exports SLURM_CONF
#                             and waits until the node is idle (returns 1 on failure, with logs)
#   slurm_cluster_stop        stops them (SIGTERM, then SIGKILL), by pid; safe to call twice
# Ports are picked free in 20000-59999.

slurm_cluster_pids=()

slurm_free_port() {
  local port
  for _ in $(seq 50); do
    port=$((20000 + RANDOM % 40000))
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then echo "$port"; return 0; fi
  done
  return 1
}

slurm_cluster_stop() {
  local pid
  for pid in "${slurm_cluster_pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${slurm_cluster_pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
  slurm_cluster_pids=()
}

slurm_cluster_start() {
  local dir=$1 ctld_port node_port i
  mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
  chmod 700 "$dir/munge"
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge/munge.key"
  munged --force --socket="$dir/munge/munge.socket" --key-file="$dir/munge/munge.key" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/munged.seed" \
    || { echo "slurm_cluster: munged did not start" >&2; cat "$dir/munge/munged.log" >&2; return 1; }
  for i in $(seq 50); do [[ -s $dir/munge/munged.pid ]] && break; sleep 0.1; done
  slurm_cluster_pids+=("$(cat "$dir/munge/munged.pid")")
  ctld_port=$(slurm_free_port) && node_port=$(slurm_free_port) || return 1
  cat > "$dir/slurm.conf" <<CONF
ClusterName=cruxtest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$node_port
CommunicationParameters=NoInAddrAny,NoCtldInAddrAny
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
MinJobAge=600
NodeName=cruxnode NodeHostname=$(hostname) NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=test Nodes=cruxnode Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONF
  export SLURM_CONF=$dir/slurm.conf
  slurmctld -f "$dir/slurm.conf" -i || { echo "slurm_cluster: slurmctld did not start" >&2; cat "$dir/slurmctld.log" >&2; return 1; }
  for i in $(seq 100); do [[ -s $dir/slurmctld.pid ]] && break; sleep 0.1; done
  slurm_cluster_pids+=("$(cat "$dir/slurmctld.pid")")
  slurmd -f "$dir/slurm.conf" -N cruxnode || { echo "slurm_cluster: slurmd did not start" >&2; cat "$dir/slurmd.log" >&2; return 1; }
  for i in $(seq 100); do [[ -s $dir/slurmd.pid ]] && break; sleep 0.1; done
  slurm_cluster_pids+=("$(cat "$dir/slurmd.pid")")
  for i in $(seq 300); do
    if [[ $(sinfo -h -N -o %t 2>/dev/null) == idle* ]]; then return 0; fi
    sleep 0.1
  done
  echo "slurm_cluster: the node did not become idle; sinfo: $(sinfo -N 2>&1)" >&2
  tail -20 "$dir/slurmctld.log" "$dir/slurmd.log" >&2
  return 1
}
