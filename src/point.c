/* point.c -- the law of one contact inside the solver (point.h). */
#include "point.h"
#include "solver.h"
#include "ss_math.h"

#include <float.h>
#include <math.h>

/* ---------------------------------------------------------------------- */
/* the soil point                                                          */
/*
 * Solve strategy (DESIGN 3.1).  With the other contacts held, the point's
 * end-of-step velocity is v = v0 + G lambda, and lambda = (lambda_n,
 * lambda_t) must satisfy the normal law and the shear law together.  Every
 * answer returned has passed the residual tests below at the point
 * returned; the tolerances are those of the caller, never relaxed.
 *
 * Normal, for a given tangential impulse: f(x) = x - A dt P(a + g x) with
 * g > 0 and P non-increasing is increasing, so it has one root, bracketed
 * by [0, A dt P(a)].  Accepted where |f| <= tol times the bracket's upper
 * end, or times the iterate while that end is not formed (tighter).
 *  - n = 1: P is piecewise affine in v_n: elastic or yield branch, times
 *    damping active (v_n < 0) or not.  On each of the four pieces f = 0 is
 *    a linear equation in x; as f is monotone, the piece whose own solution
 *    lies in it holds the root.  No iteration; the answer is re-checked
 *    against the residual and the iteration below takes over only if
 *    round-off at a kink leaves no piece consistent.
 *  - n != 1: Newton from the previous impulse (the warm lambda_n), Halley
 *    (with P'' of the envelope) when the Newton correction is large,
 *    bisection in the analytic bracket whenever a step leaves it.
 *
 * Shear, for a given normal impulse: with c_t the tangential velocity at
 * lambda_t = 0, the point sticks when the impulse that stops slip,
 * -G_tt^-1 c_t, lies inside A dt tau_max(p_n, j) (tested first, by the
 * adjugate, no inverse).  Otherwise the slip speed sigma in (0, |c_t|]
 * solves |w(sigma)| = 1, w = M^-1 c_t, M = sigma I + T(sigma) G_tt (the
 * impulse -T w opposes the slip sigma w: maximum dissipation), with
 * T(sigma) = A dt tau_f (1 - exp(-(j + dt sigma)/K)).  We solve
 * q(sigma) = 1/|w| - 1, which is affine in sigma for an isotropic block and
 * a constant bound, so Newton is nearly exact; Halley adds the curvature of
 * q (the Janosi T'' and the anisotropy) for large corrections; bisection in
 * the bracket is the fallback.  The first guess is the slip speed the
 * previous (warm) impulse gives, else |c_t|.  Accepted when ||w| - 1| <= tol.
 *
 * Coupling, G_nt != 0, in two layers:
 *  - Fast path (coupled_slip): a point that surely slips at the start (its
 *    stop-slip impulse exceeds the bound at the guessed slip speed, itself
 *    >= the bound at zero slip) is solved by Newton on both equations at
 *    once in (lambda_n, sigma), F1 = f with the shear impulse -T w inside
 *    v_n and F2 = q - 1, with their full 2x2 Jacobian (its rows scaled
 *    so that no division lies between one iterate and the next; the
 *    residual tests multiplied through by M's determinant).  From a warm
 *    start this is one step and the checking evaluation.  It returns only
 *    when both residual tests pass at the same point and the point cannot
 *    stick there; any iterate leaving lambda_n > 0, 0 < sigma <= |c_t|
 *    hands the point to the safeguarded loop.  Cold, the start is the
 *    n = 1 piece (or a Newton step from 0) with the shear held, and sigma
 *    from the isotropic slip equation sigma + T gamma = |c_t|.
 *  - Safeguarded loop: the scalar solves above, alternated.  Each shear
 *    solve also returns d lambda_t / d lambda_n (implicit derivative of its
 *    equations; -G_tt^-1 G_tn when sticking), and the next normal solve
 *    sees lambda_t linearised about the current point, i.e. the effective
 *    compliance g + G_nt . d lambda_t/d lambda_n (the Schur complement when
 *    sticking): Newton on the reduced normal equation, and the next slip
 *    guess moves by d sigma/d lambda_n.  It stops when the normal residual
 *    at the current shear impulse passes; after 20 rounds it falls back to
 *    the plain fixed point and the old step-size test.
 *  Without coupling, one normal solve and one shear solve.
 *
 * Reuse: s^(n-1) and the Janosi exponential are taken from libm once and
 * then moved to nearby arguments by short series in the small change (to
 * rounding, see pow_near and Mobil), since the iterates of one point stay
 * close together; the Janosi value at zero slip is formed only when a
 * stick test needs it. */

/* moves up to SS_POW_SERIES_MAX and SS_EXP_SERIES_MAX (ss_math.h) are done
 * by series, larger ones by libm */

/* the law of one point (ssLaw, solver.h): fixed during its solve, with the
 * cached power */
typedef ssLaw Law;

/* s^(n-1), from the last value by (1 + u)^(n-1) when s = ps (1 + u) is near
 * it: seven terms where pow would cost a log and an exp */
static inline double pow_near(Law *L, double s)
{
  return ss_pow_moved(&L->pw, s, &L->pser, 1);
}

