/* test_plate.c -- rigid bodies on soil and rigid ground, end to end through
 * the contact solver, against the closed forms of DESIGN 2.7. */
#include "articulated.h"
#include "mesh.h"
#include "model_build.h"
#include "soilsim.h"
#include "solver.h"
#include "ss_math.h"
#include "tap.h"
#include "worlds.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double G = 9.81;

typedef struct {
  ssModel *m;
  ssData *d;
  int plate, bed;
} World;

/* a flat bed (size x size, spacing h) and a box plate lx x ly x 0.05 */
static World make_world(ssSoilMaterial soil, double size, double h, double lx,
                        double ly, double mass, double ox, double oy,
                        double yaw, double lift)
{
  World w;
  ssError e;
  w.m = ss_model_new();
  w.bed = add_bed(w.m, size, h, soil);
  ssBodyDef bd = ss_body_def_default();
  bd.name = "plate";
  bd.shape = SS_GEOM_BOX;
  bd.size[0] = lx;
  bd.size[1] = ly;
  bd.size[2] = 0.05;
  bd.mass = mass;
  ss_v3_set(bd.pos, ox, oy, 0.025 + lift);
  double axis[3] = {0, 0, 1};
  ss_quat_from_axis_angle(bd.quat, axis, yaw);
  w.plate = ss_model_add_body(w.m, &bd, &e);
  w.d = ss_data_new(w.m);
  if (w.bed < 0 || w.plate < 0 || !w.d) diag("world build failed: %s", e.message);
  return w;
}

static void free_world(World *w)
{
  ss_data_free(w->d);
  ss_model_free(w->m);
}

static int run(World *w, int steps)
{
  ssError e;
  for (int k = 0; k < steps; k++)
    if (ss_step(w->m, w->d, &e) != SS_OK) {
      diag("step failed: %s", e.message);
      return 0;
    }
  return 1;
}

/* plate sinkage from its pose: depth of the bottom face centre */
static double plate_sinkage(const World *w) { return -(w->d->qpos[2] - 0.025); }

/* mean of a soil array over vertices at least `inset` inside the plate */
static double mean_under(const World *w, const double *arr, double cx,
                         double cy, double yaw, double lx, double ly,
                         double inset, int *count)
{
  const ssModel *m = w->m;
  int n = m->hfield_nx[w->bed];
  double size = m->hfield_size[0], h = size / (n - 1), sum = 0;
  int cnt = 0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double x = -0.5 * size + i * h - cx, y = -0.5 * size + j * h - cy;
      double u = cos(yaw) * x + sin(yaw) * y, v = -sin(yaw) * x + cos(yaw) * y;
      if (fabs(u) < 0.5 * lx - inset && fabs(v) < 0.5 * ly - inset) {
        sum += arr[j * n + i];
        cnt++;
      }
    }
  *count = cnt;
  return cnt ? sum / cnt : NAN;
}

static double max_outside(const World *w, const double *arr, double cx,
                          double cy, double yaw, double lx, double ly,
                          double outset)
{
  const ssModel *m = w->m;
  int n = m->hfield_nx[w->bed];
  double size = m->hfield_size[0], h = size / (n - 1), mx = 0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double x = -0.5 * size + i * h - cx, y = -0.5 * size + j * h - cy;
      double u = cos(yaw) * x + sin(yaw) * y, v = -sin(yaw) * x + cos(yaw) * y;
      if (fabs(u) > 0.5 * lx + outset || fabs(v) > 0.5 * ly + outset)
        if (fabs(arr[j * n + i]) > mx) mx = fabs(arr[j * n + i]);
    }
  return mx;
}

/* A bed turned about its normal and moved (its pose in ssData): the soil
 * points come from the collider in the bed's frame and go back to the
 * world through the pose (terrain.c; an unturned bed skips the product by
 * R), so the plate set on it at the same turn settles as on the unturned
 * bed, to 8.175 mm, its points' positions under the plate in the world. */
static void test_turned_bed(void)
{
  const double yaw = 0.5, s_ref = 8.175e-3, pos[3] = {0.3, -0.2, 0.01};
  World w = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, pos[0], pos[1], yaw, pos[2]);
  double axis[3] = {0, 0, 1};
  ss_quat_from_axis_angle(w.d->hfield_quat + 4 * w.bed, axis, yaw);
  memcpy(w.d->hfield_pos + 3 * w.bed, pos, sizeof pos);
  int good = run(&w, 1500);
  double sink = -(w.d->qpos[2] - 0.025 - pos[2]), worst = 0;
  for (int i = 0; good && i < w.d->ncontact; i++) {
    /* each point in the plate's footprint (world), on the bed's plane */
    const double *c = w.d->contact[i].pos;
    double x = c[0] - w.d->qpos[0], y = c[1] - w.d->qpos[1];
    double u = cos(yaw) * x + sin(yaw) * y, v = -sin(yaw) * x + cos(yaw) * y;
    worst = fmax(worst, fmax(fabs(u) - 0.2, fabs(v) - 0.3));
    worst = fmax(worst, fabs(c[2] - (pos[2] - sink)) - 1e-3);
  }
  ok(good && fabs(sink - s_ref) <= 0.005 * s_ref &&
         fabs(w.d->stats.soil_contact_area - 0.24) <= 1e-9 && w.d->ncontact > 0 && worst <= 1e-9,
     "a bed turned by %g rad and moved: plate sinkage %.4f mm (want %.3f), loaded area %.6f "
     "m^2, %d points within the plate's footprint in the world (worst %.2g m out)",
     yaw, 1e3 * sink, 1e3 * s_ref, w.d->stats.soil_contact_area, w.d->ncontact, worst);
  free_world(&w);
}

/* DESIGN 2.7: 20 kg, 0.4 x 0.6 m -> 8.175 mm; rut after lifting 7.766 mm */
static void test_analytic_plate(void)
{
  const double s_ref = 8.175e-3, rut_ref = 7.76625e-3;
  struct { double h, ox, oy, yaw; } cases[] = {
    {0.01, 0, 0, 0},           {0.02, 0, 0, 0},
    {0.03, 0.013, -0.007, 0},  {0.05, 0.021, 0.012, 0},
    {0.02, 0.013, -0.007, M_PI / 6}, {0.05, -0.004, 0.017, M_PI / 4},
    {0.03, 0, 0, 1.0},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    double h = cases[c].h, ox = cases[c].ox, oy = cases[c].oy, yaw = cases[c].yaw;
    World w = make_world(plate_soil(), 1.2, h, 0.4, 0.6, 20, ox, oy, yaw, 0);
    if (!run(&w, 1500)) {
      ok(0, "settle run failed");
      free_world(&w);
      continue;
    }
    char what[160];
    snprintf(what, sizeof what, "h = %g m, offset (%g, %g), heading %.3g rad: plate sinkage",
             h, ox, oy, yaw);
    close_enough(plate_sinkage(&w), s_ref, 0.005 * s_ref, what);
    close_enough(w.d->stats.soil_contact_area, 0.24, 1e-9, "  loaded area = true plate area");
    close_enough(w.d->stats.soil_normal_force, 20 * G, 1e-3 * 20 * G, "  normal force = m g at rest");
    int cnt;
    double mean = mean_under(&w, w.d->soil_sinkage, ox, oy, yaw, 0.4, 0.6, h, &cnt);
    close_enough(mean, s_ref, 0.005 * s_ref, "  soil sinkage under the plate");
    /* remove the plate: the elastic part recovers, the rut remains */
    ssError e;
    ss_remove(w.m, w.d, "plate", &e);
    run(&w, 1);
    double rut = mean_under(&w, w.d->soil_sinkage, ox, oy, yaw, 0.4, 0.6, h, &cnt);
    close_enough(rut, rut_ref, 0.01 * rut_ref, "  rut after removing the plate");
    double pl = mean_under(&w, w.d->soil_plastic, ox, oy, yaw, 0.4, 0.6, h, &cnt);
    close_enough(rut, pl, 1e-15, "  after removal sinkage = plastic sinkage");
    ok(max_outside(&w, w.d->soil_sinkage, ox, oy, yaw, 0.4, 0.6, 0.75 * h) == 0,
       "  soil outside the footprint untouched");
    free_world(&w);
  }
}

/* n != 1 and two widths separating k_c and k_phi, end to end */
static void test_envelope_shapes(void)
{
  ssSoilMaterial s = plate_soil();
  s.sinkage_exponent = 1.1;
  double p = 20 * G / 0.24, s_ref = 0.01;
  s.bekker_kphi = p / pow(s_ref, 1.1);
  World w = make_world(s, 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  run(&w, 2000);
  close_enough(plate_sinkage(&w), s_ref, 0.005 * s_ref, "n = 1.1, k_phi = p/s_ref^n: sinkage s_ref");
  free_world(&w);

  /* same area and load, widths 0.4 and 0.2: s = (p / (k_c/b + k_phi))^(1/n) */
  ssSoilMaterial c = plate_soil();
  c.bekker_kc = 5000;
  c.bekker_kphi = 6e4;
  double dims[2][2] = {{0.4, 0.6}, {0.2, 1.2}};
  for (int k = 0; k < 2; k++) {
    double b = dims[k][0];
    double want = p / (c.bekker_kc / b + c.bekker_kphi);
    World v = make_world(c, 1.6, 0.02, dims[k][0], dims[k][1], 20, 0, 0, 0, 0);
    run(&v, 2000);
    char what[96];
    snprintf(what, sizeof what, "k_c = 5000, width %.1f m: sinkage", b);
    close_enough(plate_sinkage(&v), want, 0.005 * want, what);
    free_world(&v);
  }
}

/* reloading a rut follows K_e, then the envelope */
static void test_reload(void)
{
  World w = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  run(&w, 1500);
  ssError e;
  ss_remove(w.m, w.d, "plate", &e);
  run(&w, 1);
  int n = w.m->nhfielddata;
  double *sk = malloc(n * sizeof(double)), *pl = malloc(n * sizeof(double)), *sh = malloc(n * sizeof(double));
  ss_soil_get_state(w.m, w.d, 0, sk, pl, sh, &e);
  double rut = 7.76625e-3;

  /* a 10 kg plate in the rut: elastic only, extra sinkage p/K_e */
  for (int k = 0; k < 2; k++) {
    double mass = k == 0 ? 10 : 40;
    World v = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, mass, 0, 0, 0, -rut);
    ss_soil_set_state(v.m, v.d, 0, sk, pl, sh, &e);
    run(&v, 1500);
    double pm = mass * G / 0.24;
    int cnt;
    if (k == 0) {
      close_enough(plate_sinkage(&v), rut + pm / 2e6, 0.005 * pm / 2e6,
                   "10 kg in the rut: reload along K_e (rut + p/K_e)");
      double plm = mean_under(&v, v.d->soil_plastic, 0, 0, 0, 0.4, 0.6, 0.02, &cnt);
      close_enough(plm, rut, 1e-6 * rut, "  the rut does not deepen on elastic reload");
    } else {
      close_enough(plate_sinkage(&v), pm / 1e5, 0.005 * pm / 1e5,
                   "40 kg in the rut: K_e until the envelope, then yield");
    }
    free_world(&v);
  }
  free(sk);
  free(pl);
  free(sh);
  free_world(&w);
}

