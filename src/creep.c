/* creep.c -- the creeping body solve (solver.h: ss_creep_solve).
 *
 * A free body resting on soil and loaded sideways below its full shear
 * strength creeps: its points slip at 1e-6 m/s and less, most of them at
 * nearly their full Janosi bound, a few near the instantaneous centre of
 * its slip turning round it.  Such a patch is neither stuck whole (the
 * Newton phase's stick solve: its wrench cannot be shared out within the
 * points' bounds) nor slipping everywhere (the velocity form), and the
 * Gauss-Seidel sweeps redistribute its nearly indeterminate impulses by a
 * factor close to 1 a sweep: thousands of sweeps to 1e-9 (drag.xml, step
 * 1159: 11 338).
 *
 * Yet with each point's shear bound held at its normal impulse, the step
 * of one free body is the minimum of a convex function of its velocity u
 * (6: v_com, omega, world):
 *
 *   E(u) = 1/2 (u - u_f)^T M (u - u_f) + sum_i Psi_i(J_i u),
 *
 * M = diag(m I, I_world), J_i the point's rows (n, t1, t2), and Psi_i the
 * potential of its law: -lambda_i = grad Psi_i.  The normal law lambda_n(v_n)
 * is non-increasing in v_n (DESIGN 3.1), and the shear law lambda_t =
 * -T(|v_t|) v_t / |v_t| with T = tf (1 - exp(-(j + dt |v_t|)/K)) non-
 * decreasing is the gradient of Q(|v_t|), Q' = T: convex, with a kink at
 * v_t = 0 where T(0) > 0 (a sum of norms).  grad E = 0 is the step's
 * equation, M (u - u_f) = sum J_i^T lambda_i(J_i u).
 *
 * The kink is smoothed, |v_t| -> s = sqrt(|v_t|^2 + eps^2), and Newton's
 * method with a line search on the directional derivative of E (convex:
 * monotone along the line) is run at decreasing eps (continuation), each
 * level from the last one's answer, down to an eps at which the smoothing
 * moves no sweep's answer by more than a hundredth of the tolerance (a
 * point whose slip is that small has a stop-slip impulse inside its
 * bound: its sweep visit sticks it and moves its impulse by at most
 * eps / G_tt <= eps m).  The shear bound's dependence on lambda_n (tf =
 * A dt c + mu lambda_n, the law is not a gradient there) is kept in the
 * Newton matrix and re-evaluated at every iterate; the line search sees
 * it too.  Each Newton step costs one pass over the points and a 6 x 6
 * solve.
 *
 * It is an accelerator like the Newton phase: it only moves the sweeps'
 * start.  Its answer (impulses and the velocity they give) is applied only
 * where its last level came within CREEP_LINEAR_TOL of balance before the
 * linear step; the sweeps that follow decide convergence with the same
 * measure and tolerance as always. */
#include "solver.h"
#include "point.h"
#include "ss_math.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* eps starts at this fraction of the largest slip speed and falls by
 * CREEP_EPS_STEP a level */
#define CREEP_EPS_START 0.1
#define CREEP_EPS_STEP 1e-2
/* Newton iterations of one level at most (the last level: twice that) */
#define CREEP_ITER 16
/* an intermediate level is done when the force and torque left over are
 * within this fraction of the points' impulses (the next level refines) */
#define CREEP_LEVEL_TOL 1e-6
/* the last level's eps and imbalance: this fraction of the tolerance
 * times the largest impulse (divided by the mass for eps) */
#define CREEP_FINAL 1e-2
/* the last level's answer goes to its linear step (creep_body) when its
 * imbalance is within this fraction of the points' impulses */
#define CREEP_LINEAR_TOL 1e-4
/* line search: accept a step whose directional derivative is at most
 * this fraction of the first one's size (a Wolfe curvature test; convex
 * along the line, so it also decreases E) */
#define CREEP_WOLFE 0.5
#define CREEP_SEARCH 30
/* a level whose imbalance has not halved in this many full Newton steps
 * is done: it is as close as u can hold it (the stiff points' noise,
 * creep_body) */
