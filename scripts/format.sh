#!/usr/bin/env bash
# The project's C++ sources (src, tests, bench, fuzz: *.cpp and *.hpp; not the fuzz corpora)
# against .clang-format.
#   scripts/format.sh check   list the files clang-format would change; exit 1 when there are any
#   scripts/format.sh fix     reformat them in place
# CLANG_FORMAT names the program (default: clang-format, Debian's package of that name).
set -euo pipefail

cd "$(dirname "$0")/.."
mode="${1:-check}"
clang_format="${CLANG_FORMAT:-clang-format}"

if ! command -v "$clang_format" >/dev/null 2>&1; then
  echo "format: $clang_format not found; run scripts/install-deps.sh (Debian package clang-format)" >&2
  exit 2
fi

files=()
while IFS= read -r -d '' f; do
  files+=("$f")
done < <(find src tests bench fuzz -path fuzz/corpus -prune -o \
           -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0 | sort -z)

case "$mode" in
  check)
    bad=()
    for f in "${files[@]}"; do
      if ! "$clang_format" --dry-run --Werror "$f" >/dev/null 2>&1; then
        bad+=("$f")
      fi
    done
    if [ ${#bad[@]} -eq 0 ]; then
      echo "format: ${#files[@]} files match .clang-format"
      exit 0
    fi
    echo "format: ${#bad[@]} of ${#files[@]} files differ from .clang-format ($("$clang_format" --version | sed 's/.*version //')):" >&2
    printf '  %s\n' "${bad[@]}" >&2
    echo "format: run \`make format\` (scripts/format.sh fix) to reformat them; \`clang-format --dry-run FILE\` shows the changes" >&2
    exit 1
    ;;
  fix)
    "$clang_format" -i "${files[@]}"
    echo "format: ${#files[@]} files formatted"
    ;;
  *)
    echo "usage: $0 check|fix" >&2
    exit 2
    ;;
esac
