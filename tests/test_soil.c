/* test_soil.c -- the soil law of DESIGN 2.3-2.5 against the closed forms of
 * DESIGN 2.7, material validation, and the per-point implicit solve. */
#include "soilsim.h"
#include "solver.h"
#include "ss_math.h"
#include "terrain.h"
#include "tap.h"

#include <float.h>
#include <stdlib.h>

#include <string.h>

static ssSoilMaterial plate_soil(void)
{
  ssSoilMaterial s = ss_soil_material_default();
  s.bekker_kc = 0;
  s.bekker_kphi = 1e5;
  s.sinkage_exponent = 1;
  s.elastic_stiffness = 2e6;
  return s;
}

static void test_envelope(void)
{
  ssSoilMaterial s = plate_soil();
  /* 20 kg on 0.4 x 0.6 m: p = 817.5 Pa, s = p / k_phi = 8.175 mm */
  double p = 20 * 9.81 / 0.24;
  close_enough(p, 817.5, 1e-9, "plate pressure m g / A");
  double z = pow(p / (s.bekker_kc / 0.4 + s.bekker_kphi), 1 / s.sinkage_exponent);
  close_enough(z, 8.175e-3, 1e-12, "analytic plate sinkage");
  close_enough(ss_soil_envelope(&s, 0.4, z), p, 1e-9, "envelope at the plate sinkage");
  close_enough(z - p / s.elastic_stiffness, 7.76625e-3, 1e-12, "rut after lifting");
  close_enough(ss_soil_plastic_update(&s, 0.4, z, 0), 7.76625e-3, 1e-12,
               "plastic update on the envelope leaves s - p/K_e");

  /* n != 1: k_phi = p_ref / s_ref^n reproduces p_ref at s_ref */
  ssSoilMaterial q = s;
  q.sinkage_exponent = 1.1;
  double pref = 5000, sref = 0.02;
  q.bekker_kphi = pref / pow(sref, q.sinkage_exponent);
  close_enough(ss_soil_envelope(&q, 0.3, sref), pref, 1e-8, "n = 1.1 envelope at s_ref");
  close_enough(ss_soil_envelope(&q, 0.3, 2 * sref), pref * pow(2, 1.1), 1e-7,
               "n = 1.1 envelope scales as s^n");
  double h = 1e-7, num = (ss_soil_envelope(&q, 0.3, sref + h) - ss_soil_envelope(&q, 0.3, sref - h)) / (2 * h);
  close_enough(ss_soil_envelope_slope(&q, 0.3, sref), num, 1e-4 * num, "envelope slope matches finite difference");

  /* two widths separate k_c and k_phi */
  ssSoilMaterial w = s;
  w.bekker_kc = 3000;
  w.bekker_kphi = 8e4;
  w.sinkage_exponent = 1.2;
  double zz = 0.03, b1 = 0.2, b2 = 0.5;
  double p1 = ss_soil_envelope(&w, b1, zz), p2 = ss_soil_envelope(&w, b2, zz);
  double zn = pow(zz, w.sinkage_exponent);
  double kc = (p1 - p2) / zn / (1 / b1 - 1 / b2), kphi = p1 / zn - kc / b1;
  close_enough(kc, 3000, 1e-6, "k_c recovered from two widths");
  close_enough(kphi, 8e4, 1e-5, "k_phi recovered from two widths");
}

static void test_elastic(void)
{
  ssSoilMaterial s = plate_soil();
  double sp = 0.005;
  /* reload follows K_e from the rut floor until it meets the envelope */
  close_enough(ss_soil_pressure(&s, 0.4, sp + 1e-4, sp), 2e6 * 1e-4, 1e-9,
               "reload on the elastic branch");
  ok(ss_soil_plastic_update(&s, 0.4, sp + 1e-4, sp) == sp,
     "elastic reload leaves the rut unchanged");
  /* crossing: K_e (s - sp) = k_phi s  ->  s = K_e sp / (K_e - k_phi) */
  double sx = 2e6 * sp / (2e6 - 1e5);
  close_enough(ss_soil_pressure(&s, 0.4, sx + 1e-3, sp), 1e5 * (sx + 1e-3), 1e-9,
               "beyond the crossing the envelope governs");
  ok(ss_soil_plastic_update(&s, 0.4, sx + 1e-3, sp) > sp, "yielding deepens the rut");
  ok(ss_soil_pressure(&s, 0.4, sp, sp) == 0, "no pressure at the rut floor");
  ok(ss_soil_pressure(&s, 0.4, sp - 1e-3, sp) == 0, "no pressure above the rut floor (no suction)");
  /* elastic recovery on unload is p / K_e */
  double z = 0.02, p = ss_soil_pressure(&s, 0.4, z, 0);
  close_enough(z - ss_soil_plastic_update(&s, 0.4, z, 0), p / 2e6, 1e-15, "elastic recovery p / K_e");
}

