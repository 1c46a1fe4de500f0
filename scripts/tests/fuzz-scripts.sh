# shellcheck shell=bash disable=SC2154 # s, tmp: set by scripts/test-scripts.sh, which sources this
# Sourced by scripts/test-scripts.sh (its `expect`, `check`, `$s` and `$tmp`): fuzz-campaign.sh
# and fuzz-cmin.sh, each run in a copy of the repository's layout under $tmp with the stand-in
# cargo (fake-cargo.sh) and targets `a` and `b` (fake-fuzz-target.sh).

# fuzz_repo DIR: a repository layout with the fuzz scripts and the stand-in targets built.
fuzz_repo() {
    local triple
    triple=$(rustc -vV | sed -n 's/^host: //p')
    mkdir -p "$1/scripts" "$1/fuzz/target/$triple/release" "$1/fuzz/corpus/a" "$1/fuzz/corpus/b"
    cp "$s"/fuzz-*.sh "$1/scripts/"
    cp "$s/tests/fake-fuzz-target.sh" "$1/fuzz/target/$triple/release/a"
    cp "$s/tests/fake-fuzz-target.sh" "$1/fuzz/target/$triple/release/b"
}
mkdir -p "$tmp/cargo-bin"
cp "$s/tests/fake-cargo.sh" "$tmp/cargo-bin/cargo"
fuzz_env() { env PATH="$tmp/cargo-bin:$PATH" FUZZ_SECONDS=1 "$@"; }

# fuzz-campaign.sh: a rerun reports only its own findings.
cr=$tmp/campaign
fuzz_repo "$cr"
camp=$cr/target/fuzz-campaign
expect 0 "fuzz-campaign: a clean campaign" fuzz_env bash "$cr/scripts/fuzz-campaign.sh" a b
mkdir -p "$camp/artifacts/a" && echo old >"$camp/artifacts/a/crash-old"
expect 0 "fuzz-campaign: an earlier campaign's crash is not this one's finding" \
    fuzz_env bash "$cr/scripts/fuzz-campaign.sh" a b
check "fuzz-campaign: ... it is moved aside, saying where" \
    grep -q "an earlier campaign's findings moved to target/fuzz-campaign/artifacts\.[0-9T]*Z$" "$tmp/last.out"
check "fuzz-campaign: ... kept there" test "$(cat "$camp"/artifacts.*/a/crash-old)" = old
# shellcheck disable=SC2016 # a literal backquote
check "fuzz-campaign: ... the summary counts no finding" grep -q '^| `a` | 3 | 100 | .* | 0 |$' "$camp/summary.md"
expect 1 "fuzz-campaign: a crash of this campaign is its finding" \
    fuzz_env FAKE_MODE=crash bash "$cr/scripts/fuzz-campaign.sh" a
check "fuzz-campaign: ... reported" grep -q "^finding: target a: .*/artifacts/a/crash-fake" "$tmp/last.out"
check "fuzz-campaign: ... an artifacts folder without files is not kept aside" \
    test "$(find "$camp" -maxdepth 1 -name 'artifacts.*' | wc -l)" = 1
expect 0 "fuzz-campaign: the next campaign" fuzz_env bash "$cr/scripts/fuzz-campaign.sh" a
check "fuzz-campaign: ... keeps both earlier campaigns' findings apart" \
    test "$(find "$camp" -path '*/artifacts.*/a/*' -type f | wc -l)" = 2

# fuzz-cmin.sh: the seeds are not added again, and a failed minimisation changes nothing.
mr=$tmp/cmin
fuzz_repo "$mr"
echo seed >"$mr/fuzz/corpus/a/seed-one"
echo kept >"$mr/fuzz/corpus/a/min-0000000000000000"
expect 0 "fuzz-cmin: a minimising run" fuzz_env bash "$mr/scripts/fuzz-cmin.sh" a
check "fuzz-cmin: ... a seed is not checked in again as min-*" \
    test ! -e "$mr/fuzz/corpus/a/min-$(echo seed | sha1sum | cut -c1-16)"
check "fuzz-cmin: ... the other inputs are (the seed, the old and the grown one)" \
    test "$(find "$mr/fuzz/corpus/a" -type f | wc -l)" = 3
cp -r "$mr/fuzz/corpus/a" "$tmp/cmin-before"
expect 1 "fuzz-cmin: cargo fuzz cmin's 'Failed to minimize corpus' (exit 0) stops the script" \
    fuzz_env FAKE_CMIN=fail bash "$mr/scripts/fuzz-cmin.sh" a
check "fuzz-cmin: ... naming it, with the log" grep -q "Failed to minimize corpus" "$tmp/last.out"
check "fuzz-cmin: ... the checked-in corpus unchanged" diff -r "$tmp/cmin-before" "$mr/fuzz/corpus/a"