#define CREEP_STALL 3

/* one point: its rows J (3 x 6, frame n, t1, t2; J = [f, r x f]) and its
 * law as the sweeps set it up (c->cache) */
typedef struct CPoint {
  const ssContact *c;
  const double *J;
} CPoint;

typedef struct CBody {
  int n;               /* points */
  CPoint *p;
  double m, I[9];      /* mass, world inertia */
  double uf[6];        /* free velocity */
  double *lam, *K;     /* (3 n) impulses, (9 n) d lambda / d v at the last
                          evaluation with K */
} CBody;

/* the law of point c at velocity v (contact frame) with the kink smoothed
 * by eps: lam, and with K non-NULL d lam / d v (3 x 3, row-major) */
static void creep_law(const ssContact *c, const double v[3], double eps, double lam[3],
                      double *K)
{
  const ssPointCache *pc = &c->cache;
  const ssLaw *L = &pc->law;
  double delta = -(L->g0 + L->dt * v[0]);
  if (!(delta > 0)) {
    lam[0] = lam[1] = lam[2] = 0;
    if (K) memset(K, 0, 9 * sizeof(double));
    return;
  }
  double s = L->sp + delta, sn1 = L->linear ? 1.0 : pow(s, L->m1);
  double pe = L->Ke * delta, py = L->k * s * sn1, p, slope;
  if (pe <= py) {
    p = pe;
    slope = L->Ke;
  } else {
    p = py;
    slope = L->linear ? L->k : L->k * L->n * sn1;
  }
  double dpdv = -L->dt * slope;
  if (v[0] < 0) {
    p -= L->D * v[0];
    dpdv -= L->D;
  }
  double ln = L->S * p, kn = L->S * dpdv;
  double v1 = v[1], v2 = v[2], s2 = v1 * v1 + v2 * v2 + eps * eps;
  double sig = sqrt(s2), tf = pc->tf0 + pc->mu * ln, mob = 1, e = 0;
  if (pc->mob.r > 0) {
    double x = pc->mob.x0 + pc->mob.r * sig;
    mob = -expm1(-x);
    e = 1 - mob;
  }
  double T = tf * mob;
  lam[0] = ln;
  if (!(sig > 0) || !(T > 0)) {
    lam[1] = lam[2] = 0;
    if (K) {
      memset(K, 0, 9 * sizeof(double));
      K[0] = kn;
    }
    return;
  }
  double is = 1 / sig, t1 = v1 * is, t2 = v2 * is;
  lam[1] = -T * t1;
  lam[2] = -T * t2;
  if (K) {
    /* d lam_t / d v_t = -(T/s)(I - t t^T) - tf m' t t^T (t = v_t / s),
     * d lam_t / d v_n through tf */
    double a = T * is, b = tf * e * pc->mob.r, tn = pc->mu * mob * kn;
    K[0] = kn;
    K[1] = K[2] = 0;
    K[3] = -t1 * tn;
    K[6] = -t2 * tn;
    K[4] = -a * (1 - t1 * t1) - b * t1 * t1;
    K[5] = K[7] = (a - b) * t1 * t2;
    K[8] = -a * (1 - t2 * t2) - b * t2 * t2;
  }
}

/* v = J u */
static void rows_mul(const double *J, const double u[6], double v[3])
{
  for (int k = 0; k < 3; k++) {
    const double *r = J + 6 * k;
    v[k] = r[0] * u[0] + r[1] * u[1] + r[2] * u[2] + r[3] * u[3] + r[4] * u[4] + r[5] * u[5];
  }
}

/* At u: the impulses (B->lam), grad E = M (u - u_f) - sum J^T lam into g,
 * and with A non-NULL the Newton matrix M - sum J^T K J; *F the sum of
 * |lam_i|, *lmax the largest, *smax the largest slip speed (loaded
 * points) */