static void test_viscous_shear(void)
{
  ssSoilMaterial s = ss_soil_material_default();
  close_enough(ss_soil_viscous(&s, 0.1), 200, 1e-12, "D sdot while loading");
  ok(ss_soil_viscous(&s, -0.1) == 0, "no viscous pressure while unloading");
  close_enough(ss_soil_shear_strength(&s, 1000), 100 + 0.6 * 1000, 1e-9, "Mohr-Coulomb c + mu p");
  double tf = ss_soil_shear_strength(&s, 1000), K = s.shear_displacement;
  close_enough(ss_soil_shear_limit(&s, 1000, K) / tf, 0.63212055882855767, 1e-12, "Janosi j = K_j: 63.2 %");
  close_enough(ss_soil_shear_limit(&s, 1000, 3 * K) / tf, 0.95021293163213605, 1e-12, "Janosi j = 3 K_j: 95 %");
  close_enough(ss_soil_shear_limit(&s, 1000, 4.605 * K) / tf, 0.99000, 1e-4, "Janosi j = 4.605 K_j: 99 %");
  ok(ss_soil_shear_limit(&s, 1000, 0) == 0, "no strength before any slip (K_j > 0)");
  s.shear_displacement = 0;
  close_enough(ss_soil_shear_limit(&s, 1000, 0), tf, 0, "K_j = 0: full strength at once");
}

static void test_validation(void)
{
  const char *fields[] = {"bekker_kc", "bekker_kphi", "sinkage_exponent",
                          "elastic_stiffness", "damping", "cohesion",
                          "friction_coefficient", "shear_displacement"};
  ssSoilMaterial good = ss_soil_material_default();
  ssError e;
  ok(ss_soil_material_validate(&good, &e) == SS_OK, "defaults are valid");
  for (int f = 0; f < 8; f++) {
    double bad[] = {-1, NAN, INFINITY};
    for (int k = 0; k < 3; k++) {
      ssSoilMaterial s = good;
      ((double *)&s)[f] = bad[k];
      ssStatus st = ss_soil_material_validate(&s, &e);
      ok(st == SS_ERR_VALUE && strstr(e.message, fields[f]),
         "%s = %g rejected, naming the field (%s)", fields[f], bad[k], e.message);
    }
  }
  ssSoilMaterial s = good;
  s.sinkage_exponent = 0;
  ok(ss_soil_material_validate(&s, &e) == SS_ERR_VALUE, "sinkage_exponent = 0 rejected");
  s = good;
  s.elastic_stiffness = 0;
  ok(ss_soil_material_validate(&s, &e) == SS_ERR_VALUE, "elastic_stiffness = 0 rejected");
  s = good;
  s.bekker_kc = s.bekker_kphi = 0;
  ok(ss_soil_material_validate(&s, &e) == SS_ERR_VALUE && strstr(e.message, "at least one"),
     "k_c = k_phi = 0 rejected");
}

