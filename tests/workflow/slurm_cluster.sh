# A one-node Slurm cluster on this machine for tests (sourced by tests/workflow/slurm.sh).
#
#   source slurm_cluster.sh
#   cluster_start DIR     # configures and starts munged, MariaDB, slurmdbd, slurmctld, slurmd
#   ...                   # sbatch, srun, sacct, sacctmgr, scontrol reach it (SLURM_CONF is set)
#   cluster_stop          # cancels what is left and stops every daemon it started, by pid
#
# Everything lives under DIR: the configuration (SLURM_CONF points the daemons and the clients at
# it; nothing is read from or written to /etc/slurm), a private munge key and socket, the
# accounting database, state, spool, logs and pid files. The daemons run in the foreground as
# children of this shell (munged -F, mariadbd, slurmdbd -D, slurmctld -D, slurmd -D), so their
# pids are known without reading pid files; their ports are private (CLUSTER_PORT_BASE, default
# 16817: slurmctld +0, slurmd +1, slurmdbd +2), so a cluster already on the machine is left alone.
# The node has the machine's CPUs and memory (slurmd -C); processes are tracked without cgroups
# (proctrack/linuxproc, task/none), so it runs in containers and VMs without systemd.
# Accounting is the real thing: slurmdbd over a MariaDB server on a private socket with its
# data under DIR, so sacct answers and unknown accounts are refused (AccountingStorageEnforce).
# Root only (SlurmUser=root).
#
# After cluster_start: CLUSTER_NAME, CLUSTER_ACCOUNT (an account the current user may charge),
# CLUSTER_PARTITION (a partition other than the default one), CLUSTER_CPUS, CLUSTER_MEM_MB.

CLUSTER_NAME=vpmtest
CLUSTER_ACCOUNT=vpmlab
CLUSTER_PARTITION=batch   # not the default partition (debug), so a job there was sent there
_cluster_pids=()    # started daemons, in start order
_cluster_names=()
_cluster_dir=

_cluster_log() { echo "slurm_cluster: $*" >&2; }

# _cluster_bg NAME CMD...: start a daemon in the foreground, in the background; records its pid
_cluster_bg() {
  local name=$1; shift
  "$@" > "$_cluster_dir/log/$name.out" 2>&1 &
  _cluster_pids+=($!)
  _cluster_names+=("$name")
  echo $! > "$_cluster_dir/run/$name.pid"
}

# _cluster_wait SECONDS WHAT CMD...: poll CMD until it succeeds; fail naming WHAT (and its log)
_cluster_wait() {
  local secs=$1 what=$2 i; shift 2
  for ((i = 0; i < secs * 5; i++)); do
    "$@" > /dev/null 2>&1 && return 0
    local j
    for j in "${!_cluster_pids[@]}"; do
      kill -0 "${_cluster_pids[j]}" 2>/dev/null ||
        { _cluster_log "${_cluster_names[j]} exited while waiting for $what:"; tail -20 "$_cluster_dir/log/${_cluster_names[j]}"* >&2; return 1; }
    done
    sleep 0.2
  done
  _cluster_log "no $what after $secs s"
  return 1
}

# stops what a cluster in DIR left running when its shell was killed outright (SIGKILL leaves no
# trap to run): the daemons whose pid files are there and whose environment names its SLURM_CONF
cluster_stop_stale() {
  local d f pid
  d=$(realpath -m "$1")
  for f in "$d"/run/{slurmd,slurmctld,slurmdbd,mariadbd,munged}.pid; do
    [[ -f $f ]] || continue
    pid=$(cat "$f")
    if tr '\0' '\n' 2>/dev/null < "/proc/$pid/environ" | grep -q -x -F "SLURM_CONF=$d/etc/slurm.conf"; then
      _cluster_log "stopping $(basename "$f" .pid) (pid $pid) left by an earlier run"
      kill -KILL "$pid" 2>/dev/null || true
    fi
  done
}

