#!/usr/bin/env bash
# Instructions `check` executes (valgrind's callgrind) on the first 5 MB of the corpus's
# bunny, with the Kossel profile and with an input shaper: a count that repeats exactly
# for the same binary and input whatever else the machine does, where wall times on a
# shared machine vary by ±10 %. For comparing two builds of one change (docs/performance.md).
#   scripts/instructions.sh [CORPUS_DIR] [BINARY]   (defaults: ../shared/corpus, a release build)
set -euo pipefail
cd "$(dirname "$0")/.."
corpus=${1:-../shared/corpus}
. scripts/corpus.sh
if [ -n "${2:-}" ]; then bin=$2; else cargo build --release --quiet; bin=target/release/delta-gcode; fi
bunny=$(corpus_file "$corpus/ps25_delta170_marlin2_bunny-big.gcode.xz")
head5="$out/bunny-5MB.gcode"
[ -f "$head5" ] || head -c 5000000 "$bunny" > "$head5"
for profile in machines/kossel.yaml "$(shaper_profile)"; do
  refs=$(valgrind --tool=callgrind --callgrind-out-file="$out/callgrind.out" \
    "$bin" check -q --format json -m "$profile" "$head5" 2>&1 > /dev/null |
    sed -n 's/.*I *refs: *//p')
  printf '%-24s %s instructions\n' "$(basename "$profile" .yaml)" "$refs"
done