static void creep_eval(const CBody *B, const double u[6], double eps, double g[6], double *A,
                       double *F, double *lmax, double *smax)
{
  double du[6];
  for (int k = 0; k < 6; k++) du[k] = u[k] - B->uf[k];
  for (int k = 0; k < 3; k++) g[k] = B->m * du[k];
  ss_m3_mulv(g + 3, B->I, du + 3);
  if (A) {
    memset(A, 0, 36 * sizeof(double));
    for (int k = 0; k < 3; k++) A[7 * k] = B->m;
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++) A[6 * (3 + a) + 3 + b] = B->I[3 * a + b];
  }
  double f = 0, lm = 0, sm = 0;
  for (int i = 0; i < B->n; i++) {
    const double *J = B->p[i].J;
    double v[3], *lam = B->lam + 3 * i, *K = A ? B->K + 9 * i : NULL;
    rows_mul(J, u, v);
    creep_law(B->p[i].c, v, eps, lam, K);
    if (!(lam[0] > 0)) continue;
    double ln = fabs(lam[0]) + fabs(lam[1]) + fabs(lam[2]);
    f += ln;
    if (ln > lm) lm = ln;
    double sv = sqrt(v[1] * v[1] + v[2] * v[2]);
    if (sv > sm) sm = sv;
    for (int j = 0; j < 6; j++)
      g[j] -= J[j] * lam[0] + J[6 + j] * lam[1] + J[12 + j] * lam[2];
    if (A) {
      /* A -= J^T K J */
      double KJ[18];
      for (int r = 0; r < 3; r++)
        for (int j = 0; j < 6; j++)
          KJ[6 * r + j] = K[3 * r] * J[j] + K[3 * r + 1] * J[6 + j] + K[3 * r + 2] * J[12 + j];
      for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
          A[6 * a + b] -= J[a] * KJ[b] + J[6 + a] * KJ[6 + b] + J[12 + a] * KJ[12 + b];
    }
  }
  *F = f;
  *lmax = lm;
  *smax = sm;
}

static double dot6(const double *a, const double *b)
{
  double s = 0;
  for (int k = 0; k < 6; k++) s += a[k] * b[k];
  return s;
}

/* |g|'s force and torque within ftol and ftol L */
static int balanced(const double g[6], double ftol, double L)
{
  return sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) <= ftol &&
         sqrt(g[3] * g[3] + g[4] * g[4] + g[5] * g[5]) <= ftol * L;
}

/* |g|^2 with the torque over L */
static double imbalance(const double g[6], double L)
{
  double f = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  double t = g[3] * g[3] + g[4] * g[4] + g[5] * g[5];
  return L > 0 ? f + t / (L * L) : f + t;
}

/* Newton at one eps from u, at most iters steps, until the imbalance is
 * within ftol (force) and ftol L (torque), or until it has not halved in
 * CREEP_STALL full steps (lost in the rounding of u: the stiff points'
 * noise, creep_body).  On return u is the iterate of least imbalance, g
 * and the Newton matrix A there; B's impulses and K are there too when it
 * returns 1 (balanced, or stalled at the last iterate), else a trial's.
 * Returns 0 when the iterations or a line search ran out, -1 when a step
 * is no descent (the law's coupling spoilt the direction) or the matrix
 * is singular. */
