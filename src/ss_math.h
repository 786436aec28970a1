/* ss_math.h -- small inline vector, quaternion and 3x3 matrix algebra.
 * Matrices are row-major double[9]; quaternions w, x, y, z. */
#ifndef SS_MATH_H
#define SS_MATH_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* max and min of two numbers that are not NaN: plain comparisons, where
 * fmax and fmin (which must pass over a NaN) are calls into libm */
static inline double ss_max(double a, double b) { return a > b ? a : b; }
static inline double ss_min(double a, double b) { return a < b ? a : b; }

/* 1 when q is a unit quaternion to 1e-6 in its squared length: a bed's
 * orientation as a checkpoint holds it and a step accepts it */
static inline int ss_quat_is_unit(const double q[4])
{
  return fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1) <= 1e-6;
}

/* 1 when each of v[0..n) is finite and at most vmax in magnitude */
static inline int ss_all_within(const double *v, int n, double vmax)
{
  for (int i = 0; i < n; i++)
    if (!(fabs(v[i]) <= vmax)) return 0;
  return 1;
}

/* y[0..m) += a x[0..m) for rows that do not overlap, two lanes at a time
 * (GCC's vector extension: SSE2 on x86-64, plain pairs elsewhere), the
 * same products and sums, element by element, as the scalar loop (no
 * reassociation: the results are bit for bit).  The compiler leaves the
 * short row loops of the articulated solves scalar otherwise.  y -= a x
 * is the same call with -a: y + (-a) x and y - a x round alike. */
typedef double ssV2 __attribute__((vector_size(16)));
static inline void ss_row_add_scaled(double *y, double a, const double *x, int m)
{
  ssV2 av = {a, a};
  int r = 0;
  for (; r + 2 <= m; r += 2) {
    ssV2 xv, yv;
    memcpy(&xv, x + r, sizeof xv);
    memcpy(&yv, y + r, sizeof yv);
    yv += av * xv;
    memcpy(y + r, &yv, sizeof yv);
  }
  for (; r < m; r++) y[r] += a * x[r];
}

/* y0 += a0 x and y1 += a1 x, likewise, in one pass over x */
static inline void ss_row2_add_scaled(double *y0, double a0, double *y1, double a1,
                                      const double *x, int m)
{
  ssV2 av0 = {a0, a0}, av1 = {a1, a1};
  int r = 0;
  for (; r + 2 <= m; r += 2) {
    ssV2 xv, yv0, yv1;
    memcpy(&xv, x + r, sizeof xv);
    memcpy(&yv0, y0 + r, sizeof yv0);
    memcpy(&yv1, y1 + r, sizeof yv1);
    yv0 += av0 * xv;
    yv1 += av1 * xv;
    memcpy(y0 + r, &yv0, sizeof yv0);
    memcpy(y1 + r, &yv1, sizeof yv1);
  }
  for (; r < m; r++) {
    y0[r] += a0 * x[r];
    y1[r] += a1 * x[r];
  }
}

/* y[0..m) /= a, likewise */
static inline void ss_row_div(double *y, double a, int m)
{
  ssV2 av = {a, a};
  int r = 0;
  for (; r + 2 <= m; r += 2) {
    ssV2 yv;
    memcpy(&yv, y + r, sizeof yv);
    yv /= av;
    memcpy(y + r, &yv, sizeof yv);
  }
  for (; r < m; r++) y[r] /= a;
}