/* Normal pressure at end-of-step normal velocity vn (DESIGN 3.1) and its
 * first two derivatives in vn (P' <= 0; P'' from the envelope only);
 * linear: L->linear, a constant where the caller is specialised for it.
 * sc > 0 scales both sides, for n = 1 only, whose pieces are affine: the
 * pressure times sc at the velocity vn / sc (sc = det in coupled_slip,
 * so that no division comes first); every other call passes 1, a
 * constant, and x * 1 folds away. */
static inline double law_pressure_as(Law *L, double vn, double sc, double *dP, double *d2P,
                                     const int linear)
{
  double delta = -(L->g0 * sc + L->dt * vn);
  if (!(delta > 0)) {
    *dP = *d2P = 0;
    return 0;
  }
  double s = L->sp * sc + delta;
  /* one power for the envelope and its slope: s^n = s s^(n-1) */
  double sn1 = linear ? 1.0 : pow_near(L, s);
  double pe = L->Ke * delta, py = L->k * s * sn1;
  double p, slope, curv = 0;
  if (pe <= py) {
    p = pe;
    slope = L->Ke;
  } else {
    p = py;
    slope = linear ? L->k : L->k * L->n * sn1; /* k n s^(n-1) = k for n = 1 */
    if (!linear) curv = slope * L->m1 / s;
  }
  double dpdv = -L->dt * slope;
  if (vn < 0) {
    p -= L->D * vn;
    dpdv -= L->D;
  }
  *dP = dpdv;
  *d2P = L->dt * L->dt * curv;
  return p;
}

static inline double law_pressure(Law *L, double vn, double *dP, double *d2P)
{
  return law_pressure_as(L, vn, 1, dP, d2P, L->linear);
}

/* n = 1: the root of x = A dt P(a + g x) from the four affine pieces of P
 * (elastic/yield x damped/undamped): on a piece P = c0 + c1 v, so
 * x = S (c0 + c1 a) / (1 - S c1 g).  Returns 1 with the consistent one in *x,
 * trying first the piece the guess velocity vg lies on; 0 if none is. */
static int normal_direct(const Law *L, double a, double g, double vg, double *x)
{
  double dg = -(L->g0 + L->dt * vg);
  int first = (L->Ke * dg <= L->k * (L->sp + dg) ? 0 : 2) + (vg < 0);
  for (int t = 0; t < 4; t++) {
    int piece = (first + t) & 3, yield = piece >> 1, damped = piece & 1;
    double c0 = yield ? L->k * (L->sp - L->g0) : -L->Ke * L->g0;
    double c1 = -L->dt * (yield ? L->k : L->Ke) - (damped ? L->D : 0);
    double xs = L->S * (c0 + c1 * a) / (1 - L->S * c1 * g);
    double v = a + g * xs, delta = -(L->g0 + L->dt * v);
    if (!(xs > 0 && delta > 0)) continue;
    if ((L->Ke * delta > L->k * (L->sp + delta)) != yield) continue;
    if ((v < 0) != damped) continue;
    *x = xs;
    return 1;
  }
  return 0;
}

/* lambda_n = A dt P(a + g lambda_n) (strategy above).  *at_guess is set when
 * the guess itself passes the residual test.  The bracket's upper end
 * A dt P(a) costs an evaluation of its own, so it is formed only when a
 * step needs it; until then the residual test is against the iterate
 * itself, which lies below it (a tighter test). */
static double solve_normal(Law *L, double a, double g, double guess,
                           double tol, int *iters, int *at_guess)
{
  double S = L->S, dP, d2P, f, fp, x = guess > 0 && g > 0 ? guess : 0;
  double lo = 0, hi = INFINITY, bound = 0; /* bound: A dt P(a), 0 unknown */
  *at_guess = 0;
  if (x > 0) {
    (*iters)++;
    f = x - S * law_pressure(L, a + g * x, &dP, &d2P);
    if (fabs(f) <= tol * x) {
      *at_guess = 1;
      return x;
    }
    if (f > 0) hi = x;
    else lo = x;
  } else {
    (*iters)++;
    bound = S * law_pressure(L, a, &dP, &d2P);
    if (!(bound > 0)) return 0;
    if (!(g > 0)) return bound;
    hi = bound;
    f = -bound;
  }
  fp = 1 - S * dP * g;
  if (L->linear) {
    double xd;
    if (normal_direct(L, a, g, a + g * x, &xd)) {
      (*iters)++;
      double fd = xd - S * law_pressure(L, a + g * xd, &dP, &d2P);
      if (fabs(fd) <= tol * (bound > xd ? bound : xd)) return xd;
      /* round-off at a kink: iterate from the direct answer */
      x = xd;
      f = fd;
      fp = 1 - S * dP * g;
      if (f > 0) hi = hi < x ? hi : x;
      else lo = lo > x ? lo : x;
    }
  }
  double best = x, fbest = fabs(f);
  for (int it = 0; it < 100; it++) {
    double dx = -f / fp;
    if (d2P != 0 && fabs(dx) > 1e-5 * x) {
      /* Halley: the correction of the local parabola f + f' dx + f'' dx^2/2 */
      double fpp = -S * g * g * d2P, den = 1 + 0.5 * dx * fpp / fp;
      if (den >= 0.5 && den <= 2) dx /= den;
    }
    double xn = x + dx;
    if (!(xn > lo && xn < hi)) {
      if (!bound) {
        /* the analytic bracket [0, A dt P(a)] */
        (*iters)++;
        double dPa, d2Pa;
        bound = S * law_pressure(L, a, &dPa, &d2Pa);
        if (!(bound > 0)) return 0;
        if (bound < hi) hi = bound;
      }
      if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);
    }
    /* no representable progress left: the best point found */
    if (!(fabs(xn - x) > 2 * DBL_EPSILON * x) ||
        (hi < INFINITY && !(hi - lo > 4 * DBL_EPSILON * hi)))
      return best;
    x = xn;
    (*iters)++;
    f = x - S * law_pressure(L, a + g * x, &dP, &d2P);
    if (fabs(f) <= tol * (bound > x ? bound : x)) return x;
    if (fabs(f) < fbest) {
      fbest = fabs(f);
      best = x;
    }
    if (f > 0) hi = x;
    else lo = x;
    fp = 1 - S * dP * g;
  }
  return best;
}

