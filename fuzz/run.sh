#!/bin/bash
# Runs fuzz targets from their seed corpora, two at a time, for a time that is always named:
#
#   fuzz/run.sh SECONDS TARGET...     the targets named, SECONDS each
#   fuzz/run.sh SECONDS all           every target in fuzz_targets/
#
# A run takes about SECONDS × (number of targets) / 2 of wall time on two cores, plus the build
# (all 20 targets for 600 s each: 100 minutes); the line before the run says how long.
# Crashes, hangs (10 s) and allocations above 2 GiB stop a target and are written to
# fuzz/artifacts/TARGET/. With cargo-fuzz (`cargo install cargo-fuzz`) the targets are built
# by it (RUSTC_BOOTSTRAP=1 lets a stable toolchain use the nightly flags it needs); without
# it, by plain cargo with libFuzzer's coverage instrumentation (sancov) and debug assertions.
set -uo pipefail
cd "$(dirname "$0")"
usage() {
    echo "usage: fuzz/run.sh SECONDS TARGET... | fuzz/run.sh SECONDS all" >&2
    echo "targets: $(ls fuzz_targets | sed 's/\.rs$//' | tr '\n' ' ')" >&2
    exit 2
}
[ $# -ge 2 ] || usage
SECONDS_PER_TARGET=$1
shift
[[ "$SECONDS_PER_TARGET" =~ ^[1-9][0-9]*$ ]] || usage
if [ "$*" = all ]; then
    TARGETS=$(ls fuzz_targets | sed 's/\.rs$//')
else
    TARGETS=$*
    for t in $TARGETS; do
        [ -f "fuzz_targets/$t.rs" ] || { echo "no fuzz target $t" >&2; usage; }
    done
fi
set -- $TARGETS
echo "fuzzing $# targets for $SECONDS_PER_TARGET s each, two at a time: about $(( ($# + 1) / 2 * SECONDS_PER_TARGET / 60 )) minutes after the build"
# The targets' temporary files (the atlas target writes its input to one) in a folder removed
# when the run ends.
TMPDIR=$(mktemp -d "${TMPDIR:-/tmp}/atlasmesh-fuzz-run.XXXXXX")
export TMPDIR
trap 'rm -rf "$TMPDIR"' EXIT
export RUSTC_BOOTSTRAP=1
# Line tables in the targets, for the stacks of the crashes they find.
export CARGO_PROFILE_RELEASE_DEBUG=1
if cargo fuzz --version >/dev/null 2>&1; then
    cargo fuzz build -O >/dev/null 2>&1 || cargo fuzz build -O
    fuzz() { cargo fuzz run -O "$1" "$2" "$3" -- "${@:4}"; }
else
    triple="$(rustc -vV | sed -n 's/^host: //p')"
    RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares -Cdebug-assertions -Coverflow-checks --cfg fuzzing" \
        cargo build --release --target "$triple" --target-dir target-cov || exit 1
    fuzz() { local t=$1; shift; "target-cov/$triple/release/$t" "$@"; }
    echo "built without cargo-fuzz: target-cov/$triple/release/"
fi
run() {
    local t=$1
    mkdir -p "corpus/$t" "artifacts/$t"
    fuzz "$t" "corpus/$t" "seeds/$t" \
        -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 \
        -malloc_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
        -artifact_prefix="artifacts/$t/" >"log-$t.txt" 2>&1
    echo "$t: exit $? $(grep -E '^stat::number_of_executed_units' "log-$t.txt" | awk '{print $2}') runs, peak RSS $(grep -E '^stat::peak_rss_mb' "log-$t.txt" | awk '{print $2}') MB"
}
set -- $TARGETS
while [ $# -gt 0 ]; do
    run "$1" &
    if [ $# -gt 1 ]; then run "$2" & fi
    wait
    shift; shift || true
done
