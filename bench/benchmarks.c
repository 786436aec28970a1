/* benchmarks.c -- the benchmark program of DESIGN 8: dispatches to the
 * named cases.  Timings are reported, never asserted. */
#include "bench.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

static int file_exists(const char *p)
{
  return access(p, R_OK) == 0;
}

int bench_default_scene(char *out, size_t len)
{
  const char *rel = "scenes/buggy.xml";
  const char *top = getenv("top_srcdir");
  if (top && *top) {
    snprintf(out, len, "%s/%s", top, rel);
    if (file_exists(out)) return 1;
  }
  char exe[PATH_MAX];
  ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    exe[n] = 0;
    char *slash = strrchr(exe, '/');
    if (slash) {
      *slash = 0;
      snprintf(out, len, "%s/%s", exe, rel);
      if (file_exists(out)) return 1;
      snprintf(out, len, "%s/../%s", exe, rel);
      if (file_exists(out)) return 1;
      char mk[PATH_MAX + 16];
      snprintf(mk, sizeof mk, "%s/Makefile", exe);
      FILE *f = fopen(mk, "r");
      if (f) {
        char line[PATH_MAX + 64];
        int found = 0;
        while (!found && fgets(line, sizeof line, f)) {
          if (strncmp(line, "abs_top_srcdir = ", 17) != 0) continue;
          char *v = line + 17;
          v[strcspn(v, "\r\n")] = 0;
          snprintf(out, len, "%s/%s", v, rel);
          found = file_exists(out);
        }
        fclose(f);
        if (found) return 1;
      }
    }
  }
  /* last, the working folder and its parent */
  snprintf(out, len, "%s", rel);
  if (file_exists(out)) return 1;
  snprintf(out, len, "../%s", rel);
  return file_exists(out);
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
