/* test_buggy.c -- the 896 kg double-wishbone buggy of DESIGN 7
 * (assets/buggy, scenes/buggy*.xml): statics on rigid ground, loop
 * closure, a 20 s drive on soil (speed, slip, ruts, recovery after
 * removal), steering and determinism. */
#include "dynamics.h"
#include "soilsim.h"
#include "solver.h"
#include "ss_math.h"
#include "tap.h"
#include "worlds.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* the scene at rel (from the source tree) into *m, *d; a failed test
 * line naming it where it does not load */
static int load(const char *rel, ssModel **m, ssData **d)
{
  if (load_scene_file(rel, m, d)) return 1;
  ok(0, "%s loads", rel);
  return 0;
}

/* what a run watches: the largest loop-closure error, and the solver's
 * sweeps (steps over 20 sweeps: the Newton phase did not finish them) */
typedef struct Watch {
  double closure;
  long sweeps;
  int slow, unconverged;
} Watch;

static int run(const ssModel *m, ssData *d, int n, Watch *w)
{
  ssError e;
  for (int k = 0; k < n; k++) {
    if (ss_step(m, d, &e) != SS_OK) {
      diag("step failed: %s", e.message);
      return 0;
    }
    if (!w) continue;
    if (d->closure_error > w->closure) w->closure = d->closure_error;
    w->sweeps += d->stats.sweeps;
    w->slow += d->stats.sweeps > 20;
    w->unconverged += !d->stats.converged;
  }
  return 1;
}

static int body(const ssModel *m, const char *name)
{
  int s = ss_model_find_sys(m, "buggy");
  for (int b = m->sys_bodyadr[s]; b < m->sys_bodyadr[s] + m->sys_nbody[s]; b++)
    if (!strcmp(m->body_name[b], name)) return b;
  return -1;
}

static double total_mass(const ssModel *m)
{
  int s = ss_model_find_sys(m, "buggy");
  double mass = 0;
  for (int b = m->sys_bodyadr[s]; b < m->sys_bodyadr[s] + m->sys_nbody[s]; b++)
    mass += m->body_mass[b];
  return mass;
}

/* normal force carried by the contacts of one body's colliders (N) */
static double wheel_load(const ssModel *m, const ssData *d, int b)
{
  double f = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = &d->contact[i];
    if ((c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_SOIL) && m->geom_body[c->geom] == b)
      f += c->lambda[0] * c->frame[2];
  }
  return f / m->opt.timestep;
}

static void set_drive(const ssModel *m, ssData *d, double wheel_speed)
{
  for (int k = 0; k < m->npd; k++)
    if (strstr(m->body_jntname[m->pd_body[k]], "wheel")) d->pd_target[2 * k + 1] = wheel_speed;
}

static void world_point(const ssData *d, int b, const double local[3], double p[3])
{
  ss_m3_mulv(p, d->body_xmat + 9 * b, local);
  ss_v3_add(p, p, d->body_xpos + 3 * b);
}

static const char *corner[4] = {"fl", "fr", "rl", "rr"};

/* statics on rigid ground: the wheel loads carry m g; each coil-over's
 * force (its rate times its deflection) carries the corner's sprung load
 * through the motion ratio of its linkage */
static void test_statics(void)
{
  ssModel *m;
  ssData *d;
  if (!load("scenes/buggy_rigid.xml", &m, &d)) return;
  ok(fabs(total_mass(m) - 896) < 1e-9, "the buggy weighs 896 kg (%.6g)", total_mass(m));
  set_drive(m, d, 0);
  Watch w = {0};
  run(m, d, 3000, &w);
  double closure = w.closure;
  double sum = 0, load[4];
  char name[32];
  for (int k = 0; k < 4; k++) {
    snprintf(name, sizeof name, "wheel_%s", corner[k]);
    load[k] = wheel_load(m, d, body(m, name));
    sum += load[k];
  }
  double mg = 896 * 9.81;
  close_enough(sum, mg, 0.005 * mg, "rigid ground: the four wheel loads sum to m g");
  diag("wheel loads fl %.0f fr %.0f rl %.0f rr %.0f N", load[0], load[1], load[2], load[3]);
  ok(fabs(load[0] - load[1]) < 0.01 * load[0] && fabs(load[2] - load[3]) < 0.01 * load[2],
     "left and right loads agree");
  ok(load[2] > load[0], "the rear (engine) axle carries more");

  /* virtual work: a small heave of the corner moves the spring by MR times
   * the wheel travel; measure MR from the linkage itself by perturbing the
   * lower arm joint and following the upright's ball joint */
  for (int k = 0; k < 4; k++) {
    int sp = -1;
    snprintf(name, sizeof name, "coilover_%s", corner[k]);
    for (int i = 0; i < m->nspring; i++)
      if (!strcmp(m->spring_name[i], name)) sp = i;
    int b1 = m->spring_body[2 * sp], b2 = m->spring_body[2 * sp + 1];
    const double *an = m->spring_anchor + 6 * sp, *par = m->spring_param + 3 * sp;
    double p1[3], p2[3], dv[3];
    world_point(d, b1, an, p1);
    world_point(d, b2, an + 3, p2);
    ss_v3_sub(dv, p1, p2);
    double L = ss_v3_norm(dv), F = par[0] * (par[2] - L);
    /* motion ratio: rotate the lower arm about its joint by a small angle */
    snprintf(name, sizeof name, "lower_arm_%s", corner[k]);
    int la = body(m, name);
    snprintf(name, sizeof name, "upright_%s", corner[k]);
    int up = body(m, name);
    double h = 1e-6, R[9], axis[3], piv[3], ball[3];
    ss_v3_copy(piv, d->body_xpos + 3 * la);
    ss_m3_mulv(axis, d->body_xmat + 9 * la, m->body_jntaxis + 3 * la);
    ss_v3_copy(ball, d->body_xpos + 3 * up);
    double q[4];
    ss_quat_from_axis_angle(q, axis, h);
    ss_quat_to_mat(R, q);
    double r2[3], p2n[3], balln[3], t[3];
    ss_v3_sub(r2, p2, piv);
    ss_m3_mulv(t, R, r2);
    ss_v3_add(p2n, piv, t);
    ss_v3_sub(r2, ball, piv);
    ss_m3_mulv(t, R, r2);
    ss_v3_add(balln, piv, t);
    double dvn[3];
    ss_v3_sub(dvn, p1, p2n);
    double mr = fabs((ss_v3_norm(dvn) - L) / (balln[2] - ball[2]));
    /* sprung share of the corner: the wheel load less the weight of what
     * hangs below the spring (wheel, hub, upright, half the wishbones) */
    double unsprung = (20 + 3 + 6 + 0.5 * (4 + 3)) * 9.81;
    double want = (load[k] - unsprung) / mr;
    char what[96];
    snprintf(what, sizeof what, "%s coil-over: rate x deflection = sprung load / MR (MR %.3f)",
             corner[k], mr);
    close_enough(F, want, 0.05 * want, what);
  }
  ok(closure < 1e-6, "rigid ground: loop closure error < 1e-6 m (max %.3g)", closure);
  ss_data_free(d);
  ss_model_free(m);
}

