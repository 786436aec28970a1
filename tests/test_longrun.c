/* test_longrun.c -- long runs: memory stays flat, loop closures stay
 * closed (issue 8, item 6).
 *
 * Steps an articulated world on soil for many steps and samples, after a
 * warm-up, the heap in use (glibc's mallinfo2: bytes handed out by malloc
 * and not freed) and the resident set (VmRSS in /proc/self/status).  A
 * world that reuses its buffers uses the same heap at the end as after the
 * warm-up; a per-step leak or an ever-growing cache shows as growth.
 *
 * The default world (built in below) is cheap: the plate_arm lift of
 * assets/plate_arm (a pin closure, a coil-over, a PD whose target swings
 * the lift up and down all run long) on an 11 x 11 soil bed, and a sphere
 * rolling across the bed, so contacts, loaded vertices and the warm-start
 * cache keep changing (the sweeps are capped at 40: the driven lift keeps
 * the solver at its cap most steps, and only the memory is under test
 * here).  The suite runs 10000 steps (a few seconds);
 * longer or other runs by environment:
 *   SS_LONGRUN_STEPS=100000            the 10^5 steps
 *   SS_LONGRUN_SCENE=scenes/buggy.xml  any scene instead of the built-in
 *                                      one (its PD targets stay as given)
 * Under AddressSanitizer (which keeps freed memory in quarantine, so the
 * heap and RSS numbers mean nothing) the memory checks are skipped; LSan
 * checks the leaks at exit instead. */
#include "tap.h"
#include "soilsim.h"

#include <malloc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UNDER_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && !defined(UNDER_ASAN)
#define UNDER_ASAN 1
#endif
#ifndef UNDER_ASAN
#define UNDER_ASAN 0
#endif

/* growth allowed after the warm-up: the heap must come back to where it
 * was to within a few allocator chunks; RSS moves by whole pages */
#define HEAP_SLACK (16L * 1024)
#define RSS_SLACK_KB 2048L
#define CLOSURE_MAX 1e-9

static const char *srcdir(void)
{
  const char *s = getenv("top_srcdir");
  return s && *s ? s : ".";
}

static long rss_kb(void)
{
  FILE *f = fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long kb = -1;
  while (fgets(line, sizeof line, f))
    if (!strncmp(line, "VmRSS:", 6)) {
      kb = strtol(line + 6, NULL, 10);
      break;
    }
  fclose(f);
  return kb;
}

static long heap_bytes(void)
{
  struct mallinfo2 mi = mallinfo2();
  return (long)mi.uordblks + (long)mi.hblkhd;
}

/* The built-in world, with [THIS_DIR] standing for assets/plate_arm. */
static char *builtin_scene(void)
{
  char heights[11 * 11 * 2 + 1];
  for (int i = 0; i < 11 * 11; i++) memcpy(heights + 2 * i, "0 ", 2);
  heights[11 * 11 * 2 - 1] = 0;
  const char *fmt =
      "<raisim version=\"1.0\">\n"
      "  <timeStep value=\"0.002\"/>\n"
      "  <contact_solver max_sweeps=\"40\"/>\n"
      "  <objects>\n"
      "    <articulated_system name=\"carrier\" urdf_path=\"[THIS_DIR]/plate_arm.urdf\">\n"
      "      <state pos=\"0 0 0.02\" quat=\"1 0 0 0\"/>\n"
      "      <pd joint=\"arm_a_joint\" p_gain=\"400\" d_gain=\"20\" effort_limit=\"60\"/>\n"
      "    </articulated_system>\n"
      "    <sphere name=\"ball\" mass=\"3\"> <dim radius=\"0.08\"/>\n"
      "      <state pos=\"-0.9 0.7 0.1\" lin_vel=\"0.4 -0.3 0\"/> </sphere>\n"
      "    <heightmap name=\"soil\" x_size=\"2\" y_size=\"2\" x_sample=\"11\"\n"
      "               y_sample=\"11\" height=\"%s\">\n"
      "      <soil bekker_kphi=\"100000\" sinkage_exponent=\"1\"\n"
      "            elastic_stiffness=\"2000000\" damping=\"10000\"/>\n"
      "    </heightmap>\n"
      "  </objects>\n"
      "</raisim>\n";
  size_t n = strlen(fmt) + sizeof heights + 1;
  char *s = malloc(n);
  if (s) snprintf(s, n, fmt, heights);
  return s;
}

