#!/bin/bash
# The pattern optimiser's two assignment bounds side by side, one binary
# (agent/src/formation/alignment.rs vs the interval corners; params.rs `OptimiserBound`):
# usage: optimiser-compare.sh BIN OUTROOT [SEEDS] [SIZES]. Every run of the relayed centralised
# mode with `pattern = "optimise"` (configs/formation-<size>-centralised.toml) twice, once as
# shipped (bound = "polygon") and once with `bound = "corners"` appended to a copy; one line a
# run: the first plan's cost of eq. (1), gap, nodes and optimiser seconds, then K and L.
# CORNERS_SIZES limits the corner runs (they are slow at 500: 40 nodes of six cold solves).
BIN=$1; ROOT=$2; SEEDS=${3:-"1 2 3"}; SIZES=${4:-"100 500"}
CORNERS_SIZES=${CORNERS_SIZES:-$SIZES}
mkdir -p "$ROOT"
for size in $SIZES; do
  base=configs/formation-$size-centralised.toml
  cp "$base" "$ROOT/polygon-$size.toml"
  { cat "$base"; printf '\n[formation.kernels.optimiser]\nbound = "corners"\n'; } > "$ROOT/corners-$size.toml"
  for seed in $SEEDS; do
    for bound in polygon corners; do
      case " $CORNERS_SIZES " in *" $size "*) ;; *) [ $bound = corners ] && continue ;; esac
      out=$ROOT/$bound-$size-s$seed
      "$BIN" up --scenario "$ROOT/$bound-$size.toml" --executor inprocess --seed "$seed" \
        --out "$out" --quiet > "$out.log" 2>&1
      plan=$(grep -m1 "plans epoch 1" "$out.log" | sed -E 's/.*cost ([0-9.]+):.*gap ([0-9.-]+)[^,]*, ([0-9]+) nodes, ([0-9.]+) s.*/cost \1 gap \2 nodes \3 seconds \4/')
      formed=$(grep -m1 "formation: formed at\|formation: NOT formed\|robots in place" "$out.log" | sed -E 's/^ +//')
      echo "robots $size seed $seed bound $bound | $plan | $formed"
    done
  done
done