/* A start for the normal impulse (not a solve: the coupled Newton or the
 * loop checks what follows): the n = 1 piece the solution lies on, or one
 * Newton step from 0. */
static double normal_start(Law *L, double a, double g, int *iters)
{
  double dP, d2P, x;
  (*iters)++;
  double bound = L->S * law_pressure(L, a, &dP, &d2P);
  if (!(bound > 0)) return 0;
  if (!(g > 0)) return bound;
  if (L->linear && normal_direct(L, a, g, a, &x)) return x;
  return bound / (1 - L->S * dP * g);
}

/* 2x2 helpers on the tangential block */
static void inv2(const double A[4], double R[4])
{
  double id = 1 / (A[0] * A[3] - A[1] * A[2]);
  R[0] = A[3] * id;
  R[1] = -A[1] * id;
  R[2] = -A[2] * id;
  R[3] = A[0] * id;
}

static void mul2(const double A[4], const double x[2], double y[2])
{
  double y0 = A[0] * x[0] + A[1] * x[1];
  y[1] = A[2] * x[0] + A[3] * x[1];
  y[0] = y0;
}

/* the tangential block of one contact (ssTBlock, solver.h) */
typedef ssTBlock TBlock;

static void tblock_init(TBlock *B, const double G[9])
{
  B->G[0] = G[4];
  B->G[1] = G[5];
  B->G[2] = G[7];
  B->G[3] = G[8];
  B->adj[0] = G[8];
  B->adj[1] = -G[5];
  B->adj[2] = -G[7];
  B->adj[3] = G[4];
  B->det = G[4] * G[8] - G[5] * G[7];
  B->e[0] = G[3];
  B->e[1] = G[6];
  B->inert = !(fabs(G[4]) + fabs(G[8]) > 0);
  double off = 0.5 * (G[5] + G[7]);
  B->pd = G[4] > 0 && G[4] * G[8] - off * off > 0;
}

/* the stick test |G_tt^-1 c| <= T, as |adj c| <= T |det| */
static inline int stick_fits(const TBlock *B, const double ct[2], double T)
{
  double u[2], Td = T * B->det;
  mul2(B->adj, ct, u);
  return B->det != 0 && u[0] * u[0] + u[1] * u[1] <= Td * Td;
}

/* Janosi mobilisation m = 1 - exp(-x), x = (j + dt sigma)/K, and e = 1 - m,
 * so that the bound is T = tf m, T' = tf e r, T'' = -tf e r^2 (r = dt/K).
 * m is carried directly (no 1 - exp cancellation at small x) and moved from
 * the last point by 1 - exp(-d) = d Q(d) (ss_exp_neg_q): m' = m + e d Q.
 * iK = 1/K (ss_soil_janosi_inverse); 0: a constant bound (K = 0, or a
 * rigid Coulomb contact), r = 0. */
typedef ssMobil Mobil;

static void mobil_init(Mobil *J, double j, double iK, double dt)
{
  J->r = dt * iK;
  J->x0 = (j > 0 ? j : 0) * iK;
  J->m0 = J->r > 0 ? (J->x0 > 0 ? -1 : 0) : 1;
  J->last = ss_exp_memo_start(J->x0);
}

/* m at zero slip, for the stick test (m(sigma) >= m0 bounds it for free) */
static double mobil_m0(Mobil *J)
{
  if (J->m0 < 0) J->m0 = -expm1(-J->x0);
  return J->m0;
}

static inline double mobil_at(Mobil *J, double sigma, double *e)
{
  if (!(J->r > 0)) {
    *e = 0;
    return 1;
  }
  J->last = ss_exp_memo_move(J->last, J->x0 + J->r * sigma);
  *e = J->last.e;
  return J->last.m;
}

/* The bound T = tf m(sigma), with m and e as mobil_at gives them (the
 * memo moved to sigma).  T is formed from the last point's m and e as
 * tf m + (tf e d) Q(d), and d as (x0 - x_last) + r sigma: both sums'
 * other terms are ready before sigma, so T waits on sigma for eight
 * operations where tf times mobil_at's m waits for twelve (one
 * evaluation of the coupled Newton takes two of these). */
static inline double mobil_bound(Mobil *J, double tf, double sigma, double *m, double *e)
{
  if (!(J->r > 0)) {
    *m = 1;
    *e = 0;
    return tf;
  }
  ssExpMemo c = J->last;
  double rs = J->r * sigma, x = J->x0 + rs;
  double T = ss_exp_memo_step(&c, x, (J->x0 - c.x) + rs, tf);
  J->last = c;
  *m = c.m;
  *e = c.e;
  return T;
}

