#!/usr/bin/env bash
# Times `delta-gcode check` (release build, Ts = 1 ms) on the shared corpus, with the Kossel
# profile and the same profile with an input shaper, side by side in one run with
# klipper_estimator (print time only) when KLIPPER_ESTIMATOR names its binary; prints wall
# and CPU (user + sys) seconds, MB/s, moves/s and peak RSS for each.
#   KLIPPER_ESTIMATOR=/path/to/klipper_estimator scripts/bench.sh [CORPUS_DIR] [RUNS]
# (defaults: ../shared/corpus, 3 rounds per file, each running every tool once in turn; the
# fastest wall time of each tool shown, and its ratio to klipper_estimator's, x_est).
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

# Runs "$@" once; prints its wall, user+sys and RSS. The wall time is taken with
# nanoseconds (time's own has 10 ms steps: 0 on the small files); the output is kept in
# $out/stdout.txt.
run_once() {
  local start end user sys rss
  start=$(date +%s.%N)
  /usr/bin/time -f '%U %S %M' -o "$out/time.txt" "$@" > "$out/stdout.txt" 2> /dev/null || true
  end=$(date +%s.%N)
  # The last line: a failing run (a file the profile rejects) has a note before it.
  read -r user sys rss < <(tail -n 1 "$out/time.txt")
  echo "$(echo "$end - $start" | bc) $(echo "$user + $sys" | bc) $rss"
}

printf '%-44s %-22s %8s %8s %8s %8s %10s %8s %8s\n' file tool MB wall_s cpu_s MB/s moves/s rss_MB x_est
for xz in "$corpus"/*.gcode.xz; do
  g=$(corpus_file "$xz")
  mb=$(echo "scale=2; $(stat -c %s "$g") / 1000000" | bc)
  names=("check kossel" "check $(basename "$shaped" .yaml)")
  if [ -n "${KLIPPER_ESTIMATOR:-}" ] && [ -x "$KLIPPER_ESTIMATOR" ]; then
    names+=("klipper_estimator")
  fi
  # The tools' command lines on this file, in the order of names.
  cmd0=("$bin" check -q --format json -m machines/kossel.yaml "$g")
  cmd1=("$bin" check -q --format json -m "$shaped" "$g")
  # --format json: its text output also prints a layer-time table.
  cmd2=("${KLIPPER_ESTIMATOR:-}" --config_file scripts/klipper_estimator.json5 estimate
    --format json "$g")
  # A warm-up of each, then rounds of one run of each tool in turn, so that the tools
  # compared see the same machine (a shared machine's speed drifts by tens of percent
  # within a minute); the fastest of $runs rounds is kept for each.
  best=()
  for i in "${!names[@]}"; do
    declare -n cmd="cmd$i"
    "${cmd[@]}" > /dev/null 2>&1 || true
    best+=("")
  done
  moves=0
  for _ in $(seq "$runs"); do
    for i in "${!names[@]}"; do
      declare -n cmd="cmd$i"
      line=$(run_once "${cmd[@]}")
      if [ "$i" = 0 ]; then
        moves=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["summary"]["moves"])' "$out/stdout.txt" 2> /dev/null || echo 0)
      fi
      if [ -z "${best[$i]}" ] || [ "$(echo "${line%% *} < ${best[$i]%% *}" | bc)" = 1 ]; then
        best[i]=$line
      fi
    done
  done
  est_wall=""
  [ "${#names[@]}" = 3 ] && est_wall=${best[2]%% *}
  for i in "${!names[@]}"; do
    read -r wall cpu rss <<< "${best[$i]}"
    ratio=-
    [ -n "$est_wall" ] && ratio=$(printf '%.2f' "$(echo "$wall / $est_wall" | bc -l)")
    printf '%-44s %-22s %8s %8.3f %8.3f %8.1f %10.0f %8.1f %8s\n' "$(basename "$g")" "${names[$i]}" \
      "$mb" "$wall" "$cpu" "$(echo "$mb / $wall" | bc -l)" "$(echo "$moves / $wall" | bc -l)" \
      "$(echo "$rss / 1024" | bc -l)" "$ratio"
  done
done
