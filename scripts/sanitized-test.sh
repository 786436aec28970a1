#!/bin/sh
# sanitized-test.sh -- runs one C test of the sanitized suite; the CHECKER
# (automake's LOG_COMPILER) that scripts/check-sanitized.sh passes to
# `make test`.
#
# usage: scripts/sanitized-test.sh TEST [ARGS...]
#
# Everything runs as it is, with one exception: tests/test_render runs
# without LeakSanitizer.  Its leak reports (a few 56-byte blocks) are
# allocated from code in no module at exit: the GL driver that Mesa's EGL
# loads with dlopen and unloads again, so the stacks name nothing a
# suppression could match, and unwinding through it slowly (ASan's
# fast_unwind_on_malloc=0) makes the test take over ten minutes.  The
# renderer's own allocations are still leak-checked: by valgrind in
# scripts/check-valgrind.sh (two rendered frames, clean) and by LSan in
# tests/test_cli.sh (soilsim --render).  Address errors are still checked.
case $1 in
  */test_render | test_render)
    ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
    export ASAN_OPTIONS
    ;;
esac
exec "$@"
