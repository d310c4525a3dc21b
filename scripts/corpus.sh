# Sourced by the measuring scripts: the corpus's files decompressed once into target/corpus,
# and the Kossel profile with an input shaper.
out=target/corpus
mkdir -p "$out"

# The G-code of corpus file "$1" (a .gcode.xz), decompressed once; prints its path.
corpus_file() {
  local g
  g="$out/$(basename "$1" .xz)"
  [ -f "$g" ] || xz -dkc "$1" > "$g"
  echo "$g"
}

# machines/kossel.yaml with an MZV input shaper at 40 Hz on X and Y; prints its path.
shaper_profile() {
  local shaped="$out/kossel-shaper.yaml"
  {
    cat machines/kossel.yaml
    printf '\ninput_shaper:\n  shaper_type: mzv\n  shaper_freq_x: 40\n  shaper_freq_y: 40\n'
  } > "$shaped"
  echo "$shaped"
}
