#!/bin/bash
# Issue 17 goal 3, third run (after the MIS-through-delta and landing-coverage changes):
# the second run's script with this run's results folder and binary (main at 2587aa7,
# cargo build --profile ci -p chronolux --features oidn).
OUT=/work/peers-run/results-issue17c BIN=/work/peers-run/chronolux-oidn-c \
    exec bash "$(dirname "$0")/../2026-12-02-peer-issue17b/issue17b.sh"
