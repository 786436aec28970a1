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

/* An engine flag (--raisim, --mujoco, --bullet, --chrono, --dart, --drake,
 * --ode, --physx, --soilsim): accepted and ignored, so that one command
 * line can drive several engines' benchmarks (DESIGN 8).  1 when arg is
 * one. */
int bench_engine_flag(const char *arg);

/* A --csv file made ready before any run, so that a bad path costs no
 * benchmark: a new or empty file gets the header; an existing one must
 * start with that header (rows of another layout are not mixed in).  0,
 * with a message naming who ("render", "deformable_terrain"), when it
 * cannot be opened or written or holds another header (exit 1). */
int bench_csv_prepare(const char *who, const char *path, const char *header);

/* A library error as the command line prints it: FILE:LINE (the line
 * left out where it is not known) and the message; file is used where the
 * error names none. */
struct ssError;
void bench_print_error(const struct ssError *e, const char *file);

/* The project's buggy scene (scenes/buggy.xml) into out: under
 * $top_srcdir, next to the executable, its parent, the source tree named
 * in the build folder's Makefile (out-of-tree), else the working folder or
 * its parent.  0 when none exists. */
int bench_default_scene(char *out, size_t len);

#endif
