#!/usr/bin/env bash
# The layers of docs/architecture.md, checked on the sources: each library (a folder of src/)
# includes only the public headers of the libraries it may use, never those of a library above
# it, and only the command line (src/app) includes CLI11. Prints each include against the
# layers, with the file and line it is on, and exits 1 when there is one.
#   scripts/check-layers.sh [ROOT]   (default: the repository holding this script)
set -euo pipefail

root="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
cd "$root"

# What each library may include (besides itself): the map of docs/architecture.md.
lower="core sim planner replay protocol plugin python eval view"
declare -A may_use=(
  [core]=""
  [sim]="core"
  [planner]="core"
  [eval]="core sim planner"
  [replay]="core sim planner"
  [protocol]="core sim planner"
  [plugin]="core sim planner"
  [python]="core sim planner"
  [view]="core sim planner replay"
  [base]=""
  [sandbox]="base"
  [planners]="base sandbox $lower"
  [run]="base sandbox planners $lower"
  [scenarios]="base sandbox planners run $lower"
  [batch]="base sandbox planners run scenarios $lower"
  [cluster]="base sandbox planners run scenarios batch $lower"
  [learn]="base sandbox planners run $lower"
  [app]="base sandbox planners run scenarios batch cluster $lower"
  [pybind]="base sandbox planners run scenarios batch learn $lower"
)

problems=0
for dir in src/*/; do
  lib=$(basename "$dir")
  if [[ -z "${may_use[$lib]+set}" ]]; then
    echo "src/$lib: a library docs/architecture.md does not place (add it to scripts/check-layers.sh)"
    problems=$((problems + 1))
    continue
  fi
  allowed=" $lib ${may_use[$lib]} "
  while IFS=: read -r file line text; do
    used=$(sed -E 's/.*#include "overtake\/([a-z_]+)\/.*/\1/' <<<"$text")
    if [[ "$allowed" != *" $used "* ]]; then
      echo "$file:$line: $lib includes $used, which it may not use: $text"
      problems=$((problems + 1))
    fi
  done < <(grep -rnE '^#include "overtake/[a-z_]+/' "$dir" --include='*.cpp' --include='*.hpp' --include='*.h' || true)
  if [[ "$lib" != app ]]; then
    while IFS= read -r hit; do
      echo "$hit: only the command line (src/app) includes CLI11"
      problems=$((problems + 1))
    done < <(grep -rnE '^#include <CLI/' "$dir" | cut -d: -f1,2 || true)
  fi
done
if ((problems > 0)); then
  echo "$problems include(s) against the layers"
  exit 1
fi
echo "every include follows the layers"