/* an impact compacts deeper than slow loading; lifting has no suction */
static void test_impact_and_lift(void)
{
  ssSoilMaterial s = plate_soil();
  s.damping = 2000;
  World w = make_world(s, 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0.05);
  run(&w, 1500);
  ssError e;
  ss_remove(w.m, w.d, "plate", &e);
  run(&w, 1);
  int cnt;
  double rut = mean_under(&w, w.d->soil_plastic, 0, 0, 0, 0.4, 0.6, 0.02, &cnt);
  ok(rut > 1.2 * 7.76625e-3, "dropped from 5 cm: rut %.4g mm deeper than the slow 7.766 mm", rut * 1e3);
  free_world(&w);

  /* settle, then pull up with 2 m g: the soil never pulls the plate down */
  World v = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  double up[3] = {0, 0, 2 * 20 * G}, zero[3] = {0, 0, 0};
  ss_model_add_xforce(v.m, 0, up, zero, 1.0, 1e9, &e);
  run(&v, 1000);
  int suction = 0, negative = 0;
  for (int k = 0; k < 300; k++) {
    double vz = v.d->qvel[2];
    run(&v, 1);
    if (v.d->qvel[2] - vz < 1e-3 * G * 1e-3 - 1e-12) suction++;
    if (v.d->stats.soil_normal_force < 0) negative++;
  }
  ok(suction == 0, "lifting: upward acceleration never below (F - m g)/m (%d steps)", suction);
  ok(negative == 0, "no negative soil normal force");
  ok(v.d->stats.soil_normal_force == 0 && v.d->qpos[2] > 0.05, "the plate left the soil");
  double pl = mean_under(&v, v.d->soil_plastic, 0, 0, 0, 0.4, 0.6, 0.02, &cnt);
  double sk = mean_under(&v, v.d->soil_sinkage, 0, 0, 0, 0.4, 0.6, 0.02, &cnt);
  close_enough(sk, pl, 1e-15, "the surface recovered to the rut floor");
  free_world(&v);
}

/* a horizontal pull below full strength, ramped up slowly (quasi-static,
 * like the reference): the plate creeps until the mobilized Janosi strength
 * carries the pull, F = (c A + mu m g)(1 - exp(-j/K_j)).  A sudden pull
 * overshoots that (inertia), so the ramp's increments are far shorter than
 * the plate's shear period 2 pi sqrt(m K_j / (c A + mu m g)) = 0.24 s. */
static void test_drag(void)
{
  ssSoilMaterial s = plate_soil();
  World w = make_world(s, 1.6, 0.04, 0.4, 0.6, 20, -0.2, 0, 0, 0);
  ssError e;
  const double F = 60, dt = w.m->opt.timestep;
  const int nramp = 600;
  double zero[3] = {0, 0, 0}, f[3] = {F / nramp, 0, 0};
  for (int k = 0; k < nramp; k++) ss_model_add_xforce(w.m, 0, f, zero, 1.0 + 0.005 * k, 1e9, &e);
  long sweeps = 0;
  run(&w, 1000);
  double x0 = w.d->qpos[0];
  int visits = 0, slipping = 0;
  double worst_bound = 0, worst_align = 0, power_sum = 0;
  for (int k = 0; k < 4000; k++) {
    run(&w, 1);
    sweeps += w.d->stats.sweeps;
    for (int i = 0; i < w.d->ncontact; i++) {
      const ssContact *c = &w.d->contact[i];
      if (!c->loaded) continue;
      visits++;
      double sc = c->area * dt, vt = hypot(c->v[1], c->v[2]);
      double lt = hypot(c->lambda[1], c->lambda[2]);
      double tmax = sc * ss_soil_shear_limit(&s, c->lambda[0] / sc, c->j + dt * vt);
      worst_bound = fmax(worst_bound, (lt - tmax) / (sc * ss_soil_shear_strength(&s, c->lambda[0] / sc)));
      double power = c->lambda[1] * c->v[1] + c->lambda[2] * c->v[2];
      /* where a point really slips, the shear is antiparallel to the slip;
       * below ~1e-8 m/s a slip velocity is the converged solve's noise
       * (N contacts x G x tolerance x impulse), so 1e-6 m/s is the floor */
      if (vt > 1e-6 && lt > 0) {
        slipping++;
        power_sum += power;
        worst_align = fmax(worst_align, 1 + power / (lt * vt));
      }
    }
  }
  diag("drag: %.1f sweeps per step", (double)sweeps / 4000);
  /* each point meets its bound when visited; the sweeps stop at a relative
   * impulse change of 1e-9, so the end-of-step velocities used here may
   * differ by that order: allow 1e-6 tau_f */
  ok(visits > 0 && worst_bound <= 1e-6,
     "shear within tau_max at every loaded point (%d visits, worst excess %.2g tau_f)", visits, worst_bound);
  ok(slipping > 0 && worst_align <= 1e-9,
     "shear opposes slip where points slip (%d, worst 1 + cos = %.2g)", slipping, worst_align);
  ok(power_sum <= 0, "shear never adds energy (total shear power %.3g W)", power_sum / dt);
  double tf = s.cohesion * 0.24 + s.friction_coefficient * 20 * G;
  double jstar = -s.shear_displacement * log(1 - F / tf);
  double dx = w.d->qpos[0] - x0;
  /* 3 %: the leading strip of the plate meets fresh soil with j = 0 */
  close_enough(dx, jstar, 0.03 * jstar, "creep distance from Janosi-Hanamoto");
  ok(fabs(w.d->qvel[0]) < 1e-4, "the creep stops (v = %g m/s)", w.d->qvel[0]);
  free_world(&w);

  /* above full strength the plate slides on */
  World v = make_world(s, 3.0, 0.02, 0.4, 0.6, 20, -1.0, 0, 0, 0);
  double f2[3] = {2 * tf, 0, 0};
  (void)f;
  ss_model_add_xforce(v.m, 0, f2, zero, 1.0, 1e9, &e);
  run(&v, 1600);
  double v1 = v.d->qvel[0];
  run(&v, 200);
  ok(v.d->qvel[0] > v1 && v1 > 0.1, "pulled with twice the strength it slides and accelerates");
  free_world(&v);
}

/* A soil point becomes a contact when the collider can reach it within
 * the step plus contact_margin (set to 1 cm here): the reach is the speed of the
 * collider's points along the bed's normal, |v.n| + r |n x omega|, not their
 * speed in any direction.  A ball 1.2 cm above the bed: sliding at 5 m/s
 * it reaches no point (a reach of |v| dt would take 0.5 cm more, and
 * points with them); falling at 5 m/s, or spinning at 80 rad/s about a
 * level axis (its front moves down at 8 m/s), it does. */
static void test_reach(void)
{
  const double r = 0.1, gap = 0.012;
  const struct {
    const char *what;
    double v[3], w[3];
    int reach;
  } c[] = {
      {"sliding level", {5, 0, 0}, {0, 0, 0}, 0},
      {"spinning about the vertical", {0, 0, 0}, {0, 0, 80}, 0},
      {"falling", {0, 0, -5}, {0, 0, 0}, 1},
      {"spinning about a level axis", {0, 0, 0}, {0, 80, 0}, 1},
  };
  for (int k = 0; k < 4; k++) {
    ssError e;
    ssModel *m = ss_model_new();
    m->opt.contact_margin = 0.01;
    add_soil_bed(m, 1.0, 0.02);
    ssBodyDef b = ss_body_def_default();
    b.name = "ball";
    b.shape = SS_GEOM_SPHERE;
    b.size[0] = r;
    b.mass = 1;
    ss_v3_set(b.pos, 0, 0, r + gap);
    memcpy(b.lin_vel, c[k].v, sizeof b.lin_vel);
    memcpy(b.ang_vel, c[k].w, sizeof b.ang_vel);
    ss_model_add_body(m, &b, &e);
    ssData *d = ss_data_new(m);
    ssStatus st = ss_step(m, d, &e);
    ok(st == SS_OK && (d->stats.soil_contacts > 0) == c[k].reach &&
           d->stats.soil_normal_force == 0,
       "reach: a ball %s 1.2 cm above the bed %s (%d points)", c[k].what,
       c[k].reach ? "reaches points" : "reaches none", d->stats.soil_contacts);
    ss_data_free(d);
    ss_model_free(m);
  }
}

/* Contact storage: room for a row of points at once (ss_contact_reserve),
 * then each taken without a check (ss_contact_add): the Jacobian blocks
 * follow one another, every new contact's head is zeroed over whatever
 * the array held, and a request that cannot be met is refused with the
 * contacts as they were. */
static void test_contact_storage(void)
{
  ssModel *m;
  ssData *d;
  ssError e;
  if (!plate_world(11, 1.0, 0, 0, NULL, &m, &d, &e)) {
    ok(0, "plate world: %s", e.message);
    return;
  }
  int good = ss_contact_reserve(d, 700, 36) && d->cap_contact >= 700;
  if (good) memset(d->contact, 0xa5, (size_t)d->cap_contact * sizeof *d->contact);
  d->ncontact = 0;
  for (int round = 0; good && round < 3; round++) {
    good = ss_contact_reserve(d, 300, 36);
    for (int k = 0; good && k < 300; k++) {
      int n = d->ncontact;
      ssContact *c = ss_contact_add(d, 36);
      good = c == d->contact + n && c->jadr == 36L * n && c->jlen == 36 && c->link == -1 &&
             c->lambda[0] == 0 && c->lambda[2] == 0 && c->cache_ready == 0 &&
             c->w_ready == 0 && c->type == 0;
    }
  }
  int n = d->ncontact;
  const ssContact *before = d->contact;
  int refused = !ss_contact_reserve(d, INT_MAX, 36) && d->ncontact == n && d->contact == before;
  ok(good && n == 900 && d->cap_jac >= 900 * 36 && refused,
     "contact storage: 900 contacts in rows of 300, Jacobian blocks in order and "
     "heads zeroed; an impossible request refused, the contacts kept");
  d->ncontact = 0;
  ss_data_free(d);
  ss_model_free(m);
}