static inline void ss_v3_set(double r[3], double x, double y, double z) { r[0] = x; r[1] = y; r[2] = z; }
static inline void ss_v3_copy(double r[3], const double a[3]) { r[0] = a[0]; r[1] = a[1]; r[2] = a[2]; }
static inline void ss_v3_add(double r[3], const double a[3], const double b[3]) { r[0] = a[0] + b[0]; r[1] = a[1] + b[1]; r[2] = a[2] + b[2]; }
static inline void ss_v3_sub(double r[3], const double a[3], const double b[3]) { r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2]; }
static inline void ss_v3_scale(double r[3], const double a[3], double s) { r[0] = a[0] * s; r[1] = a[1] * s; r[2] = a[2] * s; }
/* r += a * s */
static inline void ss_v3_addscl(double r[3], const double a[3], double s) { r[0] += a[0] * s; r[1] += a[1] * s; r[2] += a[2] * s; }
static inline double ss_v3_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline double ss_v3_norm(const double a[3]) { return sqrt(ss_v3_dot(a, a)); }
static inline void ss_v3_cross(double r[3], const double a[3], const double b[3])
{
  double t0 = a[1] * b[2] - a[2] * b[1];
  double t1 = a[2] * b[0] - a[0] * b[2];
  double t2 = a[0] * b[1] - a[1] * b[0];
  r[0] = t0; r[1] = t1; r[2] = t2;
}
static inline double ss_v3_normalize(double a[3])
{
  double n = ss_v3_norm(a);
  if (n > 0) { a[0] /= n; a[1] /= n; a[2] /= n; }
  return n;
}

/* r = M a */
static inline void ss_m3_mulv(double r[3], const double M[9], const double a[3])
{
  double t0 = M[0] * a[0] + M[1] * a[1] + M[2] * a[2];
  double t1 = M[3] * a[0] + M[4] * a[1] + M[5] * a[2];
  double t2 = M[6] * a[0] + M[7] * a[1] + M[8] * a[2];
  r[0] = t0; r[1] = t1; r[2] = t2;
}
/* r = M^T a */
static inline void ss_m3_mulvT(double r[3], const double M[9], const double a[3])
{
  double t0 = M[0] * a[0] + M[3] * a[1] + M[6] * a[2];
  double t1 = M[1] * a[0] + M[4] * a[1] + M[7] * a[2];
  double t2 = M[2] * a[0] + M[5] * a[1] + M[8] * a[2];
  r[0] = t0; r[1] = t1; r[2] = t2;
}
/* R = A B */
static inline void ss_m3_mul(double R[9], const double A[9], const double B[9])
{
  double t[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      t[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
  memcpy(R, t, sizeof t);
}
static inline void ss_m3_transpose(double R[9], const double A[9])
{
  double t[9] = {A[0], A[3], A[6], A[1], A[4], A[7], A[2], A[5], A[8]};
  memcpy(R, t, sizeof t);
}
/* Inverse of a general 3x3; returns the determinant (0: singular, R = 0). */
static inline double ss_m3_inv(double R[9], const double A[9])
{
  double c0 = A[4] * A[8] - A[5] * A[7];
  double c1 = A[5] * A[6] - A[3] * A[8];
  double c2 = A[3] * A[7] - A[4] * A[6];
  double det = A[0] * c0 + A[1] * c1 + A[2] * c2;
  if (det == 0) {
    memset(R, 0, 9 * sizeof(double));
    return 0;
  }
  double id = 1.0 / det;
  double t[9] = {
    c0 * id, (A[2] * A[7] - A[1] * A[8]) * id, (A[1] * A[5] - A[2] * A[4]) * id,
    c1 * id, (A[0] * A[8] - A[2] * A[6]) * id, (A[2] * A[3] - A[0] * A[5]) * id,
    c2 * id, (A[1] * A[6] - A[0] * A[7]) * id, (A[0] * A[4] - A[1] * A[3]) * id};
  memcpy(R, t, sizeof t);
  return det;
}

static inline void ss_quat_identity(double q[4]) { q[0] = 1; q[1] = q[2] = q[3] = 0; }
static inline double ss_quat_normalize(double q[4])
{
  double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 1e-150 && n < 1e150)) {
    /* squares that overflow (1e300 1e300 0 0 gave n = inf and zeros) or
     * underflow: the direction from q scaled by its largest entry first */
    double s = fmax(fmax(fabs(q[0]), fabs(q[1])), fmax(fabs(q[2]), fabs(q[3])));
    if (s > 0 && s < INFINITY) {
      double u[4] = {q[0] / s, q[1] / s, q[2] / s, q[3] / s};
      double nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3]);
      if (nu > 0) {
        for (int k = 0; k < 4; k++) q[k] = u[k] / nu;
        return nu * s;
      }
    }
  }
  if (n > 0) { q[0] /= n; q[1] /= n; q[2] /= n; q[3] /= n; }
  else ss_quat_identity(q);
  return n;
}
/* r = a * b (Hamilton product) */
static inline void ss_quat_mul(double r[4], const double a[4], const double b[4])
{
  double t[4] = {
    a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
    a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
    a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
    a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
  memcpy(r, t, sizeof t);
}
/* Row-major rotation matrix of a unit quaternion. */
static inline void ss_quat_to_mat(double R[9], const double q[4])
{
  double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - w * z);     R[2] = 2 * (x * z + w * y);
  R[3] = 2 * (x * y + w * z);     R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - w * x);
  R[6] = 2 * (x * z - w * y);     R[7] = 2 * (y * z + w * x);     R[8] = 1 - 2 * (x * x + y * y);
}
/* Quaternion of a rotation by angle |v| about v (exact exponential map). */
static inline void ss_quat_from_rotvec(double q[4], const double v[3])
{
  double a = ss_v3_norm(v);
  if (a < 1e-12) { q[0] = 1; q[1] = 0.5 * v[0]; q[2] = 0.5 * v[1]; q[3] = 0.5 * v[2]; ss_quat_normalize(q); return; }
  double s = sin(0.5 * a) / a;
  q[0] = cos(0.5 * a); q[1] = v[0] * s; q[2] = v[1] * s; q[3] = v[2] * s;
}
/* Quaternion of a rotation by angle about a unit axis. */
static inline void ss_quat_from_axis_angle(double q[4], const double axis[3], double angle)
{
  double s = sin(0.5 * angle);
  q[0] = cos(0.5 * angle); q[1] = axis[0] * s; q[2] = axis[1] * s; q[3] = axis[2] * s;
}

