/* benchmarks.c -- the benchmark program of DESIGN 8: dispatches to the
 * named cases.  Timings are reported, never asserted. */
#include "bench.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
  fprintf(f, "usage: benchmarks --bench NAME [-- options]\n"
             "cases:\n"
             "  deformable_terrain  bodies on soil (ms per step, ns per loaded point,\n"
             "                      sweeps, sinkage error), the buggy (real-time factor),\n"
             "                      the contact law alone (ns per visit)\n"
             "                      [--body=NAME] [--start=warm|cold] [--steps=N] [--repeats=R]\n"
             "                      [--contact-law] [--csv=FILE] ... (-- --help: all)\n"
             "  render              milliseconds per rendered frame\n"
             "                      [--scene FILE] [--size WxH] [--frames N] [--steps K] [--csv FILE]\n");
}

int bench_parse_long(const char *s, long lo, long hi, long *v)
{
  char *end;
  errno = 0;
  long x = strtol(s, &end, 10);
  if (errno || end == s || *end || x < lo || x > hi) return 0;
  *v = x;
  return 1;
}

int main(int argc, char **argv)
{
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      usage(stdout);
      return 0;
    }
    if (!strcmp(argv[i], "--bench") && i + 1 < argc) {
      const char *name = argv[i + 1];
      if (!strcmp(name, "render")) return bench_render(argc - i - 2, argv + i + 2);
      if (!strcmp(name, "deformable_terrain")) return bench_terrain(argc - i - 2, argv + i + 2);
      fprintf(stderr, "benchmarks: unknown case '%s'\n", name);
      usage(stderr);
      return 2;
    }
  }
  usage(stderr);
  return 2;
}
