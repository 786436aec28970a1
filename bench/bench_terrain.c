/* bench_terrain.c -- `benchmarks --bench deformable_terrain -- [options]`
 * (DESIGN 8): the plate and the articulated bodies on soil, the buggy, and
 * the contact law alone.  Times are reported, never asserted; --verify
 * turns the correctness checks into the exit status (the test suite runs
 * short verified runs). */
#include "bench.h"
#include "articulated.h"
#include "soilsim.h"
#include "solver.h"
#include "point.h"
#include "ss_math.h"
#include "worlds.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* the options' ranges: a step count that ends within days; a bed up to
 * 40^2 times the default area (2401^2 vertices, about 0.3 GB) */
#define MAX_STEPS 100000000L
#define MAX_REPEATS 10000L
#define MAX_BED_SCALE 40L

typedef struct Opt {
  const char *body;     /* rigid, articulated, pinned, multilink, buggy */
  int warm;             /* 1 warm, 0 cold */
  int contact_law;
  int linear;           /* --material=linear (n = 1) */
  int steps, repeats;
  int warmup;           /* untimed steps before the timed ones */
  int bed_scale;        /* the bed's side times this (area x scale^2) */
  const char *csv, *scene;
  int verify;
  int sweeps_only;      /* --solver=sweeps: the Gauss-Seidel sweeps alone */
} Opt;

