#!/usr/bin/env bash
# Bounded coverage-guided fuzz run of the glTF/GLB loader + frame builder (fuzz/, libFuzzer
# through libfuzzer-sys, built the way `cargo fuzz build --sanitizer none` builds it), seeded
# with the scenes of ../shared/scenes under 100 kB (the 1.7 MB TransmissionTest.glb alone
# cuts the rate from ~10³ to ~40 executions/s).
# Usage: scripts/ci/fuzz.sh [SECONDS] (default 60) [EXTRA libFuzzer FLAGS...].
# The SanitizerCoverage options (-Cpasses=sancov-module, -Cllvm-args=...) are stable rustc
# codegen flags: no nightly toolchain is needed (cargo-fuzz passes the same ones). Building
# libFuzzer itself needs a C++ compiler (`.ci/run` installs g++ when it is missing).
set -euo pipefail
cd "$(dirname "$0")/../.."
SECONDS_BUDGET="${1:-60}"
shift || true
TARGET_DIR="${CARGO_TARGET_DIR:-target}-fuzz"
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
# --target keeps the instrumentation off build scripts and proc macros (as cargo-fuzz does).
cargo build --manifest-path fuzz/Cargo.toml --release --locked \
    --target x86_64-unknown-linux-gnu --bin loader --target-dir "$TARGET_DIR"
corpus="$(mktemp -d)"
trap 'rm -rf "$corpus"' EXIT
find ../shared/scenes -maxdepth 1 \( -name '*.gltf' -o -name '*.glb' \) -size -100k \
    -exec cp {} "$corpus"/ \;
# -rss_limit_mb and -timeout make an out-of-memory or a hang a failure; any crash exits
# non-zero (the crash input is written to the working directory as crash-<sha1>).
"$TARGET_DIR/x86_64-unknown-linux-gnu/release/loader" "$corpus" \
    -max_total_time="$SECONDS_BUDGET" -rss_limit_mb=2048 -timeout=10 -max_len=2000000 \
    -print_final_stats=1 "$@" 2>&1 | tail -n 25
exit "${PIPESTATUS[0]}"
