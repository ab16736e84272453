#!/usr/bin/env bash
# Every repository file the documents and the sources point to exists:
#  - in README.md, docs/*.md and web/README.md: relative Markdown links, `](path)` and
#    `](path#anchor)` (relative to the document), and paths written out (`docs/replay.md`,
#    `config/overtake.json`, relative to the repository's root);
#  - in the sources' comments and strings (src, tests, bench, fuzz, cmake, scripts, web, the
#    CMake and make files): paths written out, relative to the root.
# A path written out is one that starts with a top-level folder of the repository. An anchor
# into a Markdown file must name one of its headings (GitHub's anchors: lower case, spaces to
# hyphens, punctuation dropped, -1, -2... for repeated headings). Prints each reference that
# does not resolve, with the file and line it is on, and exits 1 when there is one.
#   scripts/check-references.sh [ROOT]   (default: the repository holding this script)
set -euo pipefail

root="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
cd "$root"
# Headings may hold any letter; their anchors keep letters of every script.
if locale -a 2>/dev/null | grep -qix 'c.utf-\?8'; then
  export LC_ALL=C.UTF-8
fi

top_dirs='\.ci|bench|cmake|config|data|docs|fuzz|scripts|src|tests|web'
# Paths written out: a top-level folder, then path characters; `*` makes it a pattern that must
# match a file, and a placeholder ends it (`fuzz/corpus/<harness>/` names fuzz/corpus/).
path_re="(^|[^A-Za-z0-9_./*\${}-])(($top_dirs)/[A-Za-z0-9_./*-]*(#[A-Za-z0-9_-]+)?)"
# Outputs of the build and of npm, which the repository does not hold.
generated_re='^(build|web/node_modules|web/dist)(/|$)'

problems=0
report() {
  echo "$1: $2" >&2
  problems=$((problems + 1))
}

# The anchors of a Markdown file's headings, one a line (fenced code blocks skipped).
anchors_of() {
  awk '/^[[:space:]]*(```|~~~)/ { fenced = !fenced; next }
       !fenced && /^#+[[:space:]]/ { sub(/^#+[[:space:]]+/, ""); sub(/[[:space:]]+#*[[:space:]]*$/, ""); print }' "$1" |
    sed -e 's/\[\([^]]*\)\]([^)]*)/\1/g' |
    tr '[:upper:]' '[:lower:]' |
    sed -e 's/[^[:alnum:] _-]//g' -e 's/ /-/g' |
    awk '{ n = seen[$0]++; print (n ? $0 "-" n : $0) }'
}

# The folders a path written out in `file` may be relative to: the root, then the file's own
# folder and those above it (web/README.md and web/test/ speak of web/src/ as src/).
bases_of() {
  local dir bases="."
  dir="$(dirname "$1")"
  while [ "$dir" != "." ]; do
    bases="$bases:$dir"
    dir="$(dirname "$dir")"
  done
  echo "$bases"
}

# Checks one reference `target` (path, path#anchor or #anchor) found at `where`, relative to
# one of the folders in `bases` (colon-separated); `doc` is the document it is in.
check() {
  local where="$1" bases="$2" target="$3" doc="$4"
  local path="${target%%#*}" anchor="" file="" base candidate
  [[ "$target" == *"#"* ]] && anchor="${target#*#}"
  path="${path%.}"  # the end of a sentence
  if [ -z "$path" ]; then
    file="$doc"
  else
    IFS=: read -ra dirs <<<"$bases"
    for base in "${dirs[@]}"; do
      candidate="$(realpath -m --relative-to="$root" "$base/$path")"
      [[ "$candidate" =~ $generated_re ]] && return 0
      if [[ "$candidate" == *"*"* ]]; then
        if compgen -G "$candidate" >/dev/null; then file="$candidate"; break; fi
      elif [ -e "$candidate" ]; then
        file="$candidate"
        break
      fi
    done
  fi
  if [ -z "$file" ]; then
    report "$where" "$target: no such file or folder"
    return 0
  fi
  if [ -n "$anchor" ] && [[ "$file" == *.md ]]; then
    if ! anchors_of "$file" | grep -xF -- "$anchor" >/dev/null; then
      report "$where" "$target: $file has no heading with the anchor #$anchor"
    fi
  fi
}

# The paths written out in a file, as "FILE:LINE<tab>PATH" lines; with `files_only`, only those
# that end in a file name with an extension (in sources, `bench/replays/` may be a folder the
# code makes).
written_paths() {
  local f="$1" files_only="${2:-}"
  { grep -nE "$path_re" "$f" || true; } | while IFS= read -r hit; do
    local line="${hit%%:*}" text="${hit#*:}"
    grep -oE "$path_re" <<<"$text" | sed -E "s#^[^A-Za-z.]*(($top_dirs)/)#\1#" |
      while IFS= read -r ref; do
        if [ -n "$files_only" ] && ! [[ "${ref%%#*}" =~ /[^/]+\.[A-Za-z0-9*]+\.?$ ]]; then
          continue
        fi
        printf '%s:%s\t%s\n' "$f" "$line" "$ref"
      done
  done
}

docs=(README.md docs/*.md web/README.md)
sources=()
while IFS= read -r -d '' f; do
  sources+=("$f")
done < <(find src tests bench fuzz cmake scripts web .ci \
           \( -path fuzz/corpus -o -path web/node_modules -o -path tests/data \) -prune -o \
           -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.cmake' -o -name 'CMakeLists.txt' \
                      -o -name '*.sh' -o -name '*.mjs' -o -name '*.js' -o -name '*.ts' \
                      -o -name '*.html' -o -name '*.css' -o -name 'run' \) -print0 | sort -z)
sources+=(CMakeLists.txt CMakePresets.json Makefile)

# One reference a line: where, the folders it may be relative to, the reference, the document.
refs="$(mktemp)"
trap 'rm -f "$refs"' EXIT
for f in "${docs[@]}"; do
  # Markdown links, relative to the document (web addresses and mail are not files).
  { grep -noE '\]\([^) ]+\)' "$f" || true; } | while IFS= read -r hit; do
    line="${hit%%:*}"
    target="${hit#*:](}"
    target="${target%)}"
    case "$target" in
      http://* | https://* | mailto:*) continue ;;
    esac
    printf '%s:%s\t%s\t%s\t%s\n' "$f" "$line" "$(dirname "$f")" "$target" "$f"
  done
  written_paths "$f" | sed "s/\t/\t$(bases_of "$f" | sed 's#/#\\/#g')\t/; s/\$/\t$(sed 's#/#\\/#g' <<<"$f")/"
done >>"$refs"
for f in "${sources[@]}"; do
  written_paths "$f" files_only | sed "s/\t/\t$(bases_of "$f" | sed 's#/#\\/#g')\t/; s/\$/\t$(sed 's#/#\\/#g' <<<"$f")/"
done >>"$refs"

checked=0
while IFS=$'\t' read -r where bases target doc; do
  check "$where" "$bases" "$target" "$doc"
  checked=$((checked + 1))
done <"$refs"

if [ "$problems" -gt 0 ]; then
  echo "check-references: $problems of $checked references do not resolve" >&2
  exit 1
fi
echo "check-references: all $checked references resolve"
