#!/usr/bin/env bash
# Bounded coverage-guided fuzz run of the glTF/GLB loader + frame builder (fuzz/, libFuzzer
# through libfuzzer-sys, built the way `cargo fuzz build --sanitizer none` builds it), seeded
# with ../shared/scenes. Usage: scripts/ci/fuzz.sh [SECONDS] (default 60).
# Needs a nightly toolchain (the SanitizerCoverage flags); without one it says so and exits 0:
# the deterministic mutation test (crates/chronolux-io/tests/it/fuzz.rs) runs in `cargo test`
# whatever the toolchain.
set -euo pipefail
cd "$(dirname "$0")/../.."
SECONDS_BUDGET="${1:-60}"
if ! cargo +nightly --version >/dev/null 2>&1; then
    echo "fuzz: no nightly toolchain here; coverage-guided run skipped"
    exit 0
fi
TARGET_DIR="${CARGO_TARGET_DIR:-target}-fuzz"
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
# --target keeps the instrumentation off build scripts and proc macros (as cargo-fuzz does).
cargo +nightly build --manifest-path fuzz/Cargo.toml --release --locked \
    --target x86_64-unknown-linux-gnu --bin loader --target-dir "$TARGET_DIR"
corpus="$(mktemp -d)"
trap 'rm -rf "$corpus"' EXIT
cp ../shared/scenes/*.gltf ../shared/scenes/*.glb "$corpus"/
# -rss_limit_mb and -timeout make an out-of-memory or a hang a failure; any crash exits non-zero.
"$TARGET_DIR/x86_64-unknown-linux-gnu/release/loader" "$corpus" \
    -max_total_time="$SECONDS_BUDGET" -rss_limit_mb=2048 -timeout=10 -max_len=2000000 \
    -print_final_stats=1 2>&1 | tail -n 25
