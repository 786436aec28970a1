/* newton.c -- the Newton phase of the contact solve (solver.h).
 *
 * Gauss-Seidel converges slowly on a slipping wheel patch: the tangential
 * impulses of its points settle by a factor of about 0.65 a sweep, so a
 * tolerance of 1e-9 takes 20 to 30 sweeps.  Yet everything the contacts of
 * one link do to the system passes through the link's spatial velocity V_b
 * (6 numbers): the point velocities are v_i = X_i V_b, and the impulses act
 * on the system only through their spatial sum F_b = sum X_i^T lambda_i.
 * When every point of a patch slips, the law of DESIGN 3.1 written at the
 * end-of-step velocity is an explicit, piecewise smooth function
 * lambda_i(v_i):
 *
 *   delta = -(g0 + dt v_n),  lambda_n = A dt (min(K_e delta, k s^n) + D max(-v_n, 0))
 *   lambda_t = -A dt tau_max(p_n, j + dt |v_t|) v_t / |v_t|
 *
 * so the whole step reduces to an equation in the contact links' spatial
 * velocities and the joint rows' velocities y = (V_b ..., v_r ...):
 *
 *   Phi(y) = y - y_free - Lam F(y) = 0,    Lam = [J_b Y_c] (loop closures
 *                                          eliminated), F = (F_b ..., lambda_r ...)
 *
 * of size 6 per link plus one per row (27 for the buggy), which Newton's
 * method solves with the Jacobian I - Lam H, H = blockdiag(sum X_i^T K_i X_i),
 * K_i = d lambda_i / d v_i -- the six-component reduction of the contact
 * group.  A backtracking line search on |Phi|^2 (weighted by 1/Lam_kk)
 * guards each step.
 *
 * The phase is an accelerator, not a second solver: it only moves the
 * sweeps' starting point.  Gauss-Seidel sweeps follow it and decide
 * convergence with the same test as always (solver.c), so the answer meets
 * the same tolerance whatever happened here.
 *
 * A point that sticks or nearly so (the point nearest the centre of a
 * turning wheel's slip field) has no usable velocity form: its slip
 * direction turns with every step.  Such points are solved in impulse
 * form instead (NImpEval): their tangential impulses join the unknowns,
 * with the friction law as a projection (the natural map), smooth enough
 * for Newton on either side of sticking; each Newton step eliminates them
 * point by point (a Schur complement onto the links' velocities), so the
 * linear system stays 6 per link.  Where they stall (a patch whose every
 * point sticks: its tangential impulses indeterminate), the patch-level
 * stick solve (stick_solve) is tried.  The phase declines when a contact is
 * not a soil point on an articulated link or a free body or a PD row, or
 * when Newton does not converge fast; it leaves impulses and velocities
 * as it found them unless an answer it applied failed its check before
 * (then that answer, impulses and velocities consistent: solver.h).
 *
 * The creeping solve at the end of this file (ss_newton_creep) shares
 * the phase's unknowns and set-up: where the sweeps crawl on a creeping
 * patch (stick and slip mixed, which neither form here settles), it
 * minimises the laws' convex potential over them instead. */
#include "solver.h"
#include "articulated.h"
#include "ss_math.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A loaded point whose slip stiffness T/|v_t| exceeds this many times its
 * own tangential response 1/G_tt is sticking, or so nearly that its
 * velocity form is no use: a trial that puts a velocity-form point there
 * is no descent, and at the start such a point goes to impulse form. */
#define STICK_RATIO 1e3
/* Newton iterations of a solve; twice as many once points are in impulse
 * form (their kinks cost a few damped steps) */
#define MAX_ITER 8
/* A loaded point whose T/|v_t| passes this many times 1/G_tt at an
 * accepted iterate (or that sticks at the start) is solved in impulse form
 * from then on (NImpEval): its slip direction turns fast with the
 * velocity there, which the velocity form's Newton steps cannot follow. */
#define IMP_RATIO 100
/* The impulse form's d phi / d mu is 0 at a sticking point (the impulses
 * of a sticking patch are statically indeterminate): its elimination uses
 * d phi / d mu + IMP_REG G_tt, which moves the Newton step only along the
 * indeterminate directions (and by that fraction elsewhere). */
#define IMP_REG 1e-6
/* Close to the answer (|phi| below IMP_REG_NEAR of the contacts' effect,
 * as residual weighs them) a line search that finds no descent with
 * impulse-form points (their steps move far along the indeterminate
 * directions, across the natural map's kinks) tries again from the same
 * point with the regularization IMP_REG_UP times larger, up to
 * IMP_REG_MAX (a Levenberg-Marquardt damping of their impulses); each
 * later step relaxes it by IMP_REG_DOWN, back to IMP_REG.  Farther out
 * (a creeping patch whose points cross the kinks in bulk) damped steps
 * converge too slowly to pay for their evaluations; the sweeps do better
 * there. */
#define IMP_REG_NEAR 1e-5
#define IMP_REG_UP 10
#define IMP_REG_DOWN 0.5
#define IMP_REG_MAX 1

/* A soil point as the Newton phase sees it: its law's constants for this
 * step, its place in its group's frame, and the last values of its two
 * transcendental functions, from which the next evaluation moves by a
 * short series (the iterates of one step stay close together). */
typedef struct NPoint {
  double r[3];        /* position from the group's origin o, group frame
                         (rows n, t1, t2) */
  double g0, sp, S;   /* start separation, rut depth, A dt */
  double k, tf0;      /* k_c/b + k_phi; A dt c */
  double x0, gtt;     /* j/K_j; largest diagonal entry of G_tt, formed
                         where first needed (point_gtt; < 0: not yet) */
  ssPowMemo pw;       /* last s^(n-1) (pw.s = 0: none) */
  ssExpMemo mob;      /* last x = x0 + sigma dt/K_j, 1 - exp(-x), exp(-x)
                         (mob.x < 0: none) */
  int imp;            /* 1: in impulse form (its mu and NImpEval are at 2 i
                         and i of the work's arrays) */
} NPoint;

/* A point solved in impulse form: its tangential impulse mu is an unknown
 * of Newton's, with the equation of the friction law as a projection (the
 * natural map), phi = (mu - proj(mu - rho v_t)) / rho = 0, proj onto the
 * disc of radius T(|v_t|) = tf m(j + dt |v_t|), rho = 1/G_tt: mu = -T v_t/
 * |v_t| while slipping, |mu| <= T(0) and v_t = 0 while sticking, one
 * piecewise smooth equation for both, where the velocity form turns set-
 * valued.  Its normal impulse stays the explicit law of its velocity. */
/* one evaluation's values at an impulse-form point */
typedef struct NImpEval {
  double phi[2];      /* (mu - proj(mu - rho v_t)) / rho */
  double Dm[4];       /* d phi / d mu (2 x 2) */
  double Dv[4];       /* d phi / d v_t (2 x 2) */
  double e[2];        /* d phi / d v_n (through lambda_n and tf) */
} NImpEval;

/* a bed material's constants as the law uses them */
typedef struct Mat {
  double dt, n, Ke, D, mu, rj; /* rj = dt / K_j, 0 when K_j = 0 */
  int linear;
  ssPowSeries pser;            /* of s^(n-1), when not linear */
  const double *gq;            /* its group's slip_quadratics */
  double gmax;                 /* and bound on G_tt (slip_bound) */
} Mat;

/* A group: the soil points of one link (or free rigid body) on one bed,
 * in that bed's frame */
typedef struct NGroup {
  int link;           /* articulated link, or -1: the free body `body` */
  int body, sys, bed;
  double Yb[36];      /* free body: its response Y (see body_block) */
  double Lg[36];      /* its Lam in the group's frame (group_lam) */
  double gq[12];      /* the points' G_11, G_22 as quadratics in r
                         (slip_quadratics of Lg) */
  double rmax[3];     /* the largest |r_k| of its points */
  double gmax;        /* a bound on its points' G_tt (slip_bound) */
  const ssSoilMaterial *mat;
  double R[9];        /* contact frame rows n, t1, t2 (world) */
  double oref[3];     /* o less the point the body's spatial quantities
                         are about (group_motion): a free body's centre of
                         mass, a link's system's origin (ss_art_origin) */
  double o[3];        /* origin of the points' r (world) */
  const ssPowTable *pt; /* its bed's table of s^(n-1), or NULL */
  double ik;          /* 1 / K_j of its material, 0 for K_j = 0 */
  ssModulusMemo mod;  /* its points' modulus, kept for their width */
  int axes;           /* R is an unturned bed's axes (ssContact.bed_axes):
                         r = R (p - o) a permutation */
  ssV2 T[18];         /* y' = T y (group_T), row by row in pairs */
  ssV2 Ttb[36];       /* T^T's entries, each in both halves */
  Mat M;              /* its law's constants (mat_of), formed once a
                         solve: the evaluations and the check copy them */
} NGroup;

/* One evaluation's sums over a group's points, in its frame about o */
typedef struct NSum {
  double V[6];        /* the group's velocity (omega'; v_o') */
  double F[6];        /* sum (r x lambda; lambda) */
  double K[6];        /* sum of K's entries nn, 1n, 2n, 11, 12, 22 */
  double vw[9], wv[9], ww[9]; /* sums of K (-[r]x), [r]x K, [r]x K (-[r]x) */
  double Q[36], q[6]; /* the impulse-form points' elimination: d F' / d V'
                         and F' at the Newton step's constant part */
} NSum;

struct ssNewtonWork {
  int cap_n, cap_c, cap_v, cap_g;
  int *group_of;      /* (ncontact) group of each soil contact */
  int *run, nrun;     /* (ncontact + 1) the soil contacts' runs of one
                         group: run q is [run[q], run[q + 1]) */
  double *lam, *lamtry; /* (ncontact x 3) the soil points' impulses at y,
                         at the trial point */
  double *Lam;        /* (n x n) J Y over the groups' links and the rows */
  double *A;          /* (n x n) Newton matrix I - Lam H, then its LU */
  int *piv;           /* (n) */
  double *y, *yfree, *phi, *dy, *F;           /* (n) */
  double *ytry, *Ftry, *phitry;               /* (n) line-search trial */
  double *H, *Htry;   /* (ngroup x 36 + nrow) d F / d y, block diagonal,
                         the impulse-form points eliminated into it */
  double *K, *Ktry;   /* (ncontact x 6) each soil point's K = d lambda / d v
                         where H was formed (point_law's entries; only a
                         loaded point's are meaningful), at y, at the
                         trial point */
  double *q, *qtry;   /* (6 ngroup) F's part from their equations' values:
                         the step solves (I - Lam H) dy = -phi - Lam q */
  double *col;        /* (nv) one gathered response column */
  ssV2 *F2;           /* (n) residual's F, each entry in both halves */
  NPoint *pt;         /* (ncontact) the soil points' constants and caches */
  NGroup *grp;        /* (ngroup) */
  NSum *sum;          /* (ngroup) one evaluation's sums */
  int settled;        /* the last solve took no Newton step: the next one
                         forms its first H only if a step needs it */
  int ns;             /* impulse-form points of this solve */
  double reg;         /* their regularization, times G_tt (IMP_REG, more
                         after a line search without descent) */
  int *imp;           /* (ncontact) their indices */
  int *live;          /* (ncontact) an evaluation's loaded points of one
                         run of a group (evaluate_at) */
  double *mu, *mutry, *dmu; /* (ncontact x 2) their mu at y, at the trial,
                         the step */
  NImpEval *ie, *ietry; /* (ncontact) their equations at y, at the trial */
  double *stk;        /* (cap_stk) stick_solve's scratch */
  int *stk_piv;       /* (cap_stkpiv) its pivots */
  size_t cap_stk;
  int cap_stkpiv;
};

const double *ss_newton_law(const ssData *d)
{
  return d->newton ? d->newton->lam : NULL;
}

void ss_newton_work_free(ssNewtonWork *w)
{
  if (!w) return;
  free(w->group_of); free(w->run); free(w->lam); free(w->lamtry);
  free(w->Lam); free(w->A); free(w->piv); free(w->y); free(w->yfree);
  free(w->phi); free(w->dy); free(w->F); free(w->ytry); free(w->Ftry);
  free(w->phitry); free(w->H); free(w->Htry); free(w->K); free(w->Ktry);
  free(w->col); free(w->F2); free(w->pt);
  free(w->grp); free(w->sum);
  free(w->q); free(w->qtry); free(w->imp); free(w->live); free(w->mu); free(w->mutry); free(w->dmu);
  free(w->ie); free(w->ietry); free(w->stk); free(w->stk_piv);
  free(w);
}

static int grow(void *pp, size_t count, size_t size)
{
  void **p = pp, *q = realloc(*p, (count ? count : 1) * size);
  if (!q) return 0;
  *p = q;
  return 1;
}

/* room for n unknowns, nc contacts, nv velocities and ng groups */
static ssNewtonWork *work(ssData *d, int n, int nc, int nv, int ng)
{
  ssNewtonWork *w = d->newton;
  if (!w && !(w = d->newton = calloc(1, sizeof *w))) return NULL;
  if (nc > w->cap_c) {
    if (!grow(&w->group_of, (size_t)nc, sizeof(int)) ||
        !grow(&w->run, (size_t)nc + 1, sizeof(int)) ||
        !grow(&w->pt, (size_t)nc, sizeof(NPoint)) ||
        !grow(&w->lam, 3 * (size_t)nc, sizeof(double)) ||
        !grow(&w->lamtry, 3 * (size_t)nc, sizeof(double)) ||
        !grow(&w->K, 6 * (size_t)nc, sizeof(double)) ||
        !grow(&w->Ktry, 6 * (size_t)nc, sizeof(double)) ||
        !grow(&w->imp, (size_t)nc, sizeof(int)) ||
        !grow(&w->live, (size_t)nc, sizeof(int)) ||
        !grow(&w->mu, 2 * (size_t)nc, sizeof(double)) ||
        !grow(&w->mutry, 2 * (size_t)nc, sizeof(double)) ||
        !grow(&w->dmu, 2 * (size_t)nc, sizeof(double)) ||
        !grow(&w->ie, (size_t)nc, sizeof(NImpEval)) ||
        !grow(&w->ietry, (size_t)nc, sizeof(NImpEval)))
      return NULL;
    w->cap_c = nc;
  }
  if (nv > w->cap_v) {
    if (!grow(&w->col, (size_t)nv, sizeof(double))) return NULL;
    w->cap_v = nv;
  }
  if (ng > w->cap_g) {
    if (!grow(&w->grp, (size_t)ng, sizeof(NGroup)) ||
        !grow(&w->sum, (size_t)ng, sizeof(NSum)) ||
        !grow(&w->q, 6 * (size_t)ng, sizeof(double)) ||
        !grow(&w->qtry, 6 * (size_t)ng, sizeof(double)))
      return NULL;
    w->cap_g = ng;
  }
  if (n > w->cap_n) {
    double **vec[] = {&w->y, &w->yfree, &w->phi, &w->dy, &w->F,
                      &w->ytry, &w->Ftry, &w->phitry};
    for (size_t k = 0; k < sizeof vec / sizeof *vec; k++)
      if (!grow(vec[k], (size_t)n, sizeof(double))) return NULL;
    /* H needs at most 36 per group (6 unknowns): 6 n */
    if (!grow(&w->H, 6 * (size_t)n, sizeof(double)) ||
        !grow(&w->Htry, 6 * (size_t)n, sizeof(double)) ||
        !grow(&w->Lam, (size_t)n * n, sizeof(double)) ||
        !grow(&w->A, (size_t)n * n, sizeof(double)) ||
        !grow(&w->F2, (size_t)n, sizeof(ssV2)) ||
        !grow(&w->piv, (size_t)n, sizeof(int)))
      return NULL;
    w->cap_n = n;
  }
  return w;
}

/* ---------------------------------------------------------------------- */
/* the law in velocity form                                                */

/* the series are ss_math.h's (shared with src/point.c) */

/* s^(n-1) of point P, moved from its last value when near; with keep,
 * its memo stays where it was (check: the memos stay at the last
 * evaluation's y, so that H formed there later is what that evaluation
 * would have formed) */
static inline __attribute__((always_inline)) double pow_point(NPoint *P, double s,
                                                             const ssPowSeries *ser,
                                                             const int keep)
{
  return keep ? ss_pow_at(&P->pw, s, ser, 0) : ss_pow_moved(&P->pw, s, ser, 0);
}

/* Janosi mobilisation 1 - exp(-x) of point P and exp(-x) in *e; keep as
 * for pow_point */
static inline __attribute__((always_inline)) double mobil_point(NPoint *P, double x, double *e,
                                                               const int keep)
{
  ssExpMemo c = ss_exp_memo_move(P->mob, x);
  if (!keep) P->mob = c;
  *e = c.e;
  return c.m;
}

/* ---------------------------------------------------------------------- */
/* Phi and its Jacobian                                                    */

/* the unknowns: 6 per group (its link's spatial velocity), then one per
 * joint row (its velocity); contacts [0, first_row) are the soil points,
 * [first_row, ncontact) the rows */
typedef struct Setup {
  int ngroup, nrow, n, first_row;
  int linear;         /* every group's soil is linear (n = 1): its laws
                         need no power (evaluate's own form) */
  int pow_shear;      /* every group's soil nonlinear, with the power's
                         series and a shear modulus (K_j > 0): evaluate's
                         form where their tests compile away */
} Setup;

/* y_b (omega; v_P, world, about the body's point P: group_motion) in a
 * group's frame about its origin: omega' = R omega, v' = R (v_P + omega x
 * (o - P)) */
static void to_group(const NGroup *G, const double V[6], double Vg[6])
{
  double vo[3];
  ss_v3_cross(vo, V, G->oref);
  ss_v3_add(vo, vo, V + 3);
  ss_m3_mulv(Vg, G->R, V);
  ss_m3_mulv(Vg + 3, G->R, vo);
}

/* The group's impulse and its derivative back to world, about the body's
 * point P: with y' = T y, T = [[R, 0], [-R [o - P]x, R]], F = T^T F' and
 * H = T^T H' T.  group_T forms T. */
static void group_T(const NGroup *G, double T[36])
{
  const double *o = G->oref;
  double ox[9] = {0, -o[2], o[1], o[2], 0, -o[0], -o[1], o[0], 0}, Rox[9];
  ss_m3_mul(Rox, G->R, ox);
  memset(T, 0, 36 * sizeof(double));
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++) {
      T[6 * a + b] = G->R[3 * a + b];
      T[6 * (a + 3) + b + 3] = G->R[3 * a + b];
      T[6 * (a + 3) + b] = -Rox[3 * a + b];
    }
}

