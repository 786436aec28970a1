#!/bin/sh
# check-valgrind.sh -- soilsim on the main scenes under valgrind (memcheck).
#
# usage: scripts/check-valgrind.sh [SOILSIM]     (default: ./soilsim)
#
# Runs each scene for a few steps with every output switched on (export,
# CSV, rut map, and a checkpoint when this soilsim writes them) under
#   valgrind --error-exitcode=1 --leak-check=full --track-origins=yes
#            --errors-for-leak-kinds=definite,possible
#            --suppressions=scripts/valgrind.supp
# (indirect leaks hang off a definite one, which is reported)
# so that an invalid read or write, a use of uninitialised memory or any
# leak fails the run.  Scenes (steps): scenes/plate.xml (20, and two
# rendered frames, which puts the OSMesa renderer under valgrind too),
# scenes/plate_arm.xml (3), and scenes/buggy.xml (2) when it exists, which
# also loads its meshes through assimp.  scripts/valgrind.supp lists what
# the libraries we link (assimp, Mesa) report about themselves; soilsim's
# own code has no suppressions.  Prints one line per scene and ends with
# `valgrind: N scenes clean` or `valgrind: N of M scenes failed` (exit 1).
# Environment: VALGRIND_STEPS_SCALE multiplies the step counts.
set -u

src=$(cd "$(dirname "$0")/.." && pwd)
soilsim=${1:-./soilsim}
scale=${VALGRIND_STEPS_SCALE:-1}

command -v valgrind >/dev/null 2>&1 ||
  { echo "check-valgrind: valgrind not found (scripts/setup.sh installs it)"; exit 1; }
[ -x "$soilsim" ] || { echo "check-valgrind: $soilsim is not built"; exit 1; }

out=$(mktemp -d "${TMPDIR:-/tmp}/soilsim-valgrind.XXXXXX") || exit 1
trap 'rm -rf "$out"' EXIT

ckpt=0
"$soilsim" --help 2>/dev/null | grep -q -- '--checkpoint' && ckpt=1

total=0
failed=0
for spec in plate:20 plate_arm:3 buggy:2; do
  name=${spec%%:*}
  steps=$(( ${spec#*:} * scale ))
  scene=$src/scenes/$name.xml
  [ -f "$scene" ] || continue
  total=$((total + 1))
  extra=""
  [ "$ckpt" -eq 1 ] && extra="--checkpoint $out/$name.ckpt@$steps"
  [ "$name" = plate ] && extra="$extra --render $out/frames --render-every $steps"
  log=$out/$name.log
  start=$(date +%s)
  # shellcheck disable=SC2086
  CI=1 valgrind --error-exitcode=1 --leak-check=full --track-origins=yes \
    --errors-for-leak-kinds=definite,possible --num-callers=30 \
    --suppressions="$src/scripts/valgrind.supp" --log-file="$log" \
    "$soilsim" "$scene" --steps "$steps" --quiet --export "$out/$name.xml" \
    --csv "$out/$name.csv" --rut-map "$out/$name.png" --size 160x120 $extra
  rc=$?
  took=$(( $(date +%s) - start ))
  summary=$(grep -E 'ERROR SUMMARY' "$log" | tail -n 1 | sed 's/^==[0-9]*== //')
  if [ "$rc" -eq 0 ]; then
    printf 'ok    valgrind %s (%s steps, %s s): %s\n' "$name" "$steps" "$took" "$summary"
  else
    failed=$((failed + 1))
    printf 'FAIL  valgrind %s (%s steps, exit %s): %s\n' "$name" "$steps" "$rc" "$summary"
    sed -n '/Invalid\|uninitialised\|definitely lost\|indirectly lost\|possibly lost\|Mismatched\|Syscall param/,/^==[0-9]*== $/p' "$log" |
      head -n 60 | sed 's/^/      /'
    mkdir -p valgrind-logs 2>/dev/null && cp "$log" "valgrind-logs/$name.log" 2>/dev/null &&
      echo "      full log: valgrind-logs/$name.log"
  fi
done

if [ "$failed" -eq 0 ]; then
  echo "valgrind: $total scenes clean"
else
  echo "valgrind: $failed of $total scenes failed"
  exit 1
fi