/* Short series for functions moved a little from a known value (the soil
 * law's s^(n-1) and Janosi exponential between the iterates of one point,
 * src/point.c and src/newton.c): fixed length, no test per term. */

/* (1 + u)^a - 1 for |u| <= SS_POW_SERIES_MAX, |a| <= 3: seven terms; the
 * first one dropped, |C(a, 8)| u^8 <= 45 2^-64, is below 3e-18 of the
 * leading 1, far under rounding.  The binomial coefficients C(a, k) depend
 * on the exponent only and are formed once (ss_pow_series); the powers of
 * u are summed in pairs (Estrin) so that the chain of dependent operations
 * is short. */
#define SS_POW_SERIES_MAX (1.0 / 256)
typedef struct ssPowSeries {
  double a;      /* the exponent */
  double c[7];   /* C(a, 1) .. C(a, 7) */
  int ok;        /* |a| <= 3: the series holds (else always libm) */
  const struct ssPowTable *tab; /* s^a by table where no memo is near
                                   (ss_pow_tab), or NULL: libm */
} ssPowSeries;

static inline ssPowSeries ss_pow_series(double a)
{
  static const double inv[7] = {1, 1.0 / 2, 1.0 / 3, 1.0 / 4, 1.0 / 5, 1.0 / 6, 1.0 / 7};
  ssPowSeries p;
  double t = 1;
  for (int k = 0; k < 7; k++) p.c[k] = t *= (a - k) * inv[k];
  p.a = a;
  p.ok = fabs(a) <= 3;
  p.tab = NULL;
  return p;
}

static inline double ss_pow1p_m1(const ssPowSeries *p, double u)
{
  const double *c = p->c;
  double u2 = u * u, u4 = u2 * u2;
  double q = (c[0] + c[1] * u) + u2 * (c[2] + c[3] * u) + u4 * ((c[4] + c[5] * u) + u2 * c[6]);
  return u * q;
}