/* T and T^T as congruence6 reads them: the group's frame is fixed for
 * the solve, so T is formed once a solve, not at every evaluation (out
 * of line: inlined into newton_solve it moves the register allocation of
 * the F-only evaluation's loop there, two instructions more a point on
 * the settled plate) */
static __attribute__((noinline)) void group_frame(NGroup *G)
{
  double T[36];
  group_T(G, T);
  for (int k = 0; k < 18; k++) G->T[k] = (ssV2){T[2 * k], T[2 * k + 1]};
  for (int a = 0; a < 6; a++)
    for (int k = 0; k < 6; k++) G->Ttb[6 * a + k] = (ssV2){T[6 * k + a], T[6 * k + a]};
}

/* out = P A P^T (6 x 6), from P's entries each in both halves (Pb) and
 * P^T's rows in pairs (Pt): two entries of a row at a time (SSE2 pairs),
 * each entry's sum (AP^T)_ab = sum_k A_ak P_bk, then out_ab = sum_k P_ak
 * (AP^T)_kb, from 0 in the order k = 0, 1, ..., 5 as the scalar sums
 * (a product's factors commute exactly): the same values, with half the
 * arithmetic instructions and P's broadcasts formed once a solve */
static void congruence6(const ssV2 Pb[36], const ssV2 Pt[18], const double A[36],
                        double out[36])
{
  ssV2 AP[18];
  for (int a = 0; a < 6; a++) {
    ssV2 ak[6];
    for (int k = 0; k < 6; k++) ak[k] = (ssV2){A[6 * a + k], A[6 * a + k]};
    for (int j = 0; j < 3; j++) {
      ssV2 t = {0, 0};
      for (int k = 0; k < 6; k++) t += ak[k] * Pt[3 * k + j];
      AP[3 * a + j] = t;
    }
  }
  for (int j = 0; j < 3; j++)
    for (int a = 0; a < 6; a++) {
      ssV2 t = {0, 0};
      for (int k = 0; k < 6; k++) t += Pb[6 * a + k] * AP[3 * k + j];
      memcpy(out + 6 * a + 2 * j, &t, sizeof t);
    }
}

static void from_group(const NGroup *G, const double Fg[6], const double Hg[36],
                       double F[6], double H[36])
{
  for (int a = 0; a < 6; a++) {
    double t = 0;
    for (int k = 0; k < 6; k++) t += G->T[3 * k + a / 2][a % 2] * Fg[k];
    F[a] = t;
  }
  if (!Hg) return;
  /* H = T^T Hg T: P = T^T, whose transpose is T */
  congruence6(G->Ttb, G->T, Hg, H);
}

/* A group's body velocity y_b = (omega; v_P) from its system's
 * velocities u (qvel's block of the system), about the body's point P: a
 * link's J_b u about its system's origin (articulated.h), a free body's
 * (qvel = (v_c; omega) at its centre of mass c) about c itself, so that
 * no product of c's size (the distance from the origin) enters its
 * spatial quantities to cancel in the group's frame: a settled plate 1 km
 * from the origin took three times the Newton iterations of one at the
 * origin while they were about the origin (README, "Far from the
 * origin"). */
static void group_motion(const ssModel *m, const ssData *d, const NGroup *G,
                         const double *u, double V[6])
{
  if (G->link >= 0) {
    ss_art_link_motion(m, d, G->link, u, V);
    return;
  }
  ss_v3_copy(V, u + 3);
  ss_v3_copy(V + 3, u);
}

/* A free body's response Y (6 x 6, Y[6 i + k]: velocity i per unit of
 * F_k) to a spatial impulse F = (torque about its centre of mass c;
 * force), group_motion's point: dv_c = f / m, domega = I^-1 tau_c */
static void body_block(const ssModel *m, const ssData *d, int b, double Y[36])
{
  const double *Ii = d->body_iinv + 9 * b;
  double im = 1 / m->body_mass[b];
  memset(Y, 0, 36 * sizeof(double));
  for (int k = 0; k < 3; k++) {
    Y[6 * k + 3 + k] = im;
    for (int i = 0; i < 3; i++) Y[6 * (3 + i) + k] = Ii[3 * i + k];
  }
}

/* A link's or body's response to the group's points in the group's frame,
 * Lam' = T Lam T^T (y' = T y, F = T^T F'), for the stick test: a point at
 * r has tangential rows x_1 = (r x e_1; e_1), x_2 = (r x e_2; e_2) there,
 * and its G_kk = x_k^T Lam' x_k is a quadratic in r */
static void group_lam(const NGroup *G, const double Lam[36], double Lg[36])
{
  /* P = T: its entries in both halves, and T^T's rows in pairs */
  ssV2 Tb[36], Tt[18];
  for (int a = 0; a < 6; a++)
    for (int k = 0; k < 6; k++) {
      Tb[6 * a + k] = (ssV2){G->T[3 * a + k / 2][k % 2], G->T[3 * a + k / 2][k % 2]};
      Tt[3 * k + a / 2][a % 2] = G->T[3 * a + k / 2][k % 2];
    }
  congruence6(Tb, Tt, Lam, Lg);
}

/* G_11 and G_22 of a point at r (group frame) as quadratics in r, from
 * Lam' (group_lam): x_1 has -r_2, r_0, 1 at 0, 2, 4 and x_2 has r_1, -r_0,
 * 1 at 0, 1, 5, so
 *   G_11 = L00 r2^2 + L22 r0^2 + L44 - L02' r0 r2 - L04' r2 + L24' r0,
 *   G_22 = L00 r1^2 + L11 r0^2 + L55 - L01' r0 r1 + L05' r1 - L15' r0
 * with Lab' = Lab + Lba; q holds the twelve coefficients in that order */
static void slip_quadratics(const double Lg[36], double q[12])
{
  q[0] = Lg[0];
  q[1] = Lg[14];
  q[2] = Lg[28];
  q[3] = Lg[2] + Lg[12];
  q[4] = Lg[4] + Lg[24];
  q[5] = Lg[16] + Lg[26];
  q[6] = Lg[0];
  q[7] = Lg[7];
  q[8] = Lg[35];
  q[9] = Lg[1] + Lg[6];
  q[10] = Lg[5] + Lg[30];
  q[11] = Lg[11] + Lg[31];
}

/* max(G_11, G_22) of a point at r, from slip_quadratics' q */
static double slip_response(const double q[12], const double r[3])
{
  double g1 = q[0] * r[2] * r[2] + q[1] * r[0] * r[0] + q[2] - q[3] * r[0] * r[2] -
              q[4] * r[2] + q[5] * r[0];
  double g2 = q[6] * r[1] * r[1] + q[7] * r[0] * r[0] + q[8] - q[9] * r[0] * r[1] +
              q[10] * r[1] - q[11] * r[0];
  return g1 > g2 ? g1 : g2;
}

/* An upper bound on slip_response over the points with |r_k| <= R_k:
 * each term's magnitude at R, summed in slip_response's order (rounding
 * is monotone, so the sum of the magnitudes is never below the sum that
 * slip_response rounds), doubled for good measure.  The law needs a
 * point's G_tt only where T G_tt may pass IMP_RATIO |v_t|, which the
 * bound rules out for nearly every point (T G_tt / |v_t| is below 1e-2
 * of it on the rolling buggy and the settled plate), so G_tt is formed
 * only there (point_gtt) instead of for every point at the set-up. */
static double slip_bound(const double q[12], const double R[3])
{
  double g1 = fabs(q[0]) * R[2] * R[2] + fabs(q[1]) * R[0] * R[0] + fabs(q[2]) +
              fabs(q[3]) * R[0] * R[2] + fabs(q[4]) * R[2] + fabs(q[5]) * R[0];
  double g2 = fabs(q[6]) * R[1] * R[1] + fabs(q[7]) * R[0] * R[0] + fabs(q[8]) +
              fabs(q[9]) * R[0] * R[1] + fabs(q[10]) * R[1] + fabs(q[11]) * R[0];
  return 2 * (g1 > g2 ? g1 : g2);
}

static Mat mat_of(const NGroup *G, double dt)
{
  const ssSoilMaterial *mat = G->mat;
  Mat M = {dt, mat->sinkage_exponent,
           mat->elastic_stiffness, mat->damping, mat->friction_coefficient,
           G->ik > 0 ? dt / mat->shear_displacement : 0,
           mat->sinkage_exponent == 1.0, {0, {0}, 0, NULL}, G->gq, G->gmax};
  if (!M.linear) {
    M.pser = ss_pow_series(M.n - 1);
    M.pser.tab = G->pt;
  }
  return M;
}

/* a point's G_tt, formed at its first use */
static inline double point_gtt(const double gq[12], NPoint *P)
{
  if (P->gtt < 0) P->gtt = slip_response(gq, P->r);
  return P->gtt;
}

enum { UNLOADED = 0, LOADED = 1, STICKS = 2, NEAR = 3 };
enum { STUCK = 1, NEAR_STICK = 2 }; /* evaluate's flags */

/* the velocity (v_n, v_t1, v_t2) of a point at r for its group's velocity
 * V (frame about o): v = v_o + omega x r */
static inline __attribute__((always_inline)) void point_velocity(const double r[3],
                                                                 const double V[6],
                                                                 double v[3])
{
  v[0] = V[3] + V[1] * r[2] - V[2] * r[1];
  v[1] = V[4] + V[2] * r[0] - V[0] * r[2];
  v[2] = V[5] + V[0] * r[1] - V[1] * r[0];
}

/* The normal law of point P at normal velocity vn: lambda_n, and its
 * derivative d lambda_n / d v_n in *kn; -1 when unloaded (no overlap) */
static inline __attribute__((always_inline)) double point_normal(const Mat *M, NPoint *P,
                                                                 double vn, double *kn,
                                                                 const int keep)
{
  double delta = -(P->g0 + M->dt * vn);
  if (!(delta > 0)) {
    *kn = 0;
    return -1;
  }
  double sk = P->sp + delta, sn1 = M->linear ? 1.0 : pow_point(P, sk, &M->pser, keep);
  double pe = M->Ke * delta, py = P->k * sk * sn1, p, slope;
  if (pe <= py) {
    p = pe;
    slope = M->Ke;
  } else {
    p = py;
    slope = P->k * M->n * sn1;
  }
  double dpdv = -M->dt * slope;
  if (vn < 0) {
    p -= M->D * vn;
    dpdv -= M->D;
  }
  *kn = P->S * dpdv;
  return P->S * p;
}

/* The law of point P at its group's velocity V (frame about o): impulse
 * lam, and with K non-NULL the entries of K = d lambda / d v, (nn, 1n, 2n,
 * 11, 12, 22) (K_n1 = K_n2 = 0: the normal law does not see the slip).
 * Returns UNLOADED (lam = 0), LOADED, NEAR (loaded, and T / |v_t| above
 * IMP_RATIO times its own tangential response 1/G_tt: switch_points), or
 * STICKS when the point sticks or so nearly that T / |v_t| exceeds
 * STICK_RATIO / G_tt: the velocity form is set-valued there. */
static inline __attribute__((always_inline)) int point_law(const Mat *M, NPoint *P, const double V[6],
                            double lam[3], double *K, const int keep)
{
  const double *r = P->r;
  /* v = v_o + omega x r (point_velocity, the tangential part formed only
   * for a loaded point) */
  double vn = V[3] + V[1] * r[2] - V[2] * r[1], kn;
  double ln = point_normal(M, P, vn, &kn, keep);
  if (ln < 0) {
    lam[0] = lam[1] = lam[2] = 0;
    return UNLOADED;
  }
  double v1 = V[4] + V[2] * r[0] - V[0] * r[2];
  double v2 = V[5] + V[0] * r[1] - V[1] * r[0];
  /* shear: the bound T = tf m(sigma) opposes the slip */
  double sigma = sqrt(v1 * v1 + v2 * v2), tf = P->tf0 + M->mu * ln, mob = 1, e = 0;
  if (M->rj > 0) mob = mobil_point(P, P->x0 + M->rj * sigma, &e, keep);
  double T = tf * mob;
  lam[0] = ln;
  if (K) K[0] = kn;
  /* T G_tt, where the group's bound lets it pass IMP_RATIO |v_t|, and
   * its two tests (stick, near); elsewhere both fail as they would for
   * T G_tt, and are not made (nearly every point: two compares and
   * their products a point less) */
  int stick = 0, near = 0;
  if (T * M->gmax > IMP_RATIO * sigma) {
    double Tg = T * point_gtt(M->gq, P);
    stick = Tg > STICK_RATIO * sigma;
    near = Tg > IMP_RATIO * sigma;
  }
  if (!(T > 0) || !(sigma > 0) || stick) {
    /* no shear bound (LOADED), or sticking (STICKS) */
    lam[1] = lam[2] = 0;
    if (K) K[1] = K[2] = K[3] = K[4] = K[5] = 0;
    return T > 0 ? STICKS : LOADED;
  }
  double is = 1 / sigma, t1 = v1 * is, t2 = v2 * is;
  lam[1] = -T * t1;
  lam[2] = -T * t2;
  if (K) {
    /* d lambda_t / d v_t = -(T/sigma)(I - t t^T) - tf m' t t^T, and
     * d lambda_t / d v_n through tf = A dt c + mu lambda_n */
    double a = T * is, b = tf * e * M->rj, tn = M->mu * mob * K[0];
    K[1] = -t1 * tn;
    K[2] = -t2 * tn;
    K[3] = -a * (1 - t1 * t1) - b * t1 * t1;
    K[4] = (a - b) * t1 * t2;
    K[5] = -a * (1 - t2 * t2) - b * t2 * t2;
  }
  return near ? NEAR : LOADED;
}

/* The friction law of an impulse-form point in natural-map form at slip
 * velocity v (2), normal impulse ln with d ln / d v_n = kn, tangential
 * impulse mu: phi and its derivatives (NImpEval).  With project, a mu
 * outside the disc is first brought back onto its rim (radially): a
 * Newton step that turns a point's impulse along the rim (to first order
 * free there, the rim's tangent) leaves it outside by the rim's curvature,
 * an error of second order in the step that the linearization does not
 * see and that, summed over a patch, can take away all descent; no answer
 * lies outside the disc, and the projection moves mu closer to every
 * point of it. */
static void imp_map(const Mat *M, const NPoint *P, const double v[2], double ln, double kn,
                    double mu[2], int project, NImpEval *ie)
{
  double rho = 1 / P->gtt, sigma = sqrt(v[0] * v[0] + v[1] * v[1]);
  double tf = P->tf0 + M->mu * ln, mob = 1, ex = 0;
  if (M->rj > 0) {
    double x = P->x0 + M->rj * sigma;
    mob = -expm1(-x);
    ex = 1 - mob;
  }
  double T = tf * mob;
  if (project) {
    double mn = sqrt(mu[0] * mu[0] + mu[1] * mu[1]);
    if (mn > T) {
      double sc = T / mn;
      mu[0] *= sc;
      mu[1] *= sc;
    }
  }
  double z0 = mu[0] - rho * v[0], z1 = mu[1] - rho * v[1], zn = sqrt(z0 * z0 + z1 * z1);
  if (!(zn > T)) {
    /* inside the disc: phi = v_t (sticking, v_t = 0 at the answer) */
    ie->phi[0] = v[0];
    ie->phi[1] = v[1];
    ie->Dm[0] = ie->Dm[1] = ie->Dm[2] = ie->Dm[3] = 0;
    ie->Dv[0] = ie->Dv[3] = 1;
    ie->Dv[1] = ie->Dv[2] = 0;
    ie->e[0] = ie->e[1] = 0;
    return;
  }
  /* on its rim: phi = (mu - T z/|z|) / rho */
  double u0 = z0 / zn, u1 = z1 / zn, a = T / zn;
  double dTs = tf * ex * M->rj, dTn = mob * M->mu * kn;
  double w0 = sigma > 0 ? v[0] / sigma : 0, w1 = sigma > 0 ? v[1] / sigma : 0;
  ie->phi[0] = (mu[0] - T * u0) / rho;
  ie->phi[1] = (mu[1] - T * u1) / rho;
  /* d phi / d mu = (I - a (I - u u^T)) / rho; d phi / d v = a (I - u u^T)
   * - u dT/dsigma w^T / rho (w = v/|v|); d phi / d v_n = -u dT/dv_n / rho */
  ie->Dm[0] = (1 - a * (1 - u0 * u0)) / rho;
  ie->Dm[1] = ie->Dm[2] = a * u0 * u1 / rho;
  ie->Dm[3] = (1 - a * (1 - u1 * u1)) / rho;
  ie->Dv[0] = a * (1 - u0 * u0) - u0 * dTs * w0 / rho;
  ie->Dv[1] = -a * u0 * u1 - u0 * dTs * w1 / rho;
  ie->Dv[2] = -a * u0 * u1 - u1 * dTs * w0 / rho;
  ie->Dv[3] = a * (1 - u1 * u1) - u1 * dTs * w1 / rho;
  ie->e[0] = -u0 * dTn / rho;
  ie->e[1] = -u1 * dTn / rho;
}

/* An impulse-form point at its group's velocity V with tangential
 * impulse mu: lam = (lambda_n(v_n), mu), K's normal entry (the others 0:
 * mu does not move with y), and its equation's value and derivatives in
 * *ie.  Returns LOADED, or STICKS where it has no answer there
 * (unloaded). */
static __attribute__((noinline)) int imp_law(const Mat *M, NPoint *P, const double V[6],
                                             double mu[2], double lam[3], double *K,
                                             NImpEval *ie)
{
  double v[3], kn;
  point_velocity(P->r, V, v);
  double ln = point_normal(M, P, v[0], &kn, 0);
  if (ln < 0) return STICKS;
  imp_map(M, P, v + 1, ln, kn, mu, 1, ie);
  lam[0] = ln;
  lam[1] = mu[0];
  lam[2] = mu[1];
  if (K) {
    K[0] = kn;
    K[1] = K[2] = K[3] = K[4] = K[5] = 0;
  }
  return LOADED;
}

/* d phi / d mu + scale G_tt I of an impulse-form point (scale: the solve's
 * regularization, IMP_REG or more), in A; returns its determinant */
static double imp_regularized(const NPoint *P, const NImpEval *ie, double scale, double A[4])
{
  double reg = scale * P->gtt;
  A[0] = ie->Dm[0] + reg;
  A[1] = ie->Dm[1];
  A[2] = ie->Dm[2];
  A[3] = ie->Dm[3] + reg;
  return A[0] * A[3] - A[1] * A[2];
}

/* An impulse-form point's elimination into its group's sums (frame about
 * o).  With W = (d phi / d mu + scale G_tt I)^-1 its Newton step is
 * dmu = -W (phi + D_v dv_t + e dv_n), dv = X dV' (X: its rows n, t1, t2),
 * so it adds X_t^T (-W [e | D_v]) X to d F' / d V' (Q) and X_t^T (-W phi)
 * to F' at the step (q). */
