#!/bin/sh
# check-sanitized.sh -- the whole test suite built with AddressSanitizer,
# LeakSanitizer and UndefinedBehaviorSanitizer (clang).
#
# usage: scripts/check-sanitized.sh [BUILDDIR]
#
# Configures the source tree out of tree in BUILDDIR (default: build-asan in
# the source root, which git ignores; `make check-asan` uses build-asan in
# its build folder; a source tree configured in place is copied to
# BUILDDIR/tree first, see below) with
#   CC=clang CFLAGS="-fsanitize=address,undefined,float-cast-overflow
#     -fno-sanitize-recover=all -fno-omit-frame-pointer -O1 -g"
# builds everything and runs `make test` there: every C test and the shell
# tests (which run the sanitized soilsim), ending with the usual line
# `N passed, N failed`.  Any sanitizer report makes the program that hit it
# exit non-zero, so its test fails (and its log shows the report); no
# undefined-behaviour report is recoverable or suppressed.  The normal
# build is not touched.  Reconfigures only when the flags changed.
#
# Environment: SANITIZE_CC (default clang), SANITIZE_FLAGS (replaces the
# -fsanitize flags above), JOBS (default 2).  Leaks inside Mesa/LLVM
# (the renderer) and assimp are suppressed (fuzz/lsan.supp); ours are not.
# The C tests run through scripts/sanitized-test.sh, which turns leak
# checking off for tests/test_render only (why: see that script).
# Exit status: that of `make test` (0 when everything passed).
set -eu

src=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$src/build-asan}
cc=${SANITIZE_CC:-clang}
san=${SANITIZE_FLAGS:--fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all}
cflags="$san -fno-omit-frame-pointer -O1 -g"
jobs=${JOBS:-2}

say() { printf 'check-sanitized: %s\n' "$*"; }

command -v "$cc" >/dev/null 2>&1 ||
  { say "error: $cc not found (scripts/setup.sh installs clang)"; exit 1; }
[ -x "$src/configure" ] ||
  { say "error: no $src/configure (run scripts/setup.sh or autoreconf -fi)"; exit 1; }

mkdir -p "$build"
build=$(cd "$build" && pwd)

# A source tree configured in place (scripts/setup.sh builds that way)
# cannot have a second, out-of-tree build: configure refuses.  Then the
# sanitized build works on a copy of the sources in BUILDDIR/tree (git's
# file list, plus the generated configure files git ignores), refreshed on
# every run with the files' times kept, so only what changed is rebuilt.
if [ -f "$src/config.status" ]; then
  tree=$build/tree
  mkdir -p "$tree"
  if git -C "$src" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    (cd "$src" && {
      git ls-files -co --exclude-standard -z
      for f in configure Makefile.in aclocal.m4 config.h.in build-aux/*; do
        [ -f "$f" ] && printf '%s\0' "$f"
      done
    } | xargs -0 cp -a --parents -t "$tree" 2>/dev/null)
  else
    (cd "$src" && tar cf - --exclude='./build-*' --exclude='*.o' \
      --exclude='*.a' --exclude='.deps' --exclude='./config.status' \
      --exclude='./config.log' --exclude='./config.h' --exclude='./Makefile' \
      --exclude='./stamp-h1' --exclude='./soilsim' --exclude='./fuzz/obj' .) |
      (cd "$tree" && tar xf -)
  fi
  [ -x "$tree/configure" ] ||
    { say "error: could not copy the sources to $tree"; exit 1; }
  configure=$tree/configure
  cd "$tree"
else
  configure=$src/configure
  cd "$build"
fi
stamp="CC=$cc CFLAGS=$cflags"
if [ ! -f Makefile ] || [ ! -f config.status ] ||
   [ "$(cat .sanitize-flags 2>/dev/null)" != "$stamp" ] ||
   [ -n "$(find "$configure" -newer config.status 2>/dev/null)" ]; then
  say "configuring $(pwd) ($stamp)"
  "$configure" CC="$cc" CFLAGS="$cflags" LDFLAGS="$san" >configure.log 2>&1 ||
    { say "error: configure failed (see $(pwd)/config.log)"; exit 1; }
  printf '%s\n' "$stamp" >.sanitize-flags
fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}"
export LSAN_OPTIONS="suppressions=$src/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

say "building and running the suite in $(pwd) (make -j$jobs test)"
make -j"$jobs" test CHECKER="$src/scripts/sanitized-test.sh"
