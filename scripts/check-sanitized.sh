#!/bin/sh
# check-sanitized.sh -- the whole test suite built with AddressSanitizer,
# LeakSanitizer and UndefinedBehaviorSanitizer (clang).
#
# usage: scripts/check-sanitized.sh [BUILDDIR]
#
# Configures the source tree out of tree in BUILDDIR (default: build-asan in
# the source root, which git ignores; `make check-asan` passes nothing, so
# the same) with
#   CC=clang CFLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all
#     -fsanitize-recover=nonnull-attribute,pointer-overflow,float-cast-overflow
#     -fno-omit-frame-pointer -O1 -g"
# builds everything and runs `make test` there: every C test and the shell
# tests (which run the sanitized soilsim), ending with the usual line
# `N passed, N failed`.  Any sanitizer report makes the program that hit it
# exit non-zero, so its test fails (and its log shows the report), with
# two exceptions: the known reports listed in fuzz/ubsan.supp (each with
# its fix), which is why those three checks are built recoverable; any other
# report of them still stops the program (halt_on_error=1).  The normal
# build is not touched.  Reconfigures only when the flags changed.
#
# Environment: SANITIZE_CC (default clang), SANITIZE_FLAGS (replaces the
# -fsanitize flags above), JOBS (default 2).  Leaks inside Mesa/LLVM
# (the renderer) and assimp are suppressed (fuzz/lsan.supp); ours are not.
# Exit status: that of `make test` (0 when everything passed).
set -eu

src=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$src/build-asan}
cc=${SANITIZE_CC:-clang}
san=${SANITIZE_FLAGS:--fsanitize=address,undefined -fno-sanitize-recover=all -fsanitize-recover=nonnull-attribute,pointer-overflow,float-cast-overflow}
cflags="$san -fno-omit-frame-pointer -O1 -g"
jobs=${JOBS:-2}

say() { printf 'check-sanitized: %s\n' "$*"; }

command -v "$cc" >/dev/null 2>&1 ||
  { say "error: $cc not found (scripts/setup.sh installs clang)"; exit 1; }
[ -x "$src/configure" ] ||
  { say "error: no $src/configure (run scripts/setup.sh or autoreconf -fi)"; exit 1; }

mkdir -p "$build"
cd "$build"
stamp="CC=$cc CFLAGS=$cflags"
if [ ! -f Makefile ] || [ ! -f config.status ] ||
   [ "$(cat .sanitize-flags 2>/dev/null)" != "$stamp" ] ||
   [ -n "$(find "$src/configure" -newer config.status 2>/dev/null)" ]; then
  say "configuring $build ($stamp)"
  "$src/configure" CC="$cc" CFLAGS="$cflags" LDFLAGS="$san" >configure.log 2>&1 ||
    { say "error: configure failed (see $build/config.log)"; exit 1; }
  printf '%s\n' "$stamp" >.sanitize-flags
fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}"
export LSAN_OPTIONS="suppressions=$src/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="suppressions=$src/fuzz/ubsan.supp:print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

say "building and running the suite in $build (make -j$jobs test)"
make -j"$jobs" test
