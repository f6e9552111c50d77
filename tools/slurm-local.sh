#!/usr/bin/env bash
# A one-node SLURM cluster on this machine, with job accounting, for trying the SLURM profile
# (workflow/profiles/slurm) for real: `make cluster-smoke` uses it.
#
#   tools/slurm-local.sh start     install what is missing (apt-get), write the configs, start the daemons
#   tools/slurm-local.sh stop      stop the daemons this script started (by their pid files)
#   tools/slurm-local.sh status    which daemons run, sinfo, and the line to export for the clients
#   tools/slurm-local.sh env       print `export SLURM_CONF=...` (eval "$(tools/slurm-local.sh env)")
#   tools/slurm-local.sh install   only install the packages
#
# Daemons (Debian 12 packages slurm-wlm 22.05, slurmdbd, mariadb-server, munge): munged, mariadbd (the
# accounting database), slurmdbd (accounting: `sacct` answers, which the Snakemake SLURM executor needs to
# see that a job finished), slurmctld and slurmd (one node: all CPUs and memory of this machine, partition
# `debug`, cgroup memory limits so a job over its --mem is killed as OUT_OF_MEMORY like on a real cluster).
# Everything they write (configs, pid files, spool, logs, database) lives in $NATSCENE_SLURM_HOME
# (default /tmp/natscene-slurm), nothing under /etc. Clients (sbatch, squeue, sacct, Snakemake, srun inside
# jobs) find this cluster through the link /run/slurm/conf -> $NATSCENE_SLURM_HOME/etc, made while it runs
# (where SLURM clients look for a configless node's config), or SLURM_CONF=$NATSCENE_SLURM_HOME/etc/slurm.conf.
#
# Needs root (apt-get, daemons). Idempotent: `start` on a running cluster only checks it; `stop` on a
# stopped one does nothing. Ports (change with the variables below if they are taken):
# NATSCENE_SLURM_CTLD_PORT 6817, NATSCENE_SLURM_D_PORT 6818, NATSCENE_SLURM_DBD_PORT 6819,
# NATSCENE_SLURM_DB_PORT 3307 (MariaDB on 127.0.0.1 only).
set -euo pipefail

HOME_DIR=${NATSCENE_SLURM_HOME:-/tmp/natscene-slurm}
CTLD_PORT=${NATSCENE_SLURM_CTLD_PORT:-6817}
D_PORT=${NATSCENE_SLURM_D_PORT:-6818}
DBD_PORT=${NATSCENE_SLURM_DBD_PORT:-6819}
DB_PORT=${NATSCENE_SLURM_DB_PORT:-3307}
CLUSTER=natscene
PARTITION=debug
ACCOUNT=natscene
NODE=$(hostname -s)

ETC=$HOME_DIR/etc
RUN=$HOME_DIR/run
LOG=$HOME_DIR/log
SPOOL=$HOME_DIR/spool
DB=$HOME_DIR/mysql
export SLURM_CONF=$ETC/slurm.conf

say() { echo "slurm-local: $*"; }
die() { echo "slurm-local: error: $*" >&2; exit 1; }

PACKAGES=(munge mariadb-server slurm-wlm slurmdbd)
BINARIES=(munged mariadbd mariadb-install-db slurmdbd slurmctld slurmd sbatch sacct sacctmgr)