/* Driving on rigid ground (buggy_rigid.xml, 0.8 m/s asked of the rear
 * wheels): every step after the first 20 (the suspension settling from
 * its design height) converges within the 200-sweep cap, with the warm
 * start and without; both reach the same motion, at the commanded speed;
 * the warm start takes fewer sweeps.  Before rigid contacts were warm
 * started and a collider's rigid contacts solved as a block (solver.c,
 * rigid_block), the steps stopped at the cap from about 1 s on: a wheel's
 * two rim points on flat ground are nearly redundant. */
static void test_rigid_drive(void)
{
  const int N = 2000, SETTLE = 20;
  double qpos[2][64], qvel[2][64];
  long sweeps[2] = {0, 0};
  int nq = 0, nv = 0;
  for (int warm = 1; warm >= 0; warm--) {
    ssModel *m;
    ssData *d;
    if (!load("scenes/buggy_rigid.xml", &m, &d)) return;
    m->opt.terrain_warm_start = warm;
    Watch w0 = {0}, w = {0};
    int r = run(m, d, SETTLE, &w0) && run(m, d, N - SETTLE, &w);
    nq = m->nq;
    nv = m->nv;
    if (r && nq <= 64 && nv <= 64) {
      memcpy(qpos[warm], d->qpos, (size_t)nq * sizeof(double));
      memcpy(qvel[warm], d->qvel, (size_t)nv * sizeof(double));
    }
    sweeps[warm] = w.sweeps;
    ok(r && w.unconverged == 0,
       "rigid ground, warm start %s: steps %d-%d all converged (%d at the cap; %.1f "
       "sweeps a step)",
       warm ? "on" : "off", SETTLE + 1, N, w.unconverged, (double)w.sweeps / (N - SETTLE));
    ss_data_free(d);
    ss_model_free(m);
    if (!r || nq > 64 || nv > 64) return;
  }
  /* each step's impulses converged to 1e-9 of the largest: the two runs
   * part by the solves' differences, which stay far below a micrometre
   * and a micrometre a second after 2 s */
  double dq = 0, dv = 0;
  for (int k = 0; k < nq; k++) dq = fmax(dq, fabs(qpos[1][k] - qpos[0][k]));
  for (int k = 0; k < nv; k++) dv = fmax(dv, fabs(qvel[1][k] - qvel[0][k]));
  ok(dq < 1e-6 && dv < 1e-6,
     "rigid ground: warm and cold starts reach the same state after %d steps "
     "(positions %.2g, velocities %.2g apart)", N, dq, dv);
  ok(fabs(qvel[1][0] - 0.8) < 0.01, "rigid ground: the buggy drives at the commanded "
     "0.8 m/s (%.4f)", qvel[1][0]);
  ok(sweeps[1] < sweeps[0], "rigid ground: the warm start takes fewer sweeps (%ld "
     "against %ld)", sweeps[1], sweeps[0]);
  /* the wheels' blocks held together through the chassis with the drive
   * and steering rows (solver.c, system_blocks): 3.1 sweeps a step; 9.5
   * without the rows, 38 without the system's solve */
  ok(sweeps[1] <= 5L * (N - SETTLE), "rigid ground: at most 5 sweeps a step warm (%.1f)",
     (double)sweeps[1] / (N - SETTLE));
}