/* the implicit per-point solve: residual of the soil law at the answer */
static void test_point_solve(void)
{
  ssSoilMaterial s = ss_soil_material_default();
  double dt = 1e-3;
  ssContact c;
  memset(&c, 0, sizeof c);
  c.type = SS_CONTACT_SOIL;
  c.area = 4e-4;
  c.width = 0.3;
  c.sp = 0.01;
  c.j = 0.002;
  c.g0 = -0.001; /* already 1 mm into the rut floor */
  double G[9] = {0.2, 0.01, -0.02, 0.01, 0.15, 0.03, -0.02, 0.03, 0.25};
  memcpy(c.G, G, sizeof G);
  double v0[3] = {-0.5, 0.3, -0.1};
  ss_solver_soil_point(&s, dt, &c, v0, 1e-13);
  double v[3];
  for (int k = 0; k < 3; k++)
    v[k] = v0[k] + G[3 * k] * c.lambda[0] + G[3 * k + 1] * c.lambda[1] + G[3 * k + 2] * c.lambda[2];
  double delta = -(c.g0 + dt * v[0]);
  double p = ss_soil_pressure(&s, c.width, c.sp + delta, c.sp) + ss_soil_viscous(&s, -v[0]);
  close_enough(c.lambda[0], c.area * dt * p, 1e-12 * c.area * dt * p + 1e-18,
               "normal impulse satisfies the implicit law");
  double vt = hypot(v[1], v[2]), lt = hypot(c.lambda[1], c.lambda[2]);
  double tmax = ss_soil_shear_limit(&s, c.lambda[0] / (c.area * dt), c.j + dt * vt);
  ok(vt > 1e-6, "the point slips (vt = %g)", vt);
  close_enough(lt, c.area * dt * tmax, 1e-9 * c.area * dt * tmax, "slip: shear at the Janosi limit");
  ok(c.lambda[1] * v[1] + c.lambda[2] * v[2] <= 0, "shear dissipates (opposes slip)");
  double cosang = -(c.lambda[1] * v[1] + c.lambda[2] * v[2]) / (lt * vt);
  close_enough(cosang, 1, 1e-9, "shear aligned against the slip velocity");

  /* a gentle tangential drive sticks */
  c.lambda[0] = c.lambda[1] = c.lambda[2] = 0;
  c.j = 0.05;
  double v1[3] = {-0.5, 1e-6, 0}; /* stick impulse ~4e-5 N s < bound ~3.5e-4 N s */
  ss_solver_soil_point(&s, dt, &c, v1, 1e-13);
  double vt1 = v1[1] + G[3] * c.lambda[0] + G[4] * c.lambda[1] + G[5] * c.lambda[2];
  double vt2 = v1[2] + G[6] * c.lambda[0] + G[7] * c.lambda[1] + G[8] * c.lambda[2];
  ok(fabs(vt1) < 1e-12 && fabs(vt2) < 1e-12, "stick: slip stopped (%g, %g)", vt1, vt2);

  /* a point moving away from the rut floor carries nothing (no suction) */
  c.lambda[0] = c.lambda[1] = c.lambda[2] = 0;
  c.g0 = 0.0005;
  double v2[3] = {0.1, 0.2, 0};
  ss_solver_soil_point(&s, dt, &c, v2, 1e-13);
  ok(c.lambda[0] == 0 && c.lambda[1] == 0 && c.lambda[2] == 0, "separating point: zero impulse");
}

/* distance of x from the long double reference r in ulps of r (as a double) */
static double ulps(double x, long double r)
{
  double rd = (double)r, u = nextafter(fabs(rd), INFINITY) - fabs(rd);
  return (double)fabsl((long double)x - r) / u;
}

/* The table of s^a (ss_math.h) that gives each point's first power of a
 * step: within 4 ulp of the exact power over its range, for exponents of
 * both signs up to the series' limit (ss_math.h: four roundings); libm's pow, bit for bit, outside the
 * range, at zero, for negative, infinite or NaN s and for |a| > 3. */
