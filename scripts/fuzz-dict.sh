# shellcheck shell=bash
# Sourced by the fuzz scripts (fuzz-ci.sh, fuzz-cmin.sh, fuzz-task.sh): defines fuzz_dict.

# fuzz_dict TARGET: prints the path of TARGET's libFuzzer dictionary: fuzz/dict/TARGET.dict
# where there is one (obj_file's OBJ tokens: that target parses text), otherwise
# fuzz/dict/floats.dict (the f32 bit patterns of the targets that decode bytes as floats).
fuzz_dict() {
    local root
    root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
    if [ -f "$root/fuzz/dict/$1.dict" ]; then
        echo "$root/fuzz/dict/$1.dict"
    else
        echo "$root/fuzz/dict/floats.dict"
    fi
}
