#!/usr/bin/env bash
# Start a throw-away single-node Slurm cluster (slurmctld + slurmd, plus munged
# if none is usable) whose config, state, spool, logs and pids all live in
# STATE_DIR. No systemd needed. On success the only line on stdout is
#   export SLURM_CONF=STATE_DIR/slurm.conf
# so a caller can `eval "$(tests/slurm/start.sh DIR)"`. Stop with stop.sh DIR.
#
# Environment knobs (all optional):
#   SLURM_TEST_CTLD_PORT  slurmctld port (default 6817)
#   SLURM_TEST_SLURMD_PORT slurmd port   (default 6818)
#   SLURM_TEST_TIMEOUT    seconds to wait for the node to be idle (default 60)
# Exit codes: 0 ok, 2 usage, 3 not root (and packages missing), 1 other failure.
set -euo pipefail

usage() { echo "usage: $0 STATE_DIR" >&2; exit 2; }
[[ $# -eq 1 && -n $1 ]] || usage

log() { echo "slurm/start.sh: $*" >&2; }
cleanup_on_fail=0
die() {
    log "ERROR: $*"
    if ((cleanup_on_fail)); then "$here/stop.sh" "$state" >&2 || true; fi
    exit 1
}

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
mkdir -p "$1"
state=$(cd "$1" && pwd)
ctld_port=${SLURM_TEST_CTLD_PORT:-6817}
slurmd_port=${SLURM_TEST_SLURMD_PORT:-6818}
timeout=${SLURM_TEST_TIMEOUT:-60}
t0=$SECONDS

# --- 1. packages --------------------------------------------------------------
export PATH=$PATH:/usr/sbin:/sbin
have() { local p; p=$(command -v "$1" 2>/dev/null) && [[ -f $p && -x $p ]]; }
need=()
for pair in slurmctld:slurmctld slurmd:slurmd sbatch:slurm-client munged:munge; do
    have "${pair%%:*}" || need+=("${pair#*:}")
done
if [[ ${#need[@]} -gt 0 ]]; then
    if [[ $(id -u) -ne 0 ]]; then
        echo "slurm/start.sh: missing packages (${need[*]}) and not root: install them with" \
             "'apt-get install slurmctld slurmd slurm-client munge' as root, or run this as root" >&2
        exit 3
    fi
    log "installing ${need[*]} ..."
    # apt/dpkg chatter goes to stderr: stdout is reserved for the export line.
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
        slurmctld slurmd slurm-client munge; } >&2 || die "apt-get install failed"
fi
if [[ $(id -u) -ne 0 ]]; then
    echo "slurm/start.sh: must run as root (slurmd launches tasks as the submitting user," \
         "SlurmUser=root)" >&2
    exit 3
fi

# --- 2. stale state from an earlier run ---------------------------------------
if [[ -s $state/pids ]]; then
    log "found $state/pids from an earlier run; stopping those processes first"
    "$here/stop.sh" "$state" >&2 || true
fi
# After a crash (daemons SIGKILLed, so stop.sh could not scancel) job steps of
# the old run outlive it, and their completion RPCs would reach the new
# slurmctld under recycled job ids. A slurmstepd of ours is recognised by the
# descriptor it holds on our slurmd.log (its environ is overwritten by its
# process title, so it cannot carry a marker).
reap_orphan_steps() {
    local d p fd victims=() stack kids
    for d in /proc/[0-9]*; do
        [[ $(cat "$d/comm" 2>/dev/null) == slurmstepd ]] || continue
        for fd in "$d"/fd/*; do
            case $(readlink "$fd" 2>/dev/null) in
            "$state/slurmd.log" | "$state/slurmd.log (deleted)") ;;
            *) continue ;;
            esac
            stack=("${d#/proc/}")
            while ((${#stack[@]})); do  # the step and all its descendants
                p=${stack[-1]}; unset 'stack[-1]'
                victims+=("$p")
                mapfile -t kids < <(ps -o pid= --ppid "$p" 2>/dev/null | tr -d ' ')
                ((${#kids[@]})) && stack+=("${kids[@]}")
            done
            break
        done
    done
    if ((${#victims[@]})); then
        log "killing orphaned job steps of an earlier run: ${victims[*]}"
        kill -KILL "${victims[@]}" 2>/dev/null || true
    fi
}
reap_orphan_steps
rm -rf "$state/statesave" "$state/spool"
rm -f "$state"/slurmctld.log "$state"/slurmd.log "$state"/slurmctld.out "$state"/slurmd.out \
      "$state"/slurmctld.pid "$state"/slurmd.pid "$state"/munged.out "$state/pids"
mkdir -p "$state/statesave" "$state/spool"
: >"$state/pids"
cleanup_on_fail=1  # from here on, a failure stops whatever this run started

# record NAME PID: stop.sh only kills a pid whose /proc/PID/comm still says NAME
record() { echo "$1 $2" >>"$state/pids"; }

# start "$@" in its own session, in the foreground mode of the daemon, and print
# its pid. The background subshell is never a process-group leader, so setsid
# does not fork and $! is the daemon's own pid after exec.
spawn() {
    local out=$1; shift
    ( exec setsid "$@" </dev/null >>"$out" 2>&1 ) &
    echo $!
}

alive() {  # running and not a zombie
    local stat
    stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
    stat=${stat##*) }
    [[ ${stat%% *} != Z ]]
}

# --- 3. munge -----------------------------------------------------------------
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    log "munged already running and working; using it (not recorded in pids)"
else
    getent passwd munge >/dev/null || die "user 'munge' missing (broken munge package?)"
    key=/etc/munge/munge.key
    if [[ ! -s $key ]]; then
        log "creating $key"
        install -d -o munge -g munge -m 0700 /etc/munge
        if command -v mungekey >/dev/null 2>&1; then
            mungekey --create --keyfile="$key" >&2
        else
            dd if=/dev/urandom of="$key" bs=1 count=1024 status=none
        fi
    fi
    chown munge:munge "$key"
    chmod 0400 "$key"
    # no systemd-tmpfiles here: make munged's runtime dirs ourselves
    install -d -o munge -g munge -m 0755 /run/munge
    install -d -o munge -g munge -m 0700 /var/lib/munge /var/log/munge
    munged_pid=$(spawn "$state/munged.out" \
        setpriv --reuid=munge --regid=munge --init-groups /usr/sbin/munged --foreground)
    record munged "$munged_pid"
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        alive "$munged_pid" || break
        sleep 0.2
    done
    if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        cat "$state/munged.out" /var/log/munge/munged.log 2>/dev/null | tail -n 20 >&2 || true
        die "munged did not come up (munge -n | unmunge fails)"
    fi
    log "started munged (pid $munged_pid)"
fi

# --- 4. slurm.conf --------------------------------------------------------------
node=$(hostname -s)
cpus=$(nproc)
version=$(slurmctld -V | awk '{print $2}')
cat >"$state/slurm.conf" <<EOF
# Generated by tests/slurm/start.sh for Slurm $version; throw-away test cluster.
ClusterName=thorarena-test
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
MaxArraySize=10001
MinJobAge=300
KillWait=5
StateSaveLocation=$state/statesave
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$state/slurm.conf

diag() {
    log "---- last lines of slurmctld.log ----"; tail -n 25 "$state/slurmctld.log" >&2 2>/dev/null || true
    log "---- slurmctld stdout/stderr ----";     tail -n 10 "$state/slurmctld.out" >&2 2>/dev/null || true
    log "---- last lines of slurmd.log ----";    tail -n 25 "$state/slurmd.log" >&2 2>/dev/null || true
    log "---- slurmd stdout/stderr ----";        tail -n 10 "$state/slurmd.out" >&2 2>/dev/null || true
    log "---- sinfo ----"; sinfo -N -l >&2 2>&1 || true
}

# --- 5. daemons -------------------------------------------------------------------
# -c: cold start, never recover jobs from an old state dir; -i: ignore stale
# state errors. -D keeps it in the foreground so the recorded pid is exact.
ctld_pid=$(spawn "$state/slurmctld.out" slurmctld -D -c -i -f "$state/slurm.conf")
record slurmctld "$ctld_pid"
slurmd_pid=$(spawn "$state/slurmd.out" slurmd -D -N "$node" -f "$state/slurm.conf")
record slurmd "$slurmd_pid"

# --- 6. wait for the node to be idle -----------------------------------------------
deadline=$((SECONDS + timeout))
st=
while ((SECONDS < deadline)); do
    if ! alive "$ctld_pid"; then diag; die "slurmctld exited during startup"; fi
    if ! alive "$slurmd_pid"; then diag; die "slurmd exited during startup"; fi
    st=$(sinfo -h -N -n "$node" -o '%t' 2>/dev/null || true)
    [[ $st == idle ]] && break
    sleep 0.5
done
if [[ $st != idle ]]; then
    diag
    die "node $node not idle after ${timeout}s (state: '${st:-no answer}')"
fi
log "Slurm $version up in $((SECONDS - t0))s: node $node idle, $cpus CPUs, ports $ctld_port/$slurmd_port"
echo "export SLURM_CONF=$state/slurm.conf"