/* 1 - exp(-d) = d Q(d) for |d| <= SS_EXP_SERIES_MAX = 2^-10, Q returned:
 * five terms of the series (the first dropped, d^6/6!, is below 1.2e-18
 * of |d|, 1/90 of its last bit), summed by pairs and powers d^2, d^4
 * (Estrin) so that the chain of dependent operations is five long; the
 * caller's product by d (or by a multiple of d it has formed beside) is
 * the sixth */
#define SS_EXP_SERIES_MAX (1.0 / 1024)
static inline double ss_exp_neg_q(double d)
{
  double d2 = d * d, d4 = d2 * d2;
  double q01 = 1 - d * 0.5;
  double q23 = 1.0 / 6 - d * (1.0 / 24);
  return (q01 + d2 * q23) + d4 * (1.0 / 120);
}

/* s^a for one exponent a without libm, for a point's first power of a
 * step (no memo near yet): with s = 2^e m, 1 <= m < 2, and c_k the centre
 * of m's bucket among SS_POWT_N equal ones, s^a = 2^(e a) c_k^a (1 + u)^a,
 * u = (m - c_k)/c_k, |u| <= 1/(2 SS_POWT_N) = SS_POW_SERIES_MAX, so the
 * series above gives the last factor to rounding.  m - c_k is exact
 * (both in [1, 2), c_k a multiple of 2^-8); the two tabled factors were
 * rounded once each (libm's pow, < 1 ulp), and two products round, so the
 * result is within 4 ulp (test_soil; libm's pow: 1), for about 30
 * instructions where libm's pow costs about 120.
 * s outside [2^SS_POWT_EMIN, 2^(SS_POWT_EMAX + 1)) (1e-19 m to 65 km of
 * sinkage), zero, negative or not finite goes to libm. */
#define SS_POWT_N 128
#define SS_POWT_EMIN (-64)
#define SS_POWT_EMAX 15
typedef struct ssPowTable {
  int ok;                 /* formed, and the series holds for a */
  ssPowSeries ser;        /* of the exponent a (ser.tab unused) */
  double e2[SS_POWT_EMAX - SS_POWT_EMIN + 1]; /* 2^(e a) */
  double mc[SS_POWT_N];   /* c_k^a */
  double ic[SS_POWT_N];   /* 1 / c_k */
  double c[SS_POWT_N];    /* c_k itself, so that a look-up does not form it
                           * again (a conversion and two operations) */
} ssPowTable;

static inline void ss_pow_table_init(ssPowTable *t, double a)
{
  t->ser = ss_pow_series(a);
  t->ok = t->ser.ok;
  for (int e = SS_POWT_EMIN; e <= SS_POWT_EMAX; e++)
    t->e2[e - SS_POWT_EMIN] = pow(ldexp(1.0, e), a);
  for (int k = 0; k < SS_POWT_N; k++) {
    double c = 1 + (k + 0.5) / SS_POWT_N;
    t->mc[k] = pow(c, a);
    t->ic[k] = 1 / c;
    t->c[k] = c;
  }
}

static inline double ss_pow_tab(const ssPowTable *t, double s)
{
  uint64_t b;
  memcpy(&b, &s, sizeof b);
  /* the biased exponent; a sign bit makes it too large */
  int e = (int)(b >> 52) - 1023;
  if (!(t->ok && e >= SS_POWT_EMIN && e <= SS_POWT_EMAX)) return pow(s, t->ser.a);
  int k = (int)(b >> 45) & (SS_POWT_N - 1);
  uint64_t mb = (b & 0x000FFFFFFFFFFFFFull) | 0x3FF0000000000000ull;
  double m;
  memcpy(&m, &mb, sizeof m);
  double u = (m - t->c[k]) * t->ic[k], v = t->mc[k];
  return t->e2[e - SS_POWT_EMIN] * (v + v * ss_pow1p_m1(&t->ser, u));
}

/* s^a at the last s (s = 0: none), kept to be moved to a nearby s; is =
 * 1/s, formed when s is stored so that the next move's ratio does not wait
 * for a division */
