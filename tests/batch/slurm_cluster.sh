#!/bin/bash
# A Slurm cluster in a folder, for the batch tests: munged, slurmctld and one slurmd per node of
# Debian's munge and slurm-wlm (tools/debian-packages.txt), on their own socket, ports and state,
# cgroups off (process tracking by /proc). The daemons run as the calling user (root in CI).
# Each node is a slurmd of its own (`slurmd -N`, its own port, spool, pid and log files) in a UTS
# namespace of its own (`unshare --uts`), so the tasks on node nfnodeK see the host name nfnodeK,
# as on separate machines; they share this host's kernel, loopback and file systems (the shared
# file system a cluster's WORK folders live on). The host's cores and memory are split between them.
# Each node also has one GPU for Slurm to hand out (GRES `gpu`), a stand-in: a character device
# with /dev/null's numbers, which nothing opens (nf_gpu finds its devices through Vulkan).
#   slurm_cluster.sh start DIR [NODES]   prints the SLURM_CONF to export; waits until every node is
#                                        idle (NODES: 1 by default)
#   slurm_cluster.sh crash DIR NODE      kills every process of that node at once (SIGKILL: its
#                                        slurmd, job steps and tasks), as when a machine dies
#   slurm_cluster.sh stop DIR            stops the daemons and their jobs
set -euo pipefail
cmd=${1:?start|crash|stop}
dir=$(realpath -m "${2:?DIR}")
conf=$dir/slurm.conf

# The UTS namespace of the node whose slurmd wrote this pid file ("" when it is gone).
node_namespace() {
  local pid ns
  pid=$(cat "$1" 2>/dev/null) || return 0
  ns=$(readlink "/proc/$pid/ns/uts" 2>/dev/null) || return 0
  [ "$ns" != "$(readlink /proc/$$/ns/uts)" ] && echo "$ns"  # never this host's own processes
  return 0
}

# Kills every live process in that namespace with SIGKILL, again until none is left: a job step
# may start a process while the others are being killed. Zombies are dead already.
kill_namespace() {
  local ns=$1 p pids
  [ -n "$ns" ] || return 0
  for _ in $(seq 50); do
    pids=()
    for p in /proc/[0-9]*; do
      [ "$(readlink "$p/ns/uts" 2>/dev/null)" = "$ns" ] || continue
      [ "$(awk '{print $3}' "$p/stat" 2>/dev/null)" = Z ] && continue
      pids+=("${p#/proc/}")
    done
    [ ${#pids[@]} -gt 0 ] || return 0
    kill -9 "${pids[@]}" 2>/dev/null || true  # some may have ended since they were listed
    sleep 0.1
  done
  echo "processes of namespace $ns survived SIGKILL" >&2
  return 1
}

stop() {
  # A node's job steps and tasks first: they outlive their slurmd otherwise.
  for f in "$dir"/slurmd-*.pid; do
    [ -f "$f" ] && { kill_namespace "$(node_namespace "$f")" || true; }
  done
  for f in "$dir"/slurmd-*.pid "$dir/slurmctld.pid" "$dir/munged.pid"; do
    if [ -f "$f" ]; then kill "$(cat "$f")" 2>/dev/null || true; fi
  done
  for f in "$dir"/slurmd-*.pid "$dir/slurmctld.pid" "$dir/munged.pid"; do
    for _ in $(seq 50); do
      [ -f "$f" ] && kill -0 "$(cat "$f")" 2>/dev/null || break
      sleep 0.1
    done
    [ -f "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null || true
    rm -f "$f"
  done
  # Daemons of this folder whose pid file was stale or gone: found by the paths on their command
  # line (slurm.conf, slurmd-K.conf). A survivor would write into the next cluster made here (its
  # state, its node names) and revoke that cluster's job credentials.
  for pattern in "$dir/slurm" "$dir/munge/munge.socket"; do
    pkill -f -- "$pattern" 2>/dev/null || true
    for _ in $(seq 50); do pgrep -f -- "$pattern" >/dev/null || break; sleep 0.1; done
    pkill -9 -f -- "$pattern" 2>/dev/null || true
  done
}

case "$cmd" in
  stop) stop; exit 0 ;;
  crash)
    node=${3:?NODE}
    [ -f "$dir/slurmd-$node.pid" ] || { echo "no node '$node' runs in $dir" >&2; exit 1; }
    kill_namespace "$(node_namespace "$dir/slurmd-$node.pid")"
    rm -f "$dir/slurmd-$node.pid"
    exit 0 ;;
  start) ;;
  *) echo "usage: $0 start DIR [NODES] | crash DIR NODE | stop DIR" >&2; exit 2 ;;
