#!/usr/bin/env bash
# The three emulation tasks of thesis 8.7, from the layouts in examples/layouts:
#   clear:  an empty table is shown        -> push the start scene's objects off the table
#   lift:   an object is shown held up     -> bring another object there and lift it
#   close:  two objects are shown together -> bring two apart objects together
# Usage: bash examples/emulate.sh MODEL [clear|lift|close|all]
set -euo pipefail
model=${1:?usage: emulate.sh MODEL [clear|lift|close|all]}
task=${2:-all}
# the repository's afford, wherever this is run from (AFFORD overrides it)
repo=$(cd "$(dirname "$0")/.." && pwd)
afford=${AFFORD:-$repo/.venv/bin/afford}
here=$(dirname "$0")/layouts
run() { echo "== $1"; "$afford" emulate "$model" --observe "$here/$2" --start "$here/$3"; }
case "$task" in
  clear) run clear empty-table.toml clear-start-1.toml ;;
  lift)  run lift lifted-shown.toml lift-start-1.toml ;;
  close) run close close-shown.toml close-start-1.toml ;;
  all)   run clear empty-table.toml clear-start-1.toml
         run lift lifted-shown.toml lift-start-1.toml
         run close close-shown.toml close-start-1.toml ;;
  *) echo "unknown task $task" >&2; exit 2 ;;
esac