typedef struct ssPowMemo {
  double s, v, is;
} ssPowMemo;

/* s^a from p's table, or libm's pow where it has none, out of line (for
 * a caller whose loop is small: the sweeps' point law, src/point.c) */
static __attribute__((noinline, unused)) double ss_pow_far(const ssPowSeries *p, double s)
{
  return p->tab ? ss_pow_tab(p->tab, s) : pow(s, p->a);
}

/* s^a as ss_pow_moved forms it, the memo left where it is.  Where the
 * series does not reach, the table inline (near = 0: the Newton phase's
 * laws, where a call made the evaluation's loop keep every live value on
 * the stack around it, all of SSE's registers being the caller's to save,
 * at as much as the table costs) or out of line (near = 1: a small
 * caller, whose code the inline table would crowd; only libm's pow,
 * where there is no table, is a call either way). */
static inline double ss_pow_at(const ssPowMemo *c, double s, const ssPowSeries *p,
                               const int near)
{
  double u = c->s > 0 ? (s - c->s) * c->is : INFINITY;
  if (fabs(u) <= SS_POW_SERIES_MAX && p->ok) return c->v + c->v * ss_pow1p_m1(p, u);
  if (near) return ss_pow_far(p, s);
  if (p->tab) return ss_pow_tab(p->tab, s);
  return pow(s, p->a);
}

/* s^a, moved by the series p (exponent a) from the memo when s is within
 * SS_POW_SERIES_MAX of it, else from p's table (or libm; near: as
 * ss_pow_at); the memo moves to s */
static inline double ss_pow_moved(ssPowMemo *c, double s, const ssPowSeries *p,
                                  const int near)
{
  double v = ss_pow_at(c, s, p, near);
  c->s = s;
  c->v = v;
  c->is = 1 / s;
  return v;
}

/* m = 1 - exp(-x) and e = exp(-x) at the last x (x < 0: none), kept to
 * be moved to a nearby x.  m is carried directly (no 1 - exp cancellation
 * at small x); e only to absolute accuracy, all its uses (a slope, the
 * series' factor) need. */
typedef struct ssExpMemo {
  double x, m, e;
} ssExpMemo;

/* A point's memo before its first x: at x = 0 (m = 0, e = 1) where its
 * x0 (j/K_j, the least x it will be asked for) is within the series'
 * reach of 0, so that its first x comes by the series, not from libm (a
 * settled body's points, x0 about 1e-14); else none (x < 0) */
static inline ssExpMemo ss_exp_memo_start(double x0)
{
  ssExpMemo c = {x0 <= SS_EXP_SERIES_MAX ? 0 : -1, 0, 1};
  return c;
}

/* *c moved to x, with d = x - c->x as the caller formed it: by the series
 * when d is within SS_EXP_SERIES_MAX, else from libm.  Returns s m at x,
 * by the series as s m + (s e d) Q(d) from the last point's m and e, so
 * that it waits on d for the series and two operations (a caller that
 * scales m, and forms d from values ready before x, waits less) */
static inline double ss_exp_memo_step(ssExpMemo *c, double x, double d, double s)
{
  double sm;
  if (c->x >= 0 && fabs(d) <= SS_EXP_SERIES_MAX) {
    double q = ss_exp_neg_q(d), p = d * q; /* 1 - exp(-d) */
    sm = s * c->m + (s * c->e * d) * q;
    c->m += c->e * p;
    c->e -= c->e * p;
  } else {
    c->m = -expm1(-x);
    c->e = 1 - c->m;
    sm = s * c->m;
  }
  c->x = x;
  return sm;
}

/* c moved to x (ss_exp_memo_step); unchanged where x is its own */
static inline ssExpMemo ss_exp_memo_move(ssExpMemo c, double x)
{
  double d = x - c.x;
  if (d != 0) ss_exp_memo_step(&c, x, d, 1);
  return c;
}

#endif /* SS_MATH_H */