/* One evaluation of the slip equation at speed sigma: w = M^-1 c_t,
 * q = 1/|w| and its derivatives (M w = c: M' w + M w' = 0, and
 * M'' w + 2 M' w' + M w'' = 0, with M' = I + T' G, M'' = T'' G). */
typedef struct Slip {
  double sigma, m, T, dT, d2T;
  double Mi[4];
  double w[2], dw[2], Gw[2];
  double wn, q, dq;
  int ok;
} Slip;

static inline void slip_eval(const TBlock *B, Mobil *J, double tf, const double ct[2],
                      double sigma, Slip *z)
{
  const double *G = B->G;
  double e, m = mobil_at(J, sigma, &e);
  z->sigma = sigma;
  z->m = m;
  z->T = tf * m;
  z->dT = tf * e * J->r;
  z->d2T = -z->dT * J->r;
  double T = z->T;
  double M[4] = {sigma + T * G[0], T * G[1], T * G[2], sigma + T * G[3]};
  double det = M[0] * M[3] - M[1] * M[2];
  z->ok = det > 0;
  if (!z->ok) {
    /* not positive: treat as |w| = inf (sigma too small) */
    z->wn = INFINITY;
    z->q = 0;
    z->dq = 0;
    z->w[0] = z->w[1] = 0;
    return;
  }
  /* w = adj(M) c / det: |adj(M) c| and its root do not wait for the
   * division, and q = det / |adj(M) c| takes one more */
  double wa0 = M[3] * ct[0] - M[1] * ct[1], wa1 = M[0] * ct[1] - M[2] * ct[0];
  double ra = sqrt(wa0 * wa0 + wa1 * wa1), id = 1 / det;
  z->q = det / ra;
  z->wn = ra * id;
  z->w[0] = wa0 * id;
  z->w[1] = wa1 * id;
  z->Mi[0] = M[3] * id;
  z->Mi[1] = -M[1] * id;
  z->Mi[2] = -M[2] * id;
  z->Mi[3] = M[0] * id;
}

/* the slope of the evaluation z (only needed when it did not converge) */
static inline void slip_slope(const TBlock *B, Slip *z)
{
  double a[2];
  mul2(B->G, z->w, z->Gw);
  a[0] = z->w[0] + z->dT * z->Gw[0];
  a[1] = z->w[1] + z->dT * z->Gw[1];
  mul2(z->Mi, a, z->dw);
  z->dw[0] = -z->dw[0];
  z->dw[1] = -z->dw[1];
  /* q' = -(w.w') / |w|^3 */
  z->dq = -(z->w[0] * z->dw[0] + z->w[1] * z->dw[1]) * z->q * z->q * z->q;
}

/* q'' for Halley: -(w'.w' + w.w'') / |w|^3 + 3 (w.w')^2 / |w|^5 */
static double slip_curvature(const TBlock *B, const Slip *z)
{
  double Gdw[2], b[2], d2w[2];
  mul2(B->G, z->dw, Gdw);
  b[0] = z->d2T * z->Gw[0] + 2 * (z->dw[0] + z->dT * Gdw[0]);
  b[1] = z->d2T * z->Gw[1] + 2 * (z->dw[1] + z->dT * Gdw[1]);
  mul2(z->Mi, b, d2w);
  double q3 = z->q * z->q * z->q;
  double wdw = z->w[0] * z->dw[0] + z->w[1] * z->dw[1];
  double dwdw = z->dw[0] * z->dw[0] + z->dw[1] * z->dw[1];
  double wd2w = -(z->w[0] * d2w[0] + z->w[1] * d2w[1]);
  return -(dwdw + wd2w) * q3 + 3 * wdw * wdw * q3 * z->q * z->q;
}

/* Tangential impulse of one contact for a fixed normal impulse (strategy
 * above): bound T = tf m(sigma); tl = dT/dlambda_n / m.  *sigma: in, a guess
 * (<= 0: none); out, the slip speed (0 when sticking).  dl and *dsig:
 * d lambda_t / d lambda_n and d sigma / d lambda_n at the answer (for the
 * coupling and the next guess). */