cluster_start() {
  _cluster_dir=$(realpath -m "$1")
  local d=$_cluster_dir base=${CLUSTER_PORT_BASE:-16817}
  cluster_stop_stale "$d"
  rm -rf "$d"
  export SLURM_CONF=$d/etc/slurm.conf   # the daemons (which carry it in their environment) and the clients
  mkdir -p "$d"/{etc,munge,db,state,log,run}
  chmod 700 "$d/munge" "$d/etc"
  local host node cpus mem
  host=$(hostname -s)
  node=$(slurmd -C | head -1)                 # NodeName=HOST CPUs=... RealMemory=...
  cpus=$(sed -n 's/.* CPUs=\([0-9]*\).*/\1/p' <<< "$node")
  mem=$(sed -n 's/.* RealMemory=\([0-9]*\).*/\1/p' <<< "$node")
  CLUSTER_CPUS=$cpus
  CLUSTER_MEM_MB=$mem

  # munge: a key of this cluster's own, its own socket
  dd if=/dev/urandom of="$d/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$d/munge/munge.key"
  # sockets (munged's, MariaDB's, slurmd's job steps' in its spool): under DIR, or in a folder of
  # their own under /tmp when DIR is too deep for a socket path's 107 characters
  local run=$d/run
  ((${#run} <= 60)) || { run=$(mktemp -d /tmp/vpm-slurm.XXXXXX); ln -s "$run" "$d/sockets"; }
  mkdir -p "$run/spool/$host"
  local sock=$run/munge.socket
  _cluster_bg munged munged -F --force --key-file="$d/munge/munge.key" --socket="$sock" \
    --pid-file="$d/run/munged.own.pid" --log-file="$d/log/munged.log" --seed-file="$d/munge/seed"
  _cluster_wait 20 "munge socket" munge -S "$sock" -n || return 1

  # the accounting database: MariaDB on a private socket, no network, root by socket auth
  mariadb-install-db --no-defaults --datadir="$d/db" --user="$(id -un)" --auth-root-authentication-method=socket \
    --skip-test-db > "$d/log/mariadb-install-db.log" 2>&1 ||
    { _cluster_log "mariadb-install-db failed:"; tail -20 "$d/log/mariadb-install-db.log" >&2; return 1; }
  export MYSQL_UNIX_PORT=$run/mysqld.sock   # where slurmdbd's MariaDB client library connects
  _cluster_bg mariadbd mariadbd --no-defaults --datadir="$d/db" --socket="$MYSQL_UNIX_PORT" --skip-networking \
    --user="$(id -un)" --pid-file="$d/run/mariadbd.own.pid" --log-error="$d/log/mariadbd.log" \
    --innodb-buffer-pool-size=32M --innodb-log-file-size=16M
  _cluster_wait 60 "MariaDB socket" test -S "$MYSQL_UNIX_PORT" || return 1

  cat > "$d/etc/slurmdbd.conf" <<EOF
AuthType=auth/munge
AuthInfo=socket=$sock
DbdHost=localhost
DbdPort=$((base + 2))
SlurmUser=$(id -un)
StorageType=accounting_storage/mysql
StorageHost=localhost
StorageUser=$(id -un)
StorageLoc=slurm_acct_db_$CLUSTER_NAME
PidFile=$d/run/slurmdbd.own.pid
LogFile=$d/log/slurmdbd.log
DebugLevel=info
EOF
  chmod 600 "$d/etc/slurmdbd.conf"
  cat > "$d/etc/slurm.conf" <<EOF
ClusterName=$CLUSTER_NAME
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$((base + 1))
SlurmUser=$(id -un)
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$d/state
SlurmdSpoolDir=$run/spool/%n
SlurmctldPidFile=$d/run/slurmctld.own.pid
SlurmdPidFile=$d/run/slurmd.own.pid
SlurmctldLogFile=$d/log/slurmctld.log
SlurmdLogFile=$d/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# no cgroups: processes tracked through /proc, tasks bound to their CPUs by sched_setaffinity,
# a job step that outgrows its memory killed from the 1 s samples of /proc (OverMemoryKill)
ProctrackType=proctrack/linuxproc
TaskPlugin=task/affinity
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=1
JobAcctGatherParams=OverMemoryKill
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
# CPUs and memory are what jobs are given, and what they may ask for
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
AccountingStoragePort=$((base + 2))
AccountingStoragePass=$sock
AccountingStorageEnforce=associations
JobCompType=jobcomp/none
MinJobAge=300
MailProg=/bin/true
InactiveLimit=0
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 ${node#NodeName=$host }
PartitionName=debug Nodes=$host Default=YES State=UP
PartitionName=$CLUSTER_PARTITION Nodes=$host State=UP
EOF
  _cluster_bg slurmdbd slurmdbd -D
  _cluster_wait 60 "slurmdbd" sacctmgr -n list cluster || return 1
  sacctmgr -i add cluster "$CLUSTER_NAME" > "$d/log/sacctmgr.log" 2>&1 &&
    sacctmgr -i add account "$CLUSTER_ACCOUNT" cluster="$CLUSTER_NAME" >> "$d/log/sacctmgr.log" 2>&1 &&
    sacctmgr -i add user "$(id -un)" account="$CLUSTER_ACCOUNT" cluster="$CLUSTER_NAME" >> "$d/log/sacctmgr.log" 2>&1 ||
    { _cluster_log "sacctmgr failed:"; cat "$d/log/sacctmgr.log" >&2; return 1; }
  _cluster_bg slurmctld slurmctld -D
  _cluster_bg slurmd slurmd -D
  _cluster_wait 60 "idle node" bash -c '[[ $(sinfo -h -n "$1" -o %t | sort -u) == idle ]]' _ "$host" || {
    sinfo >&2; tail -20 "$d/log/slurmctld.log" "$d/log/slurmd.log" >&2; return 1; }
}

# cancels every job, waits for them to leave, then stops the daemons (last started first) by
# pid: SIGTERM, and SIGKILL after 20 s; job step daemons still there (scontrol listpids) go too
cluster_stop() {
  [[ -n $_cluster_dir ]] || return 0
  local i pid j
  if ((${#_cluster_pids[@]})) && kill -0 "${_cluster_pids[-1]}" 2>/dev/null; then
    scancel --full -u "$(id -un)" 2>/dev/null || true
    for ((j = 0; j < 150; j++)); do
      [[ -z $(squeue -h -o %i 2>/dev/null) ]] && break
      sleep 0.2
    done
    local steps
    steps=$(scontrol listpids 2>/dev/null | awk 'NR > 1 { print $1 }' || true)
    for pid in $steps; do kill -KILL "$pid" 2>/dev/null || true; done
  fi
  for ((i = ${#_cluster_pids[@]} - 1; i >= 0; i--)); do
    pid=${_cluster_pids[i]}
    kill -TERM "$pid" 2>/dev/null || continue
    for ((j = 0; j < 100; j++)); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -KILL "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  [[ -L $_cluster_dir/sockets ]] && rm -rf "$(readlink "$_cluster_dir/sockets")" "$_cluster_dir/sockets"
  _cluster_pids=()
  _cluster_names=()
  _cluster_dir=
}
