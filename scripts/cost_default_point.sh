#!/bin/sh
# rvsm cost of the default design point on every built-in scene with the least-squares
# inverse, under both threshold rules, noise off and on (k = 1): docs/fixed-point.md.
# Usage: scripts/cost_default_point.sh [OUTDIR]   (one JSON per run in OUTDIR)
set -e
OUT=${1:-out/cost}
RVSM=${RVSM:-.venv/bin/rvsm}
mkdir -p "$OUT"
$RVSM config new -o "$OUT/point.toml"
sed 's/^enabled = false/enabled = true/' "$OUT/point.toml" > "$OUT/point-noise.toml"
for rule in equal response; do
  for pt in point point-noise; do
    for s in character teapot coin grasshopper flyball driving; do
      $RVSM cost "$s" --fixed "$OUT/$pt.toml" --method inverse --thresholds "$rule" --json \
        > "$OUT/$rule-$pt-$s.json"
      echo "$rule $pt $s done"
    done
  done
done
