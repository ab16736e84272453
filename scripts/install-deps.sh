#!/usr/bin/env bash
# Installs what overtake needs to build and test, from Debian's packages, by name, and the
# web pages' Node packages (web/package-lock.json) with npm ci.
# Installs only what is missing; says what it installs; uses sudo when not root.
#
# OVERTAKE_WEB=OFF scripts/install-deps.sh: for builds without the web pages (the CMake option
# OVERTAKE_WEB=OFF, e.g. the `noweb` and `asan` presets): no Node.js, npm, web/node_modules or
# Chromium (the browser test's), only what the C++ layers need.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
web_pages=true
case "${OVERTAKE_WEB:-ON}" in
  OFF|off|Off|0|NO|no|FALSE|false) web_pages=false ;;
esac

packages=(
  cmake ninja-build g++ make pkg-config
  libeigen3-dev nlohmann-json3-dev libcli11-dev libboost-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # Python planners (--policy-py) and the Python module (OVERTAKE_PYTHON), with its tests.
  python3-dev python3-pybind11 python3-numpy python3-pytest
  # The fuzz harnesses (make fuzz-smoke, make fuzz): clang, and libFuzzer with the sanitizer
  # runtimes of the same version (libclang-rt-14-dev on Debian 12).
  clang libclang-rt-dev
  # make format-check, make format and make tidy.
  clang-format clang-tidy
  # The `cluster` tests: `bench --slurm` on a Slurm cluster of their own (scripts/local-slurm.sh).
  slurmctld slurmd slurm-client munge
)
if $web_pages; then
  packages+=(chromium)
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

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${wanted} packages present"
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
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
  echo "install-deps: done"
fi

if ! $web_pages; then
  echo "install-deps: OVERTAKE_WEB=OFF: no Node.js, npm ci or Chromium (the web pages are not built)"
  exit 0
fi

# The web pages' packages: npm ci when web/node_modules is missing or was installed from
# another package-lock.json (the stamp holds the lockfile's hash; the web build checks it).
web="$root/web"
stamp="$web/node_modules/.overtake-lock-sha256"
want="$(sha256sum "$web/package-lock.json" | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "install-deps: web/node_modules up to date"
else
  echo "install-deps: npm ci in web/ ($( [ -d "$web/node_modules" ] && echo stale || echo missing ))"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
  echo "$want" > "$stamp"
  echo "install-deps: web/node_modules installed"
fi
