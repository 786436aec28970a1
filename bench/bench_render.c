/* bench_render.c -- being written (issue 5) */
#include "bench.h"
#include <stdio.h>

int bench_render(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  fprintf(stderr, "benchmarks: the render case is not built yet\n");
  return 1;
}