/* Turning on rigid ground (buggy_rigid.xml with the rack held off
 * centre): its rim points stick and slide, and a wheel's two split its
 * load by small differences.  Solved by collider as blocks with the
 * blocks' own solve (solver.c, rigid_block) and the system's rigid
 * contacts and PD rows together every second sweep (system_blocks).
 * Turning left (rack 3 cm), steps 2001-4000 take 4.6 sweeps a step and
 * 14 stop at the 200-sweep cap.  Without the rows in the system's solve
 * (every fourth sweep) 11.2 and 13; before the block solve corrected the
 * state of its worst violation first, to a state it had not tried, and
 * judged a sliding contact settled against the block's largest impulse,
 * 18.5 and 61 (its state corrections cycled among a wheel's two rim
 * points); the collider blocks alone took 39 sweeps and capped one in
 * 25, passes alone three in five.  Turning right (2 cm), steps
 * 1001-3000: 3.6 sweeps, 3 capped (10.2 and 8 without the rows, 12.4 and
 * 21 before that).  Checked for both: at most 30 capped and 7 sweeps a
 * step, the buggy turns the way it is steered, the tie rods stay
 * closed. */
static void rigid_turn(double rack, int from, int to)
{
  ssModel *m;
  ssData *d;
  if (!load("scenes/buggy_rigid.xml", &m, &d)) return;
  for (int k = 0; k < m->npd; k++)
    if (strstr(m->body_jntname[m->pd_body[k]], "rack")) d->pd_target[2 * k] = rack;
  int chassis = body(m, "chassis");
  Watch w0 = {0}, w = {0};
  int r = run(m, d, from, &w0) && run(m, d, to - from, &w);
  const double *R = d->body_xmat + 9 * chassis;
  double yaw = atan2(R[3], R[0]);
  const char *way = rack > 0 ? "left" : "right";
  ok(r && w.unconverged <= 30 && w.sweeps <= 7L * (to - from),
     "rigid ground, turning %s: steps %d-%d stop at the sweep cap %d times (at most 30), "
     "%.1f sweeps a step (at most 7)", way, from + 1, to, w.unconverged,
     (double)w.sweeps / (to - from));
  ok(r && yaw * rack > 0 && fabs(yaw) > 0.1 && fmax(w0.closure, w.closure) < 1e-6,
     "  the buggy turns %s (yaw %.3f rad), the tie rods closed (%.2g m)", way, yaw,
     fmax(w0.closure, w.closure));
  ss_data_free(d);
  ss_model_free(m);
}

static void test_rigid_turn(void)
{
  rigid_turn(0.03, 2000, 4000);
  rigid_turn(-0.02, 1000, 3000);
}

/* 20 s on soil (the 4 cm test copy of scenes/buggy.xml), then removal */
/* the solver's packed link groups (one 6 x 6 block per wheel) reproduce
 * the full per-contact update at round-off */
static void test_packed_groups(void)
{
  ssModel *m;
  ssData *d;
  if (!load("scenes/buggy.xml", &m, &d)) return;
  run(m, d, 300, NULL);
  int nc = 0;
  double diff = solver_paths_difference(m, d, 8, &nc);
  ok(diff >= 0 && diff <= 1e-12 && nc > 400,
     "buggy on soil (%d contacts, 8 sweeps): packed and full solver paths agree, "
     "velocity difference %.3g relative", nc, diff);
  ss_data_free(d);
  ss_model_free(m);
}

/* The turning buggy: where a wheel's slip field turns about a point in
 * its patch, the point nearest it nearly sticks, its slip direction turns
 * with every Newton step in velocity form, and the phase used to stall
 * there (about a tenth of the turning steps, each then 100 sweeps).  Such
 * points are solved in impulse form (newton.c, NImpEval).  Five steps that
 * used it, each taken also by the sweeps alone from the same state: the
 * same impulses (bound as in test_newton), and the Newton steps need no
 * sweeps to speak of. */
static void test_newton_sticking(void)
{
  ssModel *m;
  ssData *d;
  if (!load("tests/data/buggy_turn_4cm.xml", &m, &d)) return;
  run(m, d, 200, NULL);
  const double tol = m->opt.solver_tolerance;
  double worst = 0;
  int good = 1, found = 0, sweeps[2] = {0, 0}, sticking = 0, k = 0;
  for (; k < 600 && found < 5 && good; k++) {
    PathCompare pc;
    good = newton_paths(m, d, &pc);
    if (!good || d->stats.newton_sticking == 0) continue;
    good = pc.converged[0] && pc.converged[1];
    found++;
    worst = fmax(worst, pc.dlam);
    sweeps[0] += pc.sweeps[0];
    sweeps[1] += pc.sweeps[1];
    sticking += d->stats.newton_sticking;
  }
  ok(good && found == 5 && worst <= 1e3 * tol && 10 * sweeps[0] <= sweeps[1],
     "turning buggy: %d steps with %d points in impulse form (of %d tried): %d sweeps "
     "after the Newton phase against %d alone; impulses %.2g apart relative (bound %.2g)",
     found, sticking, k, sweeps[0], sweeps[1], worst, 1e3 * tol);
  ss_data_free(d);
  ss_model_free(m);
}

/* The Newton phase against the sweeps alone on the driving buggy, ten
 * steps each taken both ways from the same state (bound: test_plate.c,
 * newton_case): the same impulses, and the sweeps that follow the phase a
 * fraction of those the sweeps alone need. */
