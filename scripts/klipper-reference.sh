#!/usr/bin/env bash
# Remakes the Klipper references of tests/fixtures/klipper-ref from real Klipper.
#
#   KLIPPER_DIR=… KLIPPER_PY=… KLIPPER_DICT=… [KLIPPER_COMMIT=…] scripts/klipper-reference.sh [OUT_DIR]
#
# Needs a Klipper checkout that runs (KLIPPER_DIR, with KLIPPER_PY a Python that has
# Klipper's klippy requirements) and the data dictionary of an MCU build (KLIPPER_DICT,
# e.g. the atmega2560 one of Klipper's test suite), both made as Klipper's own docs say,
# outside this repository; and numpy for the decoder. Klipper runs each file in batch mode
# (klippy.py -i FILE -o OUT.serial -d DICT) through scripts/klipper/klippy_batch.py, which
# only makes batch-mode homing read back the step position as a real MCU would (needed
# with [input_shaper]); its own parsedump.py decodes the MCU commands; decode_steps.py
# turns the step commands into carriage heights; make_fixture.py writes the fixtures.
set -euo pipefail
: "${KLIPPER_DIR:?set KLIPPER_DIR}" "${KLIPPER_PY:?set KLIPPER_PY}" "${KLIPPER_DICT:?set KLIPPER_DICT}"
here=$(cd "$(dirname "$0")" && pwd)
fix="$here/../tests/fixtures/klipper-ref"
out=${1:-$(mktemp -d)}
mkdir -p "$out"
commit=${KLIPPER_COMMIT:-$(git -C "$KLIPPER_DIR" rev-parse HEAD 2>/dev/null || echo unknown)}
for cfg in printer printer_shaper; do
  suffix=${cfg#printer}
  for name in hand arcs6000 bunny3000; do
    run="$out/$name$suffix"
    KLIPPY_BATCH_HOMING_FIX=1 "$KLIPPER_PY" "$here/klipper/klippy_batch.py" "$KLIPPER_DIR" \
      "$fix/$cfg.cfg" -i "$fix/$name.gcode" -o "$run.serial" -d "$KLIPPER_DICT" -l "$run.log"
    "$KLIPPER_PY" "$KLIPPER_DIR/klippy/parsedump.py" "$KLIPPER_DICT" "$run.serial" > "$run.dump.txt"
    "$KLIPPER_PY" "$here/klipper/decode_steps.py" --cfg "$fix/$cfg.cfg" --dict "$KLIPPER_DICT" \
      --dump "$run.dump.txt" --out "$run" --full
    python3 "$here/klipper/make_fixture.py" "$run" "$fix/$name$suffix" --commit "$commit"
  done
done
echo "references rewritten in $fix (runs in $out)"
