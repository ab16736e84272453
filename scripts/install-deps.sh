#!/usr/bin/env bash
# Installs what overtake needs to build and test, from Debian's packages, by name, and the
# web pages' Node packages (web/package-lock.json) with npm ci.
# Installs only what is missing; says what it installs; uses sudo when not root.
#
#   scripts/install-deps.sh [--all | --demo] [--dry-run]
#
# Two sets (scripts/install-deps.sh --help lists them):
#   --all (the default; make check): everything the build, the tests, the sanitizer and fuzz
#         builds, the format and clang-tidy checks and the cluster and browser tests need;
#   --demo (make demo): only what configuring the demo preset and building the `overtake`
#         binary and the Python module need, and what the demo and the README's lines run.
# --dry-run installs nothing: it prints the set, what it would install and whether it would run
# npm ci in web/.
#
# OVERTAKE_WEB=OFF scripts/install-deps.sh: for builds without the web pages (the CMake option
# OVERTAKE_WEB=OFF, e.g. the `noweb` and `asan` presets): no Node.js, npm, web/node_modules or
# Chromium (the browser test's), only what the C++ layers need.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"

# What `cmake --preset demo` and building its `overtake` binary and `overtake_py` module need
# (the demo preset builds no tests or benchmarks, so GoogleTest and Google Benchmark are not
# looked for), and what the README's Python lines then use: numpy.
demo_packages=(
  # The compiler and the build: CMake, Ninja (the presets' generator); make runs the Makefile.
  cmake ninja-build g++ make
  # Found at configure time (CMakeLists.txt) and linked or included by the binary.
  libeigen3-dev nlohmann-json3-dev libcli11-dev libboost-dev zlib1g-dev
  # `overtake tune`'s optimisers (NLopt, with its C++ header).
  libnlopt-cxx-dev
  # Python planners (--policy-py): the interpreter embedded in the binary (OVERTAKE_PYTHON=ON),
  # the Python module, and numpy, which the example Python planner imports.
  python3-dev python3-pybind11 python3-numpy
)
# The rest of what `make check` needs.
check_packages=(
  pkg-config
  # The release preset's tests and benchmarks (GoogleTest with gmock, Google Benchmark).
  libgtest-dev libgmock-dev libbenchmark-dev
  # The Python module's tests; `pip install --no-build-isolation .` into a fresh virtual
  # environment (test_install.py: venv, setuptools, wheel); the learning example's training
  # (examples/learning, PyTorch).
  python3-pytest python3-venv python3-setuptools python3-wheel python3-torch
  # The fuzz harnesses (make fuzz-smoke, make fuzz): clang, and libFuzzer with the sanitizer
  # runtimes of the same version (libclang-rt-14-dev on Debian 12).
  clang libclang-rt-dev
  # make format-check, make format and make tidy.
  clang-format clang-tidy
  # The `cluster` tests: `bench --slurm` on a Slurm cluster of their own (scripts/local-slurm.sh).
  slurmctld slurmd slurm-client munge
)

usage() {
  cat <<EOF
Usage: scripts/install-deps.sh [--all | --demo] [--dry-run]

Installs the Debian packages overtake needs that are missing (with sudo when not root), then
the web pages' Node packages with npm ci in web/ when web/node_modules is missing or stale.

  --all      everything (the default; make check): the build, the tests and benchmarks, the
             sanitizer and fuzz builds, format and clang-tidy, the cluster tests (Slurm, munge)
             and the browser test (Chromium):
               ${demo_packages[*]}
               ${check_packages[*]}
               chromium, and Node.js and npm (any installed node and npm will do)
  --demo     what make demo needs: configuring the demo preset, building the overtake
             binary with its web pages and the Python module, running the drive, and the
             README's Python lines (numpy):
               ${demo_packages[*]}
               Node.js and npm (any installed node and npm will do)
  --dry-run  install nothing; print the set, what would be installed, and whether npm ci
             would run
  -h, --help this text

OVERTAKE_WEB=OFF scripts/install-deps.sh: for builds without the web pages (the CMake option
OVERTAKE_WEB=OFF, e.g. the noweb and asan presets): no Node.js, npm, web/node_modules or
Chromium, in either set.
EOF
}

set_name=all
dry_run=false
for arg in "$@"; do
  case "$arg" in
    --all) set_name=all ;;
    --demo) set_name=demo ;;
    --dry-run) dry_run=true ;;
    -h|--help) usage; exit 0 ;;
    *)
      echo "install-deps: unknown argument '$arg' (scripts/install-deps.sh --help)" >&2
      exit 2
      ;;
  esac
done

web_pages=true
case "${OVERTAKE_WEB:-ON}" in
  OFF|off|Off|0|NO|no|FALSE|false) web_pages=false ;;
esac

packages=("${demo_packages[@]}")
if [ "$set_name" = all ]; then
  packages+=("${check_packages[@]}")
  if $web_pages; then
    packages+=(chromium)
  fi
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
# Node.js and npm: any installed node and npm will do (some nodejs packages bundle npm and
# conflict with Debian's npm package), so these are looked for as commands.
wanted=${#packages[@]}
if $web_pages; then
  wanted=$((wanted + 2))
  command -v node >/dev/null 2>&1 || missing+=(nodejs)
  command -v npm >/dev/null 2>&1 || missing+=(npm)
fi

# Which set, when it is not the default.
set_note=""
[ "$set_name" = demo ] && set_note=" (the demo's set)"

if $dry_run; then
  listed=("${packages[@]}")
  $web_pages && listed+=(nodejs npm)
  echo "install-deps: dry run, set ${set_name}: ${wanted} packages: ${listed[*]}"
  if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: would install nothing: all ${wanted} packages present"
  else
    echo "install-deps: would install ${missing[*]}"
  fi
elif [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${wanted} packages present${set_note}"
else
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
      sudo_cmd=(sudo)
    else
      echo "install-deps: missing packages (${missing[*]}) and not root, and no sudo to install them" >&2
      exit 1
    fi
  fi
  echo "install-deps: installing ${missing[*]}${set_note}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
  echo "install-deps: done"
fi

if ! $web_pages; then
  if [ "$set_name" = all ]; then
    echo "install-deps: OVERTAKE_WEB=OFF: no Node.js, npm ci or Chromium (the web pages are not built)"
  else
    echo "install-deps: OVERTAKE_WEB=OFF: no Node.js or npm ci (the web pages are not built)"
  fi
  exit 0
fi

# The web pages' packages: npm ci when web/node_modules is missing or was installed from
# another package-lock.json (the stamp holds the lockfile's hash; the web build checks it).
# The demo needs them too: the binary embeds the pages, and the demo writes the drive as one.
web="$root/web"
stamp="$web/node_modules/.overtake-lock-sha256"
want="$(sha256sum "$web/package-lock.json" | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "install-deps: web/node_modules up to date"
elif $dry_run; then
  echo "install-deps: would run npm ci in web/ ($( [ -d "$web/node_modules" ] && echo stale || echo missing ))"
else
  echo "install-deps: npm ci in web/ ($( [ -d "$web/node_modules" ] && echo stale || echo missing ))"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
  echo "$want" > "$stamp"
  echo "install-deps: web/node_modules installed"
fi