static void test_newton(void)
{
  ssModel *m;
  ssData *d;
  if (!load("scenes/buggy.xml", &m, &d)) return;
  run(m, d, 300, NULL);
  const double tol = m->opt.solver_tolerance;
  double worst = 0;
  int good = 1, sweeps[2] = {0, 0}, newton = 0, nc = 0;
  for (int k = 0; k < 10 && good; k++) {
    PathCompare pc;
    good = newton_paths(m, d, &pc) && pc.converged[0] && pc.converged[1];
    worst = fmax(worst, pc.dlam);
    sweeps[0] += pc.sweeps[0];
    sweeps[1] += pc.sweeps[1];
    newton += pc.newton[0];
    nc = pc.ncontact;
  }
  ok(good && nc > 400 && worst <= 1e3 * tol && newton > 0 && 4 * sweeps[0] <= sweeps[1],
     "buggy on soil (%d contacts), 10 steps: %d Newton iterations + %d sweeps against %d "
     "sweeps alone; impulses %.2g apart relative (bound %.2g)", nc, newton, sweeps[0],
     sweeps[1], worst, 1e3 * tol);
  ss_data_free(d);
  ss_model_free(m);
}

/* How far a step's impulses are from their laws at the step's end
 * velocities (DESIGN 3.1 for the soil points, written out with soil.c's
 * functions apart from the solver's code; the PD rows' clamped affine
 * law): the largest |law - lambda|_1 over the largest |lambda|_1 of all
 * contacts, the solver's own measure (limit rows count in the latter
 * only).  The shear in velocity form (-T v_t / |v_t|): for steps without
 * points in impulse form. */
static double law_departure(const ssModel *m, const ssData *d)
{
  const double dt = m->opt.timestep;
  double dmax = 0, lmax = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    const double *l = c->lambda, *v = c->v;
    double law[3] = {l[0], l[1], l[2]};
    if (c->type == SS_CONTACT_SOIL) {
      const ssSoilMaterial *mat = &m->hfield_soilmat[c->hfield];
      double S = c->area * dt, delta = -(c->g0 + dt * v[0]);
      law[0] = law[1] = law[2] = 0;
      if (delta > 0) {
        law[0] = S * (ss_soil_pressure(mat, c->width, c->sp + delta, c->sp) +
                      ss_soil_viscous(mat, -v[0]));
        double vt = hypot(v[1], v[2]);
        if (vt > 0) {
          double T = S * ss_soil_shear_limit(mat, l[0] / S, c->j + dt * vt);
          law[1] = -T * v[1] / vt;
          law[2] = -T * v[2] / vt;
        }
      }
    } else if (c->type == SS_CONTACT_PD) {
      law[0] = fmax(-c->row_bound, fmin(c->row_bound, c->row_a - c->row_b * v[0]));
    }
    dmax = fmax(dmax, fabs(law[0] - l[0]) + fabs(law[1] - l[1]) + fabs(law[2] - l[2]));
    lmax = fmax(lmax, fabs(l[0]) + fabs(l[1]) + fabs(l[2]));
  }
  return lmax > 0 ? dmax / lmax : 0;
}

/* What drive_two_ways records of each way's steps: Newton iterations,
 * sweeps, steps ended by the linear end, soil contacts and loaded soil
 * points; and over the steps without points in impulse form and without
 * sweeps (checked), the largest law_departure (worst). */
typedef struct Ways {
  long newton[2], sweeps[2], contacts[2], loaded[2];
  int linear[2], checked[2];
  double worst[2];
} Ways;

/* The driving buggy (scenes/buggy.xml) after 1000 steps, then N steps
 * twice from that state (its checkpoint): way k (0, 1) with the solver's
 * reference flag or an option set as set_way(m, d, k) sets it, each converged step
 * counted into *w; way_z[k] the chassis height after way k.  Two ways of
 * solving the same steps that must agree: both ways every step's
 * impulses are converged answers, within 1e3 tol of each other relative
 * (the bound of test_plate.c's newton_case), so the chassis heights part
 * by at most sum_k k eps g dt^2 = N^2/2 1e3 tol g dt^2, returned in
 * *bound (tol, the scene's solver tolerance, in *tol).  0 (with a failed
 * test line) where the scene does not load, a step fails or does not
 * converge. */
static int drive_two_ways(int N, void (*set_way)(ssModel *m, ssData *d, int way), Ways *w,
                          double way_z[2], double *tol, double *bound)
{
  ssModel *m;
  ssData *d;
  ssError e;
  memset(w, 0, sizeof *w);
  if (!load("scenes/buggy.xml", &m, &d)) return 0;
  const double dt = m->opt.timestep;
  *tol = m->opt.solver_tolerance;
  *bound = 0.5 * N * N * 1e3 * *tol * 9.81 * dt * dt;
  unsigned char *buf = NULL;
  size_t len = 0;
  int good = run(m, d, 1000, NULL) && ss_checkpoint_save_buffer(m, d, &buf, &len, &e) == SS_OK;
  int chassis = body(m, "chassis");
  for (int k = 0; k < 2 && good; k++) {
    good = ss_checkpoint_load_buffer(m, d, buf, len, &e) == SS_OK;
    set_way(m, d, k);
    for (int i = 0; i < N && good; i++) {
      good = run(m, d, 1, NULL) && d->stats.converged;
      if (!good) break;
      w->newton[k] += d->stats.newton;
      w->sweeps[k] += d->stats.sweeps;
      w->linear[k] += d->stats.newton_linear;
      w->contacts[k] += d->stats.soil_contacts;
      w->loaded[k] += d->stats.soil_loaded;
      if (d->stats.newton_sticking == 0 && d->stats.sweeps == 0) {
        w->worst[k] = fmax(w->worst[k], law_departure(m, d));
        w->checked[k]++;
      }
    }
    way_z[k] = d->body_xpos[3 * chassis + 2];
  }
  if (!good) ok(0, "driving buggy: %d steps both ways from step 1000", N);
  free(buf);
  ss_data_free(d);
  ss_model_free(m);
  return good;
}

