#!/usr/bin/env bash
# Regenerates the quick part of docs/RESULTS.md (`host-sim report --quick`: the scenarios CI
# can afford, seed 1) and fails if a number in it differs from the committed file. Only the part
# between the "quick results" markers is compared: the header (date, commit), the runs from
# synthesized samples and the wall-clock times are not.
# Usage: bash .ci/results.sh [path/to/host-sim]   (default: builds target/release/host-sim)
set -euo pipefail
cd "$(dirname "$0")/.."
HS=${1:-}
if [ -z "$HS" ]; then
  cargo build --release -p host-sim
  HS=./target/release/host-sim
fi
OUT=target/ci/RESULTS.quick.md
mkdir -p target/ci
"$HS" report --quick --out "$OUT" 2>/dev/null
quick() {
  sed -n '/^<!-- quick results: begin/,/^<!-- quick results: end -->/p' "$1"
}
if [ -z "$(quick docs/RESULTS.md)" ]; then
  echo "results: docs/RESULTS.md has no quick part (regenerate: cargo run --release -p host-sim -- report)" >&2
  exit 1
fi
if ! diff -u <(quick docs/RESULTS.md) <(quick "$OUT") > target/ci/RESULTS.diff; then
  echo "results: docs/RESULTS.md is out of date; its quick part differs from a fresh run:" >&2
  head -60 target/ci/RESULTS.diff >&2
  echo "(regenerate: cargo run --release -p host-sim -- report)" >&2
  exit 1
fi
echo "results: the quick part of docs/RESULTS.md matches a fresh run ($(quick "$OUT" | grep -c '^| `') metric rows)"