static __attribute__((noinline)) void imp_eliminate(const NPoint *P, const NImpEval *ie,
                                                   double scale, NSum *A)
{
  const double *r = P->r;
  double A0[4], det = imp_regularized(P, ie, scale, A0);
  const double W[4] = {A0[3] / det, -A0[1] / det, -A0[2] / det, A0[0] / det};
  const double x[3][6] = {{0, r[2], -r[1], 1, 0, 0},
                          {-r[2], 0, r[0], 0, 1, 0},
                          {r[1], -r[0], 0, 0, 0, 1}};
  for (int t = 0; t < 2; t++) {
    const double *Wt = W + 2 * t;
    double kn = -(Wt[0] * ie->e[0] + Wt[1] * ie->e[1]);
    double k1 = -(Wt[0] * ie->Dv[0] + Wt[1] * ie->Dv[2]);
    double k2 = -(Wt[0] * ie->Dv[1] + Wt[1] * ie->Dv[3]);
    double kx[6];
    for (int j = 0; j < 6; j++) kx[j] = kn * x[0][j] + k1 * x[1][j] + k2 * x[2][j];
    for (int i = 0; i < 6; i++) {
      double xi = x[1 + t][i];
      if (xi == 0) continue;
      for (int j = 0; j < 6; j++) A->Q[6 * i + j] += xi * kx[j];
    }
  }
  double w0 = W[0] * ie->phi[0] + W[1] * ie->phi[1], w1 = W[2] * ie->phi[0] + W[3] * ie->phi[1];
  for (int i = 0; i < 6; i++) A->q[i] -= x[1][i] * w0 + x[2][i] * w1;
}

/* An impulse-form point's step dmu from its group's dV' (see
 * imp_eliminate) */
static void imp_step(const NPoint *P, const NImpEval *ie, double scale, const double dV[6],
                     double dmu[2])
{
  double A[4], det = imp_regularized(P, ie, scale, A), dv[3];
  point_velocity(P->r, dV, dv);
  double g0 = ie->phi[0] + ie->Dv[0] * dv[1] + ie->Dv[1] * dv[2] + ie->e[0] * dv[0];
  double g1 = ie->phi[1] + ie->Dv[2] * dv[1] + ie->Dv[3] * dv[2] + ie->e[1] * dv[0];
  dmu[0] = -(A[3] * g0 - A[1] * g1) / det;
  dmu[1] = -(A[0] * g1 - A[2] * g0) / det;
}

/* s[0] += a[0] + a[1] and s[1] += b[0] + b[1] (two of h_sums' sums, its
 * halves added at the end) in one pair of doubles: in each half the same
 * additions, and fewer instructions than one sum at a time */
static inline void add_halves(double s[2], ssV2 a, ssV2 b)
{
  ssV2 v;
  memcpy(&v, s, sizeof v);
  v += (ssV2){a[0], b[0]} + (ssV2){a[1], b[1]};
  memcpy(s, &v, sizeof v);
}

/* The Jacobian's sums over the loaded points live[0, nl) of a group, into
 * A: with K = [[kn, 0, 0], [k1n, k11, k12], [k2n, k12, k22]] and the
 * point's J = [-[r]x, I], the blocks of J^T K J written out: K, K (-[r]x),
 * [r]x K and [r]x K (-[r]x).  Two points at a time, one in each half of
 * a pair of doubles (the odd one out with a zero partner, which adds
 * zeros), the halves' sums added at the end: half the arithmetic
 * instructions of a point at a time, and the same sums in another order
 * (H is Newton's Jacobian; it moves the iterates, never the check). */
static inline __attribute__((always_inline)) void h_sums(const NPoint *pt, const double *Ks,
                                                        const int *live, int nl, NSum *A)
{
  ssV2 sK[6] = {0}, vw[9] = {0}, wv[9] = {0}, ww[9] = {0};
  for (int k = 0; k < nl; k += 2) {
    /* (the offsets 6 i in size_t: formed in 64 bits at once, not in
     * int's 32 and then widened, an instruction less a point) */
    const int i = live[k];
    const double *ra = pt[i].r, *Ka = Ks + 6 * (size_t)i;
    ssV2 r0, r1, r2, kn, k1n, k2n, k11, k12, k22;
    if (k + 1 < nl) {
      const int j = live[k + 1];
      const double *rb = pt[j].r, *Kb = Ks + 6 * (size_t)j;
      r0 = (ssV2){ra[0], rb[0]};
      r1 = (ssV2){ra[1], rb[1]};
      r2 = (ssV2){ra[2], rb[2]};
      kn = (ssV2){Ka[0], Kb[0]};
      k1n = (ssV2){Ka[1], Kb[1]};
      k2n = (ssV2){Ka[2], Kb[2]};
      k11 = (ssV2){Ka[3], Kb[3]};
      k12 = (ssV2){Ka[4], Kb[4]};
      k22 = (ssV2){Ka[5], Kb[5]};
    } else {
      r0 = (ssV2){ra[0], 0};
      r1 = (ssV2){ra[1], 0};
      r2 = (ssV2){ra[2], 0};
      kn = (ssV2){Ka[0], 0};
      k1n = (ssV2){Ka[1], 0};
      k2n = (ssV2){Ka[2], 0};
      k11 = (ssV2){Ka[3], 0};
      k12 = (ssV2){Ka[4], 0};
      k22 = (ssV2){Ka[5], 0};
    }
    sK[0] += kn;
    sK[1] += k1n;
    sK[2] += k2n;
    sK[3] += k11;
    sK[4] += k12;
    sK[5] += k22;
    /* q = K (-[r]x) (its entry q00 is 0) and [r]x q, column by column:
     * a column of q and its sums, then the next, so that one column is
     * live at a time, not all of q (with the 33 sums that crowd the
     * registers, this spills less: 156 -> 148 instructions a pair);
     * each sum is the same operations as row by row */
    ssV2 q10 = k12 * r1 - k11 * r2, q20 = k22 * r1 - k12 * r2;
    vw[3] += q10;
    vw[6] += q20;
    ww[0] += r1 * q20 - r2 * q10;
    ww[3] -= r0 * q20;
    ww[6] += r0 * q10;
    ssV2 q01 = kn * r2, q11 = k1n * r2 - k12 * r0, q21 = k2n * r2 - k22 * r0;
    vw[1] += q01;
    vw[4] += q11;
    vw[7] += q21;
    ww[1] += r1 * q21 - r2 * q11;
    ww[4] += r2 * q01 - r0 * q21;
    ww[7] += r0 * q11 - r1 * q01;
    ssV2 q02 = -kn * r1, q12 = k11 * r0 - k1n * r1, q22 = k12 * r0 - k2n * r1;
    vw[2] += q02;
    vw[5] += q12;
    vw[8] += q22;
    ww[2] += r1 * q22 - r2 * q12;
    ww[5] += r2 * q02 - r0 * q22;
    ww[8] += r0 * q12 - r1 * q02;
    /* [r]x K */
    wv[0] += r1 * k2n - r2 * k1n;
    wv[1] += r1 * k12 - r2 * k11;
    wv[2] += r1 * k22 - r2 * k12;
    wv[3] += r2 * kn - r0 * k2n;
    wv[4] -= r0 * k12;
    wv[5] -= r0 * k22;
    wv[6] += r0 * k1n - r1 * kn;
    wv[7] += r0 * k11;
    wv[8] += r0 * k12;
  }
  for (int k = 0; k < 6; k += 2) add_halves(A->K + k, sK[k], sK[k + 1]);
  for (int k = 0; k < 8; k += 2) {
    add_halves(A->vw + k, vw[k], vw[k + 1]);
    add_halves(A->wv + k, wv[k], wv[k + 1]);
    add_halves(A->ww + k, ww[k], ww[k + 1]);
  }
  A->vw[8] += vw[8][0] + vw[8][1];
  A->wv[8] += wv[8][0] + wv[8][1];
  A->ww[8] += ww[8][0] + ww[8][1];
}

/* a group's H' (frame about o) from h_sums' sums */
static inline __attribute__((always_inline)) void sums_H(const NSum *A, double Hg[36])
{
  double Kv[9] = {A->K[0], 0, 0, A->K[1], A->K[3], A->K[4], A->K[2], A->K[4], A->K[5]};
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++) {
      Hg[6 * a + b] = A->ww[3 * a + b];
      Hg[6 * a + 3 + b] = A->wv[3 * a + b];
      Hg[6 * (a + 3) + b] = A->vw[3 * a + b];
      Hg[6 * (a + 3) + 3 + b] = Kv[3 * a + b];
    }
}

/* The PD rows' laws at y, lambda = clamp(a - b v, -bound, bound): F and,
 * with H, dF/dv (0 where clamped), for evaluate_at, stick_eval and
 * creep_eval */
static inline __attribute__((always_inline)) void row_laws(const ssData *d, const Setup *s,
                                                         const double *y, double *F, double *H)
{
  for (int r = 0; r < s->nrow; r++) {
    const ssContact *c = d->contact + s->first_row + r;
    int k = 6 * s->ngroup + r;
    double l = c->row_a - c->row_b * y[k], h = -c->row_b;
    if (l > c->row_bound || l < -c->row_bound) {
      l = l > 0 ? c->row_bound : -c->row_bound;
      h = 0;
    }
    F[k] = l;
    if (H) H[36 * s->ngroup + r] = h;
  }
}

/* What a form of the laws' loops knows of its material (evaluate_at,
 * check_run): nothing, linear soil, or nonlinear soil with the power's
 * series and a shear modulus; mat_form sets what the form knows in M, so
 * that the laws' tests of it compile away */
enum { FORM_ANY, FORM_LINEAR, FORM_POW_SHEAR };
static inline __attribute__((always_inline)) void mat_form(Mat *M, const int form)
{
  if (form == FORM_LINEAR) M->linear = 1;
  if (form == FORM_POW_SHEAR) {
    M->linear = 0;
    M->pser.ok = 1;
    if (!(M->rj > 0)) __builtin_unreachable();
  }
}

/* the form that knows most of material M */
static inline int form_of(const Mat *M)
{
  return M->linear ? FORM_LINEAR : M->pser.ok && M->rj > 0 ? FORM_POW_SHEAR : FORM_ANY;
}

/* F(y, mu) and H(y) = dF/dy over all contacts, the soil points' impulses
 * in lam (3 each; the rows' are their entries of F), the impulse-form
 * points' equations in ie.  H: a 6 x 6 block per group, then one value
 * per row; with_H = 0: F alone (H not touched).  Returns NEAR_STICK if
 * a velocity-form point is near sticking (point_law's NEAR), plus STUCK if one
 * sticks or an impulse-form point has no answer (the evaluation is then
 * no good). */
static inline __attribute__((always_inline)) int
evaluate_at(const ssModel *m, const ssData *d, const Setup *s, const ssNewtonWork *w,
            const double *y, double *mu, double *F, double *H, double *q,
            double *lam_out, double *restrict K_out, NImpEval *ie, const int with_H,
            const int with_imp, const int form)
{
  /* (K_out is there with H: the laws' tests of K compile away) */
  if (with_H && !K_out) __builtin_unreachable();
  memset(F, 0, (size_t)s->n * sizeof(double));
  /* each group's velocity in its frame about o; its sums in the same
   * frame: F' = (sum r x lambda; sum lambda), H' = sum J^T K J with the
   * point's J = [-[r]x, I] */
  for (int g = 0; g < s->ngroup; g++) {
    NSum *A = w->sum + g;
    memset(A, 0, sizeof *A);
    to_group(w->grp + g, y + 6 * g, A->V);
  }
  int gprev = -1, sticks = 0, near = 0, *live = w->live;
  Mat M = {0};
  for (int u = 0; u < w->nrun; u++) {
    /* a run of one group's points: their laws (impulses, and K, kept for
     * the linear end of a step: apply_linear), then their sums */
    const int i0 = w->run[u], i1 = w->run[u + 1], g = w->group_of[i0];
    NSum *A = w->sum + g;
    if (g != gprev) {
      gprev = g;
      M = w->grp[g].M;
      /* (the same values, now known where this form is compiled) */
      mat_form(&M, form);
    }
    int nl = 0;
    /* the group's velocity in a local (the laws' stores could alias the
     * sums', as the compiler sees it, and it would be loaded again at
     * every point) */
    double V[6];
    memcpy(V, A->V, sizeof V);
    for (int i = i0; i < i1; i++) {
      NPoint *P = w->pt + i;
      /* (the offsets in size_t, as in h_sums) */
      double *lam = lam_out + 3 * (size_t)i, *K = with_H ? K_out + 6 * (size_t)i : NULL;
      int st = !(with_imp && P->imp) ? point_law(&M, P, V, lam, K, 0)
                                     : imp_law(&M, P, V, mu + 2 * i, lam, K, ie + i);
      if (st == UNLOADED) continue;
      near |= st == NEAR;
      if (st == STICKS) {
        sticks = 1;
        continue;
      }
      live[nl++] = i;
      if (with_H && with_imp && P->imp) imp_eliminate(P, ie + i, w->reg, A);
    }
    /* F' = (sum r x lambda; sum lambda), point by point (in local
     * accumulators, which stay in registers) */
    double f0 = A->F[0], f1 = A->F[1], f2 = A->F[2], f3 = A->F[3], f4 = A->F[4], f5 = A->F[5];
    for (int k = 0; k < nl; k++) {
      const int i = live[k];
      /* (3 i in size_t, as in h_sums) */
      const double *r = w->pt[i].r, *lam = lam_out + 3 * (size_t)i;
      const double r0 = r[0], r1 = r[1], r2 = r[2], ln = lam[0], l1 = lam[1], l2 = lam[2];
      f0 += r1 * l2 - r2 * l1;
      f1 += r2 * ln - r0 * l2;
      f2 += r0 * l1 - r1 * ln;
      f3 += ln;
      f4 += l1;
      f5 += l2;
    }
    A->F[0] = f0;
    A->F[1] = f1;
    A->F[2] = f2;
    A->F[3] = f3;
    A->F[4] = f4;
    A->F[5] = f5;
    if (with_H) h_sums(w->pt, K_out, live, nl, A);
  }
  for (int g = 0; g < s->ngroup; g++) {
    const NSum *A = w->sum + g;
    if (!with_H) {
      from_group(w->grp + g, A->F, NULL, F + 6 * g, NULL);
      continue;
    }
    double Hg[36];
    sums_H(A, Hg);
    if (with_imp) {
      for (int k = 0; k < 36; k++) Hg[k] += A->Q[k];
      from_group(w->grp + g, A->q, NULL, q + 6 * g, NULL);
    }
    from_group(w->grp + g, A->F, Hg, F + 6 * g, H + 36 * g);
  }
  /* PD rows: lambda = clamp(a - b v, -bound, bound) */
  row_laws(d, s, y, F, with_H ? H : NULL);
  return (sticks ? STUCK : 0) | (near ? NEAR_STICK : 0);
}

/* the forms, each compiled for itself: without H, the Jacobian's work is
 * dropped at compile time, and without impulse-form points (most steps)
 * their tests and sums; on linear soil alone (the plate's) the powers'
 * code too, which would otherwise crowd the loop's registers */
static int evaluate(const ssModel *m, const ssData *d, const Setup *s,
                    const ssNewtonWork *w, const double *y, double *mu, double *F,
                    double *H, double *q, double *lam_out, double *K, NImpEval *ie)
{
  if (w->ns) return evaluate_at(m, d, s, w, y, mu, F, H, q, lam_out, K, ie, 1, 1, FORM_ANY);
  if (s->linear)
    return evaluate_at(m, d, s, w, y, mu, F, H, q, lam_out, K, ie, 1, 0, FORM_LINEAR);
  if (s->pow_shear)
    return evaluate_at(m, d, s, w, y, mu, F, H, q, lam_out, K, ie, 1, 0, FORM_POW_SHEAR);
  return evaluate_at(m, d, s, w, y, mu, F, H, q, lam_out, K, ie, 1, 0, FORM_ANY);
}

static inline __attribute__((always_inline)) int
evaluate_F(const ssModel *m, const ssData *d, const Setup *s, const ssNewtonWork *w,
           const double *y, double *mu, double *F, double *lam_out, NImpEval *ie)
{
  if (w->ns)
    return evaluate_at(m, d, s, w, y, mu, F, NULL, NULL, lam_out, NULL, ie, 0, 1, FORM_ANY);
  return s->linear
             ? evaluate_at(m, d, s, w, y, mu, F, NULL, NULL, lam_out, NULL, ie, 0, 0, FORM_LINEAR)
             : evaluate_at(m, d, s, w, y, mu, F, NULL, NULL, lam_out, NULL, ie, 0, 0, FORM_ANY);
}

/* The sweeps' measure of a solve: the largest change |law - lambda|_1 a
 * contact's law would make over the largest |lambda|_1, INFINITY if a
 * change is not finite (check and warm_check) */
typedef struct Measure {
  double dmax, lmax;
  double nf;          /* the sum of the changes' dn - dn: 0 while every
                         change is finite, NaN from the first that is not
                         (an instruction less a contact than isfinite's
                         test and flag) */
} Measure;

static inline void measure_add(Measure *q, double dn, double ln)
{
  /* not fmax: a libm call here, and it would pass over a NaN */
  q->nf += dn - dn;
  q->dmax = dn > q->dmax ? dn : q->dmax;
  q->lmax = ln > q->lmax ? ln : q->lmax;
}

static double measure_value(const Measure *q)
{
  if (!(q->nf == 0)) return INFINITY;
  return q->lmax > 0 ? q->dmax / q->lmax : 0;
}

/* A point's tangential response G_tt (2 x 2) at r, from its group's Lam'
 * (group_lam): x_k^T Lam' x_l over its tangential rows x_1, x_2 */
static void point_gtt2(const NGroup *G, const double r[3], double Gt[4])
{
  const double x[2][6] = {{-r[2], 0, r[0], 0, 1, 0}, {r[1], -r[0], 0, 0, 0, 1}};
  for (int a = 0; a < 2; a++)
    for (int b = 0; b < 2; b++) {
      double t = 0;
      for (int i = 0; i < 6; i++)
        for (int k = 0; k < 6; k++) t += x[a][i] * G->Lg[6 * i + k] * x[b][k];
      Gt[2 * a + b] = t;
    }
}

/* check's measure at an impulse-form point: the change a visit of the
 * sweeps would make to its impulse lam (held) at group velocity V, the
 * others held.  Normal: the law's impulse at v_n against the one held;
 * tangential: the natural map's value phi at the held mu, and the step
 * (d phi/d mu + d phi/d v G_tt)^-1 phi that the point's own equation
 * takes from there (G_tt: its own tangential response): 0 exactly where
 * the law holds.  INFINITY where it has no answer. */