static void solve_tangent(const TBlock *B, Mobil *J, double tf, double tl,
                          const double ct[2], double tol, double *sigma,
                          double *dsig, double lt[2], double dl[2], int *iters)
{
  double speed = sqrt(ct[0] * ct[0] + ct[1] * ct[1]), e;
  lt[0] = lt[1] = 0;
  dl[0] = dl[1] = 0;
  *dsig = 0;
  if (B->inert) {
    /* no response (static body): the slip is what it is */
    if (speed == 0) return;
    double m = mobil_at(J, speed, &e), T = tf * m;
    lt[0] = -T * ct[0] / speed;
    lt[1] = -T * ct[1] / speed;
    dl[0] = -tl * m * ct[0] / speed;
    dl[1] = -tl * m * ct[1] / speed;
    *sigma = speed;
    return;
  }
  /* stick: lambda_t = -G^-1 c_t, inside the bound at zero slip */
  if (stick_fits(B, ct, tf * mobil_m0(J))) {
    double Gi[4];
    inv2(B->G, Gi);
    mul2(Gi, ct, lt);
    mul2(Gi, B->e, dl);
    lt[0] = -lt[0];
    lt[1] = -lt[1];
    dl[0] = -dl[0];
    dl[1] = -dl[1];
    if (!(isfinite(dl[0]) && isfinite(dl[1]))) dl[0] = dl[1] = 0;
    *sigma = 0;
    return;
  }
  double lo = 0, hi = speed, x = *sigma;
  if (!(x > lo && x < hi)) x = hi;
  Slip z;
  for (int it = 0; it < 100; it++) {
    (*iters)++;
    slip_eval(B, J, tf, ct, x, &z);
    if (z.ok) slip_slope(B, &z);
    if (fabs(z.wn - 1) <= tol) break;
    double r = z.q - 1;
    if (r > 0) hi = x;
    else lo = x;
    double xn;
    if (!(z.ok && z.dq > 0)) {
      xn = 0.5 * (lo + hi);
    } else {
      double dx = -r / z.dq;
      if (fabs(dx) > 1e-5 * speed) {
        double den = 1 + 0.5 * dx * slip_curvature(B, &z) / z.dq;
        if (den >= 0.5 && den <= 2) dx /= den;
      }
      xn = x + dx;
      if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);
    }
    if (!(hi - lo > 4 * DBL_EPSILON * hi)) break;
    x = xn;
  }
  *sigma = z.sigma;
  if (!z.ok) return;
  lt[0] = -z.T * z.w[0];
  lt[1] = -z.T * z.w[1];
  /* implicit derivative in lambda_n: c_t' = G_tn, T_n = tl m; |w| = 1 fixes
   * sigma' = -(w.w_n)/(w.w_sigma) */
  double Tn = tl * z.m, rhs[2], wn_[2];
  rhs[0] = B->e[0] - Tn * z.Gw[0];
  rhs[1] = B->e[1] - Tn * z.Gw[1];
  mul2(z.Mi, rhs, wn_);
  double ws = z.w[0] * z.dw[0] + z.w[1] * z.dw[1];
  double sn = ws != 0 ? -(z.w[0] * wn_[0] + z.w[1] * wn_[1]) / ws : 0;
  double dw0 = wn_[0] + z.dw[0] * sn, dw1 = wn_[1] + z.dw[1] * sn;
  double dT = Tn + z.dT * sn;
  *dsig = isfinite(sn) ? sn : 0;
  dl[0] = -dT * z.w[0] - z.T * dw0;
  dl[1] = -dT * z.w[1] - z.T * dw1;
  if (!(isfinite(dl[0]) && isfinite(dl[1]))) dl[0] = dl[1] = 0;
}

/* Coupled Newton on (lambda_n, sigma) for a slipping point, from a close
 * start: both equations, F1 = lambda_n - A dt P(v_n) with v_n including
 * the shear impulse -T w, and F2 = 1/|w| - 1, with their full 2x2
 * Jacobian.  Returns 1 with the impulse in lam once both residuals pass at
 * the same point (and the point does not stick there; lam is written only
 * then, so it may be the contact's own); 0 leaves the point
 * to the safeguarded loop, e.g. when an iterate leaves lambda_n > 0,
 * 0 < sigma <= |c_t|.  ct0, ct1 and tf: c_t = v0_t + G_tn x and the bound's
 * tf0 + mu x at the start x, which the caller has formed (the same
 * expressions; each step forms them for the next).  sure = 0: the start
 * is not known to slip; the first evaluation tests that on its bound
 * first (0 if it may stick).  linear: L->linear, a constant, so that each
 * law has a loop of its own without the other's branches and registers. */
