#!/bin/bash
# Runs every fuzz target for SECONDS (default 600) from its seed corpus, two at a time.
# Crashes, hangs (10 s) and allocations above 2 GiB stop a target and are written to
# fuzz/artifacts/TARGET/. Needs cargo-fuzz (`cargo install cargo-fuzz`); on a stable
# toolchain RUSTC_BOOTSTRAP=1 lets it use the nightly flags it needs.
set -uo pipefail
cd "$(dirname "$0")"
SECONDS_PER_TARGET=${1:-600}
shift || true
TARGETS=${*:-ply stl obj vtk vtp vtu inp msh csv text landmarks sets atlas vtk_xml_encoded vtk51 msh_binary atlas_structure}
export RUSTC_BOOTSTRAP=1
cargo fuzz build -O >/dev/null 2>&1 || cargo fuzz build -O
run() {
    local t=$1
    mkdir -p "corpus/$t"
    cargo fuzz run -O "$t" "corpus/$t" "seeds/$t" -- \
        -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 \
        -malloc_limit_mb=2048 -max_len=65536 -print_final_stats=1 >"log-$t.txt" 2>&1
    echo "$t: exit $? $(grep -E '^stat::number_of_executed_units' "log-$t.txt" | awk '{print $2}') runs"
}
set -- $TARGETS
while [ $# -gt 0 ]; do
    run "$1" &
    if [ $# -gt 1 ]; then run "$2" & fi
    wait
    shift; shift || true
done