static double imp_check(const Mat *M, NPoint *P, const NGroup *G, const double V[6],
                        const double lam[3])
{
  const double *r = P->r;
  double v[3], kn;
  point_velocity(r, V, v);
  double ln = point_normal(M, P, v[0], &kn, 1);
  if (ln < 0) ln = kn = 0;
  NImpEval ie;
  double mu[2] = {lam[1], lam[2]};
  imp_map(M, P, v + 1, ln, kn, mu, 0, &ie);
  double Gt[4], A[4];
  point_gtt2(G, r, Gt);
  for (int a = 0; a < 2; a++)
    for (int b = 0; b < 2; b++)
      A[2 * a + b] = ie.Dm[2 * a + b] + ie.Dv[2 * a] * Gt[b] + ie.Dv[2 * a + 1] * Gt[2 + b];
  double det = A[0] * A[3] - A[1] * A[2];
  if (!(det != 0)) return INFINITY;
  double d1 = (A[3] * ie.phi[0] - A[1] * ie.phi[1]) / det;
  double d2 = (A[0] * ie.phi[1] - A[2] * ie.phi[0]) / det;
  return fabs(ln - lam[0]) + fabs(d1) + fabs(d2);
}

/* check's measure of the points [i0, i1) of one run (group g, material
 * M) at their group's velocity V (frame about o).  The forms, each
 * compiled for itself as evaluate's are: without impulse-form points
 * (with_imp = 0, most solves) their test a point goes; the material's
 * tests are known where form says so (mat_form), and compile away. */
static inline __attribute__((always_inline)) void
check_run(Mat M, const ssData *d, const ssNewtonWork *w, int g, int i0, int i1,
          const double Vg[6], Measure *q, const int with_imp, const int form)
{
  mat_form(&M, form);
  double V[6];
  memcpy(V, Vg, sizeof V);
  for (int i = i0; i < i1; i++) {
    const ssContact *c = d->contact + i;
    /* the laws keep the points' memos where they are (pow_point): at
     * the last evaluation's y, so that H formed there later
     * (ss_newton_solve) is what the evaluation would have formed */
    NPoint *P = w->pt + i;
    double lam[3], dn;
    if (with_imp && P->imp) {
      dn = imp_check(&M, P, w->grp + g, V, c->lambda);
    } else {
      dn = point_law(&M, P, V, lam, NULL, 1) == STICKS
               ? INFINITY
               : fabs(lam[0] - c->lambda[0]) + fabs(lam[1] - c->lambda[1]) +
                     fabs(lam[2] - c->lambda[2]);
    }
    measure_add(q, dn, fabs(c->lambda[0]) + fabs(c->lambda[1]) + fabs(c->lambda[2]));
  }
}

/* The check of a converged Newton solve, an exact residual: with the
 * velocities u the contacts' impulses give, each contact's law at its
 * velocity against the impulse it holds (an impulse-form point: imp_check).
 * Returns max |law - lambda|_1 over max |lambda|_1 (the sweeps' measure),
 * or INFINITY if a velocity-form point sticks there or a difference is
 * not finite. */
static double check(const ssModel *m, ssData *d, const Setup *s, const ssNewtonWork *w)
{
  for (int g = 0; g < s->ngroup; g++) {
    const NGroup *G = w->grp + g;
    double V[6];
    group_motion(m, d, G, d->qvel + m->sys_vadr[G->sys], V);
    to_group(G, V, w->sum[g].V);
  }
  Measure q = {0, 0, 0};
  int gprev = -1, form = FORM_ANY;
  Mat M = {0};
  for (int u = 0; u < w->nrun; u++) {
    const int i0 = w->run[u], i1 = w->run[u + 1], g = w->group_of[i0];
    if (g != gprev) {
      gprev = g;
      M = w->grp[g].M;
      form = form_of(&M);
    }
    const double *V = w->sum[g].V;
    if (w->ns)
      check_run(M, d, w, g, i0, i1, V, &q, 1, FORM_ANY);
    else if (form == FORM_POW_SHEAR)
      check_run(M, d, w, g, i0, i1, V, &q, 0, FORM_POW_SHEAR);
    else if (form == FORM_LINEAR)
      check_run(M, d, w, g, i0, i1, V, &q, 0, FORM_LINEAR);
    else
      check_run(M, d, w, g, i0, i1, V, &q, 0, FORM_ANY);
  }
  for (int r = 0; r < s->nrow; r++) {
    const ssContact *c = d->contact + s->first_row + r;
    double v = d->jac[c->jadr + (c->dof - c->vadr)] * d->qvel[c->dof];
    double l = c->row_a - c->row_b * v;
    if (l > c->row_bound) l = c->row_bound;
    if (l < -c->row_bound) l = -c->row_bound;
    measure_add(&q, fabs(l - c->lambda[0]), fabs(c->lambda[0]));
  }
  return measure_value(&q);
}

/* The check of the warm start itself (check's measure, without a pass of
 * its own): the contacts hold the warm impulses and d->qvel the velocities
 * they give, so the first evaluation's impulses lam and row values F, the
 * laws at those velocities, are what check would compute there.  Returns
 * max |law - lambda|_1 over max |lambda|_1, or INFINITY if a difference is
 * not finite. */
static double warm_check(const ssData *d, const Setup *s, const ssNewtonWork *w)
{
  Measure q = {0, 0, 0};
  for (int i = 0; i < s->first_row; i++) {
    const double *l = d->contact[i].lambda, *law = w->lam + 3 * i;
    measure_add(&q, fabs(law[0] - l[0]) + fabs(law[1] - l[1]) + fabs(law[2] - l[2]),
                fabs(l[0]) + fabs(l[1]) + fabs(l[2]));
  }
  for (int r = 0; r < s->nrow; r++) {
    double l = d->contact[s->first_row + r].lambda[0];
    measure_add(&q, fabs(w->F[6 * s->ngroup + r] - l), fabs(l));
  }
  return measure_value(&q);
}

/* phi = y - yfree - Lam F.  Returns |phi|^2 and sets *size to |Lam F|^2,
 * both weighted by 1/Lam_kk (an energy-like norm in which linear and
 * angular velocities and the rows compare fairly); the impulse-form
 * points' equations (velocities, in ie) add theirs weighted by 1/G_tt,
 * and G_tt |mu|^2 to the size. */
static double residual(const Setup *s, const ssNewtonWork *w, const double *y,
                       const double *F, const double *mu, const NImpEval *ie,
                       double *phi, double *size)
{
  int n = s->n;
  double sum = 0, big = 0;
  /* (Lam F)_a four rows at a time, rows a, a + 1 and a + 2, a + 3 in the
   * halves of two pairs, F_b in both halves of F2[b]: each row's sum from
   * 0 in the order b = 0, 1, ... as one row at a time, with F read once
   * for four rows (the rows left over one at a time) */
  ssV2 *F2 = w->F2;
  for (int b = 0; b < n; b++) F2[b] = (ssV2){F[b], F[b]};
  for (int a = 0; a < n;) {
    const double *L = w->Lam + (size_t)a * n;
    double t[4];
    int rows = n - a >= 4 ? 4 : 1;
    if (rows == 4) {
      const double *L1 = L + n, *L2 = L1 + n, *L3 = L2 + n;
      ssV2 t01 = {0, 0}, t23 = {0, 0};
      for (int b = 0; b < n; b++) {
        t01 += (ssV2){L[b], L1[b]} * F2[b];
        t23 += (ssV2){L2[b], L3[b]} * F2[b];
      }
      t[0] = t01[0];
      t[1] = t01[1];
      t[2] = t23[0];
      t[3] = t23[1];
    } else {
      t[0] = 0;
      for (int b = 0; b < n; b++) t[0] += L[b] * F[b];
    }
    for (int r = 0; r < rows; r++, a++, L += n) {
      phi[a] = y[a] - w->yfree[a] - t[r];
      double inv = L[a] > 0 ? 1 / L[a] : 1;
      sum += phi[a] * phi[a] * inv;
      big += t[r] * t[r] * inv;
    }
  }
  for (int k = 0; k < w->ns; k++) {
    int i = w->imp[k];
    double g = w->pt[i].gtt;
    sum += (ie[i].phi[0] * ie[i].phi[0] + ie[i].phi[1] * ie[i].phi[1]) / g;
    big += g * (mu[2 * i] * mu[2 * i] + mu[2 * i + 1] * mu[2 * i + 1]);
  }
  *size = big;
  return sum;
}

/* F, H and the residual formed again at the iterate (w->y, w->mu), after
 * points went to impulse form or the regularization changed; 0 when a
 * point sticks there (the evaluation is no good) */
static int reevaluate(const ssModel *m, const ssData *d, const Setup *s, ssNewtonWork *w,
                      double *f, double *size)
{
  if (evaluate(m, d, s, w, w->y, w->mu, w->F, w->H, w->q, w->lam, w->K, w->ie) & STUCK) return 0;
  *f = residual(s, w, w->y, w->F, w->mu, w->ie, w->phi, size);
  return 1;
}

/* A = I - Lam H (the impulse-form points eliminated into H) */
static inline __attribute__((always_inline)) void newton_matrix(const Setup *s, ssNewtonWork *w,
                                                              const double *H)
{
  int n = s->n;
  for (int a = 0; a < n; a++) {
    const double *L = w->Lam + (size_t)a * n;
    double *Ar = w->A + (size_t)a * n;
    for (int g = 0; g < s->ngroup; g++) {
      /* two columns at a time (SSE2 pairs): each entry's products and
       * sums in the order of the scalar sum
       * -(L0 H0j + L1 H1j + ... + L5 H5j) */
      const double *Hg = H + 36 * g, *Lg = L + 6 * g;
      ssV2 l[6];
      for (int k = 0; k < 6; k++) l[k] = (ssV2){Lg[k], Lg[k]};
      for (int j = 0; j < 6; j += 2) {
        ssV2 h[6];
        for (int k = 0; k < 6; k++) memcpy(&h[k], Hg + 6 * k + j, sizeof h[k]);
        ssV2 t = -(l[0] * h[0] + l[1] * h[1] + l[2] * h[2] + l[3] * h[3] + l[4] * h[4] +
                   l[5] * h[5]);
        memcpy(Ar + 6 * g + j, &t, sizeof t);
      }
    }
    for (int r = 0; r < s->nrow; r++) {
      int k = 6 * s->ngroup + r;
      Ar[k] = -L[k] * H[36 * s->ngroup + r];
    }
    Ar[a] += 1;
  }
}

/* ss_lu_factor's pivot of column k: the row below k with the largest
 * |A_ik| swapped into row k, whole (multipliers included); 0 if that
 * column is zero there (singular).  (Inlined into ss_lu_factor's two
 * places: about 1 k instructions a buggy step in calls.) */
static inline __attribute__((always_inline)) int lu_pivot(double *A, int *piv, int n, int k)
{
  int p = k, i = k + 1;
  double best = fabs(A[k * n + k]);
  /* two rows a pass (the same comparisons in the same order: the first
   * largest wins), half the loop's own instructions */
  for (; i + 1 < n; i += 2) {
    double a0 = fabs(A[i * n + k]), a1 = fabs(A[(i + 1) * n + k]);
    if (a0 > best) {
      best = a0;
      p = i;
    }
    if (a1 > best) {
      best = a1;
      p = i + 1;
    }
  }
  if (i < n && fabs(A[i * n + k]) > best) {
    best = fabs(A[i * n + k]);
    p = i;
  }
  if (!(best > 0)) return 0;
  piv[k] = p;
  if (p != k)
    for (int j = 0; j < n; j++) {
      double t = A[k * n + j];
      A[k * n + j] = A[p * n + j];
      A[p * n + j] = t;
    }
  return 1;
}

/* y0 = (y0 + a0 x) + b0 z and y1 = (y1 + a1 x) + b1 z, two rows in one
 * pass over x and z (the pivot rows of two elimination steps), two lanes
 * at a time: each entry's two updates, in the order of the steps, as
 * ss_row_add_scaled makes them */
static inline void lu_rows2_steps2(double *y0, double a0, double b0, double *y1, double a1,
                                   double b1, const double *x, const double *z, int m)
{
  ssV2 av0 = {a0, a0}, bv0 = {b0, b0}, av1 = {a1, a1}, bv1 = {b1, b1};
  int r = 0;
  for (; r + 2 <= m; r += 2) {
    ssV2 xv, zv, yv0, yv1;
    memcpy(&xv, x + r, sizeof xv);
    memcpy(&zv, z + r, sizeof zv);
    memcpy(&yv0, y0 + r, sizeof yv0);
    memcpy(&yv1, y1 + r, sizeof yv1);
    yv0 += av0 * xv;
    yv0 += bv0 * zv;
    yv1 += av1 * xv;
    yv1 += bv1 * zv;
    memcpy(y0 + r, &yv0, sizeof yv0);
    memcpy(y1 + r, &yv1, sizeof yv1);
  }
  for (; r < m; r++) {
    y0[r] += a0 * x[r];
    y0[r] += b0 * z[r];
    y1[r] += a1 * x[r];
    y1[r] += b1 * z[r];
  }
}

/* one row's updates of two elimination steps, multipliers f and g, each
 * skipped where its multiplier is 0 */
static void lu_row_steps2(double *y, double f, double g, const double *x, const double *z,
                          int m)
{
  if (f != 0) ss_row_add_scaled(y, -f, x, m);
  if (g != 0) ss_row_add_scaled(y, -g, z, m);
}

/* a, b, c and d all nonzero, or else 0 where that is not sure: their
 * product is 0 or NaN where one is 0 (and NaN where one is NaN), and is
 * 0 where all are nonzero only by underflow (|p| > 0: neither).  ss_lu_factor's pair of rows
 * takes its two-row pass only where this holds, else the row by row
 * updates, which skip a zero multiplier's and give each entry the same
 * operations otherwise: one product test instead of four compares, each
 * with its parity test. */
static inline int all_nonzero4(double a, double b, double c, double d)
{
  return fabs((a * b) * (c * d)) > 0;
}

/* LU with partial pivoting of the n x n matrix A, in place; 0 if
 * singular.  Two elimination steps k, k + 1 at a time: step k's
 * multipliers, its update of column k + 1 (the next pivot's column) and
 * then of row k + 1 (the next pivot row, once swapped in: a swap moves
 * whole rows, a row's multipliers with its pending updates), step
 * k + 1's multipliers, and then the rows below in one pass for both
 * steps.  Each entry gets the updates of the one-step-at-a-time
 * elimination, y + (-f) x (which rounds as y - f x, ss_math.h), in the
 * same order, each skipped where its multiplier is 0 as there: the same
 * factors, bit for bit, with one load and store of an entry for two
 * steps. */
int ss_lu_factor(double *A, int *piv, int n)
{
  int k = 0;
  for (; k + 1 < n; k += 2) {
    if (!lu_pivot(A, piv, n, k)) return 0;
    const double *x = A + k * n;
    double inv = 1 / x[k];
    for (int i = k + 1; i < n; i++) {
      double f = A[i * n + k] * inv;
      A[i * n + k] = f;
      if (f != 0) A[i * n + k + 1] += -f * x[k + 1];
    }
    if (!lu_pivot(A, piv, n, k + 1)) return 0;
    double *z = A + (k + 1) * n;
    int len = n - k - 2;
    if (z[k] != 0) ss_row_add_scaled(z + k + 2, -z[k], x + k + 2, len);
    double inv1 = 1 / z[k + 1];
    int i = k + 2;
    for (; i + 1 < n; i += 2) {
      double *y0 = A + i * n, *y1 = y0 + n;
      double f0 = y0[k], f1 = y1[k], g0 = y0[k + 1] * inv1, g1 = y1[k + 1] * inv1;
      y0[k + 1] = g0;
      y1[k + 1] = g1;
      if (all_nonzero4(f0, g0, f1, g1)) {
        lu_rows2_steps2(y0 + k + 2, -f0, -g0, y1 + k + 2, -f1, -g1, x + k + 2, z + k + 2, len);
      } else {
        lu_row_steps2(y0 + k + 2, f0, g0, x + k + 2, z + k + 2, len);
        lu_row_steps2(y1 + k + 2, f1, g1, x + k + 2, z + k + 2, len);
      }
    }
    if (i < n) {
      double *y = A + i * n, g = y[k + 1] * inv1;
      y[k + 1] = g;
      lu_row_steps2(y + k + 2, y[k], g, x + k + 2, z + k + 2, len);
    }
  }
  /* (an odd n's last pivot: nothing below it) */
  return k == n || lu_pivot(A, piv, n, k);
}

void ss_lu_solve(const double *A, const int *piv, int n, double *x)
{
  /* the factor's rows were swapped whole, multipliers included: all the
   * swaps first, then the substitutions */
  for (int k = 0; k < n; k++)
    if (piv[k] != k) {
      double t = x[k];
      x[k] = x[piv[k]];
      x[piv[k]] = t;
    }
  /* L's substitution row by row: x_i's updates are those of the column
   * sweep (x_i -= l_ik x_k for k = 0, 1, ...), in the same order, with
   * x_i in a register and l_i read along its row.  Two rows at a time:
   * each row's sum is a chain of dependent subtractions, and the second
   * row's, which needs x_i only for its last term, runs beside the
   * first's (the same operations, in the same order, for each row) */
  int i = 1;
  for (; i + 1 < n; i += 2) {
    const double *a0 = A + i * n, *a1 = a0 + n;
    double t0 = x[i], t1 = x[i + 1];
    for (int k = 0; k < i; k++) {
      t0 -= a0[k] * x[k];
      t1 -= a1[k] * x[k];
    }
    x[i] = t0;
    x[i + 1] = t1 - a1[i] * t0;
  }
  for (; i < n; i++) {
    double t = x[i];
    for (int k = 0; k < i; k++) t -= A[i * n + k] * x[k];
    x[i] = t;
  }
  /* (U's sums start with the term of the row just solved: one row at a
   * time) */
  for (int k = n - 1; k >= 0; k--) {
    double t = x[k];
    for (int j = k + 1; j < n; j++) t -= A[k * n + j] * x[j];
    x[k] = t / A[k * n + k];
  }
}

/* Points at y that stick or come near it (point_law's STICKS, NEAR; the
 * law run again with the points' memos kept) go to impulse
 * form, from their impulse there or, sticking, their warm start's
 * (ss_solver_warm_lambda: applied or still pending).  Returns how many
 * went. */
