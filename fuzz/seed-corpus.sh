#!/bin/sh
# seed-corpus.sh -- gather the seed corpora of the fuzz targets.
#
# usage: fuzz/seed-corpus.sh SRCDIR OUTDIR [FUZZ_CHECKPOINT]
#
# Makes OUTDIR/scene, OUTDIR/urdf, OUTDIR/mesh and OUTDIR/checkpoint
# (emptied first) and copies into them the project's own inputs:
#   scene       scenes/*.xml, tests/data/*.xml, tests/data/bad/*.xml,
#               fuzz/seeds/scene/*.xml (small scenes, one per feature)
#   urdf        assets/*/*.urdf, tests/data/urdf/*.urdf,
#               tests/data/urdf/bad/*.urdf
#   mesh        tests/data/urdf/meshes/*, assets/*/meshes/* (at most 64 KiB)
#   checkpoint  written by FUZZ_CHECKPOINT (the built fuzz_checkpoint
#               target, optional) for its own world: checkpoints restore
#               only into the world that wrote them
# Files are named after their source path, so nothing collides.  Seeds are
# only a starting point: libFuzzer keeps what it learns in its own corpus
# folder (fuzz/corpus/NAME in the build folder, see fuzz/run.sh).
set -eu

[ $# -ge 2 ] || { echo "usage: $0 SRCDIR OUTDIR [FUZZ_CHECKPOINT]" >&2; exit 2; }
src=$1
out=$2
ckpt_target=${3:-}

# copy_to NAME FILE...: copy each regular file, named after its path
copy_to() {
  dest=$out/$1
  shift
  for f in "$@"; do
    [ -f "$f" ] || continue
    size=$(wc -c <"$f")
    [ "$size" -le 65536 ] || continue
    rel=${f#"$src"/}
    cp "$f" "$dest/$(printf '%s' "$rel" | tr '/' '_')"
  done
}

for n in scene urdf mesh checkpoint; do
  rm -rf "${out:?}/$n"
  mkdir -p "$out/$n"
done

copy_to scene "$src"/scenes/*.xml "$src"/tests/data/*.xml \
  "$src"/tests/data/bad/*.xml "$src"/fuzz/seeds/scene/*.xml
copy_to urdf "$src"/assets/*/*.urdf "$src"/tests/data/urdf/*.urdf \
  "$src"/tests/data/urdf/bad/*.urdf
copy_to mesh "$src"/tests/data/urdf/meshes/* "$src"/assets/*/meshes/*

# checkpoints come from the target itself (SS_FUZZ_WRITE_SEEDS)
if [ -n "$ckpt_target" ] && [ -x "$ckpt_target" ]; then
  SS_FUZZ_WRITE_SEEDS=$out/checkpoint "$ckpt_target" >/dev/null 2>&1 ||
    echo "seeds: warning: $ckpt_target could not write checkpoint seeds" >&2
fi

for n in scene urdf mesh checkpoint; do
  printf 'seeds: %s: %s files\n' "$n" "$(ls "$out/$n" | wc -l)"
done
