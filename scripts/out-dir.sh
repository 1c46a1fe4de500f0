# shellcheck shell=bash
# Sourced by the scripts that empty an OUT_DIR of their own before writing it
# (crosscheck-verify-shards.sh, slurm-ci-crosscheck.sh, slurm-ci-fuzz.sh).
#
# own_out_dir WHO OUT NAME...: returns when OUT does not exist, or is a folder whose every entry
# (hidden ones too) is named by one of the NAMEs (shell patterns: the files and folders the
# caller writes there). Otherwise it exits 2, naming what is in the way, before the caller
# deletes anything: OUT is not a folder (a file, a dangling link), or it holds a file the
# caller did not write.
own_out_dir() {
    local who=$1 out=$2 f name
    shift 2
    if [ -e "$out" ] || [ -L "$out" ]; then
        if [ ! -d "$out" ]; then
            echo "$who: $out is not a folder; refusing to replace it (OUT_DIR is this script's own folder)" >&2
            exit 2
        fi
    fi
    [ -d "$out" ] || return 0
    for f in "$out"/* "$out"/.[!.]* "$out"/..?*; do
        [ -e "$f" ] || [ -L "$f" ] || continue
        for name in "$@"; do
            # shellcheck disable=SC2254 # NAME is a pattern
            case ${f##*/} in $name) continue 2 ;; esac
        done
        echo "$who: $out holds $f, not this script's output; refusing to empty it" >&2
        exit 2
    done
}