static int creep_level(CBody *B, double u[6], double eps, double ftol, double L, int iters,
                       int *count, double g[6], double A[36], double *F, double *lmax)
{
  double du[6], ut[6], gt[6], At[36], smax, Ft, lt;
  double ub[6], gb[6], Ab[36], Fb = *F, lb = *lmax, best = imbalance(g, L), mark = best;
  int piv[6], since = 0, r = 0, at_best = 1;
  memcpy(ub, u, sizeof ub);
  memcpy(gb, g, sizeof gb);
  memcpy(Ab, A, sizeof Ab);
  for (int it = 0; it < iters && !r; it++) {
    if (balanced(g, ftol, L)) {
      r = 1;
      break;
    }
    for (int k = 0; k < 6; k++) du[k] = -g[k];
    if (!ss_lu_factor(A, piv, 6)) return -1;
    ss_lu_solve(A, piv, 6, du);
    double s0 = dot6(du, g);
    if (!(s0 < 0)) return -1;
    /* line search on phi'(a) = du . g(u + a du), increasing in a from
     * phi'(0) = s0 < 0: a step is taken where phi' is at most
     * CREEP_WOLFE |s0| (E fell, and the step went near the line's
     * minimum or short of it); past that, a falls to the root of phi'
     * interpolated linearly from 0 (kept within [0.05 a, 0.9 a]).  Each
     * trial forms its Newton matrix too: most take the full step. */
    double a = 1;
    int ok = 0;
    for (int ls = 0; ls < CREEP_SEARCH && !ok; ls++) {
      for (int k = 0; k < 6; k++) ut[k] = u[k] + a * du[k];
      creep_eval(B, ut, eps, gt, At, &Ft, &lt, &smax);
      (*count)++;
      double phi = dot6(du, gt);
      if (phi <= -CREEP_WOLFE * s0) {
        ok = 1;
      } else {
        double t = phi == phi ? a * s0 / (s0 - phi) : 0.5 * a;
        a = t < 0.05 * a ? 0.05 * a : t > 0.9 * a ? 0.9 * a : t;
      }
    }
    if (!ok) break;
    memcpy(u, ut, sizeof ut);
    memcpy(g, gt, sizeof gt);
    memcpy(A, At, sizeof At);
    *F = Ft;
    *lmax = lt;
    double gn = imbalance(g, L);
    at_best = gn < best;
    if (at_best) {
      best = gn;
      memcpy(ub, u, sizeof ub);
      memcpy(gb, g, sizeof gb);
      memcpy(Ab, A, sizeof Ab);
      Fb = *F;
      lb = *lmax;
    }
    /* progress: the imbalance halved since the mark, or a damped step */
    if (gn <= 0.25 * mark || a < 1) {
      mark = fmin(mark, gn);
      since = 0;
    } else if (++since >= CREEP_STALL) {
      r = 1;
    }
    if (balanced(g, ftol, L)) r = 1;
  }
  if (!at_best) {
    memcpy(u, ub, sizeof ub);
    memcpy(g, gb, sizeof gb);
    memcpy(A, Ab, sizeof Ab);
    *F = Fb;
    *lmax = lb;
    /* B's arrays are not at u */
    return 0;
  }
  return r;
}