/* a model with a steel ground plane at z = 0, rubber on steel at friction
 * 0.5 and the given restitution above its threshold speed */
static ssModel *steel_ground(double restitution, double threshold, ssError *e)
{
  ssModel *m = ss_model_new();
  ss_model_add_plane(m, "ground", 0, "steel", 0, e);
  ss_model_set_pair(m, "steel", "rubber", 0.5, restitution, threshold, e);
  return m;
}

/* a 5 kg box named "box", 0.4 x 0.3 x 0.1 m, at the origin */
static ssBodyDef box_def(void)
{
  ssBodyDef b = ss_body_def_default();
  b.name = "box";
  b.size[0] = 0.4;
  b.size[1] = 0.3;
  b.size[2] = 0.1;
  b.mass = 5;
  return b;
}

/* a 5 kg rubber box, 0.2 x 0.2 x 0.1 m, on the ground at x = 2 sliding
 * along +x at 3 m/s */
static void add_slider(ssModel *m, ssError *e)
{
  ssBodyDef p = ss_body_def_default();
  p.name = "slider";
  p.size[0] = p.size[1] = 0.2;
  p.size[2] = 0.1;
  p.mass = 5;
  p.material = "rubber";
  ss_v3_set(p.pos, 2, 0, 0.05);
  p.lin_vel[0] = 3;
  ss_model_add_body(m, &p, e);
}

/* rigid ground: rest, friction and restitution from the material pairs */
static void test_rigid(void)
{
  ssError e;
  ssModel *m = steel_ground(0.5, 0.01, &e);
  ssBodyDef b = ss_body_def_default();
  b.name = "ball";
  b.shape = SS_GEOM_SPHERE;
  b.size[0] = 0.1;
  b.mass = 1;
  b.material = "rubber";
  ss_v3_set(b.pos, 0, 0, 1.1);
  ss_model_add_body(m, &b, &e);
  add_slider(m, &e);
  ssData *d = ss_data_new(m);
  /* ball falls 1 m: impact at sqrt(2 g) ~ 4.43 m/s, rebounds at e times */
  double vmin = 0, vmax_after = 0;
  int bounced = 0;
  for (int k = 0; k < 700; k++) {
    ss_step(m, d, &e);
    double vz = d->qvel[2];
    if (!bounced && vz < vmin) vmin = vz;
    if (vz > 0) bounced = 1;
    if (bounced && vz > vmax_after) vmax_after = vz;
  }
  close_enough(vmax_after / -vmin, 0.5, 0.02, "restitution 0.5 from the material pair");
  /* the slider decelerates at mu g and stops after v^2 / (2 mu g) */
  double want = 9.0 / (2 * 0.5 * G);
  close_enough(d->qpos[7] - 2, want, 0.02 * want, "sliding box stops after v^2/(2 mu g)");
  close_enough(d->qpos[9], 0.05, 1e-3, "box rests on the ground plane");
  ss_data_free(d);
  ss_model_free(m);

  /* a rigid height map inclined at 20 degrees: mu 0.5 < tan 20 = 0.364? no:
   * 0.5 > 0.364, the box stays; with mu 0.2 it slides at g (sin - mu cos) */
  for (int k = 0; k < 2; k++) {
    double mu = k == 0 ? 0.5 : 0.2, th = 20 * M_PI / 180;
    ssModel *m2 = ss_model_new();
    int n = 41;
    double *z = malloc(n * n * sizeof(double));
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) z[j * n + i] = tan(th) * (-2 + 4.0 * i / (n - 1));
    ssHfieldDef hd = ss_hfield_def_default();
    hd.name = "slope";
    hd.nx = hd.ny = n;
    hd.x_size = hd.y_size = 4;
    hd.height = z;
    ss_model_add_hfield(m2, &hd, &e);
    free(z);
    ss_model_set_pair(m2, NULL, NULL, mu, 0, 0, &e);
    ssBodyDef bx = ss_body_def_default();
    bx.name = "box";
    bx.size[0] = bx.size[1] = 0.2;
    bx.size[2] = 0.1;
    bx.mass = 2;
    double axis[3] = {0, 1, 0};
    ss_quat_from_axis_angle(bx.quat, axis, -th);
    ss_v3_set(bx.pos, 0, 0, 0.05 / cos(th));
    ss_model_add_body(m2, &bx, &e);
    ssData *d2 = ss_data_new(m2);
    for (int s = 0; s < 300; s++) ss_step(m2, d2, &e);
    double v0 = -d2->qvel[0] / cos(th), x0 = d2->qpos[0];
    for (int s = 0; s < 300; s++) ss_step(m2, d2, &e);
    double v1 = -d2->qvel[0] / cos(th);
    if (k == 0)
      ok(fabs(d2->qpos[0] - x0) < 1e-4 && fabs(v1) < 1e-3, "mu 0.5 on a 20 degree rigid height map: the box holds");
    else
      close_enough((v1 - v0) / 0.3, G * (sin(th) - mu * cos(th)), 0.02 * G,
                   "mu 0.2 on a 20 degree rigid height map: slides at g (sin - mu cos)");
    ss_data_free(d2);
    ss_model_free(m2);
  }
}

/* Rigid contacts are warm started (solver.h, ss_rigid_feature) and a
 * collider's rigid contacts solved as a block (solver.c, rigid_block): a
 * box resting on its four corners and a cylinder lying on its side (two
 * rim points), each on a ground plane, take one sweep a step once
 * settled, last step's impulses passing the check as they come; started
 * cold each step they take several; a box sliding at 3 m/s stops at
 * v^2 / (2 mu g) either way.  Warm and cold reach the same state. */
static void test_rigid_warm(void)
{
  double q[2][21];
  long sweeps[2] = {0, 0};
  int ones[2] = {0, 0}, nq = 0, good = 1;
  for (int warm = 1; warm >= 0; warm--) {
    ssError e;
    ssModel *m = steel_ground(0, 0, &e);
    ssBodyDef b = box_def();
    b.material = "rubber";
    ss_v3_set(b.pos, 0, 0, 0.05);
    ss_model_add_body(m, &b, &e);
    ssBodyDef c = ss_body_def_default();
    c.name = "log";
    c.shape = SS_GEOM_CYLINDER;
    c.size[0] = 0.1;
    c.size[1] = 0.8;
    c.mass = 10;
    c.material = "rubber";
    double xaxis[3] = {1, 0, 0};
    ss_quat_from_axis_angle(c.quat, xaxis, M_PI / 2);
    ss_v3_set(c.pos, 0, 2, 0.1);
    ss_model_add_body(m, &c, &e);
    add_slider(m, &e);
    m->opt.terrain_warm_start = warm;
    ssData *d = ss_data_new(m);
    for (int k = 0; k < 1500 && good; k++) {
      good = ss_step(m, d, &e) == SS_OK && d->stats.converged;
      /* the slider stops within 0.92 s; from then on all three rest */
      if (k >= 1000) {
        sweeps[warm] += d->stats.sweeps;
        ones[warm] += d->stats.sweeps == 1;
      }
    }
    nq = m->nq;
    if (good && nq == 21) memcpy(q[warm], d->qpos, sizeof q[warm]);
    good = good && nq == 21;
    if (warm)
      close_enough(d->qpos[14] - 2, 9.0 / (2 * 0.5 * G), 0.02 * 9.0 / (2 * 0.5 * G),
                   "warm rigid contacts: the sliding box stops after v^2/(2 mu g)");
    ss_data_free(d);
    ss_model_free(m);
  }
  ok(good && ones[1] == 500,
     "rigid contacts at rest, warm started: one sweep a step (%d steps of 500; cold: %d, "
     "%.1f sweeps a step)", ones[1], ones[0], sweeps[0] / 500.0);
  ok(good && sweeps[0] >= 2 * sweeps[1], "  started cold, at least twice the sweeps (%ld "
     "against %ld: the block's answer, then a sweep that confirms it)", sweeps[0], sweeps[1]);
  double dq = 0;
  for (int k = 0; k < nq && good; k++) dq = fmax(dq, fabs(q[1][k] - q[0][k]));
  ok(good && dq < 1e-9, "  warm and cold reach the same state (%.2g apart)", dq);

  /* the keys number the rigid supports: ground planes are limited to 10^6
   * (the count set by hand: the limit is checked before anything else) */
  ssError e;
  ssModel *m = ss_model_new();
  int first = ss_model_add_plane(m, "g0", 0, NULL, 0, &e);
  m->nplane = 1000000;
  int refused = ss_model_add_plane(m, "g1", 0, NULL, 7, &e) < 0 && m->nplane == 1000000 &&
                e.line == 7 && strstr(e.message, "at most 1000000 ground planes");
  m->nplane = 1;
  ok(first == 0 && refused, "the 1000001st ground plane is refused (%s)", e.message);
  ss_model_free(m);
}

/* Twelve bodies of every shape thrown onto rigid hills and a plane
 * (tests/data/rigid_mix.xml) land on several rigid contacts each.  The
 * boxes come to rest; the spheres, capsules and cylinders roll on (rigid
 * contacts have no rolling resistance): they came to rest only while a
 * round body's contact on a slope sat below its centre instead of where
 * it touches (terrain.c, round_on_slope), which kept it from rolling.
 * Over steps 2001-3000 the warm-started blocks take a few sweeps a step
 * (2.05 with every body at rest; 4.8 now) and about one step in a
 * hundred stops at the sweep cap (0 then, 12 now: a rolling body between
 * a hill and the plane, the rigid blocks' stick/slip boundary of README
 * "Where the solver does not yet meet its tolerance"); one pass a block
 * and cold rigid contacts took 63 sweeps and 46 capped.  Since bodies
 * meet each other, the map's peaks meet them and boxes meet edge on edge,
 * the bodies tumble into other rest places (the scene is chaotic: any
 * change early in the run moves where each one ends), and the count
 * follows them: across the builds since 4 to 70 capped steps and 4.3 to
 * 27.3 sweeps a step over steps 2001-3000 (each capped run a round body
 * rolling on a hilltop vertex and its own candidate, residuals 1e-7 to
 * 1e-5, no pair contact in it; 40 and 12.4 before a box's edges met a
 * capsule's side, from whose first such contact at step 743 the capsule
 * o3 ends wedged between the boxes o6 and o10 on a hill, the two boxes
 * touching it with its end spheres alone: 70 and 26.8-27.3, most of them
 * steps 2565-2624 there).  The bounds, 100 capped and 35 sweeps a step,
 * keep that spread and still fail where the blocks or the warm start
 * break (cold rigid contacts, --warm-start off: 100 sweeps a step and
 * 351 capped; a pass a block and cold rigid contacts, on an earlier
 * build's path: 63 sweeps and 46 capped; the sweeps alone: 200 and every
 * step).  None falls through its support. */