static inline __attribute__((always_inline)) int
coupled_slip(Law *L, const TBlock *B, Mobil *J, double tf0, double mu, const double v0[3],
             const double G[9], double tol, double x, double sigma, double ct0, double ct1,
             double tf, int sure, double lam[3], int *iters, const int linear)
{
  /* slip_eval's quantities written out on scalars (this loop is most of
   * a warm coupled visit, and the Slip record would live in memory), and
   * no division on the chain from one iterate to the next: the residual
   * tests are made multiplied through by det > 0 (for n = 1 the normal
   * residual too, from v_n det), and the Newton step from the Jacobian
   * with its rows scaled (below).  1/det is formed beside them, for the
   * impulse alone.  ||w| - 1| <= tol is tested squared, as
   * (1 - tol)^2 det^2 <= ra^2 <= (1 + tol)^2 det^2 with ra = |adj(M) c_t|
   * (the same test: both sides are positive), so that the check waits
   * on no square root; ra itself is taken only for a step. */
  const double S = L->S, *Gt = B->G, e0 = B->e[0], e1 = B->e[1];
  const double lo2 = (1 - tol) * (1 - tol), hi2 = (1 + tol) * (1 + tol);
  for (int it = 0; it < 6; it++) {
    double e = 0, m = 0, T = 0;
    int out = !(sigma > 0) || sigma * sigma > ct0 * ct0 + ct1 * ct1;
    if (!out || !sure) T = mobil_bound(J, tf, sigma, &m, &e);
    if (!sure) {
      /* the start's cheap stick test (ss_point_soil), on this first
       * evaluation's bound (not an iteration of its own): within it, the
       * point may stick */
      double ct[2] = {ct0, ct1};
      if (stick_fits(B, ct, T)) return 0;
      sure = 1;
    }
    (*iters)++;
    if (out) return 0;
    double dT = tf * e * J->r;
    double M0 = sigma + T * Gt[0], M1 = T * Gt[1], M2 = T * Gt[2], M3 = sigma + T * Gt[3];
    double det = M0 * M3 - M1 * M2;
    if (!(det > 0)) return 0;
    double wa0 = M3 * ct0 - M1 * ct1, wa1 = M0 * ct1 - M2 * ct0;
    double ra2 = wa0 * wa0 + wa1 * wa1, id = 1 / det, dd = det * det;
    double w0 = wa0 * id, w1 = wa1 * id;
    double lt0 = -T * w0, lt1 = -T * w1;
    double dP, d2P, F1d;
    if (linear) {
      /* v_n det and the residual times det, without the division */
      double vnd = (v0[0] + G[0] * x) * det - T * (G[1] * wa0 + G[2] * wa1);
      F1d = x * det - S * law_pressure_as(L, vnd, det, &dP, &d2P, linear);
    } else {
      /* v_n with 1/det applied last: the shear's share G_nt . wa is
       * formed while the division runs */
      double vn = (v0[0] + G[0] * x) - T * (G[1] * wa0 + G[2] * wa1) * id;
      F1d = (x - S * law_pressure_as(L, vn, 1, &dP, &d2P, linear)) * det;
    }
    if (fabs(F1d) <= tol * x * det && ra2 >= lo2 * dd && ra2 <= hi2 * dd) {
      /* a slip solution excludes sticking where G_tt is positive
       * definite: c_t = M w = sigma w + T G_tt w with |w| = 1 gives
       * |G_tt^-1 c_t| >= w . G_tt^-1 c_t = sigma w . G_tt^-1 w + T > T
       * (with |w| = 1 to the tolerance, to within tol T: a stick answer
       * there would be the same impulse to that tolerance).  Otherwise
       * tested, with m(sigma) >= m0 deciding most cases without m0 */
      double ct[2] = {ct0, ct1};
      if (!B->pd && stick_fits(B, ct, T) && stick_fits(B, ct, tf * mobil_m0(J))) return 0;
      lam[0] = x;
      lam[1] = lt0;
      lam[2] = lt1;
      return 1;
    }
    /* The 2x2 Newton step, with the first row (F1 and its slopes) scaled
     * by det^2 and the second (F2 = det/ra - 1) by ra^3: the same step in
     * exact arithmetic, where each entry is a polynomial in M, wa and
     * c_t.  With w = wa/det, M w' = -(w + T' G w) (slip_slope) gives
     * w' = -adj(M) aa / det^2, aa = wa + T' G wa; the derivative of w in
     * lambda_n (solve_tangent), d(c_t)/d lambda_n = G_tn = e, gives
     * adj(M) rr / det^2, rr = det e - T_n G wa.  So F2's slopes times ra^3
     * are wa . adj(M) aa and -wa . adj(M) rr; F1's take the slopes of the
     * shear impulse -T w times det^2: -ltx in lambda_n, lts in sigma.
     * Both factors are positive, so the determinant's sign test stands. */
    double Gwa0 = Gt[0] * wa0 + Gt[1] * wa1, Gwa1 = Gt[2] * wa0 + Gt[3] * wa1;
    double aa0 = wa0 + dT * Gwa0, aa1 = wa1 + dT * Gwa1;
    double ba0 = M3 * aa0 - M1 * aa1, ba1 = M0 * aa1 - M2 * aa0;
    double Tx = mu * m;
    double rr0 = det * e0 - Tx * Gwa0, rr1 = det * e1 - Tx * Gwa1;
    double bx0 = M3 * rr0 - M1 * rr1, bx1 = M0 * rr1 - M2 * rr0;
    double Txd = Tx * det, dTd = dT * det, SdP = S * dP;
    double ltx0 = Txd * wa0 + T * bx0, ltx1 = Txd * wa1 + T * bx1;
    double lts0 = T * ba0 - dTd * wa0, lts1 = T * ba1 - dTd * wa1;
    double J11 = dd - SdP * (G[0] * dd - (G[1] * ltx0 + G[2] * ltx1));
    double J12 = -SdP * (G[1] * lts0 + G[2] * lts1);
    double J21 = -(wa0 * bx0 + wa1 * bx1);
    double J22 = wa0 * ba0 + wa1 * ba1;
    double ra = sqrt(ra2), F1s = F1d * det, F2s = (det - ra) * ra2;
    double jdet = J11 * J22 - J12 * J21;
    if (!(jdet > 0)) return 0;
    x -= (J22 * F1s - J12 * F2s) / jdet;
    sigma -= (J11 * F2s - J21 * F1s) / jdet;
    if (!(x > 0)) return 0;
    /* the next evaluation's c_t and tf, at the new x */
    ct0 = v0[1] + e0 * x;
    ct1 = v0[2] + e1 * x;
    tf = tf0 + mu * x;
  }
  return 0;
}

/* The safeguarded loop of one point's solve (strategy above), from the
 * impulse c->lambda or, cold, from none; iters evaluations made so far.
 * A function of its own that reads its start from the contact: the arrays
 * that solve_tangent writes are then this loop's alone, and the coupled
 * fast path before it keeps no copy of the impulse, so it spills less
 * (out of line, a warm nonlinear visit took more instructions). */