/* The Newton phase's start (newton.c, predict): the driving buggy's last
 * two answers extrapolated, against the warm start alone
 * (solver_no_predict), 200 steps each way from step 1000 (the steady
 * drive; steps 800-1000, over a bump of the suspension's, gain little).
 * Fewer Newton iterations (2.23 against 2.57 a step; at least 5 % fewer
 * asked), no more sweeps, and the same motion (drive_two_ways' bound). */
static void predict_way(ssModel *m, ssData *d, int way)
{
  (void)m;
  d->solver_no_predict = way;
}

static void test_predictor(void)
{
  const int N = 200;
  Ways p;
  double z[2], tol, bound;
  if (!drive_two_ways(N, predict_way, &p, z, &tol, &bound)) return;
  double dz = fabs(z[0] - z[1]);
  ok(20 * p.newton[0] <= 19 * p.newton[1] && p.sweeps[0] <= p.sweeps[1] && dz <= bound,
     "driving buggy, %d steps: %.2f Newton iterations a step from the last answers "
     "extrapolated, %.2f from the warm start alone (%ld and %ld sweeps); chassis heights "
     "%.2g m apart (bound %.2g)", N, (double)p.newton[0] / N, (double)p.newton[1] / N,
     p.sweeps[0], p.sweeps[1], dz, bound);
}

/* The Newton phase's linear end (newton.c, apply_linear): the step
 * expected to end a solve is applied by the laws' linear model at its
 * start, not evaluated at its end first.  The driving buggy, 200 steps
 * each way from step 1000 (solver_no_linear_end: the reference): the
 * linear end in most steps, never in the reference; every
 * step's impulses meet their laws at the end velocities within the
 * solver's tolerance, recomputed here apart from the solver (the check
 * accepts an answer within tol in its measure; the laws' powers and
 * exponentials agree with soil.c's to a few ulp, so 2 tol); no more
 * Newton iterations (5 % slack for the paths parting at round-off); the
 * same motion (drive_two_ways' bound). */
static void linear_way(ssModel *m, ssData *d, int way)
{
  (void)m;
  d->solver_no_linear_end = way;
}

static void test_linear_end(void)
{
  const int N = 200;
  Ways l;
  double z[2], tol, bound;
  if (!drive_two_ways(N, linear_way, &l, z, &tol, &bound)) return;
  double dz = fabs(z[0] - z[1]);
  ok(l.linear[0] >= N / 2 && l.linear[1] == 0 && l.checked[0] >= N / 2 &&
         l.checked[1] >= N / 2 && l.worst[0] <= 2 * tol && l.worst[1] <= 2 * tol &&
         20 * l.newton[0] <= 21 * l.newton[1] && dz <= bound,
     "driving buggy, %d steps: the Newton phase ends by its linear model in %d (the "
     "reference %d); the impulses' largest departure from their laws %.2g and %.2g "
     "(bound %.2g, %d and %d steps); %.2f and %.2f Newton iterations a step; chassis "
     "heights %.2g m apart (bound %.2g)", N, l.linear[0], l.linear[1], l.worst[0],
     l.worst[1], 2 * tol, l.checked[0], l.checked[1], (double)l.newton[0] / N,
     (double)l.newton[1] / N, dz, bound);
}

/* contact_margin, how far beyond the collider's reach in the step a soil
 * point becomes a contact (terrain.c, geom_margin): the default 2 mm
 * against 5 cm, which turns some 300 more points a step into contacts
 * that stay unloaded.  The driving buggy, 200 steps each way from step
 * 1000 (the checkpoint keeps the option, so it is set after the load):
 * the same loaded points (their sums equal), no more Newton iterations
 * or sweeps (5 % slack for the paths parting at round-off: the groups'
 * origins are their first contacts) and the same motion (drive_two_ways'
 * bound); and by the default at most one unloaded contact for eight
 * loaded points (34 for 426; the 1 cm default before made 110). */
static void margin_way(ssModel *m, ssData *d, int way)
{
  (void)d;
  m->opt.contact_margin = way ? 0.05 : ss_option_default().contact_margin;
}

static void test_margin(void)
{
  const int N = 200;
  Ways g;
  double z[2], tol, bound;
  if (!drive_two_ways(N, margin_way, &g, z, &tol, &bound)) return;
  double dz = fabs(z[0] - z[1]);
  ok(g.loaded[0] == g.loaded[1] && g.loaded[0] > 0 &&
         8 * (g.contacts[0] - g.loaded[0]) <= g.loaded[0] &&
         20 * g.newton[0] <= 21 * g.newton[1] && g.sweeps[0] <= g.sweeps[1] && dz <= bound,
     "driving buggy, %d steps: contact_margin %g m against 0.05 m: %.1f and %.1f soil "
     "contacts a step, %.1f and %.1f loaded; %.2f and %.2f Newton iterations a step; "
     "chassis heights %.2g m apart (bound %.2g)", N, ss_option_default().contact_margin,
     (double)g.contacts[0] / N, (double)g.contacts[1] / N, (double)g.loaded[0] / N,
     (double)g.loaded[1] / N, (double)g.newton[0] / N, (double)g.newton[1] / N, dz, bound);
}