static void test_pow_table(void)
{
  const double as[] = {0.1, -0.3, 0.5, -0.9, 2.2, 1e-3, 3};
  srand(7);
  for (size_t ia = 0; ia < sizeof as / sizeof *as; ia++) {
    ssPowTable t;
    ss_pow_table_init(&t, as[ia]);
    double worst = 0, at = 0;
    for (int i = 0; i < 200000; i++) {
      /* every octave of the range, every bucket of the mantissa, and the
       * buckets' edges */
      double e = SS_POWT_EMIN + (SS_POWT_EMAX + 1 - SS_POWT_EMIN) * (rand() / (RAND_MAX + 1.0));
      double s = exp2(floor(e)) * (1 + (rand() % 4 ? rand() / (RAND_MAX + 1.0)
                                                   : (rand() % SS_POWT_N) / (double)SS_POWT_N));
      double err = ulps(ss_pow_tab(&t, s), powl((long double)s, (long double)as[ia]));
      if (err > worst) {
        worst = err;
        at = s;
      }
    }
    ok(t.ok && worst <= 4, "s^%g by table: within 4 ulp (worst %.2f at s = %.17g)", as[ia],
       worst, at);
    const double out[] = {0, 5e-324, ldexp(1, SS_POWT_EMIN) * 0.75, ldexp(1, SS_POWT_EMAX + 1),
                          1e300, -0.5, INFINITY, NAN};
    int same = 1;
    for (size_t k = 0; k < sizeof out / sizeof *out; k++) {
      double x = ss_pow_tab(&t, out[k]), y = pow(out[k], as[ia]);
      same &= memcmp(&x, &y, sizeof x) == 0;
    }
    ok(same, "s^%g by table: libm outside the table's range", as[ia]);
  }
  ssPowTable big;
  ss_pow_table_init(&big, 3.5);
  double x = ss_pow_tab(&big, 0.37), y = pow(0.37, 3.5);
  ok(!big.ok && x == y, "an exponent beyond the series (3.5): libm");

  /* the soil update's plastic sinkage with the power by table is the
   * public function's to rounding, on both branches */
  ssSoilMaterial m = ss_soil_material_default();
  m.bekker_kc = 2e3;
  m.sinkage_exponent = 1.3;
  ssPowTable t;
  ss_pow_table_init(&t, m.sinkage_exponent - 1);
  double worst = 0;
  int branches = 0;
  for (int i = 0; i < 1000; i++) {
    double z = 1e-4 + 0.1 * i / 1000.0, zp = i % 2 ? z * (1 - 1e-5 * (i % 7)) : 0.5 * z;
    double a = ss_soil_plastic_update(&m, 0.3, z, zp);
    double b = ss_soil_plastic_update_pow(&m, ss_soil_modulus(&m, 0.3), z, zp, ss_pow_tab(&t, z));
    double r = fabs(a - b) / z;
    if (r > worst) worst = r;
    branches |= a > zp ? 1 : 2;
  }
  ok(branches == 3 && worst <= 1e-14,
     "plastic update with the tabled power: the public one's to rounding (%.3g)", worst);
}

/* The Janosi memo (ss_math.h: ss_exp_memo_move): m = 1 - exp(-x) moved by
 * the series from a point that libm gave (or from x = 0, as a point's
 * first x starts) is within 4 ulp of the exact value, relative, however
 * small m is (the reason m is carried, not 1 - e) -- of the larger of
 * the two points' m: a move down to a much smaller x keeps the last
 * point's rounding, m' = m - e (1 - exp(-d)) cancelling; e within 4 ulp
 * of 1, absolute (all that its uses need).  Every move the series
 * reaches, both ways, from small to large x. */
static void test_exp_memo(void)
{
  const double x0s[] = {0, 1e-14, 3e-6, 1e-3, 0.3, 1, 4.5, 30};
  double worst_m = 0, worst_e = 0, at_x = 0, at_d = 0;
  int series = 0, moves = 0;
  srand(11);
  for (size_t i = 0; i < sizeof x0s / sizeof *x0s; i++)
    for (int k = 0; k < 4000; k++) {
      double x0 = x0s[i], d = SS_EXP_SERIES_MAX * ldexp(rand() / (RAND_MAX + 1.0), -(k % 40));
      if (k % 2) d = -d;
      if (x0 + d < 0) continue;
      ssExpMemo c = ss_exp_memo_start(x0);
      if (x0 > 0) {
        c.x = x0;
        c.m = -expm1(-x0);
        c.e = exp(-x0);
      }
      double x = x0 + d;
      series += fabs(x - x0) <= SS_EXP_SERIES_MAX;
      moves++;
      double m0 = c.m;
      c = ss_exp_memo_move(c, x);
      long double mr = -expm1l(-(long double)x);
      double big = fmax(m0, (double)mr), u = nextafter(big, INFINITY) - big;
      double em = (double)fabsl((long double)c.m - mr) / u;
      double ee = (double)fabsl((long double)c.e - expl(-(long double)x)) / DBL_EPSILON;
      if (em > worst_m) {
        worst_m = em;
        at_x = x0;
        at_d = d;
      }
      if (ee > worst_e) worst_e = ee;
    }
  ok(moves > 20000 && series == moves && worst_m <= 4,
     "Janosi memo moved by the series: m within 4 ulp (worst %.2f, x0 = %g, d = %g)", worst_m,
     at_x, at_d);
  ok(worst_e <= 4, "Janosi memo moved by the series: e within 4 ulp of 1 (worst %.2f)", worst_e);
}

int main(void)
{
  test_pow_table();
  test_exp_memo();
  test_envelope();
  test_elastic();
  test_viscous_shear();
  test_validation();
  test_point_solve();
  return done_testing();
}
