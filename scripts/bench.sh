#!/usr/bin/env bash
# Times `delta-gcode check` on the real slicer files of the shared corpus at Ts = 1 ms and
# prints MB/s, moves/s, samples/s and peak RSS.
#   scripts/bench.sh [CORPUS_DIR] [MACHINE]   (defaults: ../shared/corpus, machines/kossel.yaml)
set -euo pipefail
cd "$(dirname "$0")/.."
corpus=${1:-../shared/corpus}
machine=${2:-machines/kossel.yaml}
out=target/corpus
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/delta-gcode
printf '%-50s %8s %8s %9s %10s %12s %9s\n' file MB wall_s MB/s moves/s samples/s rss_MB
for xz in "$corpus"/*.gcode.xz; do
  g="$out/$(basename "$xz" .xz)"
  [ -f "$g" ] || xz -dkc "$xz" > "$g"
  # One warm-up run so the file is in the page cache.
  "$bin" check -q --format json -m "$machine" "$g" > /dev/null || true
  start=$(date +%s.%N)
  /usr/bin/time -v -o "$out/time.txt" "$bin" check -q --format json -m "$machine" "$g" > "$out/report.json" || true
  end=$(date +%s.%N)
  rss_kb=$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$out/time.txt")
  python3 - "$g" "$start" "$end" "$rss_kb" "$out/report.json" <<'PY'
import json, os, sys
path, start, end, rss_kb, report = sys.argv[1:]
wall = float(end) - float(start)
mb = os.path.getsize(path) / 1e6
s = json.load(open(report))["summary"]
print(f"{os.path.basename(path):<50} {mb:8.2f} {wall:8.3f} {mb / wall:9.1f} {s['moves'] / wall:10.0f} "
      f"{s['samples'] / wall:12.0f} {int(rss_kb) / 1024:9.1f}")
PY
done