int main(void)
{
  const char *env_steps = getenv("SS_LONGRUN_STEPS");
  const char *scene = getenv("SS_LONGRUN_SCENE");
  long steps = env_steps && *env_steps ? strtol(env_steps, NULL, 10) : 10000;
  if (steps < 100) steps = 100;
  long warm = steps / 10;

  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  memset(&e, 0, sizeof e);
  ssStatus st;
  if (scene && *scene) {
    st = ss_scene_load(scene, &m, &d, &e);
  } else {
    char base[1024];
    snprintf(base, sizeof base, "%s/assets/plate_arm/longrun.xml", srcdir());
    char *xml = builtin_scene();
    st = xml ? ss_scene_load_buffer(xml, strlen(xml), base, &m, &d, &e)
             : SS_ERR_NOMEM;
    free(xml);
  }
  if (!ok(st == SS_OK, "the long-run world loads (%s)",
          scene && *scene ? scene : "built in: plate_arm lift and a ball on soil")) {
    diag("%s:%d: %s", e.file, e.line, e.message);
    return done_testing();
  }
  int drive = !(scene && *scene) && m->npd > 0;

  long heap0 = 0, rss0 = 0, heap_max = 0, rss_max = 0;
  double closure_max = 0;
  long failed_at = -1, sweeps = 0, capped = 0;
  for (long k = 1; k <= steps; k++) {
    if (drive) {
      /* swing the lift: +-0.4 rad with a 1.5 s period */
      double t = d->time;
      d->pd_target[0] = 0.4 * sin(2 * 3.14159265358979323846 * t / 1.5);
      d->pd_target[1] = 0.4 * 2 * 3.14159265358979323846 / 1.5 *
                        cos(2 * 3.14159265358979323846 * t / 1.5);
    }
    if (ss_step(m, d, &e) != SS_OK) {
      failed_at = k;
      break;
    }
    sweeps += d->stats.sweeps;
    capped += !d->stats.converged;
    if (k > warm && d->closure_error > closure_max) closure_max = d->closure_error;
    if (k == warm) {
      heap0 = heap_bytes();
      rss0 = rss_kb();
    }
    if (k > warm && k % 500 == 0) {
      long h = heap_bytes(), r = rss_kb();
      if (h > heap_max) heap_max = h;
      if (r > rss_max) rss_max = r;
    }
  }
  if (!ok(failed_at < 0, "%ld steps without a failure", steps))
    diag("step %ld: %s", failed_at, e.message);
  diag("%.1f solver sweeps per step on average, %ld steps at the sweep cap",
       (double)sweeps / (double)steps, capped);
  ok(closure_max <= CLOSURE_MAX, "loop closures stay closed after the warm-up: "
     "largest error %.3g m (at most %g)", closure_max, CLOSURE_MAX);

  if (UNDER_ASAN) {
    ok(1, "# SKIP heap growth: AddressSanitizer quarantines freed memory");
    ok(1, "# SKIP RSS growth: AddressSanitizer quarantines freed memory");
  } else {
    long heap1 = heap_bytes(), rss1 = rss_kb();
    if (heap1 > heap_max) heap_max = heap1;
    if (rss1 > rss_max) rss_max = rss1;
    ok(heap_max - heap0 <= HEAP_SLACK,
       "heap in use flat from step %ld to %ld: %ld bytes after the warm-up, "
       "at most %ld later (growth %ld, allowed %ld)", warm, steps, heap0,
       heap_max, heap_max - heap0, HEAP_SLACK);
    ok(rss0 > 0 && rss_max - rss0 <= RSS_SLACK_KB,
       "resident set flat from step %ld to %ld: %ld KiB after the warm-up, "
       "at most %ld KiB later (allowed growth %ld KiB)", warm, steps, rss0,
       rss_max, RSS_SLACK_KB);
  }
  ss_data_free(d);
  ss_model_free(m);
  return done_testing();
}
