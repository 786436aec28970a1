#!/bin/sh
# setup.sh -- prepare a fresh Debian 12 machine and build soilsim.
#
# usage (as root, from anywhere in the source tree):  ./scripts/setup.sh
#
# 1. installs the Debian packages that are missing (apt-get update first,
#    and only when something is missing);
# 2. generates ./configure (autoreconf -fi) when it is missing or older than
#    configure.ac / Makefile.am;
# 3. runs ./configure when there is no Makefile or config.status is stale;
# 4. builds with make -j2.
# Running it again does only what is still needed.
set -e

PACKAGES="build-essential autoconf automake pkg-config libxml2-dev \
libassimp-dev libpng-dev libosmesa6-dev libegl-dev libfreetype-dev fonts-dejavu-core \
clang libclang-rt-14-dev valgrind"
# clang, libclang-rt-14-dev (sanitizer and libFuzzer runtimes) and valgrind:
# the fuzz targets, the sanitized suite and the valgrind check that .ci/run
# runs (README, "Hostile input and faults")

say() { printf 'setup: %s\n' "$*"; }
die() { printf 'setup: error: %s\n' "$*" >&2; exit 1; }

# Work in the source tree root whatever the caller's folder.
cd "$(dirname "$0")/.."
if [ ! -f configure.ac ] || [ ! -f Makefile.am ]; then
  die "run this script from the soilsim source tree (no configure.ac here)"
fi

# 1. packages
command -v dpkg-query >/dev/null 2>&1 ||
  die "dpkg-query not found: this script is for Debian 12 (install the packages by hand: $PACKAGES)"
missing=""
for p in $PACKAGES; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing="$missing $p"
  fi
done
if [ -n "$missing" ]; then
  say "missing packages:$missing"
  if [ "$(id -u)" -ne 0 ]; then
    die "installing packages needs root; run as root, or first:
    sudo apt-get update && sudo apt-get install -y$missing"
  fi
  command -v apt-get >/dev/null 2>&1 || die "apt-get not found"
  say "running apt-get update"
  DEBIAN_FRONTEND=noninteractive apt-get update ||
    die "apt-get update failed (network? sources.list?)"
  say "installing:$missing"
  # shellcheck disable=SC2086
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $missing ||
    die "apt-get install failed for:$missing"
else
  say "all required packages are installed"
fi

# 2. configure script
newer() { [ -n "$(find "$@" -newer configure 2>/dev/null)" ]; }
if [ ! -x configure ] || [ ! -f Makefile.in ] || newer configure.ac Makefile.am; then
  say "running autoreconf -fi"
  autoreconf -fi || die "autoreconf failed"
else
  say "configure is up to date"
fi

# 3. Makefile
if [ ! -f Makefile ] || [ ! -f config.status ] ||
   [ -n "$(find configure -newer config.status 2>/dev/null)" ]; then
  say "running ./configure"
  ./configure || die "./configure failed (see config.log)"
else
  say "Makefile is up to date"
fi

# 4. build
say "running make -j2"
make -j2 || die "the build failed"
say "done: ./soilsim is built; try 'make demo' or 'make test'"
