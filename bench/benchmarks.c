/* benchmarks.c -- the benchmark program of DESIGN 8: dispatches to the
 * named cases.  Timings are reported, never asserted. */
#include "bench.h"
#include "soilsim.h"
#include "articulated.h"
#include "urdf.h"

#include <errno.h>
#include <stdarg.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
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
             "  load                milliseconds per model load of generated inputs: a URDF\n"
             "                      chain and a wide tree (parse and build), scenes of boxes,\n"
             "                      spheres and <pair_prop>s\n"
             "                      [--count N] [--repeats R]\n"
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

/* ---------------------------------------------------------------------- */
/* load: building models of many objects                                   */

/* A growing text buffer for the generated inputs. */
typedef struct textBuf {
  char *s;
  size_t n, cap;
  int bad;  /* out of memory */
} textBuf;

static void tb_add(textBuf *b, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void tb_add(textBuf *b, const char *fmt, ...)
{
  for (int pass = 0; pass < 2 && !b->bad; pass++) {
    va_list ap;
    va_start(ap, fmt);
    int w = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
    va_end(ap);
    if (w < 0) {
      b->bad = 1;
    } else if (b->s && (size_t)w < b->cap - b->n) {
      b->n += (size_t)w;
      return;
    } else {
      size_t c = b->cap ? b->cap : 1 << 16;
      while (c < b->n + (size_t)w + 1) c *= 2;
      char *q = realloc(b->s, c);
      if (!q) b->bad = 1;
      b->s = q ? q : b->s;
      b->cap = q ? c : b->cap;
    }
  }
}

/* n links, joint k (revolute) hanging link k on link (k - 1) / fanout:
 * fanout 1 is a chain, 8 a wide tree */
static void gen_urdf(textBuf *b, long n, int fanout)
{
  tb_add(b, "<robot name=\"gen\">\n");
  for (long i = 0; i < n; i++)
    tb_add(b, "<link name=\"l%ld\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" "
              "ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>"
              "<collision><geometry><box size=\"0.1 0.1 0.1\"/></geometry></collision>"
              "</link>\n", i);
  for (long i = 1; i < n; i++)
    tb_add(b, "<joint name=\"j%ld\" type=\"revolute\"><parent link=\"l%ld\"/><child "
              "link=\"l%ld\"/><origin xyz=\"0 0 0.1\"/><axis xyz=\"0 1 0\"/></joint>\n",
           i, (i - 1) / fanout, i);
  tb_add(b, "</robot>\n");
}

/* a scene of n boxes (shape 0), n spheres (1) or n <pair_prop>s (2) */
static void gen_scene(textBuf *b, long n, int what)
{
  tb_add(b, "<raisim version=\"1.0\">\n");
  if (what == 2) {
    tb_add(b, "<material>\n");
    for (long i = 0; i < n; i++)
      tb_add(b, "<pair_prop name1=\"m%ld\" name2=\"m%ld\" friction=\"0.5\"/>\n", i, i + 1);
    tb_add(b, "</material>\n");
  }
  tb_add(b, "<objects>\n<ground name=\"ground\"/>\n");
  for (long i = 0; what < 2 && i < n; i++)
    tb_add(b, what == 0 ? "<box name=\"b%ld\" mass=\"1\"><dim x=\"0.1\" y=\"0.1\" z=\"0.1\"/>"
                          "<state pos=\"%ld %ld 1\" quat=\"1 0 0 0\"/></box>\n"
                        : "<sphere name=\"b%ld\" mass=\"1\"><dim radius=\"0.1\"/>"
                          "<state pos=\"%ld %ld 1\" quat=\"1 0 0 0\"/></sphere>\n",
           i, i % 100, i / 100);
  tb_add(b, "</objects>\n</raisim>\n");
}

static double load_now(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* One load of kind k (0 chain, 1 tree: URDF; 2 boxes, 3 spheres, 4 pairs:
 * scene); its seconds, or -1 after printing the error or wrong counts.  A
 * URDF is parsed and built into a model, not given data: the articulated
 * workspace of ss_data_new holds dense links x dofs blocks, a cost of the
 * dynamics that this case does not measure. */
static double load_once(int k, const textBuf *b, long n)
{
  ssError e;
  double t0 = load_now(), t = -1;
  if (k < 2) {
    ssUrdf *u = NULL;
    ssModel *m = NULL;
    int s = -1;
    if (ss_urdf_load_buffer(b->s, b->n, "gen.urdf", NULL, &u, &e) == SS_OK &&
        (m = ss_model_new())) {
      ssArtDef d = ss_art_def_default();
      d.name = "gen";
      d.fixed_base = 1;
      s = ss_model_add_articulated(m, u, &d, &e);
    }
    if (s >= 0 && m->nbody == n && m->ngeom == n && m->nv == n - 1)
      t = load_now() - t0;
    else if (s >= 0)
      fprintf(stderr, "benchmarks: load: the URDF built %d bodies, %d geoms, %d dofs "
              "(expected %ld, %ld, %ld)\n", m->nbody, m->ngeom, m->nv, n, n, n - 1);
    else
      bench_print_error(&e, "gen.urdf");
    ss_model_free(m);
    ss_urdf_free(u);
  } else {
    ssModel *m = NULL;
    ssData *d = NULL;
    if (ss_scene_load_buffer(b->s, b->n, "gen.xml", &m, &d, &e) != SS_OK) {
      bench_print_error(&e, "gen.xml");
      return -1;
    }
    t = load_now() - t0;
    long want = k == 4 ? 0 : n;
    if (m->nsys != want || (k == 4 && m->npair != n)) {
      fprintf(stderr, "benchmarks: load: the scene built %d systems, %d pairs\n",
              m->nsys, m->npair);
      t = -1;
    }
    ss_data_free(d);
    ss_model_free(m);
  }
  return t;
}

static int bench_load(int argc, char **argv)
{
  long count = 20000, repeats = 3;
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--")) continue;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    }
    if (bench_engine_flag(a)) continue;
    const char *eq = strchr(a, '=');
    size_t nl = eq ? (size_t)(eq - a) : strlen(a);
    int is_count = nl == 7 && !strncmp(a, "--count", nl);
    int is_rep = nl == 9 && !strncmp(a, "--repeats", nl);
    if (!is_count && !is_rep) {
      fprintf(stderr, "benchmarks: load: unknown option '%s'\n", a);
      usage(stderr);
      return 2;
    }
    const char *val = eq ? eq + 1 : (i + 1 < argc ? argv[++i] : NULL);
    long *dst = is_count ? &count : &repeats;
    if (!val || !bench_parse_long(val, is_count ? 2 : 1, is_count ? 10000000 : 1000, dst)) {
      fprintf(stderr, "benchmarks: load: %s needs a whole number in [%d, %d]\n",
              is_count ? "--count" : "--repeats", is_count ? 2 : 1,
              is_count ? 10000000 : 1000);
      return 2;
    }
  }
  static const char *const kinds[] = {"urdf_chain", "urdf_tree", "boxes", "spheres",
                                      "pair_prop"};
  printf("load: %ld objects each, best of %ld (ms per load; URDFs parsed and built, "
         "scenes loaded with their data)\n", count, repeats);
  printf("%-12s %10s %12s\n", "input", "objects", "ms/load");
  int rc = 0;
  for (int k = 0; k < 5; k++) {
    textBuf b = {NULL, 0, 0, 0};
    if (k < 2)
      gen_urdf(&b, count, k == 0 ? 1 : 8);
    else
      gen_scene(&b, count, k - 2);
    if (b.bad) {
      fprintf(stderr, "benchmarks: load: out of memory generating %s\n", kinds[k]);
      free(b.s);
      return 1;
    }
    double best = -1;
    for (long r = 0; r < repeats; r++) {
      double t = load_once(k, &b, count);
      if (t < 0) {
        rc = 1;
        break;
      }
      if (best < 0 || t < best) best = t;
    }
    free(b.s);
    if (best < 0) continue;
    printf("%-12s %10ld %12.2f\n", kinds[k], count, 1e3 * best);
    fflush(stdout);
  }
  return rc;
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
      if (!strcmp(name, "load")) return bench_load(argc - i - 2, argv + i + 2);
      if (!strcmp(name, "deformable_terrain")) return bench_terrain(argc - i - 2, argv + i + 2);
      fprintf(stderr, "benchmarks: unknown case '%s'\n", name);
      usage(stderr);
      return 2;
    }
  }
  usage(stderr);
  return 2;
}