static int soil_loop(ssContact *c, const double v0[3], double tol, int cold, int coupled,
                     int iters)
{
  const double *G = c->G;
  Law *L = &c->cache.law;
  Mobil *J = &c->cache.mob;
  const TBlock *B = &c->cache.tb;
  double tf0 = c->cache.tf0, mu = c->cache.mu;
  double ln = 0, lt[2] = {0, 0}, dl[2] = {0, 0}, sigma = 0, dsig = 0;
  int at_guess, have_lt = 0;
  if (!cold) {
    ln = c->lambda[0];
    lt[0] = c->lambda[1];
    lt[1] = c->lambda[2];
  }
  if (ln > 0 && coupled) {
    /* warm: the shear at the previous normal impulse, from the slip speed
     * the previous shear impulse gives now */
    double ct[2] = {v0[1] + G[3] * ln, v0[2] + G[6] * ln};
    double vt0 = ct[0] + B->G[0] * lt[0] + B->G[1] * lt[1];
    double vt1 = ct[1] + B->G[2] * lt[0] + B->G[3] * lt[1];
    sigma = sqrt(vt0 * vt0 + vt1 * vt1);
    solve_tangent(B, J, tf0 + mu * ln, mu, ct, tol, &sigma, &dsig, lt, dl, &iters);
    have_lt = 1;
  }
  for (int outer = 0; outer < 50; outer++) {
    /* lambda_t linearised about ln; plain fixed point if that is not a
     * positive compliance, or after many rounds */
    double geff = G[0] + G[1] * dl[0] + G[2] * dl[1];
    if (!(geff > 0) || outer >= 20) {
      dl[0] = dl[1] = 0;
      geff = G[0];
    }
    double a = v0[0] + G[1] * (lt[0] - dl[0] * ln) + G[2] * (lt[1] - dl[1] * ln);
    double ln_new = solve_normal(L, a, geff, ln, tol, &iters, &at_guess);
    if (have_lt && (at_guess || ln_new == ln)) break;
    double prev[3] = {ln, lt[0], lt[1]};
    ln = ln_new;
    double ct[2] = {v0[1] + G[3] * ln, v0[2] + G[6] * ln};
    if (ln > 0) {
      /* the slip speed moves with lambda_n at the rate the last solve found */
      sigma += dsig * (ln - prev[0]);
      solve_tangent(B, J, tf0 + mu * ln, mu, ct, tol, &sigma, &dsig, lt, dl, &iters);
    } else {
      lt[0] = lt[1] = dl[0] = dl[1] = 0;
    }
    have_lt = 1;
    if (!coupled) break;
    if (outer >= 20) {
      /* last resort of a slow fixed point: the step-size test */
      double change = fabs(ln - prev[0]) + fabs(lt[0] - prev[1]) + fabs(lt[1] - prev[2]);
      double size = fabs(ln) + fabs(lt[0]) + fabs(lt[1]);
      if (change <= 1e3 * tol * size || size == 0) break;
    }
  }
  c->lambda[0] = ln;
  c->lambda[1] = lt[0];
  c->lambda[2] = lt[1];
  return iters;
}

/* one point's solve (strategy above) with its state set up (point_setup) */
int ss_point_soil(ssContact *c, const double v0[3], double tol)
{
  const double *G = c->G;
  Law *L = &c->cache.law;
  Mobil *J = &c->cache.mob;
  const TBlock *B = &c->cache.tb;
  /* the shear bound is tf m(sigma), tf = A dt (c + mu p_n) = A dt c + mu lambda_n */
  double tf0 = c->cache.tf0, mu = c->cache.mu;

  int iters = 0, cold = 0, coupled = G[1] != 0 || G[2] != 0;
  double ln = c->lambda[0], lt[2] = {c->lambda[1], c->lambda[2]};
  /* a point without impulse that does not reach the soil at v0 keeps none:
   * lambda = 0 meets both laws (no sinkage, no pressure; no normal
   * impulse, no shear) -- what the general path below returns, at the
   * cost of one test (the points of a patch's margin, most visits of
   * which are these).  Made only where ln > 0 fails, so that a loaded
   * point passes over it in one branch (GCC would otherwise form the
   * three comparisons and combine them before branching). */
  if (!(ln > 0)) {
    if (ln == 0 && lt[0] == 0 && lt[1] == 0 && !(-(L->g0 + L->dt * v0[0]) > 0)) return 1;
  }
  if (coupled && !B->inert) {
    /* cold: a start for the normal impulse with the shear held */
    if (!(ln > 0)) ln = normal_start(L, v0[0] + G[1] * lt[0] + G[2] * lt[1], G[0], &iters);
    /* c_t as coupled_slip forms it (G_tn from B), which starts from it */
    double ct[2] = {v0[1] + B->e[0] * ln, v0[2] + B->e[1] * ln};
    double vt0 = ct[0] + B->G[0] * lt[0] + B->G[1] * lt[1];
    double vt1 = ct[1] + B->G[2] * lt[0] + B->G[3] * lt[1];
    double sig0 = sqrt(vt0 * vt0 + vt1 * vt1), tf = tf0 + mu * ln, e;
    /* cheap stick test first: beyond the bound at the guessed slip speed
     * (>= the bound at zero slip) it surely slips: the coupled Newton.
     * Warm, its first evaluation is at sig0 and makes the test itself on
     * the bound it forms there (sure = 0) */
    if (ln > 0 && sig0 > 0) {
      int sure = 0;
      if (!(lt[0] != 0 || lt[1] != 0)) {
        /* no shear to go by: sigma + T(sigma) gamma = |c_t| for an
         * isotropic block of the block's compliance gamma along c_t */
        double Gc[2], Ts = tf * mobil_at(J, sig0, &e);
        mul2(B->G, ct, Gc);
        double s1 = sig0 - Ts * (ct[0] * Gc[0] + ct[1] * Gc[1]) / (sig0 * sig0);
        if (s1 > 0.5 * sig0) sig0 = s1;
        sure = !stick_fits(B, ct, Ts);
        if (!sure) sig0 = 0; /* it may stick: not the coupled Newton */
      }
      if (sig0 > 0 &&
          (L->linear ? coupled_slip(L, B, J, tf0, mu, v0, G, tol, ln, sig0, ct[0], ct[1], tf, sure,
                                    c->lambda, &iters, 1)
                     : coupled_slip(L, B, J, tf0, mu, v0, G, tol, ln, sig0, ct[0], ct[1], tf, sure,
                                    c->lambda, &iters, 0))) {
        return iters;
      }
    }
    /* the general loop starts cold where the fast path found no start */
    cold = !(c->lambda[0] > 0);
  }
  return soil_loop(c, v0, tol, cold, coupled, iters);
}

