#!/usr/bin/env bash
# Instructions `check` executes (valgrind's callgrind) on the first 5 MB of the corpus's
# bunny, with the Kossel profile and with an input shaper, in all and per thread, in the
# order the threads start: main, firmware (read, plan, shape), the model stage's helper and
# its own thread, drive. The firmware and drive threads' counts repeat exactly for the same
# binary and input whatever else the machine does, where wall times on a shared machine
# vary by ±10 % and more; the model stage's two threads share their work differently from
# run to run (the run's peaks rise at other moments), their sum within about ±1 %.
# For comparing two builds of one change (docs/performance.md).
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
  rm -f "$out"/callgrind.out*
  valgrind --tool=callgrind --separate-threads=yes --callgrind-out-file="$out/callgrind.out" \
    "$bin" check -q --format json -m "$profile" "$head5" > /dev/null 2>&1
  threads=$(for f in "$out"/callgrind.out-*; do sed -n 's/^totals: *//p' "$f"; done)
  total=$(echo "$threads" | awk '{s += $1} END {printf "%.0f", s}')
  per=$(echo "$threads" | awk '{printf "%s%.1f", (NR > 1 ? " + " : ""), $1 / 1e6} END {print " M"}')
  printf '%-24s %s instructions (%s)\n' "$(basename "$profile" .yaml)" "$total" "$per"
done
