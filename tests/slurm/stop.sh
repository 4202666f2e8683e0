#!/usr/bin/env bash
# Stop the test cluster started by start.sh STATE_DIR: cancel its jobs (so no
# slurmstepd/task outlives it), then SIGTERM exactly the pids recorded in
# STATE_DIR/pids, SIGKILL those still alive after a few seconds. A pid is only
# signalled while /proc/PID/comm still matches the recorded name, so a recycled
# pid is never hit. Nothing else is killed. Idempotent.
set -euo pipefail

[[ $# -eq 1 && -n $1 ]] || { echo "usage: $0 STATE_DIR" >&2; exit 2; }
state=$1
pids_file=$state/pids
export PATH=$PATH:/usr/sbin:/sbin
log() { echo "slurm/stop.sh: $*" >&2; }

if [[ ! -f $pids_file ]]; then
    log "no $pids_file: nothing to stop"
    exit 0
fi

# ours NAME PID: true while PID is alive (not a zombie awaiting its reaper)
# and still the process we started
ours() {
    local comm stat
    comm=$(cat "/proc/$2/comm" 2>/dev/null) || return 1
    [[ $comm == "$1" ]] || return 1
    stat=$(cat "/proc/$2/stat" 2>/dev/null) || return 1
    stat=${stat##*) }
    [[ ${stat%% *} != Z ]]
}

names=() pids=()
while read -r name pid _; do
    [[ -n ${name:-} && ${pid:-} =~ ^[0-9]+$ ]] || continue
    names+=("$name") pids+=("$pid")
done <"$pids_file"

# Cancel jobs of this cluster while its slurmctld is still up, so their
# slurmstepd and task processes are reaped by slurmd rather than left behind.
for i in "${!pids[@]}"; do
    if [[ ${names[$i]} == slurmctld ]] && ours slurmctld "${pids[$i]}" && [[ -f $state/slurm.conf ]]; then
        jobs=$(SLURM_CONF=$state/slurm.conf timeout 10 squeue -h -o '%A' 2>/dev/null | sort -u || true)
        if [[ -n $jobs ]]; then
            # shellcheck disable=SC2086  # word splitting of the job id list is intended
            SLURM_CONF=$state/slurm.conf timeout 10 scancel $jobs 2>/dev/null || true
            for _ in $(seq 20); do
                [[ -z $(SLURM_CONF=$state/slurm.conf timeout 5 squeue -h -o '%A' 2>/dev/null || true) ]] && break
                sleep 0.5
            done
        fi
    fi
done

signal_all() {
    local sig=$1 i
    for i in "${!pids[@]}"; do
        if ours "${names[$i]}" "${pids[$i]}"; then
            kill "-$sig" "${pids[$i]}" 2>/dev/null || true
        fi
    done
}

any_alive() {
    local i
    for i in "${!pids[@]}"; do
        ours "${names[$i]}" "${pids[$i]}" && return 0
    done
    return 1
}

# slurmd/slurmctld first, munged last (it authenticates their shutdown RPCs).
order=(slurmd slurmctld munged)
for want in "${order[@]}"; do
    for i in "${!pids[@]}"; do
        [[ ${names[$i]} == "$want" ]] || continue
        if ours "$want" "${pids[$i]}"; then
            kill -TERM "${pids[$i]}" 2>/dev/null || true
            for _ in $(seq 20); do ours "$want" "${pids[$i]}" || break; sleep 0.25; done
        fi
    done
done
# anything recorded under another name, then a last SIGKILL for stragglers
signal_all TERM
for _ in $(seq 20); do any_alive || break; sleep 0.25; done
if any_alive; then
    log "sending SIGKILL to survivors"
    signal_all KILL
    for _ in $(seq 20); do any_alive || break; sleep 0.25; done
fi
if any_alive; then
    log "ERROR: some recorded processes are still alive"
    exit 1
fi
rm -f "$pids_file"
log "stopped: ${names[*]:-nothing}"
