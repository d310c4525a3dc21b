#!/usr/bin/env bash
# Times `delta-gcode check` (release build, Ts = 1 ms) on the shared corpus, with the Kossel
# profile and the same profile with an input shaper, side by side in one run with
# klipper_estimator (print time only) when KLIPPER_ESTIMATOR names its binary; prints wall
# and CPU (user + sys) seconds, MB/s, moves/s and peak RSS for each.
#   KLIPPER_ESTIMATOR=/path/to/klipper_estimator scripts/bench.sh [CORPUS_DIR] [RUNS]
# (defaults: ../shared/corpus, 3 runs per tool and file, the fastest wall time shown).
# klipper_estimator is built from its public source outside this repository
# (docs/performance.md); scripts/klipper_estimator.json5 gives it the profile's limits.
set -euo pipefail
cd "$(dirname "$0")/.."
corpus=${1:-../shared/corpus}
runs=${2:-3}
. scripts/corpus.sh
cargo build --release --quiet
bin=target/release/delta-gcode
shaped=$(shaper_profile)

# Runs "$@" $runs times after a warm-up; prints the fastest run's wall, user+sys, RSS. The
# wall time is taken with nanoseconds (time's own has 10 ms steps: 0 on the small files).
measure() {
  "$@" > /dev/null 2>&1 || true
  local best=""
  for _ in $(seq "$runs"); do
    local start end
    start=$(date +%s.%N)
    /usr/bin/time -f '%U %S %M' -o "$out/time.txt" "$@" > "$out/stdout.txt" 2> /dev/null || true
    end=$(date +%s.%N)
    # The last line: a failing run (a file the profile rejects) has a note before it.
    read -r user sys rss < <(tail -n 1 "$out/time.txt")
    wall=$(echo "$end - $start" | bc)
    line="$wall $(echo "$user + $sys" | bc) $rss"
    if [ -z "$best" ] || [ "$(echo "$wall < ${best%% *}" | bc)" = 1 ]; then best=$line; fi
  done
  echo "$best"
}

printf '%-44s %-22s %8s %8s %8s %8s %10s %8s\n' file tool MB wall_s cpu_s MB/s moves/s rss_MB
for xz in "$corpus"/*.gcode.xz; do
  g=$(corpus_file "$xz")
  mb=$(echo "scale=2; $(stat -c %s "$g") / 1000000" | bc)
  moves=""
  row() {
    read -r wall cpu rss <<< "$2"
    printf '%-44s %-22s %8s %8.3f %8.3f %8.1f %10.0f %8.1f\n' "$(basename "$g")" "$1" "$mb" \
      "$wall" "$cpu" "$(echo "$mb / $wall" | bc -l)" "$(echo "$moves / $wall" | bc -l)" \
      "$(echo "$rss / 1024" | bc -l)"
  }
  for profile in machines/kossel.yaml "$shaped"; do
    r=$(measure "$bin" check -q --format json -m "$profile" "$g")
    moves=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["summary"]["moves"])' "$out/stdout.txt" 2> /dev/null || echo 0)
    row "check $(basename "$profile" .yaml)" "$r"
  done
  if [ -n "${KLIPPER_ESTIMATOR:-}" ] && [ -x "$KLIPPER_ESTIMATOR" ]; then
    # --format json: its text output also prints a layer-time table.
    r=$(measure "$KLIPPER_ESTIMATOR" --config_file scripts/klipper_estimator.json5 estimate --format json "$g")
    row "klipper_estimator" "$r"
  fi
done