install_packages() {
  local missing=()
  for b in "${BINARIES[@]}"; do command -v "$b" >/dev/null 2>&1 || missing+=("$b"); done
  [ ${#missing[@]} -eq 0 ] && return 0
  [ "$(id -u)" = 0 ] || die "missing ${missing[*]}; run as root (apt-get install ${PACKAGES[*]}) or install them yourself"
  command -v apt-get >/dev/null || die "missing ${missing[*]} and no apt-get: install SLURM ${PACKAGES[*]} by hand"
  say "installing ${PACKAGES[*]} with apt-get (missing: ${missing[*]})"
  # Debian starts a package's service on install unless a policy forbids it; this script runs its own
  # daemons, so keep the packaged ones from starting (restored right after).
  local policy=/usr/sbin/policy-rc.d own_policy=0
  if [ ! -e "$policy" ]; then printf '#!/bin/sh\nexit 101\n' > "$policy"; chmod +x "$policy"; own_policy=1; fi
  local rc=0
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      "${PACKAGES[@]}" >/dev/null; } || rc=$?
  [ $own_policy = 1 ] && rm -f "$policy"
  [ $rc = 0 ] || die "apt-get install ${PACKAGES[*]} failed (exit $rc)"
}

# --- pid files -------------------------------------------------------------------------------------------
pid_of() {  # the pid in $RUN/$1.pid if that process is alive and is the daemon named $1
  local f=$RUN/$1.pid pid
  [ -s "$f" ] || return 1
  pid=$(tr -dc '0-9' < "$f")
  [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || return 1
  [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$1" ] || return 1  # not a recycled pid
  echo "$pid"
}
running() { pid_of "$1" >/dev/null; }

wait_for() {  # wait_for SECONDS DESCRIPTION COMMAND...: poll COMMAND until it succeeds
  local t=$1 what=$2; shift 2
  local end=$((SECONDS + t))
  until "$@" >/dev/null 2>&1; do
    [ $SECONDS -lt $end ] || die "$what did not come up within $t s (logs: $LOG)"
    sleep 0.5
  done
}

# --- configuration -----------------------------------------------------------------------------------------
write_configs() {
  mkdir -p "$ETC" "$RUN" "$LOG" "$SPOOL/ctld" "$SPOOL/d" "$DB"
  chmod 755 "$HOME_DIR" "$ETC" "$RUN" "$LOG"
  # node size from slurmd itself (CPUs, sockets, cores, RealMemory), minus 512 MB for the daemons
  local node_line mem
  node_line=$(slurmd -C | head -1)
  mem=$(sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' <<< "$node_line")
  node_line=$(sed "s/RealMemory=[0-9]*/RealMemory=$((mem > 1024 ? mem - 512 : mem))/" <<< "$node_line")
  # Memory limits: cgroup v1 (the kernel kills a job at its --mem, state OUT_OF_MEMORY); SLURM 22.05's cgroup v2
  # plugin wants systemd, so without a v1 memory hierarchy (or with NATSCENE_SLURM_CGROUP=0) the accounting
  # poller kills a job seen above its --mem instead (every 5 s, JobAcctGatherParams=OverMemoryKill).
  local proctrack=proctrack/linuxproc task=task/none gather=jobacct_gather/linux gather_params=OverMemoryKill
  if [ -d /sys/fs/cgroup/memory ] && [ "${NATSCENE_SLURM_CGROUP:-1}" = 1 ]; then
    proctrack=proctrack/cgroup task=task/cgroup gather=jobacct_gather/cgroup gather_params=
  fi
  cat > "$ETC/slurm.conf" <<EOF
# written by tools/slurm-local.sh: a one-node cluster with accounting (slurmdbd)
ClusterName=$CLUSTER
SlurmctldHost=$NODE
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$RUN/munge.socket
CredType=cred/munge
SlurmctldPort=$CTLD_PORT
SlurmdPort=$D_PORT
StateSaveLocation=$SPOOL/ctld
SlurmdSpoolDir=$SPOOL/d
SlurmctldPidFile=$RUN/slurmctld.pid
SlurmdPidFile=$RUN/slurmd.pid
SlurmctldLogFile=$LOG/slurmctld.log
SlurmdLogFile=$LOG/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MpiDefault=none
ProctrackType=$proctrack
TaskPlugin=$task
JobAcctGatherType=$gather
JobAcctGatherFrequency=5
${gather_params:+JobAcctGatherParams=$gather_params}
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=$NODE
AccountingStoragePort=$DBD_PORT
AccountingStoragePass=$RUN/munge.socket
AccountingStorageEnforce=associations
AccountingStoreFlags=job_comment
ReturnToService=2
# a job asking more CPUs or memory than the node has is refused by sbatch instead of pending forever
EnforcePartLimits=ALL
MinJobAge=300
KillWait=10
$node_line State=UNKNOWN
PartitionName=$PARTITION Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
  cat > "$ETC/cgroup.conf" <<EOF
# written by tools/slurm-local.sh: a job is held to the memory it asked for (--mem), as on a real cluster
CgroupPlugin=cgroup/v1
ConstrainCores=yes
ConstrainRAMSpace=yes
AllowedRAMSpace=100
ConstrainSwapSpace=yes
AllowedSwapSpace=0
EOF
  cat > "$ETC/slurmdbd.conf" <<EOF
# written by tools/slurm-local.sh
AuthType=auth/munge
AuthInfo=socket=$RUN/munge.socket
DbdHost=$NODE
DbdPort=$DBD_PORT
SlurmUser=root
PidFile=$RUN/slurmdbd.pid
LogFile=$LOG/slurmdbd.log
DebugLevel=info
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$DB_PORT
StorageUser=slurm
StoragePass=slurm
StorageLoc=slurm_acct_db
EOF
  chmod 600 "$ETC/slurmdbd.conf"
  cat > "$ETC/my.cnf" <<EOF
# written by tools/slurm-local.sh: the accounting database, on 127.0.0.1:$DB_PORT only
[mariadbd]
datadir=$DB
socket=$RUN/mysqld.sock
pid-file=$RUN/mariadbd.pid
log-error=$LOG/mariadbd.log
bind-address=127.0.0.1
port=$DB_PORT
user=root
innodb_buffer_pool_size=64M
innodb_log_file_size=64M
innodb_lock_wait_timeout=900
EOF
}

# --- daemons -------------------------------------------------------------------------------------------------
start_munge() {
  running munged && return 0
  if [ ! -s "$ETC/munge.key" ]; then
    dd if=/dev/urandom of="$ETC/munge.key" bs=1024 count=1 status=none
  fi
  chmod 400 "$ETC/munge.key"
  say "starting munged"
  munged --force --key-file="$ETC/munge.key" --socket="$RUN/munge.socket" --pid-file="$RUN/munged.pid" \
         --log-file="$LOG/munged.log" --seed-file="$RUN/munged.seed" \
    || die "munged did not start (log: $LOG/munged.log)"
  wait_for 10 munged test -S "$RUN/munge.socket"
}

db_query() { mariadb --socket="$RUN/mysqld.sock" -uroot -N -e "$1"; }

start_mariadb() {
  if ! running mariadbd; then
    if [ ! -d "$DB/mysql" ]; then
      say "initialising the accounting database in $DB"
      mariadb-install-db --defaults-file="$ETC/my.cnf" --auth-root-authentication-method=socket \
        > "$LOG/mariadb-install.log" 2>&1 || die "mariadb-install-db failed (log: $LOG/mariadb-install.log)"
    fi
    say "starting mariadbd on 127.0.0.1:$DB_PORT"
    nohup mariadbd --defaults-file="$ETC/my.cnf" > /dev/null 2>&1 &
    wait_for 60 mariadbd db_query "select 1"
  fi
  db_query "CREATE DATABASE IF NOT EXISTS slurm_acct_db;
            CREATE USER IF NOT EXISTS 'slurm'@'127.0.0.1' IDENTIFIED BY 'slurm';
            CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY 'slurm';
            GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';
            GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost';" \
    || die "could not create the accounting database user (log: $LOG/mariadbd.log)"
}

start_slurmdbd() {
  if ! running slurmdbd; then
    say "starting slurmdbd"
    slurmdbd || die "slurmdbd did not start (log: $LOG/slurmdbd.log)"
    wait_for 60 slurmdbd sacctmgr -n show cluster
  fi
  # the cluster, an account and root as its user (AccountingStorageEnforce=associations needs them)
  sacctmgr -n -P show cluster format=cluster | grep -qx "$CLUSTER" || sacctmgr -i -Q add cluster "$CLUSTER" >/dev/null
  sacctmgr -n -P show account format=account | grep -qx "$ACCOUNT" \
    || sacctmgr -i -Q add account "$ACCOUNT" Cluster="$CLUSTER" Description="natscene local cluster" >/dev/null
  local u
  for u in root ${SUDO_USER:-}; do
    sacctmgr -n -P show assoc user="$u" account="$ACCOUNT" format=user | grep -qx "$u" \
      || sacctmgr -i -Q add user "$u" Account="$ACCOUNT" DefaultAccount="$ACCOUNT" >/dev/null
  done
}

start_slurmctld() {
  running slurmctld && return 0
  say "starting slurmctld"
  slurmctld || die "slurmctld did not start (log: $LOG/slurmctld.log)"
  wait_for 60 slurmctld scontrol ping
}

start_slurmd() {
  running slurmd && return 0
  say "starting slurmd (node $NODE)"
  slurmd || die "slurmd did not start (log: $LOG/slurmd.log)"
  node_idle() { sinfo -h -n "$NODE" -o %t | grep -Eq '^(idle|mix|alloc)'; }
  wait_for 60 "node $NODE" node_idle
}

# Clients find a cluster through $SLURM_CONF, else /etc/slurm/slurm.conf, else /run/slurm/conf/slurm.conf
# (where a configless slurmd keeps its copy). Jobs need the last: the Snakemake job step drops every SLURM_*
# variable before it calls srun inside the job. So this cluster's etc/ is linked there while it runs.
RUNLINK=/run/slurm/conf
link_config() {
  if [ -e /etc/slurm/slurm.conf ]; then
    say "warning: /etc/slurm/slurm.conf exists (another SLURM set-up): commands inside jobs will read it, not $ETC"
    return 0
  fi
  if [ -L "$RUNLINK" ] && [ "$(readlink "$RUNLINK")" != "$ETC" ] && [ -e "$RUNLINK/slurm.conf" ]; then
    say "warning: $RUNLINK points to $(readlink "$RUNLINK"), not replaced: commands inside jobs will read it"
    return 0
  fi
  [ -e "$RUNLINK" ] && [ ! -L "$RUNLINK" ] && { say "warning: $RUNLINK is not a link, left alone"; return 0; }
  mkdir -p "$(dirname "$RUNLINK")"
  ln -sfn "$ETC" "$RUNLINK"
}
unlink_config() {
  if [ -L "$RUNLINK" ] && [ "$(readlink "$RUNLINK")" = "$ETC" ]; then rm -f "$RUNLINK"; fi
}

cmd_start() {
  install_packages
  [ "$(id -u)" = 0 ] || die "the daemons need root"
  mkdir -p "$HOME_DIR"
  write_configs
  # daemons started with other settings (an older version of this script): restart the SLURM ones
  local sum
  sum=$(cat "$ETC"/slurm.conf "$ETC"/cgroup.conf "$ETC"/slurmdbd.conf | sha256sum | cut -d' ' -f1)
  if [ -s "$RUN/config.sha256" ] && [ "$(cat "$RUN/config.sha256")" != "$sum" ]; then
    say "configuration changed: restarting the SLURM daemons"
    stop_one slurmd; stop_one slurmctld; stop_one slurmdbd
  fi
  echo "$sum" > "$RUN/config.sha256"
  start_munge
  start_mariadb
  start_slurmdbd
  start_slurmctld
  start_slurmd
  link_config
  say "cluster '$CLUSTER' up: partition '$PARTITION', account '$ACCOUNT', node $(sinfo -h -o '%n %c CPUs %m MB')"
  if [ "$(readlink "$RUNLINK" 2>/dev/null)" = "$ETC" ]; then
    say "sbatch, squeue, sacct... on this machine find it by themselves ($RUNLINK -> $ETC)"
  else
    say "clients need: export SLURM_CONF=$SLURM_CONF"
  fi
}

stop_one() {  # stop_one NAME: SIGTERM the pid in its pid file, wait, then SIGKILL
  local pid
  pid=$(pid_of "$1") || { rm -f "$RUN/$1.pid"; return 0; }
  say "stopping $1 (pid $pid)"
  kill -TERM "$pid" 2>/dev/null || true
  for _ in $(seq 120); do kill -0 "$pid" 2>/dev/null || break; sleep 0.25; done
  if kill -0 "$pid" 2>/dev/null; then say "$1 (pid $pid) ignored SIGTERM for 30 s: SIGKILL"; kill -KILL "$pid" || true; fi
  rm -f "$RUN/$1.pid"
}

cmd_stop() {
  [ -d "$RUN" ] || { say "nothing to stop ($RUN does not exist)"; return 0; }
  # reverse order of start; slurmd first so that running jobs end (they are cancelled with the node)
  if running slurmctld && command -v scancel >/dev/null; then scancel --quiet --full --state=RUNNING,PENDING -u root 2>/dev/null || true; fi
  stop_one slurmd
  stop_one slurmctld
  stop_one slurmdbd
  stop_one mariadbd
  stop_one munged
  unlink_config
}

cmd_status() {
  local d rc=0
  for d in munged mariadbd slurmdbd slurmctld slurmd; do
    if pid=$(pid_of "$d"); then echo "$d: running (pid $pid)"; else echo "$d: stopped"; rc=3; fi
  done
  if [ $rc = 0 ]; then
    sinfo
    echo "export SLURM_CONF=$SLURM_CONF"
  fi
  return $rc
}

case "${1:-}" in
  start) cmd_start ;;
  stop) cmd_stop ;;
  status) cmd_status ;;
  env) echo "export SLURM_CONF=$SLURM_CONF" ;;
  install) install_packages ;;
  *) echo "usage: $0 start|stop|status|env|install   (state in \$NATSCENE_SLURM_HOME, default /tmp/natscene-slurm)" >&2; exit 2 ;;
esac
