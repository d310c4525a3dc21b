#!/usr/bin/env bash
# Peak memory of `check` on a 1 GB G-code file (the corpus's bunny repeated 37 times):
# streaming means the resident set stays flat whatever the file's size.
#   scripts/memory.sh [CORPUS_DIR] [MACHINE]   (defaults: ../shared/corpus, machines/kossel.yaml)
set -euo pipefail
cd "$(dirname "$0")/.."
corpus=${1:-../shared/corpus}
machine=${2:-machines/kossel.yaml}
. scripts/corpus.sh
cargo build --release --quiet
one=$(corpus_file "$corpus/ps25_delta170_marlin2_bunny-big.gcode.xz")
big="$out/bunny-x37.gcode"
[ -f "$big" ] || for _ in $(seq 37); do cat "$one"; done > "$big"
for f in "$one" "$big"; do
  /usr/bin/time -f "%e s wall, %M KB peak RSS" -o "$out/mem.txt" \
    target/release/delta-gcode check -q -m "$machine" "$f" > /dev/null 2>&1 || true
  printf '%-40s %8.0f MB  %s\n' "$(basename "$f")" "$(( $(stat -c %s "$f") / 1000000 ))" "$(cat "$out/mem.txt")"
done
