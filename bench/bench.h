/* bench.h -- the benchmark program's cases (DESIGN 8). */
#ifndef SS_BENCH_H
#define SS_BENCH_H

#include <stddef.h>

/* `benchmarks --bench render [options]`: milliseconds per frame of a scene
 * (default: the buggy on its bed at 1280x720).  Returns the exit status. */
int bench_render(int argc, char **argv);

/* `benchmarks --bench deformable_terrain -- [options]` (DESIGN 8). */
int bench_terrain(int argc, char **argv);

/* s as a whole decimal integer within [lo, hi] into *v; 0 (v untouched)
 * when it is not one */
int bench_parse_long(const char *s, long lo, long hi, long *v);

/* The project's buggy scene (scenes/buggy.xml) into out: under
 * $top_srcdir, next to the executable, its parent, the source tree named
 * in the build folder's Makefile (out-of-tree), else the working folder or
 * its parent.  0 when none exists. */
int bench_default_scene(char *out, size_t len);

#endif