static int switch_points(const ssModel *m, const ssData *d, const Setup *s, ssNewtonWork *w)
{
  int moved = 0, gprev = -1;
  Mat M = {0};
  for (int g = 0; g < s->ngroup; g++) to_group(w->grp + g, w->y + 6 * g, w->sum[g].V);
  for (int i = 0; i < s->first_row; i++) {
    NPoint *P = w->pt + i;
    int g = w->group_of[i];
    if (P->imp || !(w->lam[3 * i] > 0)) continue;
    if (g != gprev) {
      gprev = g;
      M = w->grp[g].M;
    }
    double lam[3], warm[3];
    int st = point_law(&M, P, w->sum[g].V, lam, NULL, 1);
    if (st != NEAR && st != STICKS) continue;
    if (st == STICKS) ss_solver_warm_lambda(m, d, i, warm);
    const double *m0 = st == STICKS ? warm + 1 : lam + 1;
    P->imp = 1;
    point_gtt(w->grp[g].gq, P);
    w->imp[w->ns++] = i;
    w->mu[2 * i] = m0[0];
    w->mu[2 * i + 1] = m0[1];
    moved++;
  }
  return moved;
}

/* After a failed line search: every loaded velocity-form point goes to
 * impulse form, from its law's impulse at y.  Returns how many went. */
static int switch_all(ssNewtonWork *w, const Setup *s)
{
  int moved = 0;
  for (int i = 0; i < s->first_row; i++) {
    NPoint *P = w->pt + i;
    const double *l = w->lam + 3 * i;
    if (P->imp || !(l[0] > 0)) continue;
    P->imp = 1;
    point_gtt(w->grp[w->group_of[i]].gq, P);
    w->imp[w->ns++] = i;
    w->mu[2 * i] = l[1];
    w->mu[2 * i + 1] = l[2];
    moved++;
  }
  return moved;
}

/* ---------------------------------------------------------------------- */
/* set-up                                                                  */

/* Lam = J P M'^-1 J^T over the unknowns, symmetric: each pair of links of
 * a system and each pair of a link or row with a joint row from the
 * factors (ss_art_link_pair, ss_art_link_dof_pair, ss_art_dof_pair),
 * formed once and mirrored; a free body's block from its Y (body_block:
 * nothing else shares its system). */
static void lam_matrix(const ssModel *m, ssData *d, const Setup *s, ssNewtonWork *w)
{
  int n = s->n, ng = s->ngroup;
  /* every entry is written below where all groups are links of one
   * system and every row is of it too (the buggy); else the blocks
   * between systems, and a free body's with the rest, are zero */
  int sys = ng > 0 ? w->grp[0].sys : s->nrow > 0 ? d->contact[s->first_row].sys : -1, full = 1;
  for (int g = 0; g < ng; g++) full &= w->grp[g].link >= 0 && w->grp[g].sys == sys;
  for (int r = 0; r < s->nrow; r++) full &= d->contact[s->first_row + r].sys == sys;
  if (!full) memset(w->Lam, 0, (size_t)n * n * sizeof(double));
  for (int gc = 0; gc < ng; gc++) {
    const NGroup *Gc = w->grp + gc;
    if (Gc->link < 0) {
      double *out = w->Lam + (size_t)(6 * gc) * n + 6 * gc;
      for (int k = 0; k < 6; k++) {
        double V[6];
        for (int i = 0; i < 6; i++) w->col[i] = Gc->Yb[6 * i + k];
        group_motion(m, d, Gc, w->col, V);
        for (int a = 0; a < 6; a++) out[(size_t)a * n + k] = V[a];
      }
      continue;
    }
    for (int gr = 0; gr <= gc; gr++) {
      const NGroup *G = w->grp + gr;
      if (G->sys != Gc->sys || G->link < 0) continue;
      double *out = w->Lam + (size_t)(6 * gr) * n + 6 * gc;
      ss_art_link_pair(m, d, G->link, Gc->link, out, n);
      if (gr == gc) continue;
      for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
          w->Lam[(size_t)(6 * gc + b) * n + 6 * gr + a] = out[(size_t)a * n + b];
    }
  }
  /* a joint row's J is sign e_dof (sign +-1: exact) */
  for (int r = 0; r < s->nrow; r++) {
    const ssContact *c = d->contact + s->first_row + r;
    int rr = 6 * ng + r;
    double sr = d->jac[c->jadr + (c->dof - c->vadr)];
    for (int g = 0; g < ng; g++) {
      const NGroup *G = w->grp + g;
      if (G->sys != c->sys || G->link < 0) continue;
      double v[6];
      ss_art_link_dof_pair(m, d, G->link, c->dof, v);
      for (int a = 0; a < 6; a++)
        w->Lam[(size_t)(6 * g + a) * n + rr] = w->Lam[(size_t)rr * n + 6 * g + a] = sr * v[a];
    }
    for (int q = 0; q <= r; q++) {
      const ssContact *e = d->contact + s->first_row + q;
      if (e->sys != c->sys) continue;
      int qq = 6 * ng + q;
      double sq = d->jac[e->jadr + (e->dof - e->vadr)];
      w->Lam[(size_t)qq * n + rr] = w->Lam[(size_t)rr * n + qq] =
          sr * sq * ss_art_dof_pair(d, c->sys, e->dof, c->dof);
    }
  }
}

/* the unknowns' values for system velocities u (all of qvel's layout) */
static void unknowns_of(const ssModel *m, const ssData *d, const Setup *s,
                        const ssNewtonWork *w, const double *u, double *y)
{
  for (int g = 0; g < s->ngroup; g++)
    group_motion(m, d, w->grp + g, u + m->sys_vadr[w->grp[g].sys], y + 6 * g);
  for (int r = 0; r < s->nrow; r++) {
    const ssContact *c = d->contact + s->first_row + r;
    y[6 * s->ngroup + r] = d->jac[c->jadr + (c->dof - c->vadr)] * u[c->dof];
  }
}

/* the articulated system of group or row k (the rows after the groups),
 * or -1 for a free body's group */
static int art_sys(const ssData *d, const Setup *s, const ssNewtonWork *w, int k)
{
  if (k >= s->ngroup) return d->contact[s->first_row + k - s->ngroup].sys;
  return w->grp[k].link >= 0 ? w->grp[k].sys : -1;
}

/* the impulses at y into the contacts, and the velocities they give:
 * u = u_free + P M'^-1 (sum J_b^T F_b + sum J_r^T lambda_r) (links and
 * joint rows: ss_art_force_apply, one solve per system) + sum Y_b F_b
 * (free bodies) */
static void apply_at(const ssModel *m, ssData *d, const Setup *s, const ssNewtonWork *w,
                     const double *lam, const double *F)
{
  d->warm_pending = 0; /* the answer replaces the warm start, applied or not */
  /* (the contacts and their count in locals: the copies' stores could
   * alias them, as the compiler sees it, and they would be loaded again
   * at every point) */
  ssContact *contact = d->contact;
  const int np = s->first_row;
  int i = 0;
  /* (two a pass: the loop's own instructions halved) */
  for (; i + 1 < np; i += 2) {
    memcpy(contact[i].lambda, lam + 3 * i, 3 * sizeof(double));
    memcpy(contact[i + 1].lambda, lam + 3 * i + 3, 3 * sizeof(double));
  }
  if (i < np) memcpy(contact[i].lambda, lam + 3 * i, 3 * sizeof(double));
  memcpy(d->qvel, d->qvel_free, (size_t)m->nv * sizeof(double));
  /* the links' and joint rows' impulses, summed on their paths, then one
   * solve a system (ss_art_force_apply) */
  int nr = s->nrow;
  for (int g = 0; g < s->ngroup; g++)
    if (w->grp[g].link >= 0) ss_art_force_add(m, d, w->grp[g].link, F + 6 * g);
  for (int r = 0; r < nr; r++) {
    ssContact *c = d->contact + s->first_row + r;
    double l = F[6 * s->ngroup + r];
    c->lambda[0] = l;
    ss_art_dof_force_add(d, c->sys, c->dof, d->jac[c->jadr + (c->dof - c->vadr)] * l);
  }
  for (int k = 0; k < s->ngroup + nr; k++) {
    int sys = art_sys(d, s, w, k), first = sys >= 0;
    for (int e = 0; e < k && first; e++) first = art_sys(d, s, w, e) != sys;
    if (first) ss_art_force_apply(m, d, sys, d->qvel + m->sys_vadr[sys]);
  }
  for (int g = 0; g < s->ngroup; g++) {
    if (w->grp[g].link >= 0) continue;
    const double *Y = w->grp[g].Yb, *Fg = F + 6 * g;
    int sys = w->grp[g].sys;
    double *u = d->qvel + m->sys_vadr[sys];
    for (int k = 0; k < m->sys_nv[sys]; k++) {
      const double *yk = Y + 6 * k;
      u[k] += yk[0] * Fg[0] + yk[1] * Fg[1] + yk[2] * Fg[2] + yk[3] * Fg[3] + yk[4] * Fg[4] +
              yk[5] * Fg[5];
    }
  }
}

static void apply(const ssModel *m, ssData *d, const Setup *s, const ssNewtonWork *w)
{
  apply_at(m, d, s, w, w->lam, w->F);
}

/* F + H dy, the sums' linear model at the end of the step dy, into out
 * (linear_end; the creeping solve's step df = F + H dy - f) */
static inline __attribute__((always_inline)) void linear_F(const Setup *s, const ssNewtonWork *w,
                                                          double *out)
{
  for (int g = 0; g < s->ngroup; g++) {
    const double *H = w->H + 36 * g, *dy = w->dy + 6 * g;
    for (int a = 0; a < 6; a++) {
      double t = w->F[6 * g + a];
      for (int b = 0; b < 6; b++) t += H[6 * a + b] * dy[b];
      out[6 * g + a] = t;
    }
  }
  for (int r = 0; r < s->nrow; r++) {
    int k = 6 * s->ngroup + r;
    out[k] = w->F[k] + w->H[36 * s->ngroup + r] * w->dy[k];
  }
}

/* The end of the step expected to end the solve, y + dy, by the laws'
 * linear model at y instead of an evaluation there: each soil point's
 * impulse lam + K X dy (0 where it was not loaded at y) and F + H dy, the
 * model the step solved exactly.  Where the model unloads a loaded point
 * (a kink within the step) it declines, INFINITY, before applying
 * anything: a clipped impulse would part the contacts' impulses from the
 * F that gives the velocities, which the check does not see.  Where
 * the step ends the solve its error is second order in dy (1e-10 and
 * less of the impulses where the step is 1e-5 of the velocities), far
 * within the check, which decides as for any answer; only where it fails
 * are the laws evaluated at y + dy.  Impulse-form points are not
 * modelled: not with them.  linear_end forms that answer into the trial
 * buffers (0 where it declines); apply_linear applies it and returns
 * check's measure of it (INFINITY where it declined). */
static inline __attribute__((always_inline)) int linear_end(const Setup *s, ssNewtonWork *w)
{
  /* (the scratch sums' V hold each group's dy, frame about o) */
  for (int g = 0; g < s->ngroup; g++) to_group(w->grp + g, w->dy + 6 * g, w->sum[g].V);
  /* (the arrays in locals: the stores to lamtry could alias w's
   * pointers, as the compiler sees it, and they would be loaded again at
   * every point) */
  const double *lam = w->lam, *Ks = w->K;
  double *lamtry = w->lamtry;
  const NPoint *pt = w->pt;
  for (int u = 0; u < w->nrun; u++) {
    const int i1 = w->run[u + 1];
    double V[6];
    memcpy(V, w->sum[w->group_of[w->run[u]]].V, sizeof V);
    for (int i = w->run[u]; i < i1; i++) {
      /* (the offsets in size_t, as in h_sums) */
      const double *l = lam + 3 * (size_t)i, *K = Ks + 6 * (size_t)i;
      double *lt = lamtry + 3 * (size_t)i, dv[3];
      if (!(l[0] > 0)) {
        lt[0] = lt[1] = lt[2] = 0;
        continue;
      }
      point_velocity(pt[i].r, V, dv);
      double ln = l[0] + K[0] * dv[0];
      /* (lamtry is left part written: declined, nothing applies it) */
      if (!(ln > 0)) return 0;
      lt[0] = ln;
      lt[1] = l[1] + K[1] * dv[0] + K[3] * dv[1] + K[4] * dv[2];
      lt[2] = l[2] + K[2] * dv[0] + K[4] * dv[1] + K[5] * dv[2];
    }
  }
  linear_F(s, w, w->Ftry);
  return 1;
}

static double apply_linear(const ssModel *m, ssData *d, const Setup *s, ssNewtonWork *w)
{
  if (!linear_end(s, w)) return INFINITY;
  apply_at(m, d, s, w, w->lamtry, w->Ftry);
  return check(m, d, s, w);
}

/* ---------------------------------------------------------------------- */
/* the start                                                               */

/* Newton's first iterate.  The warm start (solver.c) extrapolates each
 * soil point's traction; its velocities y are 1e-2 to 3e-1 from the
 * answer on the rolling buggy (relative residual, median 6e-2): points
 * enter and leave the patch, each one's load rises and falls as the wheel
 * passes, and a stiff soil turns small velocity errors into large impulse
 * errors.  The contacts' effect on the unknowns, c = y - y_free = Lam F(y)
 * (each contact link's velocity change by its impulses), sums over the
 * whole patch and changes smoothly: extrapolated from the last two steps,
 * y_0 = y_free + 2 c_1 - c_2 starts closer (median 2e-2), and the buggy
 * takes 2.34 Newton iterations a step instead of 2.72.  It is used where
 * the two steps before were both solved by Newton steps (a step whose warm
 * start stood, or that needed sweeps or points in impulse form, starts the
 * chain again) on the same unknowns; where Newton then fails, it starts
 * once more from the warm start before any sweep, so the prediction can
 * cost time but never change which steps converge. */

/* 64-bit FNV-1a step */
static uint64_t key_add(uint64_t h, long v)
{
  uint64_t u = (uint64_t)v;
  for (int k = 0; k < 8; k++) {
    h ^= (u >> (8 * k)) & 0xff;
    h *= 0x100000001b3ull;
  }
  return h;
}

/* which unknowns: the groups' links (or bodies) and beds, the rows' dofs
 * and kinds, in order; and a link's system's origin where it is not the
 * world's (its velocities are about it: a record made about another one
 * is no start) */
static uint64_t unknowns_key(const ssData *d, const Setup *s, const ssNewtonWork *w)
{
  uint64_t h = 0xcbf29ce484222325ull;
  h = key_add(h, s->ngroup);
  h = key_add(h, s->nrow);
  for (int g = 0; g < s->ngroup; g++) {
    h = key_add(h, w->grp[g].link);
    h = key_add(h, w->grp[g].body);
    h = key_add(h, w->grp[g].bed);
    if (w->grp[g].link < 0) continue;
    const double *o = ss_art_origin(d, w->grp[g].sys);
    if (o[0] == 0 && o[1] == 0 && o[2] == 0) continue;
    for (int k = 0; k < 3; k++) {
      long bits;
      memcpy(&bits, o + k, sizeof bits);
      h = key_add(h, bits);
    }
  }
  for (int r = 0; r < s->nrow; r++) {
    const ssContact *c = d->contact + s->first_row + r;
    h = key_add(h, c->dof);
    h = key_add(h, c->type);
  }
  return h;
}

/* (solver.h) */
int ss_newton_may_predict(const ssModel *m, const ssData *d)
{
  const ssNewtonRecord *r1 = d->newton_rec, *r2 = d->newton_rec + 1;
  return m->opt.terrain_warm_start && !d->solver_no_predict && !d->solver_gs_only &&
         r1->step == d->step - 1 && r2->step == d->step - 2;
}

/* y <- y_free + 2 c_1 - c_2 where the two steps before left their answers
 * for these unknowns; 1 if it did.  A cold start (terrain_warm_start off)
 * starts cold here too. */
static int predict(const ssModel *m, const ssData *d, const Setup *s, ssNewtonWork *w,
                   uint64_t key)
{
  const ssNewtonRecord *r1 = d->newton_rec, *r2 = d->newton_rec + 1;
  if (!ss_newton_may_predict(m, d) || r1->n != s->n || r2->n != s->n || r1->key != key ||
      r2->key != key)
    return 0;
  for (int a = 0; a < s->n; a++) w->y[a] = w->yfree[a] + (2 * r1->c[a] - r2->c[a]);
  return 1;
}

/* this step's answer into d->newton_rec[2], for ss_newton_keep (out of
 * line, where GCC has placed it: inlined into newton_solve it moves that
 * function's register allocation, and the F-only evaluation's loop there
 * takes an instruction more a point on the settled plate) */
static __attribute__((noinline)) void record(ssData *d, const Setup *s, const ssNewtonWork *w,
                                             uint64_t key)
{
  ssNewtonRecord *r = d->newton_rec + 2;
  if (s->n > r->cap) {
    double *c = realloc(r->c, (size_t)s->n * sizeof *c);
    if (!c) return; /* no record: the next steps start from the warm start */
    r->c = c;
    r->cap = s->n;
  }
  for (int a = 0; a < s->n; a++) r->c[a] = w->y[a] - w->yfree[a];
  r->n = s->n;
  r->key = key;
  r->step = d->step;
}

void ss_newton_keep(ssData *d)
{
  ssNewtonRecord *r = d->newton_rec;
  if (r[2].step != d->step) return;
  ssNewtonRecord t = r[1];
  r[1] = r[0];
  r[0] = r[2];
  r[2] = t;
  r[2].step = -1;
}

static int newton_solve(const ssModel *m, ssData *d, int first_row, int *iterations,
                        int *sticking, double *residual_out, int may_predict,
                        int *predicted);

int ss_newton_solve(const ssModel *m, ssData *d, int first_row, int *iterations,
                    int *sticking, double *residual_out)
{
  int predicted = 0;
  int done = newton_solve(m, d, first_row, iterations, sticking, residual_out, 1, &predicted);
  if (done || !predicted) return done;
  /* declined from the prediction: once more from the warm start */
  int spent = *iterations;
  done = newton_solve(m, d, first_row, iterations, sticking, residual_out, 0, &predicted);
  *iterations += spent;
  return done;
}

/* The set-up of the points of one run of group gr (G), from contact i
 * while the run's key holds; returns where it ends.  The group's
 * constants, the points' largest offsets and the modulus memo in locals,
 * stored into the group at the end.  Compiled for an unturned bed's axes
 * (the points' r a permutation) and for a turned one. */