static void test_rigid_mix(void)
{
  ssModel *m;
  ssData *d;
  ssError e;
  if (!load_scene_file("tests/data/rigid_mix.xml", &m, &d)) {
    ok(0, "tests/data/rigid_mix.xml loads");
    return;
  }
  long sweeps = 0;
  int capped = 0, good = 1;
  for (int k = 0; k < 3000 && good; k++) {
    good = ss_step(m, d, &e) == SS_OK;
    if (k >= 2000) {
      sweeps += d->stats.sweeps;
      capped += !d->stats.converged;
    }
  }
  double low = INFINITY;
  for (int b = 0; b < m->nbody; b++) low = fmin(low, d->body_xpos[3 * b + 2]);
  ok(good && sweeps <= 35 * 1000 && capped <= 100,
     "twelve bodies resting or rolling on rigid hills: %.1f sweeps a step, %d of 1000 steps "
     "at the cap",
     sweeps / 1000.0, capped);
  ok(good && low > -0.3, "  none below the ground plane (lowest centre at z = %.3f m)", low);
  ss_data_free(d);
  ss_model_free(m);
}

/* A quaternion written into qpos between steps is made unit by the next
 * step (dynamics.h, ss_dyn_unit_quats), as MuJoCo's step does: a free
 * box's quaternion written three times too long steps as the unit one
 * (to round-off), a zero one as the identity, and the buggy's floating
 * chassis written twice too long as its unit one.  Before, a free body's
 * first step formed its frame and inertia from the long quaternion (no
 * rotation: 4e-4 apart after one step) and a zero one lost the step's
 * turn; the articulated kinematics normalised already. */
static void test_unit_quats(void)
{
  ssError e;
  ssModel *m = ss_model_new();
  ssBodyDef b = box_def();
  ss_v3_set(b.pos, 0, 0, 2);
  b.ang_vel[0] = 1;
  ss_model_add_body(m, &b, &e);
  ssData *a = ss_data_new(m), *c = ss_data_new(m), *z = ss_data_new(m);
  double q[4] = {1, 0.2, -0.1, 0.3};
  ss_quat_normalize(q);
  for (int k = 0; k < 4; k++) {
    a->qpos[3 + k] = q[k];
    c->qpos[3 + k] = 3 * q[k];
    z->qpos[3 + k] = 0;
  }
  int good = ss_step(m, a, &e) == SS_OK && ss_step(m, c, &e) == SS_OK &&
             ss_step(m, z, &e) == SS_OK;
  double dq = 0, n2 = 0;
  for (int k = 0; k < 7 && good; k++) dq = fmax(dq, fabs(c->qpos[k] - a->qpos[k]));
  for (int k = 3; k < 7 && good; k++) n2 += c->qpos[k] * c->qpos[k];
  ok(good && dq < 1e-14 && fabs(n2 - 1) < 1e-14,
     "a free box's quaternion written 3 times too long steps as the unit one (%.2g apart)", dq);
  /* from the identity, turned by its 1 rad/s about x over the step */
  double h = 0.5 * m->opt.timestep;
  ok(good && fabs(z->qpos[3] - cos(h)) < 1e-15 && fabs(z->qpos[4] - sin(h)) < 1e-15 &&
         z->qpos[5] == 0 && z->qpos[6] == 0,
     "  a zero one as the identity (%.17g %.3g %g %g after the step)", z->qpos[3], z->qpos[4],
     z->qpos[5], z->qpos[6]);
  ss_data_free(a);
  ss_data_free(c);
  ss_data_free(z);
  ss_model_free(m);

  ssData *d1, *d2;
  ssModel *mb, *mb2;
  if (!load_scene_file("scenes/buggy_rigid.xml", &mb, &d1) ||
      !load_scene_file("scenes/buggy_rigid.xml", &mb2, &d2)) {
    ok(0, "scenes/buggy_rigid.xml loads");
    return;
  }
  int root = mb->sys_bodyadr[0], qa = mb->body_qadr[root];
  int floating = mb->body_jnttype[root] == SS_JOINT_FLOATING;
  for (int k = 3; k < 7 && floating; k++) d2->qpos[qa + k] *= 2;
  good = floating;
  for (int s = 0; s < 50 && good; s++)
    good = ss_step(mb, d1, &e) == SS_OK && ss_step(mb2, d2, &e) == SS_OK;
  dq = 0;
  for (int k = 0; k < mb->nq && good; k++) dq = fmax(dq, fabs(d2->qpos[k] - d1->qpos[k]));
  ok(good && dq < 1e-12, "  the buggy's floating chassis written twice too long: 50 steps as "
     "from the unit one (%.2g apart)", dq);
  ss_data_free(d1);
  ss_data_free(d2);
  ss_model_free(mb);
  ss_model_free(mb2);
}

/* the cache entry with e's key, or NULL */
static const ssWarmEntry *warm_find(const ssWarmEntry *w, int n, const ssWarmEntry *e)
{
  for (int k = 0; k < n; k++)
    if (w[k].vertex == e->vertex && w[k].geom == e->geom) return w + k;
  return NULL;
}

/* entries of d whose rate is not what the rule says (ssWarmEntry): the
 * traction's change since old[] where both solves converged and it exceeds
 * tol times the traction (1-norms), else 0; *moving counts the nonzero
 * rates */
static int bad_rates(const ssData *d, const ssWarmEntry *old, int nold, int trend,
                     double tol, int *moving)
{
  int bad = 0;
  *moving = 0;
  for (int k = 0; k < d->nwarm; k++) {
    const ssWarmEntry *e = d->warm + k, *o = warm_find(old, nold, e);
    double want[3] = {0, 0, 0}, ch = 0, size = 0;
    for (int i = 0; i < 3 && trend && o; i++) {
      want[i] = e->traction[i] - o->traction[i];
      ch += fabs(want[i]);
      size += fabs(e->traction[i]);
    }
    if (ch <= tol * size) want[0] = want[1] = want[2] = 0;
    if (memcmp(e->rate, want, sizeof want)) bad++;
    *moving += e->rate[0] != 0;
  }
  return bad;
}

/* The warm start extrapolates each soil point's converged traction by its
 * change over the last step.  Checked: the rates the cache keeps (none
 * from or across an unconverged solve), that the next solve starts from
 * them (fewer sweeps than the same steps with the rates cleared), and that
 * both reach the same answer. */
/* copy of d's cache into old (room for one entry per bed vertex: one
 * collider) */
static int keep(const ssData *d, ssWarmEntry *old, int *nold)
{
  *nold = d->nwarm;
  memcpy(old, d->warm, (size_t)d->nwarm * sizeof *old);
  return d->stats.converged;
}

static void test_warm_trend(void)
{
  World w = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  World u = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  World v = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  ssData *d = w.d;
  const double tol = w.m->opt.solver_tolerance, dt = w.m->opt.timestep;
  ssWarmEntry *old = malloc((size_t)w.m->nhfielddata * sizeof *old);
  int nold = 0, moving, conv[3], bad, bad2;
  /* the sweeps' start is what the warm start serves: the Newton phase,
   * which solves a free plate's step outright, stays out */
  w.d->solver_gs_only = u.d->solver_gs_only = v.d->solver_gs_only = 1;
  if (!old || !run(&w, 12)) {
    ok(0, "warm trend: set-up");
    goto out;
  }
  /* two converged steps: rates are the tractions' changes */
  conv[0] = keep(d, old, &nold);
  run(&w, 1);
  conv[1] = d->stats.converged;
  bad = bad_rates(d, old, nold, 1, tol, &moving);
  ok(conv[0] && conv[1] && bad == 0 && moving > d->nwarm / 2,
     "sinking plate: each cached rate is the traction's change over the step (%d of %d "
     "moving, %d wrong)", moving, d->nwarm, bad);
  /* an unconverged solve keeps no rates, nor does the step after it */
  int sweeps = w.m->opt.solver_max_sweeps;
  w.m->opt.solver_max_sweeps = 1;
  run(&w, 1);
  w.m->opt.solver_max_sweeps = sweeps;
  bad = bad_rates(d, old, 0, 0, tol, &moving);
  conv[0] = keep(d, old, &nold);
  run(&w, 1);
  bad += bad_rates(d, old, nold, 0, tol, &moving);
  conv[1] = keep(d, old, &nold);
  run(&w, 1);
  conv[2] = d->stats.converged;
  bad2 = bad_rates(d, old, nold, 1, tol, &moving);
  ok(!conv[0] && conv[1] && conv[2] && bad == 0 && bad2 == 0 && moving > 0,
     "after a solve stopped at 1 sweep: no rates for two steps, then rates again");

  /* the rates seed the solve: the same 40 steps with them cleared before
   * every step need more sweeps and reach the same state.  Bound: an
   * impulse error of eps = 10 tol m g dt per step moves the plate by at
   * most sum k eps g dt^2 = N^2/2 10 tol g dt^2 */
  long with = 0, without = 0;
  if (run(&u, 16) && run(&v, 16)) {
    for (int k = 0; k < 40; k++) {
      for (int i = 0; i < v.d->nwarm; i++) memset(v.d->warm[i].rate, 0, sizeof v.d->warm[i].rate);
      run(&u, 1);
      run(&v, 1);
      with += u.d->stats.sweeps;
      without += v.d->stats.sweeps;
    }
  }
  double dz = fabs(u.d->qpos[2] - v.d->qpos[2]), bound = 0.5 * 40 * 40 * 10 * tol * G * dt * dt;
  ok(with > 0 && with < without && dz <= bound,
     "40 steps of the sinking plate: %.2f sweeps per step from the extrapolated tractions, "
     "%.2f from the last ones; heights %.2g m apart (bound %.2g)", with / 40.0,
     without / 40.0, dz, bound);

  /* settled, the tractions drift within the tolerance: no trend kept */
  run(&u, 1500);
  conv[0] = keep(u.d, old, &nold);
  run(&u, 1);
  bad = bad_rates(u.d, old, nold, conv[0] && u.d->stats.converged, tol, &moving);
  ok(bad == 0 && moving == 0 && u.d->stats.sweeps == 1,
     "settled plate: every traction change is within the tolerance, no rate kept "
     "(%d of %d, %d wrong)", moving, u.d->nwarm, bad);
out:
  free(old);
  free_world(&w);
  free_world(&u);
  free_world(&v);
}

