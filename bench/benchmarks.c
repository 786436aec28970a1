/* benchmarks.c -- the benchmark program of DESIGN 8: dispatches to the
 * named cases.  Timings are reported, never asserted. */
#include "bench.h"
#include "soilsim.h"

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

int bench_engine_flag(const char *arg)
{
  static const char *const engines[] = {"--raisim", "--mujoco", "--bullet", "--chrono",
                                        "--dart",   "--drake",  "--ode",    "--physx",
                                        "--soilsim", NULL};
  for (int k = 0; engines[k]; k++)
    if (!strcmp(arg, engines[k])) return 1;
  return 0;
}

int bench_csv_prepare(const char *who, const char *path, const char *header)
{
  FILE *f = fopen(path, "a+");
  if (!f) {
    fprintf(stderr, "benchmarks: %s: cannot open --csv file '%s': %s\n", who, path,
            strerror(errno));
    return 0;
  }
  /* "a+" reads from the start and writes at the end */
  char line[512];
  size_t hl = strlen(header);
  int bad = 0, empty = fseek(f, 0, SEEK_END) == 0 && ftell(f) == 0;
  if (empty) {
    bad = fprintf(f, "%s\n", header) < 0;
  } else {
    rewind(f);
    int same = fgets(line, sizeof line, f) && !strncmp(line, header, hl) &&
               (line[hl] == '\n' || (line[hl] == '\r' && line[hl + 1] == '\n'));
    if (!same) {
      fclose(f);
      fprintf(stderr, "benchmarks: %s: --csv file '%s' holds other columns (its first line "
                      "is not this case's header: %s); give a new file\n", who, path, header);
      return 0;
    }
  }
  if (fclose(f) || bad) {
    fprintf(stderr, "benchmarks: %s: cannot write --csv file '%s'\n", who, path);
    return 0;
  }
  return 1;
}

void bench_print_error(const ssError *e, const char *file)
{
  const char *f = e->file[0] ? e->file : file;
  if (e->line > 0)
    fprintf(stderr, "benchmarks: %s:%d: error: %s\n", f, e->line, e->message);
  else
    fprintf(stderr, "benchmarks: %s: error: %s\n", f, e->message);
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