static inline __attribute__((always_inline)) int
setup_run(const ssModel *m, const ssContact *contact, NPoint *pts, int *group_of, int i,
          int first_row, int gr, NGroup *G, const int axes)
{
  const double dt = m->opt.timestep;
  const ssContact *c = contact + i;
  const int run_link = c->link, run_sys = c->sys, run_bed = c->hfield;
  double rm0 = G->rmax[0], rm1 = G->rmax[1], rm2 = G->rmax[2];
  ssModulusMemo mod = G->mod;
  /* (and what its points read from the group: the point's stores
   * could alias them, as the compiler sees it) */
  const ssSoilMaterial *mat = G->mat;
  const double o0 = G->o[0], o1 = G->o[1], o2 = G->o[2], ik = G->ik, coh = mat->cohesion;
  do {
    group_of[i] = gr;
    /* the point's constants, its caches empty */
    NPoint *P = pts + i;
    double rel[3] = {c->pos[0] - o0, c->pos[1] - o1, c->pos[2] - o2};
    if (axes) {
      P->r[0] = rel[2];
      P->r[1] = rel[0];
      P->r[2] = rel[1];
    } else {
      ss_m3_mulv(P->r, G->R, rel);
    }
    P->g0 = c->g0;
    P->sp = c->sp;
    P->S = c->area * dt;
    P->k = ss_soil_modulus_at(mat, &mod, c->width);
    P->tf0 = P->S * coh;
    /* x0 = j / K_j as the sweeps' law forms it (point.c, mobil_init):
     * the same bits, and no division a point */
    P->x0 = (c->j > 0 ? c->j : 0) * ik;
    P->pw.s = 0;
    P->mob = ss_exp_memo_start(P->x0);
    P->imp = 0;
    P->gtt = -1;
    double a0 = fabs(P->r[0]), a1 = fabs(P->r[1]), a2 = fabs(P->r[2]);
    rm0 = a0 > rm0 ? a0 : rm0;
    rm1 = a1 > rm1 ? a1 : rm1;
    rm2 = a2 > rm2 ? a2 : rm2;
    c = contact + ++i;
  } while (i < first_row && c->type == SS_CONTACT_SOIL && c->link == run_link &&
           c->sys == run_sys && c->hfield == run_bed);
  G->rmax[0] = rm0;
  G->rmax[1] = rm1;
  G->rmax[2] = rm2;
  G->mod = mod;
  return i;
}

/* ---------------------------------------------------------------------- */
/* the patch-level stick solve                                             */

/* A point's tangential rows in its group's frame: v_t = X_t V' */
static void point_trows(const double r[3], double x[2][6])
{
  const double a[2][6] = {{-r[2], 0, r[0], 0, 1, 0}, {r[1], -r[0], 0, 0, 0, 1}};
  memcpy(x, a, sizeof a);
}

/* A += X^T l: a point's impulse l (n, t1, t2) at r as a spatial impulse
 * about the group's origin, (r x l; l), group frame */
static inline void wrench_add(double A[6], const double r[3], const double l[3])
{
  A[0] += r[1] * l[2] - r[2] * l[1];
  A[1] += r[2] * l[0] - r[0] * l[2];
  A[2] += r[0] * l[1] - r[1] * l[0];
  A[3] += l[0];
  A[4] += l[1];
  A[5] += l[2];
}

/* The laws for stick_solve at y: a sticking group's points (stick[g])
 * give their normal impulse alone (their tangential impulses are the
 * group's constraint wrench, added apart), the other groups' points
 * their velocity form, the rows theirs.  F (n, world) and, with H, dF/dy
 * (36 a group, one a row); lam (3 a soil point).  0 where a velocity-form
 * point sticks (no answer of that form). */
static int stick_eval(const ssData *d, const Setup *s, ssNewtonWork *w, const int *stick,
                      const double *y, double *F, double *H, double *lam)
{
  for (int g = 0; g < s->ngroup; g++) {
    NSum *A = w->sum + g;
    memset(A, 0, sizeof *A);
    to_group(w->grp + g, y + 6 * g, A->V);
  }
  for (int i = 0; i < s->first_row; i++) {
    int g = w->group_of[i];
    NSum *A = w->sum + g;
    NPoint *P = w->pt + i;
    const Mat *M = &w->grp[g].M;
    const double *r = P->r;
    double *l = lam + 3 * i, K[6] = {0};
    if (stick[g]) {
      double v[3];
      point_velocity(r, A->V, v);
      l[0] = point_normal(M, P, v[0], K, 0);
      l[1] = l[2] = 0;
      if (l[0] < 0) {
        l[0] = 0;
        continue;
      }
    } else {
      int st = point_law(M, P, A->V, l, K, 0);
      if (st == STICKS) return 0;
      if (st == UNLOADED) continue;
    }
    /* F' += X^T lam, H' += X^T K X (X: rows n, t1, t2) */
    const double x[3][6] = {{0, r[2], -r[1], 1, 0, 0},
                            {-r[2], 0, r[0], 0, 1, 0},
                            {r[1], -r[0], 0, 0, 0, 1}};
    const double Km[9] = {K[0], 0, 0, K[1], K[3], K[4], K[2], K[4], K[5]};
    for (int a = 0; a < 6; a++) A->F[a] += x[0][a] * l[0] + x[1][a] * l[1] + x[2][a] * l[2];
    if (!H) continue;
    double kx[3][6];
    for (int p = 0; p < 3; p++)
      for (int b = 0; b < 6; b++)
        kx[p][b] = Km[3 * p] * x[0][b] + Km[3 * p + 1] * x[1][b] + Km[3 * p + 2] * x[2][b];
    for (int a = 0; a < 6; a++)
      for (int b = 0; b < 6; b++)
        A->Q[6 * a + b] += x[0][a] * kx[0][b] + x[1][a] * kx[1][b] + x[2][a] * kx[2][b];
  }
  for (int g = 0; g < s->ngroup; g++)
    from_group(w->grp + g, w->sum[g].F, H ? w->sum[g].Q : NULL, F + 6 * g,
               H ? H + 36 * g : NULL);
  row_laws(d, s, y, F, H);
  return 1;
}

/* A point's bound at zero slip, T = tf m(j) (the stick test's) */
static double stick_bound(const Mat *M, const NPoint *P, double ln)
{
  return (P->tf0 + M->mu * ln) * (M->rj > 0 ? -expm1(-P->x0) : 1);
}

/* Group g's constraint wrench W' (group frame, in the span of B's k
 * columns) shared out over its loaded points (lam's normal entries > 0)
 * into their tangential impulses: with the least norm weighted by their
 * bounds T_i, lambda_t,i = T_i X_t,i mu, (sum T_i X_t,i^T X_t,i) mu = W'
 * (mu in B's span); a point past its bound is held on its rim in that
 * direction and the rest of W' shared out again over the others.
 * Returns the largest |lambda_t,i| / T_i (INFINITY where the others
 * cannot carry what is left); the loaded points go to impulse form (the
 * check's sticking law), the unloaded to velocity form. */
static double share_out(const Setup *s, ssNewtonWork *w, int g, const double *B, int k,
                        const double Wg[6], double *lam, int *clamped)
{
  const Mat *M = &w->grp[g].M;
  for (int i = 0; i < s->first_row; i++) clamped[i] = 0;
  double worst = INFINITY;
  for (int round = 0; round < 16; round++) {
    double Wr[6], Ms[36] = {0}, BMB[36], z[6], mu6[6] = {0};
    int pz[6], nfree = 0;
    memcpy(Wr, Wg, sizeof Wr);
    for (int i = 0; i < s->first_row; i++) {
      if (w->group_of[i] != g || !(lam[3 * i] > 0)) continue;
      const NPoint *P = w->pt + i;
      double Ti = stick_bound(M, P, lam[3 * i]), xr[2][6];
      point_trows(P->r, xr);
      if (clamped[i]) {
        for (int a = 0; a < 6; a++) Wr[a] -= xr[0][a] * lam[3 * i + 1] + xr[1][a] * lam[3 * i + 2];
        continue;
      }
      nfree++;
      for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
          Ms[6 * a + b] += Ti * (xr[0][a] * xr[0][b] + xr[1][a] * xr[1][b]);
    }
    if (!nfree) return INFINITY;
    for (int p = 0; p < k; p++) {
      z[p] = 0;
      for (int a = 0; a < 6; a++) z[p] += B[6 * a + p] * Wr[a];
      for (int q = 0; q < k; q++) {
        double t = 0;
        for (int a = 0; a < 6; a++)
          for (int b = 0; b < 6; b++) t += B[6 * a + p] * Ms[6 * a + b] * B[6 * b + q];
        BMB[k * p + q] = t;
      }
    }
    if (!ss_lu_factor(BMB, pz, k)) return INFINITY;
    ss_lu_solve(BMB, pz, k, z);
    for (int a = 0; a < 6; a++)
      for (int p = 0; p < k; p++) mu6[a] += B[6 * a + p] * z[p];
    int over = 0;
    worst = 0;
    for (int i = 0; i < s->first_row; i++) {
      if (w->group_of[i] != g) continue;
      NPoint *P = w->pt + i;
      double *l = lam + 3 * i;
      if (!(l[0] > 0)) {
        P->imp = 0;
        continue;
      }
      P->imp = 1;
      point_gtt(w->grp[g].gq, P);
      if (clamped[i]) continue;
      double Ti = stick_bound(M, P, l[0]), xr[2][6];
      point_trows(P->r, xr);
      l[1] = l[2] = 0;
      for (int a = 0; a < 6; a++) {
        l[1] += Ti * xr[0][a] * mu6[a];
        l[2] += Ti * xr[1][a] * mu6[a];
      }
      double nl = sqrt(l[1] * l[1] + l[2] * l[2]), ratio = nl / Ti;
      worst = ratio > worst ? ratio : worst;
      if (ratio > 1) {
        /* on its rim, a hair inside (the check's disc) */
        double sc = Ti * (1 - 1e-12) / nl;
        l[1] *= sc;
        l[2] *= sc;
        clamped[i] = 1;
        over++;
      }
    }
    if (!over) return worst;
  }
  return worst;
}

/* stick_solve's residual at (y, kappa) = x: R1 = y - yfree - Lam (F(y) +
 * E kappa), R2 = E^T y (the sticking groups' C_g y_g in their row-space
 * basis).  Returns |R|^2 weighted as residual weighs phi (1/Lam_kk; R2's
 * rows by 1/(e^T Lam e)), *size the weighted |Lam (F + E kappa)|^2; with
 * H, the Jacobian into A (N x N).  -1 where stick_eval has no answer. */
static double stick_residual(const ssData *d, const Setup *s, ssNewtonWork *w,
                             const int *stick, int nk, const double *E, const int *colg,
                             const double *x, double *F, double *H, double *lam, double *R,
                             double *A, double *size)
{
  int n = s->n, N = n + nk;
  if (!stick_eval(d, s, w, stick, x, F, H, lam)) return -1;
  /* the total impulse F + E kappa, in F */
  for (int j = 0; j < nk; j++)
    for (int k = 0; k < 6; k++) F[6 * colg[j] + k] += E[6 * j + k] * x[n + j];
  double f = 0, big = 0;
  for (int a = 0; a < n; a++) {
    const double *L = w->Lam + (size_t)a * n;
    double t = 0;
    for (int b = 0; b < n; b++) t += L[b] * F[b];
    R[a] = x[a] - w->yfree[a] - t;
    double inv = L[a] > 0 ? 1 / L[a] : 1;
    f += R[a] * R[a] * inv;
    big += t * t * inv;
  }
  for (int j = 0; j < nk; j++) {
    const double *e = E + 6 * j;
    int g = colg[j];
    double t = 0, ge = 0;
    for (int k = 0; k < 6; k++) {
      t += e[k] * x[6 * g + k];
      for (int l = 0; l < 6; l++) ge += e[k] * w->Lam[(size_t)(6 * g + k) * n + 6 * g + l] * e[l];
    }
    R[n + j] = t;
    f += t * t / (ge > 0 ? ge : 1);
  }
  *size = big;
  if (!A) return f;
  /* [[I - Lam H, -Lam E], [E^T, 0]] */
  memset(A, 0, (size_t)N * N * sizeof(double));
  for (int a = 0; a < n; a++) {
    const double *L = w->Lam + (size_t)a * n;
    double *Ar = A + (size_t)a * N;
    for (int g = 0; g < s->ngroup; g++)
      for (int j = 0; j < 6; j++) {
        double t = 0;
        for (int k = 0; k < 6; k++) t += L[6 * g + k] * H[36 * g + 6 * k + j];
        Ar[6 * g + j] = -t;
      }
    for (int r = 0; r < s->nrow; r++) {
      int k = 6 * s->ngroup + r;
      Ar[k] = -L[k] * H[36 * s->ngroup + r];
    }
    Ar[a] += 1;
    for (int j = 0; j < nk; j++) {
      double t = 0;
      for (int k = 0; k < 6; k++) t += L[6 * colg[j] + k] * E[6 * j + k];
      Ar[n + j] = -t;
    }
  }
  for (int j = 0; j < nk; j++)
    for (int k = 0; k < 6; k++) A[(size_t)(n + j) * N + 6 * colg[j] + k] = E[6 * j + k];
  return f;
}

/* An orthonormal basis (columns, in B) of the range of the symmetric 6 x 6
 * S by pivoted Gram-Schmidt on its columns, a column dropped once what is
 * left of it is below thr of the largest column; returns its rank */
static int range_basis(const double S[36], double thr, double B[36])
{
  double c[6][6], nrm[6], big = 0;
  int used[6] = {0}, k = 0;
  for (int j = 0; j < 6; j++) {
    nrm[j] = 0;
    for (int i = 0; i < 6; i++) {
      c[j][i] = S[6 * i + j];
      nrm[j] += c[j][i] * c[j][i];
    }
    big = nrm[j] > big ? nrm[j] : big;
  }
  if (!(big > 0)) return 0;
  for (; k < 6; k++) {
    int p = -1;
    double best = 0;
    for (int j = 0; j < 6; j++) {
      if (used[j]) continue;
      double t = 0;
      for (int i = 0; i < 6; i++) t += c[j][i] * c[j][i];
      if (t > best) {
        best = t;
        p = j;
      }
    }
    if (p < 0 || !(best > thr * thr * big)) break;
    used[p] = 1;
    double inv = 1 / sqrt(best);
    for (int i = 0; i < 6; i++) B[6 * i + k] = c[p][i] * inv;
    /* the others less their parts along it (twice: round-off) */
    for (int j = 0; j < 6; j++) {
      if (used[j]) continue;
      for (int pass = 0; pass < 2; pass++) {
        double t = 0;
        for (int i = 0; i < 6; i++) t += B[6 * i + k] * c[j][i];
        for (int i = 0; i < 6; i++) c[j][i] -= t * B[6 * i + k];
      }
    }
  }
  return k;
}

/* The patch-level stick solve.  Where every loaded point of a group
 * sticks, its tangential impulses are statically indeterminate and
 * Newton's impulse-form steps move them across their discs without
 * descent.  "All loaded points stick" is C V' = 0 (C: their tangential
 * rows), whose row space has rank k <= 6: stick_solve solves, by a small
 * Newton on (y, kappa), y - y_free - Lam (F_normal(y) + F_others(y) +
 * E kappa) = 0 and B^T V'_g = 0 (B: an orthonormal basis of C's row
 * space, E kappa the groups' constraint wrenches), then shares each
 * wrench out over the points (share_out) and applies and checks that
 * answer, which stands only where check passes.  Measured (2026-11-27):
 * drag.xml's rocking plate is tilted on its bed, so C has rank 5, and the
 * wrench about its tangent axes needs tangential impulses 1.5 to 220
 * times their bounds (the lever arms are the tilt's): 2 of its 30 stalled
 * steps stick whole (39 -> 28 steps at the cap in 1300); the rest are
 * creeping patches, the creeping solve's (below).  (Started cold, Newton
 * once restarted from the flat patch's three directions held, rocking
 * free: plate_arm.xml cold 478 -> 265 of 1000 steps at the cap.  The
 * creeping solve takes those steps; without the restart, none at the cap
 * either way, and cold plate_arm.xml 4.73 -> 3.77 s for 1000 steps.)
 * STICK_ITER: its Newton iterations; STICK_RANK: C's rank cut for the
 * whole patch (relative) */
#define STICK_ITER 30
#define STICK_RANK 1e-10

static int stick_solve(const ssModel *m, ssData *d, const Setup *s, ssNewtonWork *w,
                       double tol, double *res, double thr);

/* Where Newton stalled or declined in impulse form: the whole patch stuck
 * (every direction of C) */
static int stick_try(const ssModel *m, ssData *d, const Setup *s, ssNewtonWork *w, double tol,
                     double *res)
{
  return stick_solve(m, d, s, w, tol, res, STICK_RANK);
}

/* The stick solve of the groups whose loaded points are all in impulse
 * form, C's rows cut at thr.  Returns 1 with its answer applied and
 * checked within tol (*res its check), else 0 with the contacts and
 * velocities as it found them; with restart, 2 where its impulses fit
 * their bounds but the check fails, its y and shared-out impulses then
 * Newton's iterate (w->y, w->mu, the impulse-form points). */