/* A settled plate's warm start stands every step (the Newton phase takes
 * no step and skips its check): the cache keeps the laws' impulses at the
 * step's velocities, which run ahead of the warm impulses by the step's
 * drift.  Were it to keep the warm impulses themselves, that drift (about
 * 1e-10 of the tractions a step on this plate) would pile up until the
 * warm start missed the tolerance, every few steps.  Each loaded point's
 * cached normal traction is its law's pressure at its end-of-step
 * velocity, to round-off (1e-12 relative: the impulse divided by A dt,
 * the law evaluated again here); the warm impulses it held differ by up
 * to the tolerance (1e-9). */
static void test_settled_cache(void)
{
  World w = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0, 0);
  const ssSoilMaterial *mat = &w.m->hfield_soilmat[w.bed];
  const double dt = w.m->opt.timestep;
  int steps = 200, settled = 0, points = 0, bad = 0;
  double worst = 0, held = 0;
  if (!run(&w, 1500)) {
    ok(0, "settled plate: set-up");
    free_world(&w);
    return;
  }
  for (int k = 0; k < steps && run(&w, 1); k++) {
    const ssData *d = w.d;
    settled += d->solver_settled;
    for (int i = 0; i < d->ncontact; i++) {
      const ssContact *c = d->contact + i;
      if (c->type != SS_CONTACT_SOIL || !c->loaded) continue;
      const ssWarmEntry *e = NULL;
      for (int j = 0; j < d->nwarm && !e; j++)
        if (d->warm[j].geom == c->geom && d->warm[j].vertex == c->vertex) e = d->warm + j;
      if (!e) {
        bad++;
        continue;
      }
      double delta = -(c->g0 + dt * c->v[0]);
      double p = ss_soil_pressure(mat, c->width, c->sp + delta, c->sp) +
                 ss_soil_viscous(mat, -c->v[0]);
      worst = fmax(worst, fabs(e->traction[0] - p) / p);
      held = fmax(held, fabs(c->lambda[0] / (c->area * dt) - p) / p);
      points++;
    }
  }
  ok(settled == steps && points > 100 * steps && bad == 0 && worst <= 1e-12,
     "settled plate: its warm start stands in %d of %d steps; the cache keeps each of %d "
     "loaded points' law at its velocity (worst %.2g relative, bound 1e-12; the warm "
     "impulses held %.2g)", settled, steps, points, worst, held);
  free_world(&w);
}

/* The same plate and bed moved together far along x: the physics is the
 * same, and so must be the work.  A free body's Newton blocks are about
 * its centre of mass (newton.c, group_motion); about the world origin,
 * products of the distance cancelled in the group's frame, and at 1 km
 * the settled plate took three times the Newton iterations (its warm start
 * stood in 93 of 1500 steps against 618), at 10 km twenty times. */
static void test_far_from_origin(void)
{
  const double X[2] = {0, 1e5};
  double sink[2] = {0, 0}, xrel[2] = {0, 0};
  long newton[2] = {0, 0}, sweeps[2] = {0, 0}, settled[2] = {0, 0};
  int good = 1;
  for (int k = 0; k < 2; k++) {
    World w = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, X[k], 0, 0, 0);
    w.d->hfield_pos[3 * w.bed] = X[k];
    ssError e;
    for (int t = 0; t < 1500 && good; t++) {
      good = ss_step(w.m, w.d, &e) == SS_OK;
      newton[k] += w.d->stats.newton;
      sweeps[k] += w.d->stats.sweeps;
      settled[k] += w.d->solver_settled;
    }
    sink[k] = plate_sinkage(&w);
    xrel[k] = w.d->qpos[0] - X[k];
    free_world(&w);
  }
  ok(good && newton[1] <= newton[0] + newton[0] / 20 && sweeps[1] <= sweeps[0] + 15 &&
         settled[1] >= settled[0] - settled[0] / 20 && fabs(sink[1] - sink[0]) <= 1e-12 &&
         fabs(xrel[1] - xrel[0]) <= 1e-10,
     "a plate settling 100 km from the origin: %ld Newton iterations, %ld sweeps, warm start "
     "standing in %ld steps (at the origin %ld, %ld, %ld); sinkage %.12g against %.12g m",
     newton[1], sweeps[1], settled[1], newton[0], sweeps[0], settled[0], sink[1], sink[0]);
}

/* The Newton phase (solver.h) against the sweeps alone, one step from the
 * same state each.  Both stop at the solver tolerance tol in the sweeps'
 * measure (largest impulse change over largest impulse); a contraction of
 * rate rho leaves each within tol / (1 - rho) of the exact impulses, so
 * 1e3 tol allows rho up to 0.998 on each side -- slower than any patch
 * here -- while an error in the Newton phase's law or Jacobian shows as
 * an O(1) difference or as sweeps after it. */
static void newton_case(World *w, const char *what, int expect_newton)
{
  PathCompare pc;
  const double tol = w->m->opt.solver_tolerance;
  int good = newton_paths(w->m, w->d, &pc);
  int path = expect_newton ? pc.sweeps[0] == 0 : pc.sweeps[0] > 0;
  ok(good && pc.ncontact > 0 && pc.converged[0] && pc.converged[1] &&
     pc.dlam <= 1e3 * tol && path,
     "%s: the Newton phase %s (%d Newton iterations + %d sweeps, the sweeps alone %d); "
     "impulses %.2g apart relative (bound %.2g)", what,
     expect_newton ? "solves the step" : "declines, the sweeps solve it",
     pc.newton[0], pc.sweeps[0], pc.sweeps[1], pc.dlam, 1e3 * tol);
}

static void test_newton(void)
{
  World w = make_world(plate_soil(), 1.2, 0.02, 0.4, 0.6, 20, 0, 0, 0.3, 0);
  /* sinking from rest, settling, settled */
  int steps[] = {3, 40, 400};
  for (int k = 0, done = 0; k < 3; k++) {
    run(&w, steps[k] - done);
    done = steps[k] + 1;
    char what[64];
    snprintf(what, sizeof what, "plate (yaw 0.3) after %d steps", steps[k]);
    newton_case(&w, what, 1);
  }
  /* sliding: pushed at 0.5 m/s along x and spun at 1 rad/s */
  w.d->qvel[0] = 0.5;
  w.d->qvel[5] = 1.0;
  run(&w, 2);
  newton_case(&w, "plate sliding and spinning", 1);
  /* stopped after the slide: the shear built up (j > 0) holds the points
   * at zero slip, where the velocity form is set-valued; the phase solves
   * them in impulse form */
  run(&w, 600);
  newton_case(&w, "plate stopped after sliding (sticking)", 1);
  ok(w.d->stats.newton_sticking > 100,
     "  with its %d sticking points in impulse form", w.d->stats.newton_sticking);
  free_world(&w);
}

/* A plate coming to rest on a bed tilted by 0.07 degrees: its points
 * creep at 1e-7 m/s and less, where the Janosi shear is nearly
 * set-valued.  The sweeps alone do not converge there in 200 sweeps (all
 * of steps 100-300, before the impulse form); the Newton phase, its
 * points in impulse form, solves each step of 100-1200 (before impulses
 * were brought back onto their discs, step 319 stopped unconverged, and
 * with 16 iterations step 181: no descent at 3e-8, newton.c imp_map). */
static void test_resting_on_slope(void)
{
  ssError e;
  ssModel *m;
  ssData *d;
  if (!plate_world(41, 1.6, 0.002, 0, NULL, &m, &d, &e)) {
    ok(0, "tilted bed: %s", e.message);
    return;
  }
  World w = {m, d, 0, 0};
  int good = run(&w, 100), unconverged = 0, sweeps = 0, newton = 0, sticking = 0;
  for (int k = 0; k < 1100 && good; k++) {
    good = run(&w, 1);
    unconverged += !d->stats.converged;
    sweeps += d->stats.sweeps;
    newton += d->stats.newton;
    sticking += d->stats.newton_sticking > 0;
  }
  ok(good && unconverged == 0 && sweeps <= 20 && sticking > 100,
     "plate coming to rest on a bed tilted 0.07 deg, steps 100-1200: %d unconverged, %d sweeps, "
     "%d Newton iterations, %d steps with points in impulse form",
     unconverged, sweeps, newton, sticking);
  ss_data_free(d);
  ss_model_free(m);
}

/* A creeping collider starts without its rates (solver.c, CREEP_SLIP),
 * and with them where the Newton phase fails without.  The plate of
 * plate_arm.xml creeps at 1e-7 to 1e-5 m/s under the lift's pull, its slip
 * directions set by velocities that small: with its extrapolated warm
 * starts always, 17373 sweeps in the first 600 steps, 6 of them stopped at
 * the sweep cap; with them never, 4684 sweeps (90 steps of 301-400 over
 * 20: while the plate also sinks, the Newton phase fails from its last
 * tractions and would not from their extrapolation).  Checked: no step at
 * the cap, fewer than 1000 sweeps; at the end the plate's cached entries
 * are marked as creeping and keep their rates; and a checkpoint taken in
 * that stretch (step 320) replays the next 40 steps bit for bit. */
static void test_creeping_plate(void)
{
  ssModel *m;
  ssData *d;
  if (!load_scene_file("scenes/plate_arm.xml", &m, &d)) {
    ok(0, "plate_arm.xml loads");
    return;
  }
  ssError e;
  long sweeps = 0;
  int capped = 0, good = 1, replay = 0;
  unsigned char *ck = NULL;
  size_t nck = 0;
  double q360[64];
  for (int k = 0; k < 600 && good; k++) {
    good = ss_step(m, d, &e) == SS_OK;
    sweeps += d->stats.sweeps;
    capped += !d->stats.converged;
    if (k + 1 == 320) good = good && ss_checkpoint_save_buffer(m, d, &ck, &nck, &e) == SS_OK;
    if (k + 1 == 360 && m->nq <= 64) memcpy(q360, d->qpos, (size_t)m->nq * sizeof(double));
  }
  double slip = 0, shear = 0, normal = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    if (c->type != SS_CONTACT_SOIL || !(c->lambda[0] > 0)) continue;
    slip = fmax(slip, hypot(c->v[1], c->v[2]));
    normal += c->lambda[0];
    shear += hypot(c->lambda[1], c->lambda[2]);
  }
  int rates = 0, soil = 0, creep = 0;
  for (int i = 0; i < d->nwarm; i++) {
    const ssWarmEntry *w = d->warm + i;
    if (w->geom < 0 || (w->traction[0] == 0 && w->rate[0] == 0)) continue;
    soil++;
    creep += w->creep;
    rates += w->rate[0] != 0 || w->rate[1] != 0 || w->rate[2] != 0;
  }
  ok(good && capped == 0 && sweeps < 1000 && slip < 1e-4 && shear > 1e-3 * normal &&
         soil > 600 && creep == soil && rates > 600,
     "plate_arm, 600 steps: %ld sweeps, %d at the cap; its creeping plate (slip %.2g m/s, "
     "shear %.2g of the normal load) marks %d of %d cached entries creeping, %d keep a rate",
     sweeps, capped, slip, shear / normal, creep, soil, rates);
  /* the checkpoint of step 320, restored, runs to step 360's coordinates */
  ssData *r = ss_data_new(m);
  if (good && r && m->nq <= 64 && ss_checkpoint_load_buffer(m, r, ck, nck, &e) == SS_OK) {
    int fine = 1;
    for (int k = 0; k < 40 && fine; k++) fine = ss_step(m, r, &e) == SS_OK;
    replay = fine && !memcmp(r->qpos, q360, (size_t)m->nq * sizeof(double));
  }
  ok(replay, "plate_arm: its checkpoint of step 320 (creeping marks in the cache) replays "
     "steps 321-360 bit for bit");
  free(ck);
  ss_data_free(r);
  ss_data_free(d);
  ss_model_free(m);
}

