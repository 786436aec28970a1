/* point.h -- the law of one contact inside the solver (point.c): the
 * implicit soil law of one quadrature point (DESIGN 3.1), solved for its
 * impulse with every other contact held, and the Coulomb cone of a rigid
 * contact.  The Gauss-Seidel sweeps (solver.c) call these once per visit.
 *
 * Internal to the library; the layout of the contact is solver.h's. */
#ifndef SS_POINT_H
#define SS_POINT_H

#include "soilsim.h"
#include "ss_math.h"

#include <float.h>

/* The Bekker envelope's modulus k_c/b + k_phi for width b, as every user
 * of the law forms it (the sweeps' and the Newton phase's set-up, the soil
 * update, soil.c): no division where k_c = 0 (the same value) */
static inline double ss_soil_modulus(const ssSoilMaterial *mat, double b)
{
  return (b > 0 && mat->bekker_kc != 0 ? mat->bekker_kc / b : 0) + mat->bekker_kphi;
}

/* 1/K_j of the Janosi-Hanamoto law (DESIGN 2.3), or 0 where the bound is
 * fully mobilized at once: K_j = 0, and a K_j so small that its reciprocal
 * overflows (below 2^-1024, about 5.6e-309 m: a subnormal).  Such a K_j
 * reaches tau_f within a slip of 1e-300 m, the same law as K_j = 0 to
 * every tolerance, and 1/K_j = inf would make j/K_j NaN at j = 0.  The
 * soil law (soil.c) and both solves (point.c, newton.c) decide by it. */
static inline double ss_soil_janosi_inverse(const ssSoilMaterial *mat)
{
  double K = mat->shear_displacement, ik = K > 0 ? 1 / K : 0;
  return ik <= DBL_MAX ? ik : 0;
}

/* ss_soil_modulus kept for the last width b (b NAN: none): the points of
 * one collider share its width, so a loop over them forms it (a
 * division) once, the same bits */
typedef struct ssModulusMemo {
  double b, k;
} ssModulusMemo;

static inline double ss_soil_modulus_at(const ssSoilMaterial *mat, ssModulusMemo *c, double b)
{
  if (!(b == c->b)) {
    c->b = b;
    c->k = ss_soil_modulus(mat, b);
  }
  return c->k;
}

/* A soil point's law (DESIGN 3.1) as its solve uses it (solver.c): set up
 * once per step from the contact and its material, plus the values the
 * solve reuses between visits -- the last power s^(n-1) and the last
 * Janosi mobilisation, from which the next visit moves by short series
 * instead of calling pow and expm1. */
typedef struct ssLaw {
  double S;          /* A dt */
  double dt, g0, sp; /* step, start separation, rut depth */
  double k, n, m1;   /* k_c/b + k_phi, exponent, n - 1 */
  double Ke, D;
  int linear;        /* n == 1 */
  ssPowSeries pser;  /* the series of s^(n-1) (not formed when linear) */
  ssPowMemo pw;      /* last power s^(n-1) (pw.s = 0: none yet) */
} ssLaw;

/* Janosi mobilisation m = 1 - exp(-x), x = (j + dt sigma)/K, and e = 1 - m
 * (solver.c: mobil_at) */
typedef struct ssMobil {
  double r;          /* dt/K, 0 when constant */
  double x0, m0;     /* j/K and m there (zero slip; m0 < 0 not yet known) */
  ssExpMemo last;    /* the last point (last.x < 0: none) */
} ssMobil;

/* The tangential block of one contact, fixed for its whole solve. */
typedef struct ssTBlock {
  double G[4];   /* G_tt */
  double adj[4]; /* its adjugate: G_tt^-1 = adj / det, no division needed
                    to compare |G_tt^-1 c| with a bound */
  double det;
  double e[2];   /* G_tn = d c_t / d lambda_n */
  int inert;     /* G_tt = 0: no response (static body) */
  int pd;        /* x . G_tt x > 0 for x != 0 (its symmetric part positive
                    definite): a slip solution cannot also stick */
} ssTBlock;

/* The point's solve state kept on the contact (the contact is rebuilt
 * every step).  ss_solver_solve sets it up once per step before the
 * sweeps; ss_solver_soil_point sets it up at every call, keeping the
 * reused values only while what they were made from is unchanged (n - 1;
 * j/K and dt/K).  Empty, whatever its bytes, while the contact's
 * cache_ready is 0 (ssContact): a new contact's cache is not written at
 * all, so that the steps without sweeps never touch its cache lines. */
typedef struct ssPointCache {
  ssLaw law;
  ssMobil mob;
  ssTBlock tb;
  double tf0, mu;           /* shear bound tf = tf0 + mu lambda_n: A dt c, mu */
} ssPointCache;

/* Set up the law of soil contact c for this step from its material
 * (c->cache): the constants always, the reused power and mobilisation only
 * while what they were made from is unchanged.  tab: the bed's table of
 * s^(n-1) for the first power (ss_solver_pow_table), or NULL: libm. */
void ss_point_setup(const ssSoilMaterial *mat, const ssPowTable *tab, double dt,
                    ssContact *c);
/* New impulse c->lambda of a soil contact set up by ss_point_setup, given
 * the velocity v0 it would have without its own impulse (others held);
 * c->lambda is the first guess.  Returns the number of inner iterations. */
int ss_point_soil(ssContact *c, const double v0[3], double tol);
/* New impulse c->lambda of a rigid contact: Coulomb cone with the normal
 * velocity target c->vn_target. */
void ss_point_rigid(ssContact *c, const double v0[3], double tol);

#endif
