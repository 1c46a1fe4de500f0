# shellcheck shell=bash
# Sourced by the CI cluster stage's checks (scripts/slurm-ci-*.sh): bounded waits on Slurm jobs,
# their final states, and the scheduler's own account of a job when a check fails. Talks to the
# cluster SLURM_CONF names (scripts/slurm-local.sh exports it). Accounting (slurmdbd) is not
# configured there, so `sacct` has nothing to say: the record of finished jobs is
# `scontrol show job` (kept MinJobAge = 1 h) and the jobcomp log.

# Fails the check: prints the message, then every job named in `jobs_seen` as the scheduler
# reports it (`scontrol show job`, the jobcomp records) with its output files' last lines.
# (scripts/slurm-local.sh prints the daemons' logs when the stage exits non-zero.)
jobs_seen=()
fail() {
    echo "FAILED: $*" >&2
    local j f
    for j in "${jobs_seen[@]}"; do
        echo "---- scontrol show job $j" >&2
        scontrol show job "$j" >&2 || true
        if [ -n "${SLURM_LOCAL_DIR:-}" ] && [ -f "$SLURM_LOCAL_DIR/log/jobcomp.log" ]; then
            echo "---- jobcomp records of job $j" >&2
            grep -E "JobId=$j( |_)|ArrayJobId=$j " "$SLURM_LOCAL_DIR/log/jobcomp.log" >&2 || true
        fi
        for f in $(scontrol show job "$j" 2>/dev/null | sed -n 's/^ *StdOut=//p' | sort -u); do
            [ -f "$f" ] || continue
            echo "---- last lines of $f" >&2
            tail -n 20 "$f" >&2
        done
    done
    exit 1
}

# submit VAR SBATCH_ARGS...: sbatch --parsable; sets VAR to the job id and remembers it for
# `fail` (a variable, not output: a command substitution would forget it).
submit() {
    local var=$1 id
    shift
    id=$(sbatch --parsable "$@") || fail "sbatch $*"
    id=${id%%;*}
    jobs_seen+=("$id")
    printf -v "$var" '%s' "$id"
}

# wait_for SECONDS WHAT COMMAND...: runs COMMAND every 0.2 s until it succeeds; fails naming
# WHAT after SECONDS.
wait_for() {
    local timeout=$1 what=$2
    local deadline=$((SECONDS + timeout))
    shift 2
    until "$@"; do
        [ "$SECONDS" -lt "$deadline" ] || fail "waited $timeout s for $what"
        sleep 0.2
    done
}

# True when every task of the jobs is listed and none is pending, running, completing or
# being requeued (false while squeue cannot answer).
jobs_ended() {
    local ids states
    ids=$(IFS=,; echo "$*")
    states=$(squeue -h -t all -j "$ids" -o '%T') || return 1
    [ -n "$states" ] &&
        ! grep -qvE '^(COMPLETED|FAILED|CANCELLED|TIMEOUT|OUT_OF_MEMORY|NODE_FAIL|PREEMPTED|BOOT_FAIL|DEADLINE)$' <<<"$states"
}

# wait_jobs SECONDS JOB...: waits until every task of the jobs has ended.
wait_jobs() {
    local timeout=$1
    shift
    wait_for "$timeout" "jobs $* to end" jobs_ended "$@"
}

# job_field JOB FIELD: the FIELD of `scontrol show job JOB` (JOB: an id, or ARRAY_INDEX for
# one array task), e.g. `job_field 12_1 JobState` -> COMPLETED.
job_field() {
    scontrol -o show job "$1" | head -n 1 | tr ' ' '\n' | sed -n "s/^$2=//p"
}

# expect_job JOB STATE EXIT: fails unless the job (or array task) ended in STATE with ExitCode
# EXIT (`code:signal`, e.g. 0:0).
expect_job() {
    local state code
    state=$(job_field "$1" JobState)
    code=$(job_field "$1" ExitCode)
    [ "$state" = "$2" ] && [ "$code" = "$3" ] ||
        fail "job $1 ended $state with exit code $code, expected $2 with $3"
}