/* drag.xml run for `steps` steps, warm-started or not: how many stopped at
 * the sweep cap, in all and from step `from` on (0: it did not load or a
 * step failed) */
static int drag_capped(int warm, int steps, int from, int *capped, int *late, int *most)
{
  ssModel *m;
  ssData *d;
  *capped = *late = *most = 0;
  if (!load_scene_file("scenes/drag.xml", &m, &d)) return 0;
  m->opt.terrain_warm_start = warm;
  ssError e;
  int good = 1;
  for (int k = 0; k < steps && good; k++) {
    good = ss_step(m, d, &e) == SS_OK;
    *capped += !d->stats.converged;
    *late += k + 1 >= from && !d->stats.converged;
    if (d->stats.sweeps > *most) *most = d->stats.sweeps;
  }
  ss_data_free(d);
  ss_model_free(m);
  return good;
}

/* The plate of drag.xml, pulled by 60 N below its shear strength, stops
 * at t = 1.16 s and rocks on its front edge: its points slip at 1e-6 m/s
 * and less, forwards ahead of the line it pitches about and backwards
 * behind it, one row of them stuck.  The Newton phase stalls there (its
 * stick solve finds no sharing of the wrench within the points' bounds:
 * the patch is not stuck whole) and the sweeps crawl (11 338 of them to
 * the tolerance at step 1159); before the creeping solve (newton.c)
 * 28 of the first 1300 steps stopped at the sweep cap, now none, and no
 * step needs more than 21 sweeps. */
static void test_drag_stops(void)
{
  int capped, late, most, good = drag_capped(1, 1300, 1220, &capped, &late, &most);
  ok(good && capped == 0 && most <= 25,
     "drag.xml, 1300 steps: %d at the sweep cap (28 before the creeping solve), at most "
     "%d sweeps a step", capped, most);
}

/* The same drag started cold every step (terrain_warm_start off, which
 * DESIGN 3 says must reach the same tolerance): the creeping steps that
 * the Newton phase cannot take from a cold start (115 of 1500 stopped at
 * the cap before the creeping solve, 241 before the stick solve) now
 * converge too. */
static void test_drag_stops_cold(void)
{
  int capped, late, most, good = drag_capped(0, 1500, 1300, &capped, &late, &most);
  ok(good && capped == 0 && most <= 25,
     "drag.xml cold, 1500 steps: %d at the sweep cap (115 before the creeping solve), at "
     "most %d sweeps a step", capped, most);
}

/* The creeping solve's answer is the step's: at step 1159 of
 * drag.xml (the plate rocking on its front edge, slipping both ways about
 * a row of stuck points) the same step taken by the sweeps alone, with
 * their cap raised to 20 000, converges after about 11 000 sweeps.  The
 * body's velocity is unique (the minimum of a strictly convex function,
 * newton.c): the two agree within 1e-6 of its largest component (the
 * sweeps contract by about 0.998 a sweep there, so their answer at a
 * change of 1e-9 a sweep is that far from the limit); so do the slipping
 * points' impulses, which their laws set from it.  The stuck row's
 * impulses are statically indeterminate (only their sum is set) and are
 * not compared one by one. */
static void test_creep_matches_sweeps(void)
{
  ssModel *m;
  ssData *d;
  if (!load_scene_file("scenes/drag.xml", &m, &d)) {
    ok(0, "drag.xml loads");
    return;
  }
  ssError e;
  int good = 1, conv[2] = {0, 0}, sweeps[2] = {0, 0}, passes = 0, nc = 0;
  for (int k = 0; k < 1158 && good; k++) good = ss_step(m, d, &e) == SS_OK;
  m->opt.solver_max_sweeps = 20000;
  unsigned char *buf = NULL;
  size_t len = 0;
  double u[6], *lam = NULL, du = 0, un = 0, dl = 0, lm = 0;
  good = good && m->nv == 6 && ss_checkpoint_save_buffer(m, d, &buf, &len, &e) == SS_OK;
  for (int path = 0; path < 2 && good; path++) {
    if (path) good = ss_checkpoint_load_buffer(m, d, buf, len, &e) == SS_OK;
    d->solver_gs_only = !path;
    good = good && ss_step(m, d, &e) == SS_OK;
    if (!good) break;
    conv[path] = d->stats.converged;
    sweeps[path] = d->stats.sweeps;
    if (!path) {
      nc = d->ncontact;
      memcpy(u, d->qvel, sizeof u);
      good = (lam = malloc((size_t)(nc ? nc : 1) * 3 * sizeof(double))) != NULL;
      for (int i = 0; good && i < nc; i++) memcpy(lam + 3 * i, d->contact[i].lambda, sizeof(double) * 3);
      continue;
    }
    passes = d->stats.newton;
    good = d->ncontact == nc;
    for (int k = 0; good && k < 6; k++) {
      du = fmax(du, fabs(d->qvel[k] - u[k]));
      un = fmax(un, fabs(u[k]));
    }
    for (int i = 0; good && i < nc; i++) {
      const ssContact *c = d->contact + i;
      const double *a = c->lambda, *b = lam + 3 * i;
      lm = fmax(lm, fabs(b[0]) + fabs(b[1]) + fabs(b[2]));
      /* a slipping point (faster than 1e-12 m/s both ways) */
      if (hypot(c->v[1], c->v[2]) > 1e-12)
        dl = fmax(dl, fabs(a[0] - b[0]) + fabs(a[1] - b[1]) + fabs(a[2] - b[2]));
    }
  }
  d->solver_gs_only = 0;
  ok(good && conv[0] && conv[1] && sweeps[1] <= 25 && sweeps[0] > 1000 && passes > 0 &&
         du <= 1e-6 * un && dl <= 1e-6 * lm,
     "drag.xml step 1159: the creeping solve (%d sweeps, %d passes over the points) and "
     "the sweeps alone (%d sweeps) agree: velocity within %.2g of its largest component, the "
     "slipping points' impulses within %.2g of the largest",
     sweeps[1], passes, sweeps[0], un > 0 ? du / un : du, lm > 0 ? dl / lm : dl);
  free(buf);
  free(lam);
  ss_data_free(d);
  ss_model_free(m);
}

/* One step of d taken twice from the same state, by the sweeps alone
 * (their cap raised to 30 000) and by the whole solver: 1 when both
 * converged, with the largest difference of the velocities over the
 * largest velocity in *dq, the sweeps alone's count in *gs and the whole
 * solver's sweeps and Newton-phase and creeping passes in *sw, *passes */
static int step_against_sweeps(ssModel *m, ssData *d, double *dq, int *gs, int *sw, int *passes)
{
  ssError e;
  unsigned char *buf = NULL;
  size_t len = 0;
  int keep = m->opt.solver_max_sweeps, good = 0, nv = m->nv;
  double *u = malloc((size_t)(nv ? nv : 1) * sizeof(double)), du = 0, un = 0;
  m->opt.solver_max_sweeps = 30000;
  if (u && ss_checkpoint_save_buffer(m, d, &buf, &len, &e) == SS_OK) {
    d->solver_gs_only = 1;
    int a = ss_step(m, d, &e) == SS_OK && d->stats.converged;
    *gs = d->stats.sweeps;
    memcpy(u, d->qvel, (size_t)nv * sizeof(double));
    d->solver_gs_only = 0;
    int b = a && ss_checkpoint_load_buffer(m, d, buf, len, &e) == SS_OK &&
            ss_step(m, d, &e) == SS_OK && d->stats.converged;
    *sw = d->stats.sweeps;
    *passes = d->stats.newton;
    for (int k = 0; k < nv; k++) {
      du = fmax(du, fabs(d->qvel[k] - u[k]));
      un = fmax(un, fabs(u[k]));
    }
    *dq = un > 0 ? du / un : du;
    good = a && b;
  }
  m->opt.solver_max_sweeps = keep;
  free(buf);
  free(u);
  return good;
}

/* plate_arm.xml started cold every step (terrain_warm_start off): its
 * plate creeps under the lift's pull, rocking on the bed, 641 of its 651
 * points at their bounds and slipping at up to 1e-7 m/s.  The Newton
 * phase stalls there and the sweeps crawl: before the creeping solve 25
 * of the first 400 steps stopped at the sweep cap (264 of 1000), now
 * none.  At step 147 the sweeps alone converge in about 190 sweeps; the
 * whole solver's answer (the creeping solve's, checked by the sweeps)
 * gives the system the same velocities within 1e-6 of the largest (the
 * sweeps' own stopping error where they contract by about 0.9 a sweep is
 * 1e-8; the creeping answer's are the law's within 1e-9). */
static void test_plate_arm_cold(void)
{
  ssModel *m;
  ssData *d;
  if (!load_scene_file("scenes/plate_arm.xml", &m, &d)) {
    ok(0, "plate_arm.xml loads");
    return;
  }
  m->opt.terrain_warm_start = 0;
  ssError e;
  int good = 1, capped = 0, creeping = 0, gs = 0, sw = 0, passes = 0, same = 0;
  double dq = -1;
  for (int k = 0; k < 400 && good; k++) {
    if (k == 146) same = step_against_sweeps(m, d, &dq, &gs, &sw, &passes);
    else good = ss_step(m, d, &e) == SS_OK;
    capped += !d->stats.converged;
    creeping += d->stats.sweeps >= 10 && d->stats.newton > 16;
  }
  ok(good && capped == 0 && creeping > 50,
     "plate_arm.xml cold, 400 steps: %d at the sweep cap (25 before the creeping solve), %d "
     "steps taken by the creeping solve", capped, creeping);
  ok(same && gs > 100 && sw <= 30 && dq <= 1e-6,
     "plate_arm.xml cold, step 147: the sweeps alone (%d sweeps) and the creeping solve (%d "
     "sweeps, %d passes) give the same velocities within %.2g of the largest", gs, sw, passes,
     dq);
  ss_data_free(d);
  ss_model_free(m);
}