/* The point's law from the contact and its material (ssPointCache): the
 * constants always, the reused power and mobilisation kept while what they
 * were made from is unchanged. */
void ss_point_setup(const ssSoilMaterial *mat, const ssPowTable *tab, double dt,
                    ssContact *c)
{
  ssPointCache *k = &c->cache;
  /* written field by field in place: a compound literal of the law (184
   * bytes) is zeroed by `rep stos` first, dear at once per point and
   * step (see ss_contact_new) */
  Law *L = &k->law;
  double m1 = mat->sinkage_exponent - 1;
  int keep_pw = c->cache_ready && L->pw.s > 0 && L->m1 == m1;
  L->S = c->area * dt;
  L->dt = dt;
  L->g0 = c->g0;
  L->sp = c->sp;
  L->k = ss_soil_modulus(mat, c->width);
  L->n = mat->sinkage_exponent;
  L->m1 = m1;
  L->Ke = mat->elastic_stiffness;
  L->D = mat->damping;
  L->linear = mat->sinkage_exponent == 1.0;
  if (!L->linear) {
    L->pser = ss_pow_series(m1);
    L->pser.tab = tab;
  } else {
    L->pser = (ssPowSeries){0, {0}, 0, NULL};
  }
  if (!keep_pw) L->pw = (ssPowMemo){0, 0, 0};
  Mobil J;
  mobil_init(&J, c->j, ss_soil_janosi_inverse(mat), dt);
  if (!(c->cache_ready && k->mob.x0 == J.x0 && k->mob.r == J.r)) k->mob = J;
  c->cache_ready = 1;
  tblock_init(&k->tb, c->G);
  k->tf0 = L->S * mat->cohesion;
  k->mu = mat->friction_coefficient;
}

int ss_solver_soil_point(const ssSoilMaterial *mat, double dt, ssContact *c,
                         const double v0[3], double tol)
{
  ss_point_setup(mat, NULL, dt, c);
  return ss_point_soil(c, v0, tol);
}

/* ---------------------------------------------------------------------- */
/* the rigid point: Coulomb cone with a normal velocity target            */

void ss_point_rigid(ssContact *c, const double v0[3], double tol)
{
  const double *G = c->G;
  if (!(G[0] > 0)) return;
  TBlock B;
  tblock_init(&B, G);
  Mobil J;
  mobil_init(&J, 0, 0, 0);
  double ln = c->lambda[0], lt[2] = {c->lambda[1], c->lambda[2]}, dl[2];
  double sigma = 0, dsig;
  int iters = 0, coupled = G[1] != 0 || G[2] != 0;
  for (int it = 0; it < 50; it++) {
    double vn = v0[0] + G[1] * lt[0] + G[2] * lt[1];
    double ln_new = (c->vn_target - vn) / G[0];
    if (ln_new < 0) ln_new = 0;
    double ct[2] = {v0[1] + G[3] * ln_new, v0[2] + G[6] * ln_new};
    double lt_new[2] = {0, 0};
    if (ln_new > 0) solve_tangent(&B, &J, c->mu * ln_new, c->mu, ct, tol, &sigma, &dsig, lt_new, dl, &iters);
    double change = fabs(ln_new - ln) + fabs(lt_new[0] - lt[0]) + fabs(lt_new[1] - lt[1]);
    double size = fabs(ln_new) + fabs(lt_new[0]) + fabs(lt_new[1]);
    ln = ln_new;
    lt[0] = lt_new[0];
    lt[1] = lt_new[1];
    if (!coupled || change <= 1e3 * tol * size || size == 0) break;
  }
  c->lambda[0] = ln;
  c->lambda[1] = lt[0];
  c->lambda[2] = lt[1];
}
