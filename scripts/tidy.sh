#!/usr/bin/env bash
# clang-tidy (the checks in .clang-tidy) over the sources in src/, with the compile commands of
# a configured build tree (default build/release: `cmake --preset release`).
#   scripts/tidy.sh [BUILD_DIR] [FILE...]
# Runs one clang-tidy per core (JOBS=N to change); prints every finding and exits 1 when there
# is one. CLANG_TIDY names the program (default: clang-tidy, Debian's package of that name).
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
build="${1:-build/release}"
shift || true
clang_tidy="${CLANG_TIDY:-clang-tidy}"
jobs="${JOBS:-$(nproc)}"

if ! command -v "$clang_tidy" >/dev/null 2>&1; then
  echo "tidy: $clang_tidy not found; run scripts/install-deps.sh (Debian package clang-tidy)" >&2
  exit 2
fi
if [ ! -f "$build/compile_commands.json" ]; then
  echo "tidy: $build/compile_commands.json is missing; configure first (cmake --preset release)" >&2
  exit 2
fi

files=("$@")
if [ ${#files[@]} -eq 0 ]; then
  while IFS= read -r -d '' f; do
    files+=("$f")
  done < <(find src -type f -name '*.cpp' -print0 | sort -z)
fi

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

# The compile commands are GCC's: clang does not know some of its warning options, and the
# compiler's own warnings are the GCC build's business (-Werror there), not clang-tidy's.
# Boost 1.74 sees clang's C++20 coroutines only when told (as CMakeLists.txt does for clang).
printf '%s\0' "${files[@]}" |
  xargs -0 -P "$jobs" -I{} sh -c '
    f="$1"; log="$2/$(printf %s "$f" | tr / _).log"
    "$3" -p "$4" --quiet --extra-arg=-Wno-unknown-warning-option --extra-arg=-Wno-error \
         --extra-arg=-DBOOST_ASIO_HAS_CO_AWAIT=1 "$f" >"$log" 2>&1 || echo "$f" >>"$2/failed"
  ' _ {} "$out" "$clang_tidy" "$build"

findings=0
for log in "$out"/*.log; do
  if grep -q 'warning:\|error:' "$log"; then
    # clang-tidy's summary lines ("N warnings generated.") are noise once the findings are shown.
    grep -v '^[0-9]* warnings\? generated\.$\|^Suppressed [0-9]* warnings' "$log"
    findings=$((findings + $(grep -c ': \(warning\|error\): ' "$log")))
  fi
done
if [ -f "$out/failed" ] || [ "$findings" -gt 0 ]; then
  echo "tidy: ${findings} finding(s) in ${#files[@]} files" >&2
  exit 1
fi
echo "tidy: ${#files[@]} files clean"