static int stick_solve(const ssModel *m, ssData *d, const Setup *s, ssNewtonWork *w,
                       double tol, double *res, double thr)
{
  int n = s->n, ng = s->ngroup, nc = d->ncontact, nv = m->nv, Nmax = n + 6 * ng;
  size_t need = (size_t)Nmax * Nmax + 5 * (size_t)Nmax + 2 * (size_t)n +
                (36 * (size_t)ng + s->nrow) + 36 * (size_t)ng + 36 * (size_t)ng +
                3 * (size_t)nc + nv + 3 * (size_t)s->first_row;
  if (need > w->cap_stk) {
    if (!grow(&w->stk, need, sizeof(double))) return 0;
    w->cap_stk = need;
  }
  if (Nmax + 7 * ng + s->first_row > w->cap_stkpiv) {
    if (!grow(&w->stk_piv, (size_t)(Nmax + 7 * ng + s->first_row), sizeof(int))) return 0;
    w->cap_stkpiv = Nmax + 7 * ng + s->first_row;
  }
  double *A = w->stk, *x = A + (size_t)Nmax * Nmax, *xt = x + Nmax, *R = xt + Nmax,
         *Rt = R + Nmax, *dx = Rt + Nmax, *F = dx + Nmax, *Ft = F + n, *H = Ft + n,
         *E = H + 36 * ng + s->nrow, *Bs = E + 36 * ng, *save = Bs + 36 * ng,
         *lam = save + 3 * (size_t)nc + nv;
  int *piv = w->stk_piv, *colg = piv + Nmax, *stick = colg + 6 * ng,
      *clamped = stick + ng;
  /* the sticking groups: loaded points, every one in impulse form, at y;
   * each one's row space of C (its loaded points' tangential rows) */
  int nk = 0, nstick = 0;
  for (int g = 0; g < ng; g++) stick[g] = -1;
  for (int i = 0; i < s->first_row; i++) {
    int g = w->group_of[i];
    if (!(w->lam[3 * i] > 0)) continue;
    if (!w->pt[i].imp) stick[g] = 0;
    else if (stick[g] < 0) stick[g] = 1;
  }
  for (int g = 0; g < ng; g++) {
    if (stick[g] < 0) stick[g] = 0;
    if (!stick[g]) continue;
    double S[36] = {0}, T[36];
    for (int i = 0; i < s->first_row; i++) {
      if (w->group_of[i] != g || !(w->lam[3 * i] > 0)) continue;
      double xr[2][6];
      point_trows(w->pt[i].r, xr);
      for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) S[6 * a + b] += xr[0][a] * xr[0][b] + xr[1][a] * xr[1][b];
    }
    double *B = Bs + 36 * g;
    int k = range_basis(S, thr, B);
    if (!k) return 0;
    nstick++;
    /* E's columns: T^T b (world), the wrench of kappa = e_j */
    group_T(w->grp + g, T);
    for (int j = 0; j < k; j++, nk++) {
      colg[nk] = g;
      for (int a = 0; a < 6; a++) {
        double t = 0;
        for (int c = 0; c < 6; c++) t += T[6 * c + a] * B[6 * c + j];
        E[6 * nk + a] = t;
      }
    }
    piv[Nmax + 6 * ng + g] = k;
  }
  if (!nstick) return 0;
  int N = n + nk;
  /* from Newton's iterate, kappa its tangential wrench's part in each row
   * space (all of it: the impulse-form points' wrench lies there) */
  memcpy(x, w->y, (size_t)n * sizeof(double));
  for (int j = 0; j < nk; j++) {
    int g = colg[j];
    double Wt[6] = {0};
    for (int i = 0; i < s->first_row; i++) {
      if (w->group_of[i] != g) continue;
      double xr[2][6];
      point_trows(w->pt[i].r, xr);
      for (int a = 0; a < 6; a++) Wt[a] += xr[0][a] * w->lam[3 * i + 1] + xr[1][a] * w->lam[3 * i + 2];
    }
    /* j's column of B: j less the group's first column */
    int j0 = j;
    while (j0 > 0 && colg[j0 - 1] == g) j0--;
    const double *B = Bs + 36 * g;
    double t = 0;
    for (int a = 0; a < 6; a++) t += B[6 * a + (j - j0)] * Wt[a];
    x[n + j] = t;
  }
  double size, f = stick_residual(d, s, w, stick, nk, E, colg, x, F, H, lam, R, A, &size);
  int it = 0;
  for (; it < STICK_ITER && f >= 0; it++) {
    if (f <= 1e-28 * size) break;
    if (!ss_lu_factor(A, piv, N)) {
      f = -2;
      break;
    }
    for (int a = 0; a < N; a++) dx[a] = -R[a];
    ss_lu_solve(A, piv, N, dx);
    double alpha = 1, ft = -1, st;
    int ok = 0;
    for (int ls = 0; ls < 12 && !ok; ls++, alpha *= 0.5) {
      for (int a = 0; a < N; a++) xt[a] = x[a] + alpha * dx[a];
      ft = stick_residual(d, s, w, stick, nk, E, colg, xt, Ft, NULL, lam, Rt, NULL, &st);
      ok = ft >= 0 && ft <= (1 - 1e-4 * alpha) * f;
    }
    if (!ok) break;
    memcpy(x, xt, (size_t)N * sizeof(double));
    f = stick_residual(d, s, w, stick, nk, E, colg, x, F, H, lam, R, A, &size);
  }
  if (!(f >= 0)) return 0;
  /* F at x: the normal and velocity-form impulses (lam), then each sticking
   * group's wrench W' = B kappa shared out over its loaded points with the
   * least norm weighted by their bounds at zero slip (T_i = tf m(j)):
   * lambda_t,i = T_i X_t,i mu, (sum T_i X_t,i^T X_t,i) mu = W', mu in
   * the row space */
  stick_eval(d, s, w, stick, x, F, NULL, lam);
  double worst = 0;
  for (int g = 0, j0 = 0; g < ng; g++) {
    if (!stick[g]) continue;
    int k = piv[Nmax + 6 * ng + g];
    const double *B = Bs + 36 * g;
    double Wg[6] = {0};
    for (int a = 0; a < 6; a++)
      for (int j = 0; j < k; j++) Wg[a] += B[6 * a + j] * x[n + j0 + j];
    double r = share_out(s, w, g, B, k, Wg, lam, clamped);
    worst = r > worst ? r : worst;
    j0 += k;
  }
  if (!(worst <= 1)) return 0;
  /* the groups' F from the shared-out impulses (what apply gives the
   * velocities), the rows' from stick_eval */
  for (int g = 0; g < ng; g++) {
    if (!stick[g]) continue;
    double Fg[6] = {0};
    for (int i = 0; i < s->first_row; i++) {
      if (w->group_of[i] != g) continue;
      wrench_add(Fg, w->pt[i].r, lam + 3 * i);
    }
    from_group(w->grp + g, Fg, NULL, F + 6 * g, NULL);
  }
  for (int g = 0; g < ng; g++)
    if (!stick[g])
      for (int i = 0; i < s->first_row; i++)
        if (w->group_of[i] == g) w->pt[i].imp = 0;
  /* applied and checked; the state as found where the check fails */
  for (int i = 0; i < nc; i++) memcpy(save + 3 * i, d->contact[i].lambda, 3 * sizeof(double));
  memcpy(save + 3 * (size_t)nc, d->qvel, (size_t)nv * sizeof(double));
  int pending = d->warm_pending, ns = w->ns;
  w->ns = 1;
  apply_at(m, d, s, w, lam, F);
  double r = check(m, d, s, w);
  if (r <= tol) {
    *res = r;
    return 1;
  }
  w->ns = ns;
  for (int i = 0; i < nc; i++) memcpy(d->contact[i].lambda, save + 3 * i, 3 * sizeof(double));
  memcpy(d->qvel, save + 3 * (size_t)nc, (size_t)nv * sizeof(double));
  d->warm_pending = pending;
  return 0;
}

/* The trial point becomes the iterate: y, F, H, K and lam swapped with
 * their trial buffers */
static inline void take_trial(ssNewtonWork *w)
{
  double *t;
  t = w->y; w->y = w->ytry; w->ytry = t;
  t = w->F; w->F = w->Ftry; w->Ftry = t;
  t = w->H; w->H = w->Htry; w->Htry = t;
  t = w->K; w->K = w->Ktry; w->Ktry = t;
  t = w->lam; w->lam = w->lamtry; w->lamtry = t;
}

/* The Newton phase's set-up for contacts [0, first_row) (soil points on
 * articulated links or free bodies) and [first_row, ncontact) (PD rows):
 * the groups, their points' constants, Lam and the groups' frames and
 * laws.  NULL where the contacts do not suit it (or out of memory). */
static inline __attribute__((always_inline)) ssNewtonWork *setup(const ssModel *m, ssData *d,
                                                                    int first_row, Setup *sp)
{
  if (first_row == 0) return NULL;
  /* suited: soil points on articulated links or free bodies (checked
   * where each run of one link or body on one bed starts, below), PD
   * rows */
  int ngroup = 0, nrow = d->ncontact - first_row;
  for (int i = first_row; i < d->ncontact; i++)
    if (!(d->contact[i].type == SS_CONTACT_PD && d->contact[i].nv > 0)) return NULL;
  ssNewtonWork *w = work(d, 0, d->ncontact, m->nv, 0);
  if (!w) return NULL;
  /* groups: one per link (or body) and bed (a link's contacts may come in
   * several runs); every point of a bed shares the bed's frame (the
   * bed's axes, terrain.c's frame_from_bed: the same bits for all its
   * points of a step), so it is compared only where a run starts.  A run
   * at a time: its group found, then its points while the key holds
   * (setup_run). */
  const double dt = m->opt.timestep;
  const ssContact *contact = d->contact;
  NPoint *pts = w->pt;
  int *group_of = w->group_of;
  int nrun = 0;
  for (int i = 0; i < first_row;) {
    const ssContact *c = contact + i;
    if (c->type != SS_CONTACT_SOIL) return NULL;
    w->run[nrun++] = i;
    if (!(c->nv > 0 && (c->link >= 0 || (c->nv == 6 && m->sys_type[c->sys] == SS_SYS_FREE))))
      return NULL;
    int gr = 0;
    while (gr < ngroup && !(w->grp[gr].link == c->link && w->grp[gr].sys == c->sys &&
                           w->grp[gr].mat == &m->hfield_soilmat[c->hfield]))
      gr++;
    if (gr == w->cap_g && !work(d, 0, 0, 0, 2 * gr + 4)) return NULL;
    NGroup *G = w->grp + gr;
    if (gr == ngroup) {
      ngroup++;
      G->link = c->link;
      G->sys = c->sys;
      G->body = c->link >= 0 ? c->link : m->geom_body[c->geom];
      G->bed = c->hfield;
      G->mat = &m->hfield_soilmat[c->hfield];
      G->pt = ss_solver_pow_table(m, d, c->hfield);
      G->ik = ss_soil_janosi_inverse(G->mat);
      G->mod.b = NAN;
      memcpy(G->R, c->frame, sizeof G->R);
      G->axes = c->bed_axes;
      memcpy(G->o, c->pos, sizeof G->o);
      ss_v3_sub(G->oref, G->o,
                c->link < 0 ? d->body_xipos + 3 * G->body : ss_art_origin(d, c->sys));
      G->rmax[0] = G->rmax[1] = G->rmax[2] = 0;
      if (c->link < 0) body_block(m, d, G->body, G->Yb);
    } else if (memcmp(G->R, c->frame, sizeof G->R)) {
      return NULL;
    }
    i = G->axes ? setup_run(m, contact, pts, group_of, i, first_row, gr, G, 1)
                : setup_run(m, contact, pts, group_of, i, first_row, gr, G, 0);
  }
  w->run[nrun] = first_row;
  w->nrun = nrun;
  int n = 6 * ngroup + nrow;
  if (!work(d, n, 0, 0, ngroup)) return NULL;
  Setup s = {ngroup, nrow, n, first_row, 1, 1};
  for (int g = 0; g < ngroup; g++) s.linear &= w->grp[g].mat->sinkage_exponent == 1.0;

  lam_matrix(m, d, &s, w);
  /* the stick test's G_tt, from each group's diagonal block of Lam: the
   * quadratics that give a point's, and their bound over the group */
  for (int g = 0; g < ngroup; g++) {
    double Lb[36];
    group_frame(w->grp + g);
    for (int a = 0; a < 6; a++)
      for (int k = 0; k < 6; k++) Lb[6 * a + k] = w->Lam[(size_t)(6 * g + a) * n + 6 * g + k];
    group_lam(w->grp + g, Lb, w->grp[g].Lg);
    slip_quadratics(w->grp[g].Lg, w->grp[g].gq);
    w->grp[g].gmax = slip_bound(w->grp[g].gq, w->grp[g].rmax);
    w->grp[g].M = mat_of(w->grp + g, dt);
    const Mat *M = &w->grp[g].M;
    s.pow_shear &= form_of(M) == FORM_POW_SHEAR;
  }
  *sp = s;
  return w;
}

static int newton_solve(const ssModel *m, ssData *d, int first_row, int *iterations,
                        int *sticking, double *residual_out, int may_predict,
                        int *predicted)
{
  *iterations = 0;
  *sticking = 0;
  *residual_out = INFINITY;
  Setup s;
  ssNewtonWork *w = setup(m, d, first_row, &s);
  if (!w) return 0;
  const int ngroup = s.ngroup, n = s.n;
  unknowns_of(m, d, &s, w, d->qvel_free, w->yfree);
  uint64_t key = unknowns_key(d, &s, w);
  int from_last = *predicted = may_predict && predict(m, d, &s, w, key);
  if (!from_last) {
    /* from the warm start: its impulses and velocities (solver.c applies
     * them only now, where a solve starts from them) */
    ss_solver_warm_apply(m, d);
    unknowns_of(m, d, &s, w, d->qvel, w->y);
  }
  /* Newton with backtracking on |phi|^2, until |phi| is within ten times
   * the solver's tolerance of the contacts' effect |Lam F| (both weighted,
   * see residual); then the answer is applied and checked against every
   * contact's law (check), which decides, and Newton goes on while the
   * check fails.  (Trying the check at 10 tol saves the last iteration in
   * about a sixth of the buggy's steps, for a failed check in 3 %.)  The
   * step that Newton's rate expects to end the solve is applied by the
   * laws' linear model and checked at once, without evaluating the laws
   * at its end first (apply_linear): where its check passes (the rolling
   * buggy: 188 of 200 steps, tests/test_buggy.c) that evaluation is saved;
   * where it declines or its check fails, the loop goes on as without it
   * (after a failed check the contacts and d->qvel hold that answer, as
   * after any failed check).  The
   * contacts and d->qvel are untouched until an answer is applied. */
  const double tol = m->opt.solver_tolerance, tol2 = tol * tol, try2 = 100 * tol2;
  double size, size_try;
  /* After a step that needed no Newton step the warm start usually
   * passes the check at once, and H would go unused: it is then formed
   * only when a step needs it, by a second pass at the same y (into the
   * trial buffers, F and lam kept). */
  int have_H = !w->settled;
  w->settled = 0;
  w->ns = 0;
  w->reg = IMP_REG;
  int st = have_H ? evaluate(m, d, &s, w, w->y, w->mu, w->F, w->H, w->q, w->lam, w->K, w->ie)
                  : evaluate_F(m, d, &s, w, w->y, w->mu, w->F, w->lam, w->ie);
  /* points that stick or nearly so at the start: impulse form */
  if (st && switch_points(m, d, &s, w)) {
    st = evaluate(m, d, &s, w, w->y, w->mu, w->F, w->H, w->q, w->lam, w->K, w->ie);
    have_H = 1;
  }
  if (st & STUCK) return 0;
  int limit = w->ns ? 2 * MAX_ITER : MAX_ITER;
  double f = residual(&s, w, w->y, w->F, w->mu, w->ie, w->phi, &size);
  int it = 0, stalled = 0, rescued = 0;
  double rel_prev = 0;
  for (;;) {
    if (f <= try2 * size || stalled || it >= limit) {
      /* stalled far from the answer (a patch near sticking, where the
       * velocity form is nearly set-valued): the stick solve, else the
       * sweeps from the warm start.  Velocity-form points alone there (a
       * cold start on a plate that has come to rest: Newton crawls
       * towards a stick it cannot reach in that form) go to impulse form
       * first, as after a failed line search, so that the stick solve
       * can take their patch */
      int far = f > tol2 * size && !(f <= tol * size);
      if (far) {
        if (!w->ns) {
          if (!(switch_all(w, &s) && reevaluate(m, d, &s, w, &f, &size))) break;
          have_H = 1;
        }
        if (!stick_try(m, d, &s, w, tol, residual_out)) break;
        *iterations = it;
        *sticking = w->ns;
        return 1;
      } else {
        /* the warm start may stand as it is (a settled body): then
         * neither the apply nor check's pass is needed, and w->lam holds
         * the laws' impulses at its velocities (ss_newton_law) */
        if (!from_last && it == 0 && w->ns == 0 &&
            (*residual_out = warm_check(d, &s, w)) <= tol) {
          w->settled = 1;
          return 2;
        }
        apply(m, d, &s, w);
        *residual_out = check(m, d, &s, w);
        if (*residual_out > tol && (stalled || it >= limit) && w->ns)
          stick_try(m, d, &s, w, tol, residual_out);
      }
      if (*residual_out <= tol || stalled || it >= limit) {
        *iterations = it;
        *sticking = w->ns;
        w->settled = it == 0 && w->ns == 0;
        if (*residual_out <= tol && it > 0 && w->ns == 0) record(d, &s, w, key);
        return 1;
      }
    }
    if (!have_H) {
      if (evaluate(m, d, &s, w, w->y, w->mu, w->Ftry, w->H, w->q, w->lamtry, w->K, w->ietry) &
          STUCK)
        return 0;
      have_H = 1;
    }
    it++;
    newton_matrix(&s, w, w->H);
    if (!ss_lu_factor(w->A, w->piv, n)) {
      stalled = 1;
      continue;
    }
    /* (I - Lam H) dy = -phi + Lam q, then each impulse-form point's dmu */
    for (int a = 0; a < n; a++) {
      double t = -w->phi[a];
      if (w->ns) {
        const double *L = w->Lam + (size_t)a * n;
        for (int b = 0; b < 6 * ngroup; b++) t += L[b] * w->q[b];
      }
      w->dy[a] = t;
    }
    ss_lu_solve(w->A, w->piv, n, w->dy);
    for (int k = 0; k < w->ns; k++) {
      int i = w->imp[k];
      double dV[6];
      to_group(w->grp + w->group_of[i], w->dy + 6 * w->group_of[i], dV);
      imp_step(w->pt + i, w->ie + i, w->reg, dV, w->dmu + 2 * i);
    }
    /* the trials' eliminations (the next step's) relax the regularization
     * again */
    double reg_step = w->reg;
    if (w->reg > IMP_REG) w->reg = fmax(IMP_REG, IMP_REG_DOWN * w->reg);
    /* Newton's rate, rel' = C rel^2 (rel = sqrt(f / size); C from the
     * last step, 1 before it): a step expected to end well within the
     * convergence test forms no H at its trials (it would go unused); the
     * loop's top forms it if a step follows after all */
    double rel = sqrt(f / size);
    double rate = rel_prev > 0 ? rel / (rel_prev * rel_prev) : 1;
    int trial_H = !(rate * rel * rel <= tol);
    rel_prev = rel;
    double alpha = 1, ftry = f, *t;
    int ok = 0, fl = 0;
    for (int ls = 0; ls < 8 && !ok; ls++, alpha *= 0.5) {
      for (int a = 0; a < n; a++) w->ytry[a] = w->y[a] + alpha * w->dy[a];
      for (int k = 0; k < w->ns; k++) {
        int i = w->imp[k];
        w->mutry[2 * i] = w->mu[2 * i] + alpha * w->dmu[2 * i];
        w->mutry[2 * i + 1] = w->mu[2 * i + 1] + alpha * w->dmu[2 * i + 1];
      }
      if (ls == 0 && !trial_H && !w->ns && !d->solver_no_linear_end) {
        /* the step expected to end the solve: its end by the laws'
         * linear model, applied and checked; the laws are evaluated
         * there only if the check fails (apply_linear) */
        double res = apply_linear(m, d, &s, w);
        if (res <= tol) {
          t = w->y; w->y = w->ytry; w->ytry = t;
          *residual_out = res;
          *iterations = it;
          *sticking = 0;
          record(d, &s, w, key);
          d->stats.newton_linear = 1;
          return 1;
        }
      }
      /* a trial that makes a point stick is no descent either */
      fl = trial_H ? evaluate(m, d, &s, w, w->ytry, w->mutry, w->Ftry, w->Htry, w->qtry,
                              w->lamtry, w->Ktry, w->ietry)
                   : evaluate_F(m, d, &s, w, w->ytry, w->mutry, w->Ftry, w->lamtry, w->ietry);
      if (fl & STUCK) continue;
      ftry = residual(&s, w, w->ytry, w->Ftry, w->mutry, w->ietry, w->phitry, &size_try);
      ok = ftry <= (1 - 1e-4 * alpha) * f;
    }
    /* no descent: a kink Newton cannot cross, or round-off.  Once, where
     * velocity-form points are left, all go to impulse form (a patch
     * creeping near sticking, whose slip directions are too sensitive for
     * the velocity form even below IMP_RATIO) and Newton tries again. */
    if (!ok && !rescued) {
      rescued = 1;
      if (switch_all(w, &s) && reevaluate(m, d, &s, w, &f, &size)) {
        have_H = 1;
        limit = 2 * MAX_ITER;
        continue;
      }
    }
    /* no descent in impulse form: the same point again with the
     * impulse-form points damped more (IMP_REG_UP) */
    if (!ok && w->ns && reg_step < IMP_REG_MAX && f <= IMP_REG_NEAR * IMP_REG_NEAR * size) {
      w->reg = reg_step * IMP_REG_UP;
      if (reevaluate(m, d, &s, w, &f, &size)) {
        have_H = 1;
        continue;
      }
    }
    if (!ok) {
      stalled = 1;
      continue;
    }
    take_trial(w);
    t = w->q; w->q = w->qtry; w->qtry = t;
    t = w->phi; w->phi = w->phitry; w->phitry = t;
    t = w->mu; w->mu = w->mutry; w->mutry = t;
    NImpEval *te = w->ie;
    w->ie = w->ietry;
    w->ietry = te;
    f = ftry;
    size = size_try;
    have_H = trial_H;
    /* points that came near sticking: impulse form from here on (their
     * mu at the trial were their law's, so the swap above kept them) */
    if ((fl & NEAR_STICK) && switch_points(m, d, &s, w)) {
      if (!reevaluate(m, d, &s, w, &f, &size)) break;
      have_H = 1;
      /* and up to 2 MAX_ITER iterations in all to settle them */
      limit = 2 * MAX_ITER;
    }
  }
  *iterations = it;
  *sticking = w->ns;
  return 0;
}