/* drag_slide.xml: its plate, pulled past its strength for 0.5 s, slides
 * 0.75 m, stops at t = 1.75 s and then rests on its rut: before the
 * creeping solve 49 of its 2500 steps stopped at the sweep cap, now
 * none */
static void test_drag_slide_stops(void)
{
  ssModel *m;
  ssData *d;
  if (!load_scene_file("scenes/drag_slide.xml", &m, &d)) {
    ok(0, "drag_slide.xml loads");
    return;
  }
  ssError e;
  int good = 1, capped = 0, most = 0;
  for (int k = 0; k < 2500 && good; k++) {
    good = ss_step(m, d, &e) == SS_OK;
    capped += !d->stats.converged;
    if (d->stats.sweeps > most) most = d->stats.sweeps;
  }
  ok(good && capped == 0 && most <= 25,
     "drag_slide.xml, 2500 steps: %d at the sweep cap (49 before the creeping solve), at "
     "most %d sweeps a step", capped, most);
  ss_data_free(d);
  ss_model_free(m);
}

/* The first power of each point's step comes from its bed's table of
 * s^(n-1) (solver.h, ss_solver_pow_tables), formed for the exponent the
 * material holds: a material changed between steps (n 0.9 -> 1.1, the
 * envelope below 1 m drops and the plate yields again) gets a
 * table of its own before the next step's contacts, and the soil update
 * with it leaves every loaded vertex's rut where the public law puts it. */
static void test_power_table(void)
{
  ssError e;
  ssModel *m;
  ssData *d;
  ssSoilMaterial soil = plate_soil();
  soil.sinkage_exponent = 0.9;
  if (!plate_world(41, 1.6, 0, 0, &soil, &m, &d, &e)) {
    ok(0, "plate on n = 0.9: %s", e.message);
    return;
  }
  World w = {m, d, 0, 0};
  int good = run(&w, 200);
  const ssPowTable *t = ss_solver_pow_table(m, d, 0);
  int before = t && t->ser.a == 0.9 - 1;
  ssSoilMaterial *mat = &m->hfield_soilmat[0];
  mat->sinkage_exponent = 1.1;
  good = good && run(&w, 1);
  t = ss_solver_pow_table(m, d, 0);
  int after = t && t->ser.a == 1.1 - 1;
  double worst = 0;
  int loaded = 0, yielding = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    if (c->type != SS_CONTACT_SOIL || !c->loaded) continue;
    double z = c->sp - (c->g0 + m->opt.timestep * c->v[0]);
    double want = ss_soil_plastic_update(mat, c->width, z, c->sp);
    worst = fmax(worst, fabs(d->soil_plastic[c->vertex] - want) / z);
    loaded++;
    yielding += want > c->sp;
  }
  ok(good && before && after && yielding > 100 && worst <= 1e-14,
     "power tables follow the material's exponent (n 0.9, then 1.1: %d, %d); %d ruts of %d "
     "loaded points deepened, as the public law deepens them to %.2g",
     before, after, yielding, loaded, worst);
  ss_data_free(d);
  ss_model_free(m);
}

/* the regular nside-gon prism of circumradius r and height hz standing on
 * its base (z from -hz/2 to hz/2) as a triangle mesh: the corners (bottom,
 * top alternating), then the two caps' centres; each side two triangles,
 * each cap a fan.  v: (2 nside + 2) x 3, t: 4 nside x 3 */
static void prism_mesh(int nside, double r, double hz, double *v, int *t)
{
  for (int i = 0; i < nside; i++)
    for (int k = 0; k < 2; k++) {
      double *p = v + 3 * (2 * i + k);
      p[0] = r * cos(2 * M_PI * i / nside);
      p[1] = r * sin(2 * M_PI * i / nside);
      p[2] = k ? 0.5 * hz : -0.5 * hz;
    }
  int cb = 2 * nside, ct = cb + 1;
  v[3 * cb] = v[3 * cb + 1] = v[3 * ct] = v[3 * ct + 1] = 0;
  v[3 * cb + 2] = -0.5 * hz;
  v[3 * ct + 2] = 0.5 * hz;
  for (int i = 0; i < nside; i++) {
    int j = (i + 1) % nside, b0 = 2 * i, t0 = b0 + 1, b1 = 2 * j, t1 = b1 + 1;
    int f[12] = {b0, b1, t1, b0, t1, t0, cb, b1, b0, ct, t0, t1};
    memcpy(t + 12 * i, f, sizeof f);
  }
}

/* a box lx x ly x lz as a flat-shaded mesh: each face its own 4 vertices
 * (24, as a file with per-face normals gives them), 12 triangles */
static void box_mesh_split(double lx, double ly, double lz, double *v, int *t)
{
  /* each face: its axis, its side, and its corners counter-clockwise seen
   * from outside */
  int nv = 0;
  for (int a = 0; a < 3; a++)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      int b = (a + 1) % 3, c = (a + 2) % 3;
      double h[3] = {0.5 * lx, 0.5 * ly, 0.5 * lz};
      double uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (int k = 0; k < 4; k++) {
        double *p = v + 3 * (nv + k);
        p[a] = sgn * h[a];
        p[b] = uv[k][0] * h[b];
        p[c] = sgn * uv[k][1] * h[c];
      }
      int f[6] = {nv, nv + 1, nv + 2, nv, nv + 2, nv + 3};
      memcpy(t + 6 * (nv / 4), f, sizeof f);
      nv += 4;
    }
}

/* One step, without gravity, of a 20 kg link whose collider is the mesh
 * (v, t), turned by turn about z in the link, with its flat bottom (mesh z
 * = zb) 1 mm into a 1.2 m soil bed of spacing h, the link at (ox, oy)
 * turned by yaw: the loaded area (-1 on failure).  *nhull: the mesh's
 * footprint points; *all: every soil point near it was loaded. */
