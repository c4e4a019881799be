#!/usr/bin/env bash
# From nothing to a model: explore, discover effect categories, pick features, train,
# and measure the model on interactions it has not seen. After `make setup` (or
# `make test`), from anywhere: bash examples/pipeline.sh [OUT_DIR]
set -euo pipefail
out=${1:-example-out}
# the repository's afford, wherever this is run from (AFFORD overrides it)
repo=$(cd "$(dirname "$0")/.." && pwd)
afford=${AFFORD:-$repo/.venv/bin/afford}
mkdir -p "$out"
"$afford" explore --scene table --interactions 5000 --seed 1 --workers 2 -o "$out/train.afford"
"$afford" explore --scene table --interactions 1000 --seed 2 --workers 2 -o "$out/test.afford"
"$afford" cluster "$out/train.afford" -o - \
  | "$afford" select-features - -o - \
  | "$afford" train - -o "$out/table.model.afford"
"$afford" evaluate "$out/table.model.afford" "$out/test.afford" --baselines
"$afford" inspect "$out/table.model.afford" --plots "$out/plots"