/* Solve one body's points [c0, c0 + n): 1 with its answer applied */
static int creep_body(const ssModel *m, ssData *d, ssContact *c0, int n, double tol, CBody *B,
                      int *count)
{
  int b = m->geom_body[c0->geom], vadr = c0->vadr;
  B->n = n;
  B->m = m->body_mass[b];
  if (!(B->m > 0) || ss_m3_inv(B->I, d->body_iinv + 9 * b) == 0) return 0;
  memcpy(B->uf, d->qvel_free + vadr, sizeof B->uf);
  double L = 0;
  const double *com = d->body_xipos + 3 * b;
  for (int i = 0; i < n; i++) {
    B->p[i].c = c0 + i;
    B->p[i].J = d->jac + c0[i].jadr;
    double r[3];
    ss_v3_sub(r, c0[i].pos, com);
    L = fmax(L, ss_v3_norm(r));
  }
  double u[6], g[6], A[36], F, lmax, smax;
  int piv[6];
  memcpy(u, d->qvel + vadr, sizeof u);
  creep_eval(B, u, 0, g, A, &F, &lmax, &smax);
  (*count)++;
  if (!(lmax > 0) || !(F > 0)) return 0;
  /* the last level's eps: a point slipping slower sticks at its sweep
   * visit, its impulse moved by at most eps / G_tt <= eps m */
  double eps_end = CREEP_FINAL * tol * lmax / B->m;
  double eps = fmax(CREEP_EPS_START * smax, eps_end);
  for (int first = 1;; first = 0) {
    int last = !(eps > eps_end);
    if (last) eps = eps_end;
    /* (a new eps: g, A and the impulses formed again there) */
    if (!first || eps > 0) {
      creep_eval(B, u, eps, g, A, &F, &lmax, &smax);
      (*count)++;
    }
    int r = last ? creep_level(B, u, eps, CREEP_FINAL * tol * lmax, L, 2 * CREEP_ITER, count,
                               g, A, &F, &lmax)
                 : creep_level(B, u, eps, CREEP_LEVEL_TOL * F, L, CREEP_ITER, count, g, A,
                               &F, &lmax);
    if (r < 0) return 0;
    if (last) {
      if (r == 0) {
        creep_eval(B, u, eps, g, A, &F, &lmax, &smax);
        (*count)++;
      }
      break;
    }
    eps *= CREEP_EPS_STEP;
  }
  /* The last step by the laws' linear model: at the answer the stiff
   * points' impulses (T/eps, the slip within the smoothing) turn the last
   * bits of u into noise in the body's balance that no u can remove; the
   * impulses lambda + K J du of the Newton step du balance it exactly, and
   * the velocity they give is u + du to rounding.  A stiff point's
   * impulse moves there by what its sweep visit sees as a change of at
   * most its own response times the slip it stands for (below the
   * rounding of u). */
  if (!balanced(g, CREEP_LINEAR_TOL * F, L)) return 0;
  double du[6];
  for (int k = 0; k < 6; k++) du[k] = -g[k];
  if (!ss_lu_factor(A, piv, 6)) return 0;
  ss_lu_solve(A, piv, 6, du);
  for (int i = 0; i < n; i++) {
    double *lam = B->lam + 3 * i, dv[3];
    if (!(lam[0] > 0)) continue;
    const double *K = B->K + 9 * i;
    rows_mul(B->p[i].J, du, dv);
    for (int r = 0; r < 3; r++)
      lam[r] += K[3 * r] * dv[0] + K[3 * r + 1] * dv[1] + K[3 * r + 2] * dv[2];
  }
  /* apply: the impulses, and the velocity they give the body (as the
   * sweeps move it: u = u_f + sum W lambda) */
  double *q = d->qvel + vadr;
  memcpy(q, B->uf, sizeof B->uf);
  for (int i = 0; i < n; i++) {
    ssContact *c = c0 + i;
    const double *W = d->jac + c->jadr + 18, *lam = B->lam + 3 * i;
    memcpy(c->lambda, lam, 3 * sizeof(double));
    for (int k = 0; k < 6; k++)
      q[k] += W[3 * k] * lam[0] + W[3 * k + 1] * lam[1] + W[3 * k + 2] * lam[2];
  }
  return 1;
}

/* the body of contact i, and the end of its run */
static int body_run(const ssModel *m, const ssData *d, int i, int *end)
{
  int b = m->geom_body[d->contact[i].geom], e = i + 1;
  while (e < d->ncontact && m->geom_body[d->contact[e].geom] == b) e++;
  *end = e;
  return b;
}

int ss_creep_applies(const ssModel *m, const ssData *d)
{
  if (!d->ncontact) return 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    if (c->type != SS_CONTACT_SOIL || c->link >= 0 || c->nv != 6) return 0;
  }
  /* each body's points in one run (the runs by rising body, as the
   * contacts come collider by collider) */
  for (int i = 0, last = -1, e; i < d->ncontact; i = e) {
    int b = body_run(m, d, i, &e);
    if (b <= last) return 0;
    last = b;
  }
  return 1;
}

int ss_creep_solve(const ssModel *m, ssData *d, double tol, int *count)
{
  int n = d->ncontact;
  CBody B;
  B.p = malloc((size_t)n * sizeof *B.p);
  B.lam = malloc((size_t)n * 3 * sizeof(double));
  B.K = malloc((size_t)n * 9 * sizeof(double));
  int done = B.p && B.lam && B.K;
  for (int i = 0, e; i < n && done; i = e) {
    body_run(m, d, i, &e);
    done = creep_body(m, d, d->contact + i, e - i, tol, &B, count);
  }
  free(B.p);
  free(B.lam);
  free(B.K);
  return done;
}