static double mesh_loaded_area(const double *v, int nv, const int *t, int nt, double zb,
                               double turn, double h, double ox, double oy, double yaw,
                               int *nhull, int *all)
{
  ssError e;
  double area = -1, zaxis[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
  ssModel *m = ss_model_new();
  ssData *d = NULL;
  ssMesh *me = NULL;
  ss_v3_set(m->opt.gravity, 0, 0, 0);
  ssUrdf *u = urdf_new();
  add_link(u, "body", 20, NULL, 1, 1, 1);
  ssArtDef def = ss_art_def_default();
  def.name = "mesh";
  def.fixed_base = 0;
  ss_v3_set(def.pos, ox, oy, -zb - 0.001);
  ss_quat_from_axis_angle(def.quat, zaxis, yaw);
  int sys = ss_model_add_articulated(m, u, &def, &e);
  ss_urdf_free(u);
  *nhull = -1;
  *all = 0;
  if (add_bed(m, 1.2, h, plate_soil()) < 0 || sys < 0 ||
      ss_mesh_from_arrays(v, nv, t, nt, &me, &e) != SS_OK) {
    diag("mesh world: %s", e.message);
    goto done;
  }
  *nhull = me->nhull;
  double size[3], q[4];
  for (int k = 0; k < 3; k++) size[k] = me->hi[k] - me->lo[k];
  ss_quat_from_axis_angle(q, zaxis, turn);
  int mi = ss_model_push_mesh(m, me, "mesh", &e);
  if (mi < 0) {
    ss_mesh_free(me);
    goto done;
  }
  if (ss_model_push_geom(m, m->sys_bodyadr[sys], SS_GEOM_MESH, size, zero, q, 0, NULL, 1, mi,
                         &e) < 0 ||
      !(d = ss_data_new(m)) || ss_step(m, d, &e) != SS_OK) {
    diag("mesh world: %s", e.message);
    goto done;
  }
  area = d->stats.soil_contact_area;
  *all = d->stats.soil_contacts > 0 && d->stats.soil_loaded == d->stats.soil_contacts;
done:
  ss_data_free(d);
  ss_model_free(m);
  return area;
}

/* DESIGN 2.6 for mesh colliders: a convex mesh's footprint is the hull of
 * its projected vertices, so its loaded area is its true area for any
 * placement and heading and any spacing (it was its bounding box's
 * coverage, kept where a cell's line hit the mesh: 0.1200 and 0.1280
 * m^2 for the 64-gon's 0.1255 at 4 cm, by placement) */
static void test_mesh_quadrature(void)
{
  enum { NS = 64, NB = 600 };
  static double v[3 * (2 * NB + 2)];
  static int t[3 * 4 * NB];
  const double place[5][3] = {{0, 0, 0},
                              {0.0123, -0.0071, 0},
                              {0.0311, 0.0173, 0.37},
                              {-0.0417, 0.0059, 1.9},
                              {0.0052, 0.0131, -2.6}};
  const double spacing[2] = {0.04, 0.02};
  double r = 0.2, poly = 0.5 * NS * r * r * sin(2 * M_PI / NS);

  /* the 64-gon prism of the audit, standing */
  prism_mesh(NS, r, 0.1, v, t);
  double worst = 0, lo = INFINITY, hi = 0;
  int nhull = 0, all = 1, points = 1;
  for (int s = 0; s < 2; s++)
    for (int k = 0; k < 5; k++) {
      int nh, loaded;
      double a = mesh_loaded_area(v, 2 * NS + 2, t, 4 * NS, -0.05, 0, spacing[s],
                                  place[k][0], place[k][1], place[k][2], &nh, &loaded);
      worst = fmax(worst, fabs(a - poly) / poly);
      lo = fmin(lo, a);
      hi = fmax(hi, a);
      all &= loaded;
      points &= nh == 2 * NS + 2;
      nhull = nh;
    }
  ok(points, "64-gon prism mesh: its %d distinct vertices are its footprint points", nhull);
  ok(worst <= 1e-9 && all,
     "  on soil at 4 and 2 cm, 5 placements and headings: loaded area = the 64-gon's %.9g "
     "(%.12g to %.12g, worst rel %.2g), every point loaded", poly, lo, hi, worst);

  /* a 0.4 x 0.6 x 0.05 box, flat-shaded (each corner split in 3), its
   * vertices turned by 0.6 rad about z in the mesh's frame (so that its
   * bounding box there is larger), and the mesh turned in its link */
  box_mesh_split(0.4, 0.6, 0.05, v, t);
  for (int k = 0; k < 24; k++) {
    double x = v[3 * k], y = v[3 * k + 1];
    v[3 * k] = cos(0.6) * x - sin(0.6) * y;
    v[3 * k + 1] = sin(0.6) * x + cos(0.6) * y;
  }
  worst = 0;
  points = all = 1;
  for (int s = 0; s < 2; s++)
    for (int k = 0; k < 5; k++) {
      int nh, loaded;
      double a = mesh_loaded_area(v, 24, t, 12, -0.025, 0.5, spacing[s], place[k][0],
                                  place[k][1], place[k][2], &nh, &loaded);
      worst = fmax(worst, fabs(a - 0.24) / 0.24);
      all &= loaded;
      points &= nh == 8;
    }
  ok(points, "flat-shaded box mesh (24 vertices): its 8 corners are its footprint points");
  ok(worst <= 1e-9 && all,
     "  turned in its frame and in its link, at 4 and 2 cm, 5 placements and headings: loaded area = "
     "0.24 m^2 (worst rel %.2g), every point loaded", worst);

  /* more distinct vertices than SS_MESH_HULL_MAX: no footprint points, the
   * bounding box's footprint (converging with the spacing, not exact) */
  prism_mesh(NB, r, 0.1, v, t);
  double big = 0.5 * NB * r * r * sin(2 * M_PI / NB);
  int nh, loaded;
  double a = mesh_loaded_area(v, 2 * NB + 2, t, 4 * NB, -0.05, 0, 0.02, place[1][0],
                              place[1][1], place[1][2], &nh, &loaded);
  ok(nh == 0 && fabs(a - big) / big < 0.03 && loaded,
     "600-gon prism mesh (%d distinct vertices > SS_MESH_HULL_MAX %d): no footprint points "
     "(%d); its bounding box's footprint, loaded area %.6g within 3%% of %.6g",
     2 * NB + 2, SS_MESH_HULL_MAX, nh, a, big);
}


/* a mesh of tests/data/urdf/meshes (from $top_srcdir) */
static const char *mesh_file(char *buf, size_t cap, const char *name)
{
  const char *top = getenv("top_srcdir");
  snprintf(buf, cap, "%s/tests/data/urdf/meshes/%s", top && *top ? top : ".", name);
  return buf;
}

/* Stand-alone mesh bodies (ss_model_add_body, SS_GEOM_MESH).  The unit
 * cube of cube.obj (z from 0 to 1: off-centre) scaled to the plate of
 * DESIGN 2.7: its body frame's origin is the centroid (the geom at
 * -centroid), its inertia the box formula's, and it settles on the plate
 * soil to the analytic 8.175 mm as the box does (test_analytic_plate). */
static void test_mesh_body(void)
{
  const double s_ref = 8.175e-3, lx = 0.4, ly = 0.6, lz = 0.05, mass = 20;
  char path[1024];
  ssError e;
  World w;
  w.m = ss_model_new();
  w.bed = add_bed(w.m, 1.2, 0.02, plate_soil());
  ssBodyDef bd = ss_body_def_default();
  bd.name = "plate";
  bd.shape = SS_GEOM_MESH;
  bd.mesh_path = mesh_file(path, sizeof path, "cube.obj");
  bd.mesh_scale[0] = lx;
  bd.mesh_scale[1] = ly;
  bd.mesh_scale[2] = lz;
  bd.mass = mass;
  ss_v3_set(bd.pos, 0, 0, 0.5 * lz);
  w.plate = ss_model_add_body(w.m, &bd, &e);
  w.d = w.plate >= 0 ? ss_data_new(w.m) : NULL;
  if (!ok(w.plate >= 0 && w.d, "mesh body: cube.obj scaled to 0.4 x 0.6 x 0.05 m is added")) {
    diag("%s", e.message);
    free_world(&w);
    return;
  }
  int b = w.m->sys_bodyadr[w.plate], g = w.m->ngeom - 1;
  const double *I = w.m->body_inertia + 9 * b, *gp = w.m->geom_pos + 3 * g;
  double want[3] = {mass * (ly * ly + lz * lz) / 12, mass * (lx * lx + lz * lz) / 12,
                    mass * (lx * lx + ly * ly) / 12};
  double worst = 0;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      worst = fmax(worst, fabs(I[3 * i + j] - (i == j ? want[i] : 0)) / want[0]);
  ok(worst < 1e-12 && w.m->body_mass[b] == mass,
     "mesh body: mass 20 kg and the box formula's inertia (worst relative error %.2g)", worst);
  ok(fabs(gp[0]) < 1e-15 && fabs(gp[1]) < 1e-15 && fabs(gp[2] + 0.5 * lz) < 1e-15 &&
         w.m->geom_type[g] == SS_GEOM_MESH && w.m->geom_mesh[g] >= 0 &&
         fabs(w.m->geom_size[3 * g + 2] - lz) < 1e-15,
     "mesh body: the off-centre mesh (z from 0 to 0.05) sits at -centroid = (%g, %g, %g) "
     "in the body frame: its state's pos is the centre of mass", gp[0], gp[1], gp[2]);
  int good = run(&w, 1500);
  if (good) close_enough(plate_sinkage(&w), s_ref, 0.005 * s_ref, "mesh body plate sinkage (8.175 mm)");
  else ok(0, "mesh body: settle run");
  close_enough(w.d->stats.soil_contact_area, 0.24, 1e-9, "  loaded area = the plate's");
  free_world(&w);

  /* an open mesh encloses no volume: refused without an inertia, taken
   * with one (its frame at the surface's centroid) */
  char open_path[1024];
  const char *top = getenv("top_srcdir");
  snprintf(open_path, sizeof open_path, "%s/tests/data/bad/open_box.obj", top && *top ? top : ".");
  ssModel *m = ss_model_new();
  ssBodyDef ob = ss_body_def_default();
  ob.name = "bucket";
  ob.shape = SS_GEOM_MESH;
  ob.mesh_path = open_path;
  ob.mass = 2;
  int r = ss_model_add_body(m, &ob, &e);
  ok(r < 0 && e.code == SS_ERR_VALUE && strstr(e.message, "encloses no volume") &&
         strstr(e.message, "open_box.obj") && m->nsys == 0 && m->nmesh == 0,
     "an open mesh without an inertia is refused, nothing added (%s)", e.message);
  ob.inertia_given = 1;
  ob.inertia[0] = ob.inertia[3] = ob.inertia[5] = 0.1;
  r = ss_model_add_body(m, &ob, &e);
  ok(r >= 0 && m->nmesh == 1 && m->body_inertia[9 * m->sys_bodyadr[r]] == 0.1,
     "... and taken with one");
  ob.name = "missing";
  ob.mesh_path = "/no/such/rock.obj";
  r = ss_model_add_body(m, &ob, &e);
  ok(r < 0 && strstr(e.message, "/no/such/rock.obj") && m->nsys == 1,
     "a mesh file that does not exist: the error names it (%s)", e.message);
  ob.mesh_path = open_path;
  ob.mesh_scale[1] = 0;
  r = ss_model_add_body(m, &ob, &e);
  ok(r < 0 && strstr(e.message, "scale value 2 is 0"), "scale 0 is refused (%s)", e.message);
  ss_model_free(m);
}

/* A rock (a regular octahedron, vertices 0.1 m from its centre) set on a
 * ground plane on one face comes to rest on that face's three vertices:
 * its centre at 0.1 / sqrt 3 above the plane (on its bounding box's
 * corners it would be 0.1 sqrt 3), its rigid contacts at its vertices. */
static void test_mesh_rock(void)
{
  const double a = 0.1, th = acos(1 / sqrt(3.0));
  char path[1024];
  ssError e;
  ssModel *m = ss_model_new();
  ss_model_add_plane(m, "ground", 0, NULL, 0, &e);
  ssBodyDef bd = ss_body_def_default();
  bd.name = "rock";
  bd.shape = SS_GEOM_MESH;
  bd.mesh_path = mesh_file(path, sizeof path, "octa.obj");
  bd.mesh_scale[0] = bd.mesh_scale[1] = bd.mesh_scale[2] = a;
  bd.mass = 3;
  double axis[3] = {sqrt(0.5), -sqrt(0.5), 0};
  ss_quat_from_axis_angle(bd.quat, axis, th);
  ss_v3_set(bd.pos, 0.3, -0.2, a / sqrt(3.0) + 0.01);
  int s = ss_model_add_body(m, &bd, &e);
  ssData *d = s >= 0 ? ss_data_new(m) : NULL;
  if (!ok(d != NULL, "octahedron rock builds")) {
    diag("%s", e.message);
    ss_model_free(m);
    return;
  }
  int good = 1;
  for (int k = 0; k < 800 && good; k++) good = ss_step(m, d, &e) == SS_OK;
  double z = d->qpos[2], worst = 0;
  int nrigid = 0;
  for (int i = 0; i < d->ncontact; i++) {
    if (d->contact[i].type != SS_CONTACT_RIGID) continue;
    nrigid++;
    /* each contact at a vertex: |c - centre| = a */
    double r[3];
    ss_v3_sub(r, d->contact[i].pos, d->qpos);
    worst = fmax(worst, fabs(ss_v3_norm(r) - a));
  }
  ok(good && fabs(z - a / sqrt(3.0)) < 1e-4 && nrigid == 3 && worst < 1e-4,
     "an octahedron rock rests on a face's vertices: centre %.5f m up (want %.5f; "
     "its box's corners would give %.5f), %d rigid contacts, each %.2g m off a vertex",
     z, a / sqrt(3.0), a * sqrt(3.0), nrigid, worst);
  ss_data_free(d);
  ss_model_free(m);
}

int main(void)
{
  test_analytic_plate();
  test_turned_bed();
  test_envelope_shapes();
  test_reload();
  test_impact_and_lift();
  test_drag();
  test_rigid();
  test_rigid_warm();
  test_rigid_mix();
  test_unit_quats();
  test_reach();
  test_contact_storage();
  test_warm_trend();
  test_newton();
  test_settled_cache();
  test_far_from_origin();
  test_resting_on_slope();
  test_creeping_plate();
  test_drag_stops();
  test_drag_stops_cold();
  test_creep_matches_sweeps();
  test_drag_slide_stops();
  test_plate_arm_cold();
  test_power_table();
  test_mesh_quadrature();
  test_mesh_body();
  test_mesh_rock();
  return done_testing();
}