esac
nodes=${3:-1}
[[ "$nodes" =~ ^[1-9][0-9]*$ ]] || { echo "NODES must be a positive whole number, not '$nodes'" >&2; exit 2; }
for tool in munged slurmctld slurmd sinfo unshare; do
  command -v "$tool" >/dev/null || { echo "$tool is missing: install munge and slurm-wlm (tools/nf deps)" >&2; exit 1; }
done
unshare --uts true 2>/dev/null || { echo "unshare --uts failed: the test cluster's nodes need a host name each (root, CAP_SYS_ADMIN)" >&2; exit 1; }

stop
rm -rf "$dir"
mkdir -p "$dir"/{munge,state,log}
: > "$dir/gres.conf"
chmod 700 "$dir/munge"
head -c 1024 /dev/urandom > "$dir/munge/munge.key"
chmod 400 "$dir/munge/munge.key"
munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed"

host=$(hostname -s)
# Free ports (slurmctld's, then one per node), so that a cluster the machine may already run is
# left alone.
read -r ctld_port node_ports <<<"$(python3 -c 'import socket, sys
s=[socket.socket() for _ in range(1 + int(sys.argv[1]))]
[x.bind(("127.0.0.1",0)) for x in s]
print(" ".join(str(x.getsockname()[1]) for x in s))' "$nodes")"
read -r -a ports <<<"$node_ports"
cpus=$(( $(nproc) / nodes )); [ "$cpus" -ge 1 ] || cpus=1
mem=$(( $(awk '/MemTotal/{print $2}' /proc/meminfo) / 1024 / 2 / nodes ))
{
  cat <<CONF
ClusterName=nfbatch
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
StateSaveLocation=$dir/state
SlurmctldPidFile=$dir/slurmctld.pid
SlurmctldLogFile=$dir/log/slurmctld.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=2
ReturnToService=2
# A node silent for 6 s is down and its requeueable jobs go back to the queue (a cluster's
# default is 300 s; the test crashes a node and waits for this).
SlurmdTimeout=6
GresTypes=gpu
MpiDefault=none
KillWait=60
MinJobAge=3600
CONF
  for k in $(seq "$nodes"); do
    echo "NodeName=nfnode$k NodeHostname=nfnode$k NodeAddr=127.0.0.1 Port=${ports[$((k - 1))]} CPUs=$cpus RealMemory=$mem Gres=gpu:1 State=UNKNOWN"
  done
  echo "PartitionName=batch Nodes=ALL Default=YES MaxTime=INFINITE State=UP"
} > "$conf"
export SLURM_CONF=$conf
slurmctld -c -f "$conf"
for k in $(seq "$nodes"); do
  node=nfnode$k
  mkdir -p "$dir/spool-$node" "$dir/dev-$node"
  # Slurm takes the GPU's number from the file's name and wants a device there.
  mknod "$dir/dev-$node/nvidia0" c 1 3
  echo "NodeName=$node Name=gpu File=$dir/dev-$node/nvidia0" >> "$dir/gres.conf"
  # The node's own files; slurmd warns that its configuration's hash differs from slurmctld's.
  { cat "$conf"
    echo "SlurmdSpoolDir=$dir/spool-$node"
    echo "SlurmdPidFile=$dir/slurmd-$node.pid"
    echo "SlurmdLogFile=$dir/log/slurmd-$node.log"; } > "$dir/slurmd-$node.conf"
  unshare --uts sh -c "hostname $node && exec slurmd -f '$dir/slurmd-$node.conf' -N $node"
done
for _ in $(seq 100); do
  if [ "$(sinfo -h -N -t idle -o %N 2>/dev/null | sort -u | wc -l)" -eq "$nodes" ]; then echo "$conf"; exit 0; fi
  sleep 0.2
done
echo "the test cluster did not come up; its logs:" >&2
tail -n 20 "$dir"/log/*.log >&2
stop
exit 1