/* The warm start waits (solver.c, warm_start) where the Newton phase may
 * start from its prediction, and is applied only where a solve starts
 * from it after all: the Newton phase declining its prediction, its
 * points that stick taking their warm impulses (ss_solver_warm_lambda),
 * the sweeps.  The turning buggy (scenes/buggy_turn.xml), whose Newton
 * phase puts points in impulse form, some of them sticking (step 856
 * took its warm impulses 0 before ss_solver_warm_lambda): 200 steps from
 * step 800, both ways from one checkpoint; the checkpoints after them the
 * same bytes. */
static void test_warm_deferred(void)
{
  ssModel *m;
  ssData *d;
  ssError e;
  if (!load("scenes/buggy_turn.xml", &m, &d)) return;
  unsigned char *buf = NULL, *end[2] = {NULL, NULL};
  size_t len = 0, end_len[2] = {0, 0};
  int good = run(m, d, 800, NULL) && ss_checkpoint_save_buffer(m, d, &buf, &len, &e) == SS_OK;
  int deferred = 0, sticking = 0;
  for (int k = 0; k < 2 && good; k++) {
    good = ss_checkpoint_load_buffer(m, d, buf, len, &e) == SS_OK;
    d->solver_warm_eager = k;
    for (int i = 0; i < 200 && good; i++) {
      int defer = !k && ss_newton_may_predict(m, d);
      good = run(m, d, 1, NULL);
      deferred += defer;
      sticking += defer && d->stats.newton_sticking > 0;
    }
    good = good && ss_checkpoint_save_buffer(m, d, &end[k], &end_len[k], &e) == SS_OK;
  }
  d->solver_warm_eager = 0;
  ok(good && end_len[0] == end_len[1] && !memcmp(end[0], end[1], end_len[0]) &&
         deferred >= 100 && sticking > 0,
     "turning buggy, 200 steps: the warm start deferred in %d steps (%d with points in "
     "impulse form) and applied at once: the same bytes after them", deferred, sticking);
  free(buf);
  free(end[0]);
  free(end[1]);
  ss_data_free(d);
  ss_model_free(m);
}

static void test_drive(void)
{
  ssModel *m;
  ssData *d;
  if (!load("tests/data/buggy_4cm.xml", &m, &d)) return;
  int chassis = body(m, "chassis"), wrl = body(m, "wheel_rl");
  double x0 = d->body_xipos[3 * chassis], slip_sum = 0;
  Watch watch = {0};
  int slip_n = 0;
  ssError e;
  /* 18 s, the run the scene and README suggest: it ends with the car
   * still on its bed (at 20 s, what they said before, its front wheels
   * had left it and the car was falling) */
  const int N = 18000;
  for (int k = 0; k < N; k++) {
    if (!run(m, d, 1, &watch)) break;
    if (k > 2000 && k % 100 == 0) {
      /* slip ratio of the rear wheel: 1 - v / (omega r) */
      double w = d->qvel[m->body_dofadr[wrl]], v = d->qvel[m->body_dofadr[chassis]];
      slip_sum += 1 - v / (w * 0.3611);
      slip_n++;
    }
  }
  double x1 = d->body_xipos[3 * chassis], speed = (x1 - x0) / (N * 1e-3);
  ok(speed > 0.5 && speed < 0.9, "on soil the chassis advances at %.3f m/s over %d s (0.5-0.9)",
     speed, N / 1000);
  /* every wheel over the bed at the end, its rim inside the far edge */
  double bed_end = m->hfield_center[0] + 0.5 * m->hfield_size[0], front = -INFINITY;
  static const char *const wheel[4] = {"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"};
  for (int k = 0; k < 4; k++) {
    int b = body(m, wheel[k]);
    front = fmax(front, b >= 0 ? d->body_xipos[3 * b] + 0.3611 : INFINITY);
  }
  ok(front < bed_end && watch.unconverged == 0,
     "after %d s the car is still on its bed (foremost rim at x = %.2f m, the bed ends at "
     "%.2f m) and every step converged", N / 1000, front, bed_end);
  double slip = slip_sum / slip_n;
  ok(slip > 0.02 && slip < 0.5, "the driven rear wheels slip (mean slip ratio %.3f)", slip);
  ok(watch.closure < 1e-6, "loop closure error < 1e-6 m over the whole drive (max %.3g)",
     watch.closure);
  /* the warm-start cache in the order a step's points arrive (solver.c
   * cmp_warm): by collider, then vertex, the joint rows last */
  int wheels = d->nwarm > 0 && d->warm[0].geom >= 0, rows = 0, ordered = 1;
  for (int k = 1; k < d->nwarm; k++) {
    const ssWarmEntry *a = d->warm + k, *b = a - 1;
    wheels += a->geom >= 0 && b->geom != a->geom;
    rows += a->geom < 0;
    ordered &= b->geom == a->geom ? b->vertex < a->vertex
                                  : (unsigned)b->geom < (unsigned)a->geom;
  }
  ok(ordered && wheels == 4 && rows > 0, "warm-start cache: %d entries, of 4 wheels by "
     "collider, then vertex, and %d joint rows last", d->nwarm, rows);

  /* ruts: permanent sinkage under the wheel tracks, none away from them
   * (the tracks run from 1.5 m behind the chassis' centre of mass at the
   * start to 1.8 m ahead of it at the end: the front axle is 1.4 m ahead
   * of it, a wheel's radius 0.36 m) */
  int h = 0, nx = m->hfield_nx[h], ny = m->hfield_ny[h];
  double dx = m->hfield_size[0] / (nx - 1), dy = m->hfield_size[1] / (ny - 1);
  double track_max = 0, off_track = 0;
  for (int j = 0; j < ny; j++) {
    double y = -3 + j * dy;
    for (int i = 0; i < nx; i++) {
      double x = -8 + i * dx, sp = d->soil_plastic[j * nx + i];
      int in_x = x > x0 - 1.5 && x < x1 + 1.8;
      int on = fabs(fabs(y) - 0.75) < 0.12 || fabs(fabs(y) - 0.78) < 0.12;
      if (in_x && on) track_max = fmax(track_max, sp);
      if (fabs(y) < 0.5 || fabs(y) > 1.1 || x < x0 - 1.5 || x > x1 + 1.8)
        off_track = fmax(off_track, fabs(d->soil_sinkage[j * nx + i]));
    }
  }
  /* the typical rut: the median of the deepest point across the rear
   * right track, over the straight part of the drive (the start, where
   * the wheels spin up from rest, digs deepest) */
  double *prof = malloc((size_t)nx * sizeof(double));
  int np = 0;
  for (int i = 0; i < nx; i++) {
    double x = -8 + i * dx, deep = 0;
    if (x < x0 + 2 || x > x1 - 1) continue;
    for (int j = 0; j < ny; j++) {
      double y = -3 + j * dy;
      if (fabs(y + 0.78) < 0.12) deep = fmax(deep, d->soil_plastic[j * nx + i]);
    }
    prof[np++] = deep;
  }
  for (int a = 1; a < np; a++)
    for (int b = a; b > 0 && prof[b - 1] > prof[b]; b--) {
      double t = prof[b];
      prof[b] = prof[b - 1];
      prof[b - 1] = t;
    }
  double median = np ? prof[np / 2] : 0;
  free(prof);
  ok(median > 0.02 && median < 0.10,
     "ruts of several centimetres under the tracks (median %.1f mm along the rear track, deepest %.1f mm)",
     median * 1e3, track_max * 1e3);
  ok(off_track == 0, "the soil outside the tracks is untouched (max %.3g m)", off_track);

  /* remove the car: the elastic part recovers, the ruts remain */
  int n = m->nhfielddata;
  double *s_before = malloc(n * sizeof(double)), *p_before = malloc(n * sizeof(double));
  memcpy(s_before, d->soil_sinkage, n * sizeof(double));
  memcpy(p_before, d->soil_plastic, n * sizeof(double));
  ss_remove(m, d, "buggy", &e);
  run(m, d, 1, NULL);
  double risen = 0, rut_kept = 1;
  int loaded = 0;
  for (int k = 0; k < n; k++) {
    if (d->soil_plastic[k] != p_before[k]) rut_kept = 0;
    if (s_before[k] > p_before[k]) {
      loaded++;
      risen = fmax(risen, s_before[k] - d->soil_sinkage[k]);
      if (d->soil_sinkage[k] != d->soil_plastic[k]) rut_kept = 0;
    }
  }
  ok(loaded > 0 && risen > 0, "after removal the surface rose by the elastic part (%.3f mm at most, %d vertices)",
     risen * 1e3, loaded);
  ok(rut_kept, "after removal the ruts remain (plastic sinkage unchanged)");
  free(s_before);
  free(p_before);
  ss_data_free(d);
  ss_model_free(m);
}

