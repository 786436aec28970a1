/* bench_render.c -- `benchmarks --bench render`: milliseconds per rendered
 * frame (DESIGN 6, 8).
 *
 *   benchmarks --bench render [--scene FILE] [--size WxH] [--frames N]
 *                             [--steps K] [--csv FILE]
 *
 * Loads the scene (default: scenes/buggy.xml of the source tree), steps it
 * K times (default 0) so that the bed has ruts, then draws N frames
 * (default 10) of the same state at WxH (default 1280x720) with the scene's
 * camera.  Reports the first frame (context warm-up, shader compilation),
 * the median and the spread of the others in wall-clock time, the CPU
 * time per frame of the whole process (llvmpipe's threads included), and
 * the median time of a frame written as a PNG file (what --render pays).  The
 * GL backend is whatever the renderer picks (SOILSIM_GL=osmesa|egl chooses).
 * Timings are reported, never asserted. */
#include "bench.h"

#include "render.h"
#include "soilsim.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static double wall_s(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double cpu_s(void)
{
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Median of n sorted values. */
static double median_of(const double *v, long n)
{
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void usage(FILE *f)
{
  fprintf(f,
          "usage: benchmarks --bench render [--scene FILE] [--size WxH] "
          "[--frames N] [--steps K] [--csv FILE]\n"
          "  --scene FILE   world XML (default: scenes/buggy.xml of the source tree)\n"
          "  --size WxH     image size (default 1280x720)\n"
          "  --frames N     frames to time after the first (default 10)\n"
          "  --steps K      simulation steps before rendering (default 0)\n"
          "  --csv FILE     append one row (header first if the file is new)\n"
          "An engine flag such as --raisim is accepted and ignored.\n"
          "environment: SOILSIM_GL=osmesa|egl picks the GL backend\n");
}

static int parse_size(const char *s, int *w, int *h)
{
  const char *x = strchr(s, 'x');
  if (!x) return 0;
  char a[32];
  size_t n = (size_t)(x - s);
  if (n == 0 || n >= sizeof a) return 0;
  memcpy(a, s, n);
  a[n] = 0;
  long lw, lh;
  if (!bench_parse_long(a, 1, SS_RENDER_MAX_SIDE, &lw) ||
      !bench_parse_long(x + 1, 1, SS_RENDER_MAX_SIDE, &lh))
    return 0;
  *w = (int)lw;
  *h = (int)lh;
  return 1;
}

int bench_render(int argc, char **argv)
{
  const char *scene = NULL, *csv = NULL;
  int width = 1280, height = 720;
  long frames = 10, steps = 0;
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--")) continue;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    }
    if (bench_engine_flag(a)) continue;
    /* --opt VALUE or --opt=VALUE */
    const char *eq = strchr(a, '=');
    char name[32];
    size_t nl = eq ? (size_t)(eq - a) : strlen(a);
    if (nl >= sizeof name) nl = sizeof name - 1;
    memcpy(name, a, nl);
    name[nl] = 0;
    const char *val = eq ? eq + 1 : (i + 1 < argc ? argv[i + 1] : NULL);
    int known = !strcmp(name, "--scene") || !strcmp(name, "--size") ||
                !strcmp(name, "--frames") || !strcmp(name, "--steps") ||
                !strcmp(name, "--csv");
    if (!known) {
      fprintf(stderr, "benchmarks: render: unknown option '%s'\n", a);
      usage(stderr);
      return 2;
    }
    if (!val) {
      fprintf(stderr, "benchmarks: render: %s needs a value\n", name);
      return 2;
    }
    if (!eq) i++;
    if (!strcmp(name, "--scene")) {
      scene = val;
    } else if (!strcmp(name, "--csv")) {
      csv = val;
    } else if (!strcmp(name, "--size")) {
      if (!parse_size(val, &width, &height)) {
        fprintf(stderr, "benchmarks: render: invalid --size '%s' (WxH, 1 to %d)\n",
                val, SS_RENDER_MAX_SIDE);
        return 2;
      }
    } else if (!strcmp(name, "--frames")) {
      if (!bench_parse_long(val, 1, 100000, &frames)) {
        fprintf(stderr, "benchmarks: render: invalid --frames '%s' (1 to 100000)\n", val);
        return 2;
      }
    } else if (!bench_parse_long(val, 0, 100000000, &steps)) {
      fprintf(stderr, "benchmarks: render: invalid --steps '%s'\n", val);
      return 2;
    }
  }

  char path[PATH_MAX + 64];
  if (!scene) {
    if (!bench_default_scene(path, sizeof path)) {
      fprintf(stderr, "benchmarks: render: cannot find scenes/buggy.xml; "
                      "give --scene FILE or set top_srcdir\n");
      return 1;
    }
    scene = path;
  }

  static const char header[] = "bench,scene,width,height,backend,steps,frames,first_ms,"
                                "median_ms,min_ms,max_ms,mean_ms,cpu_ms,png_frame_ms";
  if (csv && !bench_csv_prepare("render", csv, header)) return 1;
  ssError err;
  ss_error_clear(&err);
  ssModel *m = NULL;
  ssData *d = NULL;
  if (ss_scene_load(scene, &m, &d, &err) != SS_OK) {
    bench_print_error(&err, scene);
    return 1;
  }
  ssRenderOptions o = ss_render_options_default();
  o.width = width;
  o.height = height;
  ssRenderer *r = ss_render_new(m, &o, &err);
  if (!r) {
    fprintf(stderr, "benchmarks: render: the renderer could not start: %s\n",
            err.message);
    ss_data_free(d);
    ss_model_free(m);
    return 1;
  }
  int status = 1;
  unsigned char *rgba = malloc((size_t)width * (size_t)height * 4);
  double *times = malloc(sizeof *times * (size_t)frames);
  if (!rgba || !times) {
    fprintf(stderr, "benchmarks: render: out of memory\n");
    goto done;
  }

  /* step first so that the bed has ruts and the camera has moved */
  ss_forward(m, d);
  double t_step = wall_s();
  for (long k = 0; k < steps; k++) {
    if (ss_step(m, d, &err) != SS_OK) {
      fprintf(stderr, "benchmarks: render: step %ld failed: %s\n", k + 1, err.message);
      goto done;
    }
  }
  ss_forward(m, d);
  t_step = wall_s() - t_step;

  double t0 = wall_s();
  if (ss_render_pixels(r, m, d, rgba, &err) != SS_OK) {
    fprintf(stderr, "benchmarks: render: %s\n", err.message);
    goto done;
  }
  double first = wall_s() - t0;
  double c0 = cpu_s(), w0 = wall_s();
  for (long k = 0; k < frames; k++) {
    double t = wall_s();
    if (ss_render_pixels(r, m, d, rgba, &err) != SS_OK) {
      fprintf(stderr, "benchmarks: render: %s\n", err.message);
      goto done;
    }
    times[k] = wall_s() - t;
  }
  double cpu = (cpu_s() - c0) / (double)frames;
  double mean = (wall_s() - w0) / (double)frames;
  qsort(times, (size_t)frames, sizeof *times, cmp_double);
  double median = median_of(times, frames);
  double fastest = times[0], slowest = times[frames - 1];

  /* what --render pays per frame: drawing plus the PNG file (written
   * atomically, as the command line does) */
  const char *tmp = getenv("TMPDIR");
  char png[PATH_MAX];
  snprintf(png, sizeof png, "%s/soilsim-bench-render-%ld.png", tmp && *tmp ? tmp : "/tmp",
           (long)getpid());
  long nwrite = frames < 5 ? frames : 5;
  for (long k = 0; k < nwrite; k++) {
    double t = wall_s();
    if (ss_render_frame(r, m, d, png, &err) != SS_OK) {
      fprintf(stderr, "benchmarks: render: %s: %s\n", err.file, err.message);
      unlink(png);
      goto done;
    }
    times[k] = wall_s() - t;
  }
  unlink(png);
  qsort(times, (size_t)nwrite, sizeof *times, cmp_double);
  double with_png = median_of(times, nwrite);
  const char *backend = ss_render_backend_name(r);
  long ncpu = sysconf(_SC_NPROCESSORS_ONLN);

  const char *base = strrchr(scene, '/');
  base = base ? base + 1 : scene;
  printf("render benchmark: %s at %dx%d, %s backend, %ld CPUs online\n", base, width,
         height, backend, ncpu);
  if (steps > 0)
    printf("  %ld steps first (%.1f s), simulated time %.3f s\n", steps, t_step, d->time);
  printf("  %-28s %10s\n", "", "ms");
  printf("  %-28s %10.1f\n", "first frame", first * 1e3);
  printf("  %-28s %10.1f\n", "median of the rest", median * 1e3);
  printf("  %-28s %10.1f\n", "fastest", fastest * 1e3);
  printf("  %-28s %10.1f\n", "slowest", slowest * 1e3);
  printf("  %-28s %10.1f\n", "mean", mean * 1e3);
  printf("  %-28s %10.1f\n", "CPU per frame (all threads)", cpu * 1e3);
  printf("  %-28s %10.1f\n", "frame + PNG file (median)", with_png * 1e3);
  printf("  (%ld frames after the first; timings are reported, never asserted)\n",
         frames);

  if (csv) {
    FILE *f = fopen(csv, "a");
    if (!f) {
      fprintf(stderr, "benchmarks: render: %s: cannot open: %s\n", csv, strerror(errno));
      goto done;
    }
    /* (its header: bench_csv_prepare, before the run) */
    fprintf(f, "render,%s,%d,%d,%s,%ld,%ld,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", base,
            width, height, backend, steps, frames, first * 1e3, median * 1e3,
            fastest * 1e3, slowest * 1e3, mean * 1e3, cpu * 1e3, with_png * 1e3);
    if (fclose(f) != 0) {
      fprintf(stderr, "benchmarks: render: %s: cannot write: %s\n", csv, strerror(errno));
      goto done;
    }
  }
  status = 0;
done:
  free(rgba);
  free(times);
  ss_render_free(r);
  ss_data_free(d);
  ss_model_free(m);
  return status;
}
