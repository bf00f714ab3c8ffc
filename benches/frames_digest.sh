#!/usr/bin/env bash
# Digests of small frames of every built-in scene with every sampler, and of the Cornell box
# with every classical method: one line per run, `scene sampler|method frame sha256`. Two
# builds that print the same lines render the same bits (on the same adapter). Used to show
# that a refactor changed no frame:
#   benches/frames_digest.sh target/release/irad > after.txt
#   benches/frames_digest.sh /path/to/old/irad > before.txt; diff before.txt after.txt
# Options after the binary go to every render (e.g. --backend gl). About 3 minutes on 2 cores.
set -euo pipefail
bin=${1:?usage: frames_digest.sh IRAD_BINARY [RENDER FLAGS...]}
shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
digest() { # label, then render arguments
  local label=$1
  shift
  rm -rf "$out/r"
  "$bin" render "$@" --out "$out/r" "${extra[@]}" >/dev/null 2>"$out/err" || {
    echo "$label FAILED: $(tail -1 "$out/err")"
    return
  }
  for f in "$out"/r/frame_*.exr; do
    echo "$label $(basename "$f" .exr) $(sha256sum "$f" | cut -c1-16)"
  done
}
extra=("$@")
for scene in cornell cornell-orbit cornell-light cornell-box two-rooms furnace; do
  for sampler in uniform cdf mh frozen rejection smc rmsmc; do
    digest "$scene $sampler" "$scene" --sampler "$sampler" --size 32x32 --frames 0..3 --vpls 64
  done
done
digest "atrium mh" atrium --sampler mh --size 32x32 --frames 0..2 --vpls 64
for method in progressive hierarchical stochastic; do
  digest "cornell $method" cornell --method "$method" --size 16x16 --frames 0..2
done