/* steering: the rack held to the left turns the car to the left.  The
 * turning wheels' patches have points near sticking in about a quarter of
 * the steps; the Newton phase solves nearly all of them: 960 sweeps in
 * the 6000 steps, 14 steps over 20 sweeps, none unconverged (with 8
 * iterations and 4 more after each switch to impulse form, and without
 * the projection onto the discs: 3882, 44 and 5; with 16 iterations but
 * without the projection: 1122, 11 and 2). */
static void test_steering(void)
{
  ssModel *m;
  ssData *d;
  if (!load("tests/data/buggy_turn_4cm.xml", &m, &d)) return;
  int chassis = body(m, "chassis");
  Watch w = {0};
  run(m, d, 6000, &w);
  const double *R = d->body_xmat + 9 * chassis;
  double yaw = atan2(R[3], R[0]);
  ok(yaw > 0.1, "a rack offset to the left turns the buggy left (yaw %.3f rad)", yaw);
  ok(d->body_xipos[3 * chassis + 1] > 0.05, "  and it drifts to +y (%.3f m)", d->body_xipos[3 * chassis + 1]);
  ok(w.closure < 1e-6, "  the tie rods stay closed (max error %.3g m)", w.closure);
  ok(w.sweeps <= 2000 && w.slow <= 25 && w.unconverged <= 1,
     "  the Newton phase solves the turning steps: %ld sweeps in 6000 steps, %d steps over 20 "
     "sweeps, %d unconverged", w.sweeps, w.slow, w.unconverged);
  ss_data_free(d);
  ss_model_free(m);
}

/* the same scene run twice exports identical files */
static void test_determinism(void)
{
  char out[2][256];
  for (int k = 0; k < 2; k++) {
    ssModel *m;
    ssData *d;
    ssError e;
    if (!load_scene_file("tests/data/buggy_4cm.xml", &m, &d)) return;
    run(m, d, 300, NULL);
    snprintf(out[k], sizeof out[k], "/tmp/soilsim-buggy-%ld-%d.xml", (long)getpid(), k);
    ss_scene_export(m, d, out[k], &e);
    ss_data_free(d);
    ss_model_free(m);
  }
  FILE *a = fopen(out[0], "rb"), *b = fopen(out[1], "rb");
  int same = a && b;
  while (same) {
    int ca = fgetc(a), cb = fgetc(b);
    if (ca != cb) same = 0;
    if (ca == EOF || cb == EOF) break;
  }
  if (a) fclose(a);
  if (b) fclose(b);
  ok(same, "the same buggy scene run twice exports identical files");
  remove(out[0]);
  remove(out[1]);
}