static double now(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double median(double *v, int n)
{
  qsort(v, (size_t)n, sizeof *v, cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* one CSV row (with --csv; its header: bench_csv_prepare) with the soil's
 * material, linear (n = 1) or nonlinear (empty for a world without soil:
 * linear < 0), and the --scene given (quoted as
 * RFC 4180 has it, empty for a built-in body); 0 and a message when it
 * cannot be written */
static int csv_row(const Opt *o, const char *kind, int linear, double ms, double ns_point,
                   double sweeps, double newton, double err)
{
  if (!o->csv) return 1;
  FILE *f = fopen(o->csv, "a");
  int bad = !f || fprintf(f, "%s,%s,%s,%s,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,", kind,
                          o->contact_law ? "" : o->body, o->warm ? "warm" : "cold",
                          linear < 0 ? "" : linear ? "linear" : "nonlinear", o->steps, o->repeats, ms, ns_point,
                          sweeps, err, newton) < 0;
  if (!bad && o->scene) {
    bad = fputc('"', f) == EOF;
    for (const char *c = o->scene; *c && !bad; c++)
      bad = (*c == '"' && fputc('"', f) == EOF) || fputc(*c, f) == EOF;
    bad = bad || fputc('"', f) == EOF;
  }
  bad = bad || fputc('\n', f) == EOF;
  if (f && fclose(f)) bad = 1;
  if (bad)
    fprintf(stderr, "benchmarks: deformable_terrain: cannot write --csv file '%s'\n", o->csv);
  return !bad;
}

/* ---------------------------------------------------------------------- */
/* bodies on soil                                                          */

typedef struct Run {
  double seconds, sweeps, newton, points, sinkage, soil_normal, dt;
  double stage[6]; /* mean wall time a step of each stage (ssStepStats) */
  int linear;      /* the first soil bed's sinkage exponent is 1; -1 no soil */
  int ok;
} Run;

/* build the chosen body on its bed (plate soil, 2 cm), or load the buggy */
static int build(const Opt *o, ssModel **mout, ssData **dout, char *why, size_t cap)
{
  ssError e;
  if (!strcmp(o->body, "buggy")) {
    /* a scene given is that scene or an error, never the default */
    if (o->scene) {
      if (ss_scene_load(o->scene, mout, dout, &e) == SS_OK) return 1;
      snprintf(why, cap, "cannot load --scene '%s': %s", o->scene, e.message);
      return 0;
    }
    /* else the project's buggy, from the build or source tree */
    char path[PATH_MAX + 64];
    if (!bench_default_scene(path, sizeof path)) {
      snprintf(why, cap, "cannot find scenes/buggy.xml; give --scene=FILE or set top_srcdir");
      return 0;
    }
    if (ss_scene_load(path, mout, dout, &e) == SS_OK) return 1;
    snprintf(why, cap, "cannot load the buggy scene (give --scene=FILE): %s", e.message);
    return 0;
  }
  ssModel *m = ss_model_new();
  double bed = 1.2 * o->bed_scale, h = 0.02;
  int sys;
  if (!strcmp(o->body, "rigid")) {
    ssBodyDef bd = ss_body_def_default();
    bd.name = "plate";
    bd.size[0] = 0.4;
    bd.size[1] = 0.6;
    bd.size[2] = 0.05;
    bd.mass = 20;
    bd.pos[2] = 0.025;
    sys = ss_model_add_body(m, &bd, &e);
  } else {
    ssUrdf *u = !strcmp(o->body, "articulated") ? carrier60()
              : !strcmp(o->body, "pinned")      ? carrier60_pinned()
              : !strcmp(o->body, "multilink")   ? fourpad64()
                                                : NULL;
    if (!u) {
      snprintf(why, cap, "unknown --body=%s (rigid, articulated, pinned, multilink, buggy)", o->body);
      ss_model_free(m);
      return 0;
    }
    ssArtDef def = ss_art_def_default();
    def.name = o->body;
    def.fixed_base = 0;
    def.pos[2] = !strcmp(o->body, "multilink") ? 0.12 : 0.025;
    if (!strcmp(o->body, "multilink")) bed = 1.4 * o->bed_scale;
    sys = ss_model_add_articulated(m, u, &def, &e);
    ss_urdf_free(u);
  }
  add_soil_bed(m, bed, h);
  m->opt.terrain_warm_start = o->warm;
  if (sys < 0 || !(*dout = ss_data_new(m))) {
    snprintf(why, cap, "cannot build the %s body: %s", o->body, e.message);
    ss_model_free(m);
    return 0;
  }
  *mout = m;
  return 1;
}

/* one timed step; a function of its own so that a profiler can count the
 * timed steps alone (valgrind --tool=callgrind --toggle-collect=timed_step) */
__attribute__((noinline)) static ssStatus timed_step(const ssModel *m, ssData *d, ssError *e)
{
  return ss_step(m, d, e);
}

static Run run_body(const Opt *o)
{
  Run r = {0};
  ssModel *m;
  ssData *d;
  char why[1200];
  if (!build(o, &m, &d, why, sizeof why)) {
    fprintf(stderr, "benchmarks: %s\n", why);
    return r;
  }
  m->opt.terrain_warm_start = o->warm;
  d->solver_gs_only = o->sweeps_only;
  r.linear = -1;
  for (int h = m->nhfield - 1; h >= 0; h--)
    if (m->hfield_soil[h]) r.linear = m->hfield_soilmat[h].sinkage_exponent == 1;
  ssError e;
  for (int k = 0; k < o->warmup; k++) {
    if (ss_step(m, d, &e) != SS_OK) {
      fprintf(stderr, "benchmarks: warm-up step %d failed: %s\n", k + 1, e.message);
      ss_data_free(d);
      ss_model_free(m);
      return r;
    }
  }
  double t0 = now();
  long sweeps = 0, newton = 0, points = 0;
  for (int k = 0; k < o->steps; k++) {
    if (timed_step(m, d, &e) != SS_OK) {
      fprintf(stderr, "benchmarks: step %d failed: %s\n", k + 1, e.message);
      ss_data_free(d);
      ss_model_free(m);
      return r;
    }
    sweeps += d->stats.sweeps;
    newton += d->stats.newton;
    points += d->stats.soil_loaded;
    for (int i = 0; i < 6; i++) r.stage[i] += d->stats.time_stage[i];
  }
  r.seconds = now() - t0;
  for (int i = 0; i < 6; i++) r.stage[i] /= o->steps;
  r.sweeps = (double)sweeps / o->steps;
  r.newton = (double)newton / o->steps;
  r.points = (double)points / o->steps;
  r.soil_normal = d->stats.soil_normal_force;
  r.dt = m->opt.timestep;
  /* the plate's (or pads') sinkage: mean of the loaded soil under them */
  double sum = 0;
  int n = 0;
  for (int k = 0; k < d->nsoil_loaded; k++) {
    sum += d->soil_sinkage[d->soil_loaded[k]];
    n++;
  }
  r.sinkage = n ? sum / n : 0;
  r.ok = 1;
  ss_data_free(d);
  ss_model_free(m);
  return r;
}

static int bench_bodies(const Opt *o)
{
  double *ms = calloc((size_t)o->repeats, sizeof(double));
  Run last = {0};
  for (int k = 0; k < o->repeats; k++) {
    last = run_body(o);
    if (!last.ok) {
      free(ms);
      return 1;
    }
    ms[k] = 1e3 * last.seconds / o->steps;
  }
  double med = median(ms, o->repeats);
  free(ms);
  int buggy = !strcmp(o->body, "buggy");
  double s_ref = 8.175e-3, err = buggy ? 0 : (last.sinkage - s_ref) / s_ref;
  double ns_point = last.points > 0 ? 1e6 * med / last.points : 0;
  printf("%-12s %-5s%s %6d steps x %d: %9.4f ms/step  %8.1f ns/point/step  %5.2f sweeps + "
         "%4.2f Newton/step  %7.1f loaded points",
         o->body, o->warm ? "warm" : "cold", o->sweeps_only ? " (sweeps only)" : "", o->steps,
         o->repeats, med, ns_point,
         last.sweeps, last.newton, last.points);
  if (buggy)
    printf("  real-time factor %.3f (%s)\n", last.dt / (1e-3 * med),
           o->scene ? o->scene : "scenes/buggy.xml");
  else
    printf("  sinkage %.4f mm (analytic 8.175, error %+.3f %%)\n", last.sinkage * 1e3, 100 * err);
  /* where the time goes, from the step's own stage clocks (the last
   * repeat's mean): a profile without a profiler */
  static const char *stage_name[6] = {"kinematics", "free velocity", "contacts",
                                      "solve", "cache + soil update", "integration"};
  double total = 0;
  for (int i = 0; i < 6; i++) total += last.stage[i];
  printf("  stages (last repeat, us/step and share):");
  for (int i = 0; i < 6; i++)
    printf(" %s %.1f (%.0f %%)%s", stage_name[i], 1e6 * last.stage[i],
           total > 0 ? 100 * last.stage[i] / total : 0, i < 5 ? "," : "\n");
  if (!csv_row(o, o->sweeps_only ? "body_sweeps_only" : "body", last.linear, med, ns_point,
               last.sweeps, last.newton, err))
    return 1;
  if (o->verify && buggy) {
    /* said, not refused: a loop over every body with --verify still runs */
    printf("verify: none for the buggy (no closed-form sinkage to check against)\n");
    return 0;
  }
  if (o->verify) {
    /* warm and cold starts reach the same converged answer */
    Opt other = *o;
    other.warm = !o->warm;
    Run r2 = run_body(&other);
    double diff = fabs(r2.sinkage - last.sinkage);
    int same = r2.ok && diff <= 1e-6 * s_ref;
    printf("verify: warm and cold sinkage differ by %.3g m: %s\n", diff, same ? "ok" : "FAILED");
    /* settled bodies sit at the analytic sinkage */
    int settled = fabs(err) < 0.01;
    printf("verify: sinkage within 1 %% of 8.175 mm: %s\n", settled ? "ok" : "FAILED");
    return same && settled ? 0 : 1;
  }
  return 0;
}

/* ---------------------------------------------------------------------- */
/* the contact law alone: 32 anisotropic points                            */

static unsigned long long lcg = 0x9E3779B97F4A7C15ull;
static double rnd(void)
{
  lcg = lcg * 6364136223846793005ull + 1442695040888963407ull;
  return (double)(lcg >> 11) * (1.0 / 9007199254740992.0);
}

static int bench_contact_law(const Opt *o)
{
  enum { N = 32 };
  ssSoilMaterial mat = ss_soil_material_default();
  if (o->linear) mat.sinkage_exponent = 1;
  const double dt = 1e-3, tol = 1e-12;
  ssContact c[N];
  memset(c, 0, sizeof c);
  lcg = 0x9E3779B97F4A7C15ull;
  for (int i = 0; i < N; i++) {
    c[i].type = SS_CONTACT_SOIL;
    c[i].area = 2e-4 + 4e-4 * rnd();
    c[i].width = 0.1 + 0.3 * rnd();
    c[i].sp = 0.02 * rnd();
    /* fresh, partially and fully mobilized shear */
    c[i].j = i % 3 == 0 ? 0 : i % 3 == 1 ? mat.shear_displacement : 10 * mat.shear_displacement;
    c[i].g0 = -0.002 * rnd();
    /* anisotropic SPD response: A A^T + diag */
    double A[9];
    for (int k = 0; k < 9; k++) A[k] = 0.2 * (rnd() - 0.5);
    for (int r = 0; r < 3; r++)
      for (int s = 0; s < 3; s++) {
        double t = 0;
        for (int k = 0; k < 3; k++) t += A[3 * r + k] * A[3 * s + k];
        c[i].G[3 * r + s] = t + (r == s ? 0.05 + 0.1 * rnd() : 0);
      }
  }
  long visits = 0;
  double *ns = calloc((size_t)o->repeats, sizeof(double));
  /* the inputs of every visit, made before the clock starts so that only
   * the normal and shear updates are timed (DESIGN 8): changing loads and
   * slip speeds */
  double *in = malloc((size_t)o->steps * N * 3 * sizeof(double));
  if (!ns || !in) {
    free(ns);
    free(in);
    fprintf(stderr, "benchmarks: out of memory\n");
    return 1;
  }
  for (int it = 0; it < o->steps; it++)
    for (int i = 0; i < N; i++) {
      double ph = 0.01 * it + i, *v = in + 3 * ((size_t)it * N + i);
      v[0] = -0.3 * (1 + sin(ph));
      v[1] = 0.2 * sin(1.3 * ph) * (i % 4 == 0 ? 1e-4 : 1);
      v[2] = 0.1 * cos(0.7 * ph);
    }
  int bad_p = 0, bad_bound = 0, bad_align = 0, bad_power = 0;
  /* Warm, a visit is what a solver sweep does to a contact: the normal and
   * shear update (ss_point_soil) with the law's constants formed once, as
   * the solver forms them once per step (ss_point_setup), and the last
   * impulse and the cached power and mobilisation as the start.  The
   * bed's table of powers is formed before, as a run forms it once. */
  ssPowTable tab;
  ss_pow_table_init(&tab, mat.sinkage_exponent - 1);
  const ssPowTable *pt = mat.sinkage_exponent != 1 && tab.ok ? &tab : NULL;
  for (int i = 0; i < N; i++) ss_point_setup(&mat, pt, dt, &c[i]);
  for (int rep = 0; rep < o->repeats; rep++) {
    double t0 = now();
    for (int it = 0; it < o->steps; it++) {
      const double *vi = in + 3 * (size_t)it * N;
      for (int i = 0; i < N; i++) {
        if (!o->warm) {
          /* cold: a new contact, no first guess and nothing cached from the
           * last visit; its set-up is part of its first visit */
          c[i].lambda[0] = c[i].lambda[1] = c[i].lambda[2] = 0;
          c[i].cache_ready = 0;
          ss_point_setup(&mat, pt, dt, &c[i]);
        }
        ss_point_soil(&c[i], vi + 3 * i, tol);
      }
    }
    double el = now() - t0;
    visits = (long)o->steps * N;
    ns[rep] = 1e9 * el / visits;
    /* verify the last solutions: pressure, feasibility, alignment, power */
    const double *vlast = in + 3 * (size_t)(o->steps - 1) * N;
    for (int i = 0; i < N; i++) {
      const ssContact *p = &c[i];
      double v[3];
      for (int k = 0; k < 3; k++)
        v[k] = vlast[3 * i + k] + p->G[3 * k] * p->lambda[0] + p->G[3 * k + 1] * p->lambda[1] +
               p->G[3 * k + 2] * p->lambda[2];
      double sc = p->area * dt, delta = -(p->g0 + dt * v[0]);
      double pn = ss_soil_pressure(&mat, p->width, p->sp + delta, p->sp) + ss_soil_viscous(&mat, -v[0]);
      if (fabs(p->lambda[0] - sc * pn) > 1e-9 * (sc * pn) + 1e-18) bad_p++;
      double vt = hypot(v[1], v[2]), lt = hypot(p->lambda[1], p->lambda[2]);
      double tmax = sc * ss_soil_shear_limit(&mat, p->lambda[0] / sc, p->j + dt * vt);
      if (lt > tmax * (1 + 1e-9) + 1e-18) bad_bound++;
      double pw = p->lambda[1] * v[1] + p->lambda[2] * v[2];
      if (pw > 1e-12 * lt * (vt + 1e-12)) bad_power++;
      if (vt > 1e-9 && lt > 0 && 1 + pw / (lt * vt) > 1e-6) bad_align++;
    }
  }
  double med = median(ns, o->repeats);
  free(ns);
  free(in);
  printf("contact law  %-9s %-4s %d contacts x %d iterations x %d: %7.1f ns per contact visit\n",
         o->linear ? "linear" : "nonlinear", o->warm ? "warm" : "cold", N, o->steps, o->repeats, med);
  int good = !bad_p && !bad_bound && !bad_align && !bad_power;
  printf("checks: normal pressure %s, shear within tau_max %s, shear opposes slip %s, "
         "never adds energy %s\n", bad_p ? "FAILED" : "ok", bad_bound ? "FAILED" : "ok",
         bad_align ? "FAILED" : "ok", bad_power ? "FAILED" : "ok");
  if (!csv_row(o, "contact_law", o->linear, 0, med, 0, 0, good ? 0 : 1)) return 1;
  return good ? 0 : 1;
}

static void terrain_usage(FILE *f)
{
  fprintf(f, "usage: benchmarks --bench deformable_terrain -- [options]\n"
             "  --body=rigid|articulated|pinned|multilink|buggy  (default rigid)\n"
             "  --start=warm|cold  --steps=N (1..%ld)  --repeats=R (1..%ld)\n"
             "  --warmup=N (0..%ld)  --bed-scale=K (1..%ld)  --csv=FILE  --verify\n"
             "  --solver=newton|sweeps  --scene=FILE (--body=buggy only)\n"
             "  --contact-law [--material=linear|nonlinear]\n"
             "Options take their value as --option=VALUE or --option VALUE; an\n"
             "engine flag (--raisim, --mujoco, --bullet, --chrono, --dart, --drake,\n"
             "--ode, --physx, --soilsim) is accepted and ignored.  --material belongs\n"
             "to --contact-law; --body, --solver, --bed-scale, --warmup and --scene\n"
             "to the bodies.\n",
          MAX_STEPS, MAX_REPEATS, MAX_STEPS, MAX_BED_SCALE);
}

/* one of the words (NULL-terminated) or -1 */
static int word_of(const char *v, const char *const *words)
{
  for (int k = 0; words[k]; k++)
    if (!strcmp(v, words[k])) return k;
  return -1;
}

/* An option with a value: one of its words (the word's index into ival,
 * or the word itself into sval), an integer in [lo, hi] into ival, or
 * any string into sval. */
typedef struct ValOpt {
  const char *name;
  const char *const *words; /* NULL-terminated, or NULL: no word list */
  const char *allowed;      /* the words, as the message lists them */
  long lo, hi;
  int *ival;
  const char **sval;
} ValOpt;

int bench_terrain(int argc, char **argv)
{
  Opt o = {"rigid", 1, 0, 0, 0, 5, 0, 1, NULL, NULL, 0, 0};
  static const char *const bodies[] = {"rigid", "articulated", "pinned", "multilink",
                                       "buggy", NULL};
  static const char *const starts[] = {"cold", "warm", NULL};
  static const char *const materials[] = {"nonlinear", "linear", NULL};
  static const char *const solvers[] = {"newton", "sweeps", NULL};
  const ValOpt opts[] = {
      {"--body", bodies, "rigid, articulated, pinned, multilink or buggy", 0, 0, NULL,
       &o.body},
      {"--start", starts, "warm or cold", 0, 0, &o.warm, NULL},
      {"--material", materials, "linear or nonlinear", 0, 0, &o.linear, NULL},
      {"--solver", solvers, "newton or sweeps", 0, 0, &o.sweeps_only, NULL},
      {"--steps", NULL, NULL, 1, MAX_STEPS, &o.steps, NULL},
      {"--repeats", NULL, NULL, 1, MAX_REPEATS, &o.repeats, NULL},
      {"--warmup", NULL, NULL, 0, MAX_STEPS, &o.warmup, NULL},
      {"--bed-scale", NULL, NULL, 1, MAX_BED_SCALE, &o.bed_scale, NULL},
      {"--csv", NULL, NULL, 0, 0, NULL, &o.csv},
      {"--scene", NULL, NULL, 0, 0, NULL, &o.scene},
  };
  const int nopt = (int)(sizeof opts / sizeof opts[0]);
  unsigned given = 0; /* bit k: opts[k] given */
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--")) continue;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      terrain_usage(stdout);
      return 0;
    }
    if (!strcmp(a, "--contact-law")) {
      o.contact_law = 1;
      continue;
    }
    if (!strcmp(a, "--verify")) {
      o.verify = 1;
      continue;
    }
    if (bench_engine_flag(a)) continue;
    /* --option=VALUE or --option VALUE */
    const char *eq = strchr(a, '=');
    size_t nl = eq ? (size_t)(eq - a) : strlen(a);
    const ValOpt *p = NULL;
    for (int k = 0; k < nopt && !p; k++)
      if (strlen(opts[k].name) == nl && !strncmp(a, opts[k].name, nl)) p = opts + k;
    if (!p) {
      fprintf(stderr, "benchmarks: deformable_terrain: unknown option '%s'\n", a);
      terrain_usage(stderr);
      return 2;
    }
    const char *v = eq ? eq + 1 : i + 1 < argc ? argv[++i] : NULL;
    if (!v || !*v) {
      fprintf(stderr, "benchmarks: deformable_terrain: %s needs a value\n", p->name);
      return 2;
    }
    int ok = 1;
    if (p->words) {
      int k = word_of(v, p->words);
      ok = k >= 0;
      if (ok && p->ival) *p->ival = k;
      if (ok && p->sval) *p->sval = v;
    } else if (p->ival) {
      long x;
      ok = bench_parse_long(v, p->lo, p->hi, &x);
      if (ok) *p->ival = (int)x;
    } else {
      *p->sval = v;
    }
    if (!ok) {
      char range[64];
      snprintf(range, sizeof range, "an integer from %ld to %ld", p->lo, p->hi);
      fprintf(stderr, "benchmarks: deformable_terrain: invalid %s '%s': must be %s\n",
              p->name, v, p->words ? p->allowed : range);
      return 2;
    }
    given |= 1u << (p - opts);
  }
  /* an option the chosen case does not read is refused, not ignored: the
   * bodies' beds have their own soil (the plate soil of DESIGN 2.7, n = 1;
   * the buggy scene's), and the contact law builds no body */
  for (int k = 0; k < nopt; k++) {
    if (!(given >> k & 1)) continue;
    const char *nm = opts[k].name;
    int law_only = !strcmp(nm, "--material");
    int body_only = !strcmp(nm, "--body") || !strcmp(nm, "--solver") ||
                    !strcmp(nm, "--bed-scale") || !strcmp(nm, "--warmup") ||
                    !strcmp(nm, "--scene");
    if (law_only && !o.contact_law) {
      fprintf(stderr, "benchmarks: deformable_terrain: %s chooses the contact law's "
                      "material: it needs --contact-law (the bodies' beds have their own "
                      "soil)\n", nm);
      return 2;
    }
    if (body_only && o.contact_law) {
      fprintf(stderr, "benchmarks: deformable_terrain: %s does not apply to --contact-law "
                      "(it times the law alone, on no body)\n", nm);
      return 2;
    }
  }
  if (o.scene && strcmp(o.body, "buggy")) {
    fprintf(stderr, "benchmarks: deformable_terrain: --scene loads a vehicle scene: it "
                    "needs --body=buggy (the %s body is built in)\n", o.body);
    return 2;
  }
  if (!o.steps) o.steps = o.contact_law ? 2000 : !strcmp(o.body, "buggy") ? 2000 : 1500;
  if (o.csv && !bench_csv_prepare("deformable_terrain", o.csv,
                                  "case,body,start,material,steps,repeats,ms_per_step,"
                                  "ns_per_point,sweeps_per_step,error,newton_per_step,scene"))
    return 1;
  return o.contact_law ? bench_contact_law(&o) : bench_bodies(&o);
}