/* ---------------------------------------------------------------------- */
/* the creeping solve                                                      */

/* A patch that creeps (its points slip at 1e-6 m/s and less, most at
 * their full Janosi bound, and where its body rocks or turns some slip
 * one way and some the other about a row of stuck points) is neither
 * stuck whole (stick_solve: no sharing of its wrench stays within the
 * points' bounds) nor slipping everywhere, and the impulse form stalls
 * on it; the sweeps contract by about 0.998 a sweep there (drag.xml's
 * step 1159: 11 338 sweeps to the tolerance).
 *
 * Yet with each point's shear bound held at its normal impulse the step
 * is the minimum of a convex function.  Let f be the impulses in the
 * unknowns' space (F's: 6 a group, one a row) and y = y_free + Lam f.
 * The laws are gradients, F(y) = -grad Psi(y) with Psi convex (the
 * normal law non-increasing in v_n, the shear law -T(|v_t|) v_t/|v_t| the
 * gradient of the integral of T, T non-decreasing, with a kink at zero
 * slip; a PD row's impulse non-increasing in its velocity), so
 *
 *   E(f) = 1/2 f^T Lam f + Psi(y_free + Lam f)
 *
 * is convex (Lam = J Y J^T is positive semidefinite), with grad E =
 * Lam (f - F(y)) = -phi: its minima are the step's answers, and no
 * inverse of Lam is needed (it is singular where links outnumber the
 * dofs, the buggy's).  Newton's step dy of the phase, (I - Lam H) dy =
 * -phi, is E's Newton step df = F - f + H dy (Lam df = dy), and E's slope
 * along it is (f - F(y))^T dy < 0.
 *
 * The kink is smoothed, |v_t| -> (|v_t|^2 + eps^2)^(1/2), and Newton with
 * a line search on that slope (monotone along the line) runs at eps
 * falling by CREEP_EPS_STEP a level, each from the last one's answer
 * (continuation), down to an eps below which a point's sweep visit sticks
 * it and moves its impulse by less than CREEP_FINAL times the tolerance
 * (eps / G_tt's least eigenvalue, its own response).  The shear bound's
 * dependence on lambda_n (tf = A dt c + mu lambda_n: there the law is not
 * a gradient) is kept in H and seen by the line search.  At the last eps
 * the stuck points' stiffness T/eps turns the last bits of y into noise
 * in phi that no y removes; the last step is applied by the laws' linear
 * model (linear_end), whose impulses hold what y cannot, and the sweeps
 * that follow check that answer with their own measure and tolerance. */

/* eps starts at this fraction of the largest slip and falls by
 * CREEP_EPS_STEP a level */
#define CREEP_EPS_START 0.1
#define CREEP_EPS_STEP 1e-2
/* Newton steps of one level at most (the last level: twice that) */
#define CREEP_ITER 16
/* an intermediate level is done when |phi| is within this fraction of
 * |Lam F| (residual's weights) */
#define CREEP_LEVEL_TOL 1e-6
/* the last eps: this fraction of the tolerance times the largest impulse
 * times the least of the points' tangential responses; and the last
 * level's |phi|: this fraction of the tolerance of |Lam F| */
#define CREEP_FINAL 1e-2
/* the last level's answer goes to the linear end only when |phi| is
 * within this fraction of |Lam F| there */
#define CREEP_LINEAR_TOL 1e-4
/* line search: a step is taken where the slope is at most this fraction
 * of its first value's size (a Wolfe curvature test: convex along the
 * line, E fell) */
#define CREEP_WOLFE 0.5
#define CREEP_SEARCH 30
/* a level whose |phi| has not halved in this many full Newton steps is
 * done: as close as y holds it (its best iterate kept) */
#define CREEP_STALL 3
/* a solve gives up after this many passes over the points: its answers
 * take 60 to 470 (cold plate_arm.xml: median 129, 95 % within 184), and
 * where it does not find one (a turning buggy's patches) it went on to
 * 1400 */
#define CREEP_PASSES 400

/* the smoothed law of point P at its group's velocity V: lam and K (the
 * 6 entries of point_law), and its slip |v_t| (unsmoothed); 0 where
 * unloaded (lam = 0) */
static int creep_point(const Mat *M, NPoint *P, const double V[6], double eps, double lam[3],
                       double K[6], double *slip)
{
  double v[3], kn;
  point_velocity(P->r, V, v);
  double ln = point_normal(M, P, v[0], &kn, 1);
  *slip = sqrt(v[1] * v[1] + v[2] * v[2]);
  if (ln < 0) {
    lam[0] = lam[1] = lam[2] = 0;
    memset(K, 0, 6 * sizeof(double));
    return 0;
  }
  double s = sqrt(v[1] * v[1] + v[2] * v[2] + eps * eps), tf = P->tf0 + M->mu * ln;
  double mob = 1, e = 0;
  if (M->rj > 0) {
    mob = -expm1(-(P->x0 + M->rj * s));
    e = 1 - mob;
  }
  double T = tf * mob;
  lam[0] = ln;
  K[0] = kn;
  if (!(s > 0) || !(T > 0)) {
    lam[1] = lam[2] = 0;
    K[1] = K[2] = K[3] = K[4] = K[5] = 0;
    return 1;
  }
  /* d lam_t / d v_t = -(T/s)(I - t t^T) - tf m' t t^T (t = v_t / s, |t| < 1
   * by the smoothing), d lam_t / d v_n through tf */
  double is = 1 / s, t1 = v[1] * is, t2 = v[2] * is;
  double a = T * is, b = tf * e * M->rj, tn = M->mu * mob * kn;
  lam[1] = -T * t1;
  lam[2] = -T * t2;
  K[1] = -t1 * tn;
  K[2] = -t2 * tn;
  K[3] = -a * (1 - t1 * t1) - b * t1 * t1;
  K[4] = (a - b) * t1 * t2;
  K[5] = -a * (1 - t2 * t2) - b * t2 * t2;
  return 1;
}

/* The smoothed laws at y: F (n, world), H (36 a group, one a row), each
 * point's lam and K; *lmax the largest |lam|_1, *smax the largest slip */
static void creep_eval(const ssData *d, const Setup *s, ssNewtonWork *w, const double *y,
                       double eps, double *F, double *H, double *lam, double *K, double *lmax,
                       double *smax)
{
  double lm = 0, sm = 0;
  for (int g = 0; g < s->ngroup; g++) {
    NSum *A = w->sum + g;
    memset(A, 0, sizeof *A);
    to_group(w->grp + g, y + 6 * g, A->V);
  }
  for (int u = 0; u < w->nrun; u++) {
    const int i0 = w->run[u], i1 = w->run[u + 1], g = w->group_of[i0];
    NSum *A = w->sum + g;
    const Mat *M = &w->grp[g].M;
    int nl = 0;
    for (int i = i0; i < i1; i++) {
      NPoint *P = w->pt + i;
      double *l = lam + 3 * i, sv;
      if (!creep_point(M, P, A->V, eps, l, K + 6 * i, &sv)) continue;
      w->live[nl++] = i;
      double lv = fabs(l[0]) + fabs(l[1]) + fabs(l[2]);
      sm = sv > sm ? sv : sm;
      lm = lv > lm ? lv : lm;
      /* F' += X^T lam */
      wrench_add(A->F, P->r, l);
    }
    h_sums(w->pt, K, w->live, nl, A);
  }
  for (int g = 0; g < s->ngroup; g++) {
    double Hg[36];
    sums_H(w->sum + g, Hg);
    from_group(w->grp + g, w->sum[g].F, Hg, F + 6 * g, H + 36 * g);
  }
  row_laws(d, s, y, F, H);
  *lmax = lm;
  *smax = sm;
}

/* the impulses the contacts hold, in the unknowns' space (F's form) */
static void held_impulses(const ssData *d, const Setup *s, ssNewtonWork *w, double *f)
{
  for (int g = 0; g < s->ngroup; g++) memset(w->sum[g].F, 0, sizeof w->sum[g].F);
  for (int i = 0; i < s->first_row; i++)
    wrench_add(w->sum[w->group_of[i]].F, w->pt[i].r, d->contact[i].lambda);
  for (int g = 0; g < s->ngroup; g++) from_group(w->grp + g, w->sum[g].F, NULL, f + 6 * g, NULL);
  for (int r = 0; r < s->nrow; r++) f[6 * s->ngroup + r] = d->contact[s->first_row + r].lambda[0];
}

/* the least tangential response (G_tt's least eigenvalue) over the loaded
 * points (lam[0] > 0) */
static double least_response(const Setup *s, const ssNewtonWork *w, const double *lam)
{
  double gmin = INFINITY;
  for (int i = 0; i < s->first_row; i++) {
    if (!(lam[3 * i] > 0)) continue;
    double Gt[4];
    point_gtt2(w->grp + w->group_of[i], w->pt[i].r, Gt);
    double tr = Gt[0] + Gt[3], det = Gt[0] * Gt[3] - Gt[1] * Gt[2];
    double disc = sqrt(fmax(0, 0.25 * tr * tr - det));
    gmin = fmin(gmin, 0.5 * tr - disc);
  }
  return gmin;
}

static double dotn(const double *a, const double *b, int n)
{
  double t = 0;
  for (int k = 0; k < n; k++) t += a[k] * b[k];
  return t;
}

/* the creeping solve's scratch: f at y, its trial and step, the best
 * iterate */
typedef struct Creep {
  double *f, *ft, *df, *yb, *fb;
  int count;
} Creep;

/* Newton at one eps from (w->y, c->f), with w->F, w->H, w->lam, w->K at
 * w->y on entry, at most iters steps, until |phi|^2 <= tol2 |Lam F|^2 or a
 * stall.  On return (w->y, c->f) is the best iterate and the arrays are
 * at it.  Returns 0, or -1 where a step is no descent or the matrix is
 * singular. */
static int creep_level(const ssData *d, const Setup *s, ssNewtonWork *w, Creep *c, double eps,
                       double tol2, int iters)
{
  const int n = s->n;
  double lm, sm, size, res = residual(s, w, w->y, w->F, NULL, NULL, w->phi, &size);
  double best = res, mark = res;
  int since = 0, at_best = 1;
  memcpy(c->yb, w->y, (size_t)n * sizeof(double));
  memcpy(c->fb, c->f, (size_t)n * sizeof(double));
  for (int it = 0; it < iters && !(res <= tol2 * size); it++) {
    if (c->count >= CREEP_PASSES) return -1;
    newton_matrix(s, w, w->H);
    if (!ss_lu_factor(w->A, w->piv, n)) return -1;
    for (int a = 0; a < n; a++) w->dy[a] = -w->phi[a];
    ss_lu_solve(w->A, w->piv, n, w->dy);
    /* df = F + H dy - f */
    linear_F(s, w, c->df);
    for (int a = 0; a < n; a++) c->df[a] -= c->f[a];
    double s0 = 0;
    for (int a = 0; a < n; a++) s0 += (c->f[a] - w->F[a]) * w->dy[a];
    /* (no descent: round-off at the answer, or the coupling's asymmetry
     * far from it; the best iterate stands) */
    if (!(s0 < 0)) break;
    /* line search on the slope (f + a df - F(y + a dy)) . dy, increasing
     * in a: taken where it is at most CREEP_WOLFE |s0|; past that, a falls
     * to the root of the slope interpolated linearly from 0 (within
     * [0.05 a, 0.9 a]) */
    double al = 1;
    int ok = 0;
    for (int ls = 0; ls < CREEP_SEARCH && !ok; ls++) {
      for (int a = 0; a < n; a++) {
        w->ytry[a] = w->y[a] + al * w->dy[a];
        c->ft[a] = c->f[a] + al * c->df[a];
      }
      creep_eval(d, s, w, w->ytry, eps, w->Ftry, w->Htry, w->lamtry, w->Ktry, &lm, &sm);
      c->count++;
      double sl = 0;
      for (int a = 0; a < n; a++) sl += (c->ft[a] - w->Ftry[a]) * w->dy[a];
      if (sl <= -CREEP_WOLFE * s0) {
        ok = 1;
      } else {
        double t = sl == sl ? al * s0 / (s0 - sl) : 0.5 * al;
        al = t < 0.05 * al ? 0.05 * al : t > 0.9 * al ? 0.9 * al : t;
      }
    }
    if (!ok) break;
    take_trial(w);
    double *t = c->f;
    c->f = c->ft;
    c->ft = t;
    res = residual(s, w, w->y, w->F, NULL, NULL, w->phi, &size);
    at_best = res < best;
    if (at_best) {
      best = res;
      memcpy(c->yb, w->y, (size_t)n * sizeof(double));
      memcpy(c->fb, c->f, (size_t)n * sizeof(double));
    }
    /* progress: |phi| halved since the mark, or a damped step */
    if (res <= 0.25 * mark || al < 1) {
      mark = fmin(mark, res);
      since = 0;
    } else if (++since >= CREEP_STALL) {
      break;
    }
  }
  if (!at_best) {
    memcpy(w->y, c->yb, (size_t)n * sizeof(double));
    memcpy(c->f, c->fb, (size_t)n * sizeof(double));
    creep_eval(d, s, w, w->y, eps, w->F, w->H, w->lam, w->K, &lm, &sm);
    c->count++;
    residual(s, w, w->y, w->F, NULL, NULL, w->phi, &size);
  }
  return 0;
}

int ss_newton_creep(const ssModel *m, ssData *d, int first_row, double tol, int *count)
{
  Setup s;
  ssNewtonWork *w = setup(m, d, first_row, &s);
  if (!w) return 0;
  const int n = s.n;
  w->ns = 0;
  Creep c = {NULL, NULL, NULL, NULL, NULL, 0};
  double *buf = malloc((size_t)5 * n * sizeof(double));
  int done = 0;
  if (!buf) return 0;
  c.f = buf;
  c.ft = buf + n;
  c.df = buf + 2 * n;
  c.yb = buf + 3 * n;
  c.fb = buf + 4 * n;
  /* the start: the impulses the contacts hold and the velocities they
   * give (y = y_free + Lam f, as the sweeps keep them) */
  unknowns_of(m, d, &s, w, d->qvel_free, w->yfree);
  held_impulses(d, &s, w, c.f);
  for (int a = 0; a < n; a++) w->y[a] = w->yfree[a] + dotn(w->Lam + (size_t)a * n, c.f, n);
  double lmax, smax, size;
  creep_eval(d, &s, w, w->y, 0, w->F, w->H, w->lam, w->K, &lmax, &smax);
  c.count++;
  double gmin = least_response(&s, w, w->lam);
  double eps_end = CREEP_FINAL * tol * lmax * gmin;
  if (lmax > 0 && eps_end > 0 && isfinite(eps_end)) {
    double eps = fmax(CREEP_EPS_START * smax, eps_end);
    done = 1;
    for (;;) {
      int last = !(eps > eps_end);
      if (last) eps = eps_end;
      creep_eval(d, &s, w, w->y, eps, w->F, w->H, w->lam, w->K, &lmax, &smax);
      c.count++;
      double lt = last ? CREEP_FINAL * tol : CREEP_LEVEL_TOL;
      if (creep_level(d, &s, w, &c, eps, lt * lt, last ? 2 * CREEP_ITER : CREEP_ITER) < 0) {
        done = 0;
        break;
      }
      if (last) break;
      eps *= CREEP_EPS_STEP;
    }
  }
  /* the last step by the laws' linear model, from an answer within
   * CREEP_LINEAR_TOL */
  if (done) {
    double res = residual(&s, w, w->y, w->F, NULL, NULL, w->phi, &size);
    done = res <= CREEP_LINEAR_TOL * CREEP_LINEAR_TOL * size;
    if (done) {
      newton_matrix(&s, w, w->H);
      done = ss_lu_factor(w->A, w->piv, n);
    }
    if (done) {
      for (int a = 0; a < n; a++) w->dy[a] = -w->phi[a];
      ss_lu_solve(w->A, w->piv, n, w->dy);
      done = linear_end(&s, w);
    }
    if (done) apply_at(m, d, &s, w, w->lamtry, w->Ftry);
  }
  *count += c.count;
  free(buf);
  return done;
}