/* the soil reach (terrain.c) of an articulated link's geoms: any point
 * within the geom's bounding radius moves along the bed normal n at most
 * ss_dyn_geom_approach, and some point on that sphere moves at it (r along
 * n x omega), with the link's velocity from the joints' (arbitrary
 * velocities here); never more than the speed bound in any direction */
static void test_reach(void)
{
  ssModel *m;
  ssData *d;
  if (!load("scenes/buggy.xml", &m, &d)) return;
  int s = ss_model_find_sys(m, "buggy");
  unsigned x = 12345;
  for (int k = m->sys_vadr[s]; k < m->sys_vadr[s] + m->sys_nv[s]; k++) {
    x = x * 1103515245u + 12345u;
    d->qvel[k] = ((x >> 8) & 0xffff) / 32768.0 - 1;
  }
  ss_forward(m, d);
  const double n[3] = {0, 0, 1};
  int bad = 0, checked = 0;
  double worst = 0;
  for (int g = 0; g < m->ngeom; g++) {
    if (m->body_sys[m->geom_body[g]] != s) continue;
    double rad = ss_dyn_geom_radius(m, g), a = ss_dyn_geom_approach(m, d, g, rad, n);
    double top = 0;
    const int N = 4000;
    for (int i = 0; i < N; i++) {
      /* a Fibonacci sphere of radius rad about the geom centre */
      double z = 1 - (2 * i + 1.0) / N, rho = sqrt(1 - z * z), phi = 2.399963229728653 * i;
      double p[3] = {rad * rho * cos(phi), rad * rho * sin(phi), rad * z}, v[3];
      ss_v3_add(p, p, d->geom_xpos + 3 * g);
      ss_dyn_point_velocity(m, d, m->geom_body[g], p, v);
      top = fmax(top, fabs(ss_v3_dot(v, n)));
    }
    checked++;
    double rel = (a - top) / a;
    worst = fmax(worst, rel);
    if (!(top <= a * (1 + 1e-12) && rel < 2e-3 && a <= ss_dyn_geom_speed(m, d, g, rad)))
      bad++;
  }
  ok(checked > 0 && bad == 0,
     "reach: on %d geoms of the moving buggy no point within the bounding radius "
     "outruns the approach bound, which is met to %.1e (sampled) and is below "
     "the speed bound",
     checked, worst);
  ss_data_free(d);
  ss_model_free(m);
}

/* The buggy and its bed moved together 100 km along x: the same drive,
 * and the same work.  An articulated system's spatial vectors are about
 * its own origin near it (articulated.h, ss_art_origin); about the world
 * origin the buggy 1 km out took 10 Newton iterations a step and 1.4
 * sweeps against 2.3 and 0.01, at 100 km the solver's tolerance was out
 * of reach in many steps.  The drive from the same state must agree to
 * round-off of the distances (1e5 m x 1e-16 a step, summed: 1e-8 m is
 * generous) and cost no more than 5 % more Newton iterations. */
static void test_far_from_origin(void)
{
  const double X = 1e5;
  const int N = 600;
  long newton[2] = {0, 0}, sweeps[2] = {0, 0};
  double pos[2][3];
  int good = 1;
  for (int k = 0; k < 2 && good; k++) {
    ssModel *m;
    ssData *d;
    if (!load("scenes/buggy.xml", &m, &d)) return;
    int chassis = body(m, "chassis"), root = m->sys_qadr[0];
    if (k) {
      d->qpos[root] += X;
      d->hfield_pos[0] += X;
      ss_forward(m, d);
    }
    ssError e;
    for (int i = 0; i < N && good; i++) {
      good = ss_step(m, d, &e) == SS_OK && d->stats.converged;
      newton[k] += d->stats.newton;
      sweeps[k] += d->stats.sweeps;
    }
    ss_v3_copy(pos[k], d->body_xpos + 3 * chassis);
    pos[k][0] -= k ? X : 0;
    ss_data_free(d);
    ss_model_free(m);
  }
  double dx = fabs(pos[1][0] - pos[0][0]), dz = fabs(pos[1][2] - pos[0][2]);
  ok(good && 20 * newton[1] <= 21 * newton[0] && sweeps[1] <= sweeps[0] + 10 && dx <= 1e-8 &&
         dz <= 1e-8,
     "the buggy 100 km from the origin, %d steps: %ld Newton iterations and %ld sweeps (at "
     "the origin %ld and %ld); the chassis %.2g m (x) and %.2g m (z) from its path there",
     N, newton[1], sweeps[1], newton[0], sweeps[0], dx, dz);
}

int main(void)
{
  test_statics();
  test_rigid_drive();
  test_rigid_turn();
  test_steering();
  test_determinism();
  test_packed_groups();
  test_newton();
  test_predictor();
  test_linear_end();
  test_margin();
  test_warm_deferred();
  test_newton_sticking();
  test_drive();
  test_reach();
  test_far_from_origin();
  return done_testing();
}
