/* articulated.c -- reduced-coordinate articulated systems (see
 * articulated.h for the formulation). */
#include "articulated.h"
#include "dynamics.h"
#include "mesh.h"
#include "model_build.h"
#include "solver.h"
#include "ss_math.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the grid of a system's spatial origin (ssArtWork.org), in metres: a
 * power of two, so that the rounded origin and a position's offset from it
 * are exact */
#define ART_ORIGIN_GRID 64.0

struct ssArtWork {
  int sys, nv, nb, b0, v0;
  int nrow;              /* closure rows (pin 3, distance 1, equality 1) */
  int neq, *eq;          /* closures of this system (model indices) */
  int *dof_body;         /* (nv) body of each local dof */
  int *dof_parent;       /* (nv) LTDL parent dof, -1 at the root */
  int *anc, *anc_adr;    /* (sum of depths), (nv + 1): dof k's chain to the
                            root, k first, at anc + anc_adr[k] (the factor's
                            and solves' loops read their dofs from it: a
                            parent's index is then no load that waits for
                            the last one) */
  int *arel;             /* (sum of depths) anc_adr[anc[q]] - q: where entry
                            q's dof's own chain starts, less q (reduce's
                            L_{path[i] path[t]}, path a chain at anc + a, is
                            L[arel[a + i] + a + t], one load for three) */
  int *dsc, *dsc_adr;    /* (2 (sum of depths - nv)), (nv + 1): the dofs i
                            whose chains hold dof k below i, descending, at
                            dsc + 2 dsc_adr[k], each as i and the entry's
                            index t in anc and L (L_ik = L[t]): the rows a
                            wide ltdl_solve's first pass gathers into k's */
  unsigned char *live;   /* (nv) scratch of that pass: rows not all zero */
  double *S;             /* (nv x 6) motion subspace columns, world */
  double *vel;           /* (nb x 6) body spatial velocities */
  double *acc;           /* (nb x 6) bias accelerations */
  double *frc;           /* (nb x 6) RNEA forces */
  double *Ic;            /* (nb x 36) composite inertias, world, by columns
                            (entry ij at 6 j + i: m6v_cols); the bodies'
                            own spatial inertias until the backward pass */
  double *L;             /* (sum of depths) M' = M + implicit terms on the
                            tree's pattern, then its LTDL factor, row k along
                            k's chain: L[anc_adr[k] + t] is L_kj, j =
                            anc[anc_adr[k] + t] (t = 0: D_k), so that row k's
                            tail from t on is row j's start */
  double *rhs, *x, *y;   /* (nv) scratch */
  double *K;             /* (nrow x nv) closure Jacobian */
  int *kcol, *nkcol;     /* (nrow x nv), (nrow) each row's columns that
                            closures may write (its bodies' paths, or its
                            two dofs), ascending: K is zero elsewhere */
  double *phi;           /* (nrow) closure residual */
  double *MiKT;          /* (nv x nrow) M'^-1 K^T */
  double *A;             /* (nrow x nrow) Cholesky factor of K M'^-1 K^T */
  double *Z;             /* (6 x nrow) scratch of body_response */
  unsigned char *row_on; /* (nrow) 0: row dropped as dependent */
  double *Y;             /* (nb x nv x 6) projected responses P M'^-1 J_b^T */
  double *Lam;           /* (nb x 36) J_b Y_b */
  unsigned char *Yok;    /* (nb) Y_b valid for this step */
  /* the Newton phase's factored route to the same responses
   * (ss_art_link_pair): b's path dofs, descending, and on them X_b = T J_b^T
   * and X_b / D (M'^-1 = T^T D^-1 T, T = L^-T the tree solve's first
   * sweep), and W_b = L_A^-1 K M'^-1 J_b^T (nr x 6, A = L_A L_A^T) */
  int *padr, *npath;     /* (nb) b's path, its last dof's chain: npath dofs of anc from padr */
  int *bord;             /* (sum of depths) each chain of anc with every
                            body's dofs ascending (the bodies from the
                            chain's first up): a link's path at bord + padr
                            in the order of a walk of its bodies */
  double *Xp, *XD;       /* (nb x nv x 6), rows on the path */
  double *Wp;            /* (nb x nr x 6) */
  unsigned char *Xok;    /* (nb) valid for this step */
  double *fsum;          /* (nv) sum of J_b^T F_b (ss_art_force_add) */
  /* the same for single dofs (a joint row's e_k, its path k's chain): Xd
   * and XDd (nv x nv), dok (nv), Wd (nv x nr) */
  double *Xd, *XDd, *Wd;
  unsigned char *dok;
  int rank_deficient;    /* rows dropped in the last factorization */
  double *kin_q;         /* (the system's nq) the qpos of the last
                            ss_art_forward, whose poses and S stand */
  int kin_ok;            /* 0: no ss_art_forward yet */
  unsigned char *clo_body; /* (nb) 1: a closure's body or an ancestor of one
                            (the poses phi reads) */
  int kin_part;          /* 1: forward_poses posed only the clo_body bodies */
  double org[3];         /* the point the spatial vectors are about
                            (ss_art_origin): the root's position rounded to
                            a multiple of ART_ORIGIN_GRID, set by
                            forward_rest */
  uint64_t kin_gen;      /* ss_art_forward's runs */
  uint64_t clo_gen;      /* kin_gen where closures last formed K and phi
                            (they depend on the poses, S and qpos alone) */
};

/* ---------------------------------------------------------------------- */
/* spatial algebra (world axes, about the system's origin): motion (w; v) */

/* r = a x b (motion cross motion) */
static void mcross(double r[6], const double a[6], const double b[6])
{
  double t[6], u[3];
  ss_v3_cross(t, a, b);
  ss_v3_cross(t + 3, a, b + 3);
  ss_v3_cross(u, a + 3, b);
  ss_v3_add(t + 3, t + 3, u);
  memcpy(r, t, sizeof t);
}

/* r = a x* f (motion cross force) */
static void fcross(double r[6], const double a[6], const double f[6])
{
  double t[6], u[3];
  ss_v3_cross(t, a, f);
  ss_v3_cross(u, a + 3, f + 3);
  ss_v3_add(t, t, u);
  ss_v3_cross(t + 3, a, f + 3);
  memcpy(r, t, sizeof t);
}

static inline void m6v(double r[6], const double M[36], const double v[6])
{
  /* same summation order as a running sum from 0 */
  for (int i = 0; i < 6; i++) {
    const double *a = M + 6 * i;
    r[i] = a[0] * v[0] + a[1] * v[1] + a[2] * v[2] + a[3] * v[3] + a[4] * v[4] + a[5] * v[5];
  }
}

/* r = M v, M (6 x 6) by columns (entry ij at C[6 j + i]): the six sums in
 * three pairs, each a column at a time, in m6v's order (from the first
 * product, left to right) */
static inline void m6v_cols(double r[6], const double C[36], const double v[6])
{
  ssV2 r0, r1, r2, c0, c1, c2, vj = {v[0], v[0]};
  memcpy(&c0, C, sizeof c0);
  memcpy(&c1, C + 2, sizeof c1);
  memcpy(&c2, C + 4, sizeof c2);
  r0 = c0 * vj;
  r1 = c1 * vj;
  r2 = c2 * vj;
  for (int j = 1; j < 6; j++) {
    const double *cj = C + 6 * j;
    vj = (ssV2){v[j], v[j]};
    memcpy(&c0, cj, sizeof c0);
    memcpy(&c1, cj + 2, sizeof c1);
    memcpy(&c2, cj + 4, sizeof c2);
    r0 += c0 * vj;
    r1 += c1 * vj;
    r2 += c2 * vj;
  }
  memcpy(r, &r0, sizeof r0);
  memcpy(r + 2, &r1, sizeof r1);
  memcpy(r + 4, &r2, sizeof r2);
}

/* r += a, in three pairs (the same sums as an element loop, whose
 * vectorised form would first check whether r and a overlap) */
static inline void add6(double r[6], const double a[6])
{
  for (int i = 0; i < 6; i += 2) {
    ssV2 x, y;
    memcpy(&x, r + i, sizeof x);
    memcpy(&y, a + i, sizeof y);
    x += y;
    memcpy(r + i, &x, sizeof x);
  }
}

/* p += S_k u_k (u_k at u[ldu k]) for the dofs k0 to k0 + nd - 1 in turn,
 * the six sums in three pairs */
static inline void add_motion(ssV2 p[3], const double *S, int k0, int nd, const double *u,
                              size_t ldu)
{
  for (int k = k0; k < k0 + nd; k++) {
    ssV2 uk = {u[ldu * k], u[ldu * k]}, sk;
    for (int i = 0; i < 3; i++) {
      memcpy(&sk, S + 6 * k + 2 * i, sizeof sk);
      p[i] += sk * uk;
    }
  }
}

static double dot6(const double a[6], const double b[6])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5];
}

/* out = R I R^T (out neither R nor I): ss_m3_mul's T = R I, then T R^T
 * with the terms of R^T's columns read from R's rows, the products and
 * sums of ss_m3_mul's, without a transposed copy of R */
static inline void rotate_inertia(double out[9], const double R[9], const double I[9])
{
  double T[9];
  ss_m3_mul(T, R, I);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      out[3 * i + j] =
          T[3 * i] * R[3 * j] + T[3 * i + 1] * R[3 * j + 1] + T[3 * i + 2] * R[3 * j + 2];
}

/* spatial inertia about the system's origin of mass m, COM c (from that
 * origin), inertia Ic (world axes, about the COM):
 * [[Ic - m [c]x[c]x, m [c]x], [-m [c]x, m 1]], by columns (entry ij at
 * I6[6 j + i]) */
static void spatial_inertia(double I6[36], double mass, const double c[3],
                            const double Ic[9])
{
  double cx[9] = {0, -c[2], c[1], c[2], 0, -c[0], -c[1], c[0], 0}, cc[9];
  ss_m3_mul(cc, cx, cx);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      I6[6 * j + i] = Ic[3 * i + j] - mass * cc[3 * i + j];
      I6[6 * (3 + j) + i] = mass * cx[3 * i + j];
      I6[6 * j + 3 + i] = -mass * cx[3 * i + j];
      I6[6 * (3 + j) + 3 + i] = i == j ? mass : 0;
    }
}

/* ---------------------------------------------------------------------- */
/* workspace                                                               */

static int sys_closures(const ssModel *m, int s, int *eq, int *rows)
{
  int n = 0, r = 0;
  for (int k = 0; k < m->neq; k++) {
    if (m->eq_sys[k] != s) continue;
    if (eq) eq[n] = k;
    n++;
    r += m->eq_type[k] == SS_CLOSURE_PIN ? 3 : 1;
  }
  if (rows) *rows = r;
  return n;
}

/* the last dof (index in the system) of body a or of its nearest ancestor
 * that has one, -1 if none: where a solve's sweep from a towards the root
 * starts (the LTDL parent of a child's first dof, a link's path) */
static int last_dof(const ssModel *m, const ssArtWork *w, int a)
{
  while (a >= 0 && !m->body_ndof[a]) a = m->body_parent[a];
  return a >= 0 ? m->body_dofadr[a] - w->v0 + m->body_ndof[a] - 1 : -1;
}

void ss_art_work_free(ssArtWork *w)
{
  if (!w) return;
  free(w->eq); free(w->dof_body); free(w->dof_parent); free(w->anc); free(w->anc_adr);
  free(w->arel); free(w->bord);
  free(w->dsc); free(w->dsc_adr); free(w->live);
  free(w->S);
  free(w->vel); free(w->acc); free(w->frc); free(w->Ic);
  free(w->L); free(w->rhs); free(w->x); free(w->y);
  free(w->K); free(w->phi); free(w->MiKT); free(w->A); free(w->Z); free(w->row_on);
  free(w->Y); free(w->Lam); free(w->Yok);
  free(w->padr); free(w->npath); free(w->Xp); free(w->XD); free(w->Wp); free(w->Xok);
  free(w->fsum); free(w->Xd); free(w->XDd); free(w->Wd);
  free(w->dok); free(w->kin_q); free(w->clo_body); free(w->kcol); free(w->nkcol);
  free(w);
}

ssArtWork *ss_art_work_new(const ssModel *m, int s)
{
  ssArtWork *w = calloc(1, sizeof *w);
  if (!w) return NULL;
  w->sys = s;
  w->nv = m->sys_nv[s];
  w->nb = m->sys_nbody[s];
  w->b0 = m->sys_bodyadr[s];
  w->v0 = m->sys_vadr[s];
  w->neq = sys_closures(m, s, NULL, &w->nrow);
  size_t nv = w->nv ? w->nv : 1, nb = w->nb, nr = w->nrow ? w->nrow : 1;
  w->eq = calloc(w->neq ? w->neq : 1, sizeof(int));
  w->dof_body = calloc(nv, sizeof(int));
  w->dof_parent = calloc(nv, sizeof(int));
  w->S = calloc(nv * 6, sizeof(double));
  w->vel = calloc(nb * 6, sizeof(double));
  w->acc = calloc(nb * 6, sizeof(double));
  w->frc = calloc(nb * 6, sizeof(double));
  w->Ic = calloc(nb * 36, sizeof(double));
  w->rhs = calloc(nv, sizeof(double));
  w->x = calloc(nv, sizeof(double));
  w->y = calloc(nv > nr ? nv : nr, sizeof(double));
  w->K = calloc(nr * nv, sizeof(double));
  w->phi = calloc(nr, sizeof(double));
  w->MiKT = calloc(nv * nr, sizeof(double));
  w->A = calloc(nr * nr, sizeof(double));
  w->Z = calloc(6 * nr, sizeof(double));
  w->row_on = calloc(nr, 1);
  w->Y = calloc(nb * nv * 6, sizeof(double));
  w->Lam = calloc(nb * 36, sizeof(double));
  w->Yok = calloc(nb, 1);
  w->padr = calloc(nb ? nb : 1, sizeof(int));
  w->npath = calloc(nb ? nb : 1, sizeof(int));
  w->Xp = calloc(nb * nv * 6, sizeof(double));
  w->XD = calloc(nb * nv * 6, sizeof(double));
  w->Wp = calloc(nb * nr * 6, sizeof(double));
  w->Xok = calloc(nb ? nb : 1, 1);
  w->fsum = calloc(nv, sizeof(double));
  w->Xd = calloc(nv * nv, sizeof(double));
  w->XDd = calloc(nv * nv, sizeof(double));
  w->Wd = calloc(nv * nr, sizeof(double));
  w->dok = calloc(nv, 1);
  w->kin_q = calloc(m->sys_nq[s] ? (size_t)m->sys_nq[s] : 1, sizeof(double));
  w->clo_body = calloc(nb ? nb : 1, 1);
  w->kcol = calloc(nr * nv, sizeof(int));
  w->nkcol = calloc(nr, sizeof(int));
  if (!w->kin_q || !w->clo_body || !w->kcol || !w->nkcol || !w->padr || !w->npath ||
      !w->Xp || !w->XD || !w->Wp || !w->Xok || !w->fsum || !w->Xd || !w->XDd || !w->Wd || !w->dok) {
    ss_art_work_free(w);
    return NULL;
  }
  if (!w->eq || !w->dof_body || !w->dof_parent || !w->S || !w->vel || !w->acc ||
      !w->frc || !w->Ic || !w->rhs || !w->x || !w->y ||
      !w->K || !w->phi || !w->MiKT || !w->A || !w->Z || !w->row_on || !w->Y || !w->Lam ||
      !w->Yok) {
    ss_art_work_free(w);
    return NULL;
  }
  sys_closures(m, s, w->eq, NULL);
  /* the bodies whose poses phi reads: the closures' and their ancestors */
  for (int e = 0; e < w->neq; e++)
    for (int q = 0; q < 2; q++)
      for (int a = m->eq_body[2 * w->eq[e] + q]; a >= 0; a = m->body_parent[a])
        w->clo_body[a - w->b0] = 1;
  w->clo_gen = UINT64_MAX;
  /* LTDL parent of each dof: the previous dof of its joint, else the last
   * dof of the nearest ancestor that has one */
  for (int lb = 0; lb < w->nb; lb++) {
    int b = w->b0 + lb, nd = m->body_ndof[b];
    if (!nd) continue;
    int k0 = m->body_dofadr[b] - w->v0;
    int par = last_dof(m, w, m->body_parent[b]);
    for (int k = 0; k < nd; k++) {
      w->dof_body[k0 + k] = lb;
      w->dof_parent[k0 + k] = k ? k0 + k - 1 : par;
    }
  }
  /* the chains to the root (parents come before their children) */
  int nanc = 0;
  for (int k = 0; k < w->nv; k++)
    for (int j = k; j >= 0; j = w->dof_parent[j]) nanc++;
  w->anc = malloc((size_t)(nanc ? nanc : 1) * sizeof(int));
  w->anc_adr = malloc((nv + 1) * sizeof(int));
  w->L = malloc((size_t)(nanc ? nanc : 1) * sizeof(double));
  w->arel = malloc((size_t)(nanc ? nanc : 1) * sizeof(int));
  w->bord = malloc((size_t)(nanc ? nanc : 1) * sizeof(int));
  if (!w->anc || !w->anc_adr || !w->L || !w->arel || !w->bord) {
    ss_art_work_free(w);
    return NULL;
  }
  nanc = 0;
  for (int k = 0; k < w->nv; k++) {
    w->anc_adr[k] = nanc;
    for (int j = k; j >= 0; j = w->dof_parent[j]) w->anc[nanc++] = j;
  }
  w->anc_adr[w->nv] = nanc;
  for (int q = 0; q < nanc; q++) w->arel[q] = w->anc_adr[w->anc[q]] - q;
  /* a chain's runs of one body's dofs (descending in anc) reversed */
  for (int k = 0; k < w->nv; k++)
    for (int q = w->anc_adr[k], e; q < w->anc_adr[k + 1]; q = e) {
      for (e = q + 1; e < w->anc_adr[k + 1] && w->dof_body[w->anc[e]] == w->dof_body[w->anc[q]];
           e++) {
      }
      for (int i = q; i < e; i++) w->bord[i] = w->anc[q + e - 1 - i];
    }
  /* each link's path: the chain of its last dof (none: empty) */
  for (int lb = 0; lb < w->nb; lb++) {
    int top = last_dof(m, w, w->b0 + lb);
    if (top < 0) continue;
    w->padr[lb] = w->anc_adr[top];
    w->npath[lb] = w->anc_adr[top + 1] - w->anc_adr[top];
  }
  /* each dof's descendants from the chains, descending (i from the last) */
  w->dsc = malloc((size_t)(nanc > w->nv ? 2 * (nanc - w->nv) : 1) * sizeof(int));
  w->dsc_adr = calloc(nv + 1, sizeof(int));
  w->live = malloc(nv);
  int *fill = malloc(nv * sizeof(int));
  if (!w->dsc || !w->dsc_adr || !w->live || !fill) {
    free(fill);
    ss_art_work_free(w);
    return NULL;
  }
  for (int t = 0; t < nanc; t++) w->dsc_adr[w->anc[t] + 1]++;
  for (int k = 0; k < w->nv; k++) {
    w->dsc_adr[k + 1] += w->dsc_adr[k] - 1; /* less k's own entry */
    fill[k] = w->dsc_adr[k];
  }
  for (int i = w->nv - 1; i >= 0; i--)
    for (int t = w->anc_adr[i] + 1; t < w->anc_adr[i + 1]; t++) {
      int q = fill[w->anc[t]]++;
      w->dsc[2 * q] = i;
      w->dsc[2 * q + 1] = t;
    }
  free(fill);
  /* each closure row's columns, from the dofs closures writes (path_zero
   * and point_rows along both bodies' paths; an equality's two dofs) */
  unsigned char *on = calloc(nv, 1);
  if (!on) {
    ss_art_work_free(w);
    return NULL;
  }
  for (int e = 0, r = 0; e < w->neq; e++) {
    int k = w->eq[e], b1 = m->eq_body[2 * k], b2 = m->eq_body[2 * k + 1];
    int rows = m->eq_type[k] == SS_CLOSURE_PIN ? 3 : 1, nc = 0;
    int *col = w->kcol + (size_t)r * w->nv;
    if (m->eq_type[k] == SS_CLOSURE_EQUALITY) {
      on[m->body_dofadr[b1] - w->v0] = on[m->body_dofadr[b2] - w->v0] = 1;
    } else {
      for (int j = last_dof(m, w, b1); j >= 0; j = w->dof_parent[j]) on[j] = 1;
      for (int j = last_dof(m, w, b2); j >= 0; j = w->dof_parent[j]) on[j] = 1;
    }
    for (int j = 0; j < w->nv; j++)
      if (on[j]) {
        col[nc++] = j;
        on[j] = 0;
      }
    for (int q = 0; q < rows; q++, r++) {
      if (q) memcpy(w->kcol + (size_t)r * w->nv, col, (size_t)nc * sizeof(int));
      w->nkcol[r] = nc;
    }
  }
  free(on);
  return w;
}

/* ---------------------------------------------------------------------- */
/* kinematics                                                              */

/* World pose of every body of system s from qpos (xpos, xquat per body,
 * indexed by body - first body), and where xmat is not NULL its rotation
 * matrix (xmat, the same indexing): each body's matrix formed once, from
 * its final quaternion, serves its children's joints as well (the bits of
 * the matrix they would form from it).  Where only is not NULL, only the
 * bodies lb with only[lb] == want (their parents posed before) */
static void kinematics(const ssModel *m, int s, const double *qpos, double *xpos,
                       double *xquat, double *xmat, const unsigned char *only, int want)
{
  int b0 = m->sys_bodyadr[s];
  for (int lb = 0; lb < m->sys_nbody[s]; lb++) {
    if (only && only[lb] != want) continue;
    int b = b0 + lb, par = m->body_parent[b], type = m->body_jnttype[b];
    double *p = xpos + 3 * lb, *q = xquat + 4 * lb;
    const double *qa = m->body_qadr[b] >= 0 ? qpos + m->body_qadr[b] : NULL;
    if (par < 0) {
      if (type == SS_JOINT_FLOATING) {
        memcpy(p, qa, 3 * sizeof(double));
        memcpy(q, qa + 3, 4 * sizeof(double));
      } else {
        memcpy(p, m->body_jntpos + 3 * b, 3 * sizeof(double));
        memcpy(q, m->body_jntquat + 4 * b, 4 * sizeof(double));
      }
      if (xmat) ss_quat_to_mat(xmat + 9 * lb, q);
      continue;
    }
    const double *pp = xpos + 3 * (par - b0), *pq = xquat + 4 * (par - b0), *Rp;
    double Rl[9], off[3], jq[4];
    if (xmat) {
      Rp = xmat + 9 * (par - b0);
    } else {
      ss_quat_to_mat(Rl, pq);
      Rp = Rl;
    }
    ss_m3_mulv(off, Rp, m->body_jntpos + 3 * b);
    ss_v3_add(p, pp, off);
    ss_quat_mul(jq, pq, m->body_jntquat + 4 * b);
    const double *ax = m->body_jntaxis + 3 * b;
    switch (type) {
    case SS_JOINT_REVOLUTE: {
      double r[4];
      ss_quat_from_axis_angle(r, ax, qa[0]);
      ss_quat_mul(q, jq, r);
      break;
    }
    case SS_JOINT_PRISMATIC: {
      double Rj[9], d[3];
      memcpy(q, jq, 4 * sizeof(double));
      ss_quat_to_mat(Rj, jq);
      ss_m3_mulv(d, Rj, ax);
      ss_v3_addscl(p, d, qa[0]);
      break;
    }
    case SS_JOINT_SPHERICAL:
      ss_quat_mul(q, jq, qa);
      break;
    default:
      memcpy(q, jq, 4 * sizeof(double));
      break;
    }
    ss_quat_normalize(q);
    if (xmat) ss_quat_to_mat(xmat + 9 * lb, q);
  }
}

/* ss_art_forward in two halves: the poses (kin_q is their qpos; kin_ok
 * stays 0 until the second half), then the centres of mass and motion
 * subspaces, which the closure-drift passes that read phi alone do
 * without.  With part, only the bodies phi reads are posed (clo_body): the
 * others follow in forward_rest, which must then come before qpos moves */
static void forward_poses(const ssModel *m, ssData *d, int s, int part)
{
  ssArtWork *w = d->art[s];
  int b0 = w->b0;
  kinematics(m, s, d->qpos, d->body_xpos + 3 * b0, d->body_xquat + 4 * b0,
             d->body_xmat + 9 * b0, part ? w->clo_body : NULL, 1);
  memcpy(w->kin_q, d->qpos + m->sys_qadr[s], (size_t)m->sys_nq[s] * sizeof(double));
  w->kin_ok = 0;
  w->kin_part = part;
  w->kin_gen++;
}

static void forward_rest(const ssModel *m, ssData *d, int s)
{
  ssArtWork *w = d->art[s];
  int b0 = w->b0;
  if (w->kin_part)
    kinematics(m, s, d->qpos, d->body_xpos + 3 * b0, d->body_xquat + 4 * b0,
               d->body_xmat + 9 * b0, w->clo_body, 0);
  w->kin_part = 0;
  /* the origin of the spatial vectors: near the system, so that no
   * product of its distance from the world origin enters them (the
   * motion subspaces' p x a, the inertias' c x c) to cancel in what is
   * formed from them; on a coarse grid, so that it stays where it is
   * from step to step (the Newton phase's records hold velocities about
   * it) and is exactly 0 for a system near the world origin (+0.0: no
   * signed zero) */
  for (int k = 0; k < 3; k++)
    w->org[k] = ART_ORIGIN_GRID * nearbyint(d->body_xpos[3 * b0 + k] / ART_ORIGIN_GRID) + 0.0;
  for (int lb = 0; lb < w->nb; lb++) {
    int b = b0 + lb;
    const double *R = d->body_xmat + 9 * b;
    double off[3], p[3];
    ss_v3_sub(p, d->body_xpos + 3 * b, w->org);
    ss_m3_mulv(off, R, m->body_ipos + 3 * b);
    ss_v3_add(d->body_xipos + 3 * b, d->body_xpos + 3 * b, off);
    int nd = m->body_ndof[b];
    if (!nd) continue;
    double *S = w->S + 6 * (m->body_dofadr[b] - w->v0);
    const double *ax = m->body_jntaxis + 3 * b;
    switch (m->body_jnttype[b]) {
    case SS_JOINT_REVOLUTE:
      ss_m3_mulv(S, R, ax);
      ss_v3_cross(S + 3, p, S);
      break;
    case SS_JOINT_PRISMATIC:
      ss_v3_set(S, 0, 0, 0);
      ss_m3_mulv(S + 3, R, ax);
      break;
    case SS_JOINT_SPHERICAL:
      for (int k = 0; k < 3; k++) {
        double *c = S + 6 * k;
        ss_v3_set(c, R[k], R[3 + k], R[6 + k]);
        ss_v3_cross(c + 3, p, c);
      }
      break;
    case SS_JOINT_FLOATING:
      memset(S, 0, 36 * sizeof(double));
      for (int k = 0; k < 3; k++) {
        S[6 * k + 3 + k] = 1;         /* linear velocity of the base origin */
        double *c = S + 6 * (3 + k);  /* world angular velocity */
        c[k] = 1;
        ss_v3_cross(c + 3, p, c);
      }
      break;
    default:
      break;
    }
  }
  w->kin_ok = 1;
}

void ss_art_forward(const ssModel *m, ssData *d, int s)
{
  forward_poses(m, d, s, 0);
  forward_rest(m, d, s);
}

/* (articulated.h) */
int ss_art_forward_current(const ssModel *m, const ssData *d, int s)
{
  const ssArtWork *w = d->art[s];
  return w->kin_ok &&
         !memcmp(w->kin_q, d->qpos + m->sys_qadr[s], (size_t)m->sys_nq[s] * sizeof(double));
}

/* ---------------------------------------------------------------------- */
/* LTDL factorization of M' (Featherstone, RBDA 6.3)                        */

static int ltdl_factor(ssArtWork *w)
{
  /* L holds M' on the tree's pattern (k and its ancestors, the only
   * entries the factor and ltdl_solve read), as ss_art_free_velocity
   * formed it */
  int n = w->nv;
  double *L = w->L;
  /* the largest pivot: a comparison where fmax would be a call, the same
   * maximum (a NaN is passed over as fmax does; no -0 comes) */
  double dmax = 0;
  for (int k = 0; k < n; k++) {
    double d = fabs(L[w->anc_adr[k]]);
    dmax = d > dmax ? d : dmax;
  }
  /* the chains' addresses and k's pivot in locals: the row updates'
   * stores through L would otherwise reload them for every row i */
  const int *adr = w->anc_adr, *anc = w->anc;
  for (int k = n - 1; k >= 0; k--) {
    double *Lk = L + adr[k], dk = Lk[0];
    if (!(dk > 1e-14 * dmax)) return -1 - k;
    /* i runs up k's chain; its own chain is the rest of k's, so row i's
     * entries are row k's from t on, both contiguous: an odd row's first
     * entry alone, then the updates two at a time (each entry's one update
     * the same operation wherever it falls) */
    const int *ak = anc + adr[k];
    const int nk = adr[k + 1] - adr[k];
    for (int t = 1; t < nk; t++) {
      double a = Lk[t] / dk, *Li = L + adr[ak[t]];
      const double *lk = Lk + t;
      ssV2 av = {a, a};
      int m = nk - t, u = m & 1;
      if (u) Li[0] -= a * lk[0];
      for (; u < m; u += 2) {
        ssV2 x, y;
        memcpy(&x, lk + u, sizeof x);
        memcpy(&y, Li + u, sizeof y);
        y -= av * x;
        memcpy(Li + u, &y, sizeof y);
      }
      Lk[t] = a;
    }
  }
  return 0;
}

/* The tree solve's last pass for 2 np columns of row i from c on, in
 * registers (np pairs): the row over D_i, then less L_ij x_j over i's
 * ancestors j in turn (the same operations, in the same order, as a
 * division of the row and then row updates: x - h y rounds as their
 * x + (-h) y, ss_math.h).  np is a constant at each call, so that the
 * pairs unroll into registers. */
static inline __attribute__((always_inline)) void
chain_sum(const ssArtWork *w, double *X, size_t m, int i, int c, int np)
{
  const double *L = w->L;
  double *xi = X + m * i + c, d = L[w->anc_adr[i]];
  ssV2 a[8], x, dv = {d, d};
  for (int q = 0; q < np; q++) {
    memcpy(&x, xi + 2 * q, sizeof x);
    a[q] = x / dv;
  }
  for (int t = w->anc_adr[i] + 1; t < w->anc_adr[i + 1]; t++) {
    ssV2 hv = {L[t], L[t]};
    const double *xj = X + m * w->anc[t] + c;
    for (int q = 0; q < np; q++) {
      memcpy(&x, xj + 2 * q, sizeof x);
      a[q] -= hv * x;
    }
  }
  for (int q = 0; q < np; q++) memcpy(xi + 2 * q, &a[q], sizeof x);
}

/* The tree solve's first pass for 2 np columns of row k from c on, as a
 * wide ltdl_solve makes it, in registers (np pairs): less L_ik x_i over the
 * rows i below k, descending, whose rows are not all zero (the row updates
 * that rows i would make of k, in the order they make them: x - h y rounds
 * as x + (-h) y, ss_math.h).  Returns whether the result has an entry that
 * is not zero (a NaN counts). */
static inline __attribute__((always_inline)) int
desc_sum(const ssArtWork *w, double *X, size_t m, int k, int c, int np)
{
  typedef long long ssM2 __attribute__((vector_size(16))); /* a pair's comparison */
  const double *L = w->L;
  double *xk = X + m * k + c;
  ssV2 a[8], x, zero = {0, 0};
  for (int q = 0; q < np; q++) memcpy(&a[q], xk + 2 * q, sizeof x);
  for (int u = w->dsc_adr[k]; u < w->dsc_adr[k + 1]; u++) {
    int i = w->dsc[2 * u];
    if (!w->live[i]) continue;
    double h = L[w->dsc[2 * u + 1]];
    ssV2 hv = {h, h};
    const double *xi = X + m * i + c;
    for (int q = 0; q < np; q++) {
      memcpy(&x, xi + 2 * q, sizeof x);
      a[q] -= hv * x;
    }
  }
  ssM2 nz = {0, 0};
  for (int q = 0; q < np; q++) {
    memcpy(xk + 2 * q, &a[q], sizeof x);
    nz |= a[q] != zero;
  }
  return (nz[0] | nz[1]) != 0;
}

/* X <- M'^-1 X for m columns at once, X (n x m, row k = dof k).  The first
 * pass moves each row into its ancestors only: the zero rows of a sparse X
 * (Jacobian columns, closure rows: a path or two in the tree) cost nothing
 * there.  Each column sees the same operations in the same order whatever
 * m (so the same bits). */
static inline void ltdl_solve(const ssArtWork *w, double *X, int m)
{
  int n = w->nv;
  const double *L = w->L;
  if (m >= 8) {
    /* wide blocks (the closure rows' columns, MiKT): the first pass as
     * gathers into each row from the rows below it (desc_sum), sixteen or
     * eight columns at a time, the rest one at a time, each row's sums in
     * registers instead of row updates in memory */
    for (int k = n - 1; k >= 0; k--) {
      int c = 0, live = 0;
      for (; c + 16 <= m; c += 16) live |= desc_sum(w, X, (size_t)m, k, c, 8);
      for (; c + 8 <= m; c += 8) live |= desc_sum(w, X, (size_t)m, k, c, 4);
      for (; c < m; c++) {
        double *xk = X + (size_t)m * k + c, x = *xk;
        for (int u = w->dsc_adr[k]; u < w->dsc_adr[k + 1]; u++) {
          int i = w->dsc[2 * u];
          if (w->live[i]) x -= L[w->dsc[2 * u + 1]] * X[(size_t)m * i + c];
        }
        *xk = x;
        live |= x != 0;
      }
      w->live[k] = live;
    }
  } else if (m == 1) {
    /* one column (a velocity, a sum of impulses): x_j - h x_i where the
     * rows' update adds (-h) x_i, the same bits without a negation each */
    for (int i = n - 1; i >= 0; i--) {
      double xi = X[i];
      if (xi == 0) continue;
      for (int t = w->anc_adr[i] + 1; t < w->anc_adr[i + 1]; t++) X[w->anc[t]] -= L[t] * xi;
    }
  } else {
    for (int i = n - 1; i >= 0; i--) {
      const double *xi = X + (size_t)m * i;
      int r = 0;
      while (r < m && xi[r] == 0) r++;
      if (r == m) continue;
      for (int t = w->anc_adr[i] + 1; t < w->anc_adr[i + 1]; t++) {
        int j = w->anc[t];
        double h = L[t], *xj = X + (size_t)m * j;
        ss_row_add_scaled(xj, -h, xi, m);
      }
    }
  }
  /* the division by D and the last pass, row by row towards the leaves
   * (row i's ancestors are final before it): a response block's six
   * columns in three pairs; wider blocks (the closure rows' columns, MiKT)
   * sixteen or eight columns at a time, the rest one at a time, each
   * column's sum in a register */
  for (int i = 0; i < n; i++) {
    if (m == 6) {
      chain_sum(w, X, 6, i, 0, 3);
      continue;
    }
    int c = 0;
    for (; c + 16 <= m; c += 16) chain_sum(w, X, (size_t)m, i, c, 8);
    for (; c + 8 <= m; c += 8) chain_sum(w, X, (size_t)m, i, c, 4);
    for (; c < m; c++) {
      double *xi = X + (size_t)m * i + c, x = *xi / L[w->anc_adr[i]];
      for (int t = w->anc_adr[i] + 1; t < w->anc_adr[i + 1]; t++)
        x -= L[t] * X[(size_t)m * w->anc[t] + c];
      *xi = x;
    }
  }
}

/* ---------------------------------------------------------------------- */
/* Jacobians                                                               */

/* r (length nv) += s * (point Jacobian row along dir of world point p on
 * body b): sum over path dofs of dir . (v_k + w_k x p); for nd <= 3
 * directions at once (dir (nd x 3), row q at r + q ld: a pin's three rows),
 * in one walk of the path with each S_k loaded once (in locals: the rows'
 * stores would make it a reload per row) */
static inline void point_rows(const ssModel *m, const ssArtWork *w, int b, const double pw[3],
                              const double *dir, int nd, double s, double *r, int ld)
{
  double pxd[9], p[3];
  ss_v3_sub(p, pw, w->org);
  for (int q = 0; q < nd; q++) ss_v3_cross(pxd + 3 * q, p, dir + 3 * q);
  for (int a = b; a >= 0; a = m->body_parent[a]) {
    int na = m->body_ndof[a];
    if (!na) continue;
    int k0 = m->body_dofadr[a] - w->v0;
    for (int k = k0; k < k0 + na; k++) {
      /* six scalars (a copied array stayed on the stack: a store and a
       * load more each); the sums as ss_v3_dot's */
      const double *Sk = w->S + 6 * k;
      double c0 = Sk[0], c1 = Sk[1], c2 = Sk[2], c3 = Sk[3], c4 = Sk[4], c5 = Sk[5];
      for (int q = 0; q < nd; q++) {
        const double *e = dir + 3 * q, *f = pxd + 3 * q;
        r[q * ld + k] +=
            s * ((c3 * e[0] + c4 * e[1] + c5 * e[2]) + (c0 * f[0] + c1 * f[1] + c2 * f[2]));
      }
    }
  }
}

static void body_point(const ssData *d, int b, const double local[3], double p[3])
{
  ss_m3_mulv(p, d->body_xmat + 9 * b, local);
  ss_v3_add(p, p, d->body_xpos + 3 * b);
}

/* r[k] = 0 for the dofs k on body b's path (those point_rows adds to), in
 * nd rows (row q at r + q ld): the LTDL chain from its last dof */
static void path_zero(const ssModel *m, const ssArtWork *w, int b, double *r, int nd, int ld)
{
  for (int k = last_dof(m, w, b); k >= 0; k = w->dof_parent[k])
    for (int q = 0; q < nd; q++) r[q * ld + k] = 0;
}

/* closure residual phi and, with rows, closure rows K (nrow x nv) at the
 * current kinematics (phi's bits the same either way).  A row's entries on
 * its two bodies' paths are zeroed and summed anew; the rest of the row is
 * never written and stays the zeros of K's calloc (the closures and their
 * rows are fixed), without a memset per call.  Without rows K is left as
 * it was (clo_gen says where it stands): the drift loop's chord steps read
 * phi alone */
static void closures(const ssModel *m, const ssData *d, ssArtWork *w, int rows)
{
  int n = w->nv, r = 0;
  if (rows) w->clo_gen = w->kin_gen;
  for (int e = 0; e < w->neq; e++) {
    int k = w->eq[e], b1 = m->eq_body[2 * k], b2 = m->eq_body[2 * k + 1];
    const double *an = m->eq_anchor + 6 * k;
    switch (m->eq_type[k]) {
    case SS_CLOSURE_PIN: {
      double p1[3], p2[3];
      body_point(d, b1, an, p1);
      body_point(d, b2, an + 3, p2);
      /* its three rows (directions x, y, z) in one walk of each path */
      const double dir[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      double *Kr = w->K + (size_t)r * n;
      for (int i = 0; i < 3; i++) w->phi[r + i] = p1[i] - p2[i];
      r += 3;
      if (!rows) break;
      path_zero(m, w, b1, Kr, 3, n);
      path_zero(m, w, b2, Kr, 3, n);
      point_rows(m, w, b1, p1, dir, 3, 1, Kr, n);
      point_rows(m, w, b2, p2, dir, 3, -1, Kr, n);
      break;
    }
    case SS_CLOSURE_DISTANCE: {
      double p1[3], p2[3], dv[3];
      body_point(d, b1, an, p1);
      body_point(d, b2, an + 3, p2);
      ss_v3_sub(dv, p1, p2);
      double len = ss_v3_normalize(dv), *Kr = w->K + (size_t)r * n;
      w->phi[r++] = len - m->eq_data[2 * k];
      if (!rows) break;
      path_zero(m, w, b1, Kr, 1, n);
      path_zero(m, w, b2, Kr, 1, n);
      point_rows(m, w, b1, p1, dv, 1, 1, Kr, n);
      point_rows(m, w, b2, p2, dv, 1, -1, Kr, n);
      break;
    }
    case SS_CLOSURE_EQUALITY: {
      double ratio = m->eq_data[2 * k], off = m->eq_data[2 * k + 1];
      double *Kr = w->K + (size_t)r * n;
      int k1 = m->body_dofadr[b1] - w->v0, k2 = m->body_dofadr[b2] - w->v0;
      w->phi[r++] = d->qpos[m->body_qadr[b1]] - ratio * d->qpos[m->body_qadr[b2]] - off;
      if (!rows) break;
      Kr[k1] = 0;
      Kr[k2] = 0;
      Kr[k1] += 1;
      Kr[k2] -= ratio;
      break;
    }
    }
  }
}

/* MiKT = M'^-1 K^T and the Cholesky factor of A = K M'^-1 K^T; dependent
 * rows (pivot below 1e-10 of the largest diagonal) are dropped. */
static void factor_closures(ssArtWork *w)
{
  int n = w->nv, nr = w->nrow;
  w->rank_deficient = 0;
  /* MiKT = M'^-1 K^T, its nr columns solved together (K^T two entries of
   * a row at a time, one store each pair) */
  for (int i = 0; i < n; i++) {
    const double *ki = w->K + i;
    double *mi = w->MiKT + (size_t)i * nr;
    int r = 0;
    for (; r + 2 <= nr; r += 2) {
      ssV2 v = {ki[(size_t)r * n], ki[(size_t)(r + 1) * n]};
      memcpy(mi + r, &v, sizeof v);
    }
    if (r < nr) mi[r] = ki[(size_t)r * n];
  }
  ltdl_solve(w, w->MiKT, nr);
  /* A = K MiKT (lower triangle, row by row over K's nonzeros, in pairs
   * (ss_row_add_scaled, whose loop the compiler need not guard against
   * overlap); each entry summed over k in order): the lower triangle is all
   * that the Cholesky factor and the closure solves read */
  double *A = w->A, amax = 0;
  for (int i = 0; i < nr; i++) {
    double *Ai = A + (size_t)i * nr;
    const double *Ki = w->K + (size_t)i * n;
    const int *col = w->kcol + (size_t)i * n;
    for (int j = 0; j <= i; j++) Ai[j] = 0;
    for (int c = 0; c < w->nkcol[i]; c++) {
      int k = col[c];
      double kik = Ki[k];
      if (kik == 0) continue;
      ss_row_add_scaled(Ai, kik, w->MiKT + (size_t)k * nr, i + 1);
    }
    amax = Ai[i] > amax ? Ai[i] : amax; /* fmax's (a sum from +0 is no -0) */
  }
  for (int j = 0; j < nr; j++) {
    double s = A[j * nr + j];
    for (int k = 0; k < j; k++) s -= A[j * nr + k] * A[j * nr + k];
    if (!(s > 1e-10 * amax)) {
      w->row_on[j] = 0;
      w->rank_deficient++;
      for (int i = j; i < nr; i++) A[i * nr + j] = 0;
      continue;
    }
    w->row_on[j] = 1;
    double l = sqrt(s);
    const double *aj = A + j * nr;
    A[j * nr + j] = l;
    /* rows i and i + 1 together: each chain of dependent subtractions
     * beside the other's, the same operations in the same order */
    int i = j + 1;
    for (; i + 1 < nr; i += 2) {
      double *a0 = A + i * nr, *a1 = a0 + nr, t0 = a0[j], t1 = a1[j];
      for (int k = 0; k < j; k++) {
        t0 -= a0[k] * aj[k];
        t1 -= a1[k] * aj[k];
      }
      a0[j] = t0 / l;
      a1[j] = t1 / l;
    }
    if (i < nr) {
      double *a0 = A + i * nr, t = a0[j];
      for (int k = 0; k < j; k++) t -= a0[k] * aj[k];
      a0[j] = t / l;
    }
  }
}

/* closure_forward's row i of six columns (and row i + 1 where two, a
 * constant at each call) in registers, three pairs a row: row i + 1's sums
 * beside row i's over k < i, each z_k loaded once for both, then its term
 * of the finished z_i (the same products and sums, in the same order, as
 * closure_forward's row updates; z - a x rounds as their z + (-a) x:
 * ss_math.h) */
static inline __attribute__((always_inline)) void
forward_rows6(const double *A, int nr, double *Z, int i, int two)
{
  const double *a0 = A + (size_t)nr * i, *a1 = a0 + nr;
  double *zi = Z + 6 * (size_t)i;
  ssV2 z[6], x[3];
  for (int q = 0; q < 3 + 3 * two; q++) memcpy(&z[q], zi + 2 * q, sizeof x[0]);
  for (int k = 0; k < i; k++) {
    const double *zk = Z + 6 * (size_t)k;
    ssV2 av = {a0[k], a0[k]};
    for (int q = 0; q < 3; q++) {
      memcpy(&x[q], zk + 2 * q, sizeof x[q]);
      z[q] -= av * x[q];
    }
    if (two) {
      ssV2 bv = {a1[k], a1[k]};
      for (int q = 0; q < 3; q++) z[3 + q] -= bv * x[q];
    }
  }
  ssV2 dv = {a0[i], a0[i]};
  for (int q = 0; q < 3; q++) z[q] /= dv;
  if (two) {
    ssV2 av = {a1[i], a1[i]}, ev = {a1[i + 1], a1[i + 1]};
    for (int q = 0; q < 3; q++) z[3 + q] = (z[3 + q] - av * z[q]) / ev;
  }
  for (int q = 0; q < 3 + 3 * two; q++) memcpy(zi + 2 * q, &z[q], sizeof x[0]);
}

/* Z <- A^-1 Z over the active rows (dropped rows give 0), for m columns
 * at once, Z (nr x m, row i = closure row i); each column sees the same
 * operations in the same order whatever m: closure_solve, in its two
 * halves, Z <- L_A^-1 Z (forward) and Z <- L_A^-T Z (backward), A = L_A L_A^T */
static inline void closure_forward(const ssArtWork *w, double *Z, int m)
{
  int nr = w->nrow;
  const double *A = w->A;
  for (int i = 0; i < nr; i++) {
    double *zi = Z + (size_t)m * i;
    if (m == 1 && i + 1 < nr && w->row_on[i] && w->row_on[i + 1]) {
      /* one column: rows i and i + 1 together, each row's chain of
       * dependent sums beside the other's (row i + 1 needs z_i only for
       * its last term), the same operations in the same order (t - a z
       * rounds as the row update's t + (-a) z: ss_math.h) */
      const double *a0 = A + i * nr, *a1 = a0 + nr;
      double t0 = Z[i], t1 = Z[i + 1];
      for (int k = 0; k < i; k++) {
        t0 -= a0[k] * Z[k];
        t1 -= a1[k] * Z[k];
      }
      t0 /= a0[i];
      t1 -= a1[i] * t0;
      Z[i] = t0;
      Z[i + 1] = t1 / a1[i + 1];
      i++;
      continue;
    }
    if (!w->row_on[i]) {
      for (int r = 0; r < m; r++) zi[r] = 0;
      continue;
    }
    if (m == 6) {
      /* a link probe's six columns: with the next row where it is on */
      if (i + 1 < nr && w->row_on[i + 1]) {
        forward_rows6(A, nr, Z, i, 1);
        i++;
      } else {
        forward_rows6(A, nr, Z, i, 0);
      }
      continue;
    }
    for (int k = 0; k < i; k++) {
      double a = A[i * nr + k];
      ss_row_add_scaled(zi, -a, Z + (size_t)m * k, m);
    }
    ss_row_div(zi, A[i * nr + i], m);
  }
}

static inline void closure_backward(const ssArtWork *w, double *Z, int m)
{
  int nr = w->nrow;
  const double *A = w->A;
  for (int i = nr - 1; i >= 0; i--) {
    double *zi = Z + (size_t)m * i;
    if (!w->row_on[i]) {
      for (int r = 0; r < m; r++) zi[r] = 0;
      continue;
    }
    for (int k = i + 1; k < nr; k++) {
      double a = A[k * nr + i];
      ss_row_add_scaled(zi, -a, Z + (size_t)m * k, m);
    }
    ss_row_div(zi, A[i * nr + i], m);
  }
}

static inline void closure_solve(const ssArtWork *w, double *Z, int m)
{
  closure_forward(w, Z, m);
  closure_backward(w, Z, m);
}

/* t = A z, A (rows x cols, row-major), each row's sum from +0 over the
 * columns in order; four rows at a time in two pair registers, their chains
 * of dependent sums beside each other and each z_j loaded once for the four
 * (MiKT z, M u) */
static void mat_vec(const double *A, int rows, int cols, const double *z, double *t)
{
  int k = 0;
  for (; k + 4 <= rows; k += 4) {
    const double *a0 = A + (size_t)k * cols, *a1 = a0 + cols, *a2 = a1 + cols, *a3 = a2 + cols;
    ssV2 s01 = {0, 0}, s23 = {0, 0};
    for (int j = 0; j < cols; j++) {
      ssV2 zj = {z[j], z[j]};
      s01 += (ssV2){a0[j], a1[j]} * zj;
      s23 += (ssV2){a2[j], a3[j]} * zj;
    }
    memcpy(t + k, &s01, sizeof s01);
    memcpy(t + k + 2, &s23, sizeof s23);
  }
  for (; k < rows; k++) {
    const double *ak = A + (size_t)k * cols;
    double s = 0;
    for (int j = 0; j < cols; j++) s += ak[j] * z[j];
    t[k] = s;
  }
}

/* x (already M'^-1 b) <- P x: remove the part that violates K x = 0 */
static void project(const ssArtWork *w, double *x)
{
  int n = w->nv, nr = w->nrow;
  if (!nr) return;
  double z[64], *zz = nr <= 64 ? z : malloc((size_t)nr * sizeof(double));
  if (!zz) return;
  /* K x over each row's columns (the rest of K is zero: the same sum) */
  for (int r = 0; r < nr; r++) {
    const double *Kr = w->K + (size_t)r * n;
    const int *col = w->kcol + (size_t)r * n;
    double s = 0;
    for (int c = 0; c < w->nkcol[r]; c++) s += Kr[col[c]] * x[col[c]];
    zz[r] = s;
  }
  closure_solve(w, zz, 1);
  double *t = w->y; /* (scratch: no caller projects w->y) */
  mat_vec(w->MiKT, n, nr, zz, t);
  for (int k = 0; k < n; k++) x[k] -= t[k];
  if (zz != z) free(zz);
}

/* ---------------------------------------------------------------------- */
/* dynamics                                                                */

static int is_ancestor(const ssModel *m, int a, int b)
{
  for (; b >= 0; b = m->body_parent[b])
    if (b == a) return 1;
  return 0;
}

ssStatus ss_art_free_velocity(const ssModel *m, ssData *d, int s, ssError *err)
{
  ssArtWork *w = d->art[s];
  const double dt = m->opt.timestep;
  int n = w->nv, b0 = w->b0;
  double *u = d->qvel + w->v0;

  /* body velocities, bias accelerations and spatial inertias (RNEA forward) */
  for (int lb = 0; lb < w->nb; lb++) {
    int b = b0 + lb, par = m->body_parent[b], nd = m->body_ndof[b];
    double *v = w->vel + 6 * lb, *a = w->acc + 6 * lb;
    if (par >= 0) {
      memcpy(v, w->vel + 6 * (par - b0), 6 * sizeof(double));
      memcpy(a, w->acc + 6 * (par - b0), 6 * sizeof(double));
    } else {
      memset(v, 0, 6 * sizeof(double));
      /* the ground accelerates upwards at g: gravity without body forces */
      a[0] = a[1] = a[2] = 0;
      ss_v3_scale(a + 3, m->opt.gravity, -1);
    }
    if (nd) {
      int k0 = m->body_dofadr[b] - w->v0;
      /* su = S qdot over the joint's dofs, three pairs of sums from +0 */
      ssV2 p[3] = {{0, 0}, {0, 0}, {0, 0}};
      add_motion(p, w->S, k0, nd, u, 1);
      double su[6], c[6];
      memcpy(su, p, sizeof su);
      if (m->body_jnttype[b] == SS_JOINT_FLOATING) {
        /* d/dt of the base's columns: only the origin term moves */
        memset(c, 0, sizeof c);
        ss_v3_cross(c + 3, u + k0, u + k0 + 3);
      } else {
        mcross(c, v, su); /* v_parent x S qdot */
      }
      add6(v, su);
      add6(a, c);
    }
    double Iw[9];
    rotate_inertia(Iw, d->body_xmat + 9 * b, m->body_inertia + 9 * b);
    double cr[3];
    ss_v3_sub(cr, d->body_xipos + 3 * b, w->org);
    spatial_inertia(w->Ic + 36 * lb, m->body_mass[b], cr, Iw);
    /* f = I a + v x* I v, I a formed in f */
    double Iv[6], vf[6], *f = w->frc + 6 * lb;
    m6v_cols(Iv, w->Ic + 36 * lb, v);
    m6v_cols(f, w->Ic + 36 * lb, a);
    fcross(vf, v, Iv);
    add6(f, vf);
    /* a system of one floating link is a free rigid body: its gyroscopic
     * torque w x (I w) about the centre of mass, which v x* I v holds, as
     * a free body's (ss_dyn_gyro; a couple, the same about O_s).  Not a
     * link of a larger tree: backward Euler of the link as if it were
     * free dissipates where a joint holds its w off a principal axis (a
     * rotor with products of inertia on a revolute joint at 50 rad/s
     * slowed to 43 in 10 s); the tree's implicit form would need the
     * bias's velocity derivative, not symmetric, in M' */
    if (w->nb == 1 && m->body_jnttype[b] == SS_JOINT_FLOATING) {
      double Iww[3], gexp[3], gimp[3];
      ss_m3_mulv(Iww, Iw, v);
      ss_v3_cross(gexp, v, Iww);
      ss_dyn_gyro(Iw, v, dt, gimp);
      for (int i = 0; i < 3; i++) f[i] += gimp[i] - gexp[i];
    }
    /* external loads at the centre of mass */
    for (int k = 0; k < m->nxforce; k++) {
      if (m->xforce_body[k] != b) continue;
      if (!ss_dyn_xforce_active(m, d, k)) continue;
      const double *F = m->xforce_force + 3 * k, *Tq = m->xforce_torque + 3 * k;
      double cxf[3];
      ss_v3_cross(cxf, cr, F);
      for (int i = 0; i < 3; i++) {
        f[i] -= Tq[i] + cxf[i];
        f[3 + i] -= F[i];
      }
    }
  }

  /* backward pass: bias forces c (in rhs, negated) and composite inertias
   * (each body's Ic, its spatial inertia from the forward pass, takes its
   * children's before it is added to its parent's) */
  for (int lb = w->nb - 1; lb >= 0; lb--) {
    int b = b0 + lb, par = m->body_parent[b], nd = m->body_ndof[b];
    const double *f = w->frc + 6 * lb;
    if (nd) {
      int k0 = m->body_dofadr[b] - w->v0;
      for (int k = 0; k < nd; k++) w->rhs[k0 + k] = -dot6(w->S + 6 * (k0 + k), f);
    }
    if (par >= 0) {
      /* the parent's force and inertia (a column at a time) take the
       * child's */
      int lp = par - b0;
      add6(w->frc + 6 * lp, f);
      for (int j = 0; j < 6; j++) add6(w->Ic + 36 * lp + 6 * j, w->Ic + 36 * lb + 6 * j);
    }
  }

  /* CRBA: M[k][j] = S_j . (Ic_b S_k) for j on the path of k, into M' on
   * the tree's pattern (L, where M u reads them, and the dampers and
   * springs below add their implicit terms and ltdl_factor factors it);
   * M's other entries are zero */
  for (int lb = 0; lb < w->nb; lb++) {
    int b = b0 + lb, nd = m->body_ndof[b];
    if (!nd) continue;
    int k0 = m->body_dofadr[b] - w->v0;
    for (int k = k0; k < k0 + nd; k++) {
      double F[6];
      m6v_cols(F, w->Ic + 36 * lb, w->S + 6 * k);
      /* two of k's chain at a time, S_j . F and S_j' . F in a pair (each
       * dot6's products and sums in its order) */
      ssV2 f[6];
      for (int i = 0; i < 6; i++) f[i] = (ssV2){F[i], F[i]};
      int t = w->anc_adr[k], te = w->anc_adr[k + 1];
      for (; t + 2 <= te; t += 2) {
        int j0 = w->anc[t], j1 = w->anc[t + 1];
        const double *s0 = w->S + 6 * j0, *s1 = w->S + 6 * j1;
        ssV2 v = (ssV2){s0[0], s1[0]} * f[0];
        for (int i = 1; i < 6; i++) v += (ssV2){s0[i], s1[i]} * f[i];
        w->L[t] = v[0];
        w->L[t + 1] = v[1];
      }
      if (t < te) {
        int j = w->anc[t];
        w->L[t] = dot6(w->S + 6 * j, F);
      }
    }
  }

  /* rhs = M u + dt (-c + explicit forces); implicit terms go into M'.
   * Row k of M u sums over j ascending from +0, as a dense row would, but
   * over the tree's pattern alone: k's ancestors and k (its chain in L,
   * reversed), then its descendants i (dsc reversed; M_ki = M_ik, L's entry
   * of row i).  The terms left out are M_kj u_j = 0 x u_j, +-0 for the
   * finite u that a step starts from, which leave a sum from +0 as it
   * stands (it is never -0) */
  for (int k = 0; k < n; k++) {
    double sum = 0;
    for (int t = w->anc_adr[k + 1] - 1; t >= w->anc_adr[k]; t--) sum += w->L[t] * u[w->anc[t]];
    for (int q = w->dsc_adr[k + 1] - 1; q >= w->dsc_adr[k]; q--)
      sum += w->L[w->dsc[2 * q + 1]] * u[w->dsc[2 * q]];
    w->rhs[k] = sum + dt * w->rhs[k];
  }

  /* joint dampers and springs, implicit (into M' = L: a dof's diagonal
   * leads its chain) */
  for (int lb = 0; lb < w->nb; lb++) {
    int b = b0 + lb, nd = m->body_ndof[b], t = m->body_jnttype[b];
    if (!nd || t == SS_JOINT_FLOATING) continue;
    int k0 = m->body_dofadr[b] - w->v0;
    double dmp = m->body_jntdamping[b], stf = m->body_jntstiffness[b];
    for (int k = k0; k < k0 + nd; k++) w->L[w->anc_adr[k]] += dt * dmp;
    if (stf > 0 && nd == 1) {
      w->L[w->anc_adr[k0]] += dt * dt * stf;
      w->rhs[k0] -= dt * stf * (d->qpos[m->body_qadr[b]] - m->body_jntref[b]);
    }
  }

  /* point-to-point spring-dampers: implicit when both ends lie on one
   * chain (the rank-one term keeps the tree's sparsity), else explicit */
  double *Js = w->y;
  for (int k = 0; k < m->nspring; k++) {
    int b1 = m->spring_body[2 * k], b2 = m->spring_body[2 * k + 1];
    if (m->body_sys[b1] != s) continue;
    const double *an = m->spring_anchor + 6 * k, *par = m->spring_param + 3 * k;
    double p1[3], p2[3], dv[3];
    body_point(d, b1, an, p1);
    body_point(d, b2, an + 3, p2);
    ss_v3_sub(dv, p1, p2);
    double len = ss_v3_normalize(dv);
    memset(Js, 0, (size_t)n * sizeof(double));
    point_rows(m, w, b1, p1, dv, 1, 1, Js, n);
    point_rows(m, w, b2, p2, dv, 1, -1, Js, n);
    double tension = par[0] * (len - par[2]);
    int low = is_ancestor(m, b1, b2) ? b2 : is_ancestor(m, b2, b1) ? b1 : -1;
    if (low >= 0) {
      double c = dt * (par[1] + dt * par[0]);
      /* Js is zero off the deeper end's path (both paths are on it): its
       * dofs i, in any order (each writes only L's row i and rhs_i) */
      const int *path = w->anc + w->padr[low - b0];
      for (int q = 0; q < w->npath[low - b0]; q++) {
        int i = path[q];
        if (Js[i] == 0) continue;
        /* (the chain's pairs only, all on the tree's pattern: i and its
         * ancestors j in L's row i) */
        for (int t = w->anc_adr[i]; t < w->anc_adr[i + 1]; t++) {
          int j = w->anc[t];
          if (Js[j] != 0) w->L[t] += c * Js[i] * Js[j];
        }
        w->rhs[i] -= dt * tension * Js[i];
      }
    } else {
      /* the rate of extension (the explicit force's only use) */
      double ldot = 0;
      for (int i = 0; i < n; i++) ldot += Js[i] * u[i];
      double f = tension + par[1] * ldot;
      for (int i = 0; i < n; i++) w->rhs[i] -= dt * f * Js[i];
    }
  }

  int bad = ltdl_factor(w);
  if (bad) {
    int k = -1 - bad;
    return ss_error_set(err, SS_ERR_NUMERIC, NULL, 0,
                        "articulated system '%s': the mass matrix is singular "
                        "at the joint of link '%s' (a massless moving link?)",
                        m->sys_name[s], m->body_name[b0 + w->dof_body[k]]);
  }
  memcpy(u, w->rhs, (size_t)n * sizeof(double));
  ltdl_solve(w, u, 1);
  if (w->nrow) {
    /* K and phi stand where the poses do since closures formed them (the
     * closure projection's last pass of the step before, whose poses this
     * step kept: ss_forward_step) */
    if (w->clo_gen != w->kin_gen) closures(m, d, w, 1);
    factor_closures(w);
    project(w, u);
  }
  memset(w->Yok, 0, (size_t)w->nb);
  memset(w->Xok, 0, (size_t)w->nb);
  memset(w->dok, 0, (size_t)n);
  return SS_OK;
}

/* The Newton phase's route to the links' and joint rows' responses, which
 * never forms Y_b (nv x 6, whose sweep away from the root fills the whole
 * tree):
 *   J_a P M'^-1 J_b^T = (T J_a^T)^T D^-1 (T J_b^T) - (L_A^-1 Z_a)^T (L_A^-1 Z_b)
 * with the tree factors M' = L^T D L (ltdl_factor), T = L^-T the solve's
 * first sweep (ltdl_solve), towards the root, which keeps J_b^T on b's
 * path, so M'^-1 = T^T D^-1 T; Z_b = K M'^-1 J_b^T = (J_b MiKT)^T and
 * A = L_A L_A^T (dropped rows give 0).  X_b = T J_b^T and W_b = L_A^-1 Z_b
 * are formed once per step and link or dof (link_probe, dof_probe); a
 * pair's block then sums over the dofs the two paths share and the
 * closure rows (probe_pair). */

/* A link (six columns, J_b^T = its path's S rows) or a dof k (one column,
 * e_k) as the factored route sees it: its path dofs, descending, X and X/D
 * on them in the path's order (path[t]'s row at t ncol, ncol its columns,
 * so that the sweeps over the path index them without reading the path),
 * and W (nr x ncol) */
typedef struct Probe {
  const int *path;
  int np;
  const double *X, *XD, *W;
} Probe;

/* X = T J^T, X/D and W = L_A^-1 K M'^-1 J^T of a probe on path (np dofs, a
 * chain in anc; J's rows: S on the path for a link, e_path[0] for a dof) */
static void reduce(ssArtWork *w, const int *path, int np, int ncol, double *X, double *XD,
                   double *W)
{
  int nr = w->nrow;
  const int *rel = w->arel + (path - w->anc);
  /* the tree solve's first sweep on the path: row t takes -L_{path[i]
   * path[t]} X_path[i] from each i < t in turn (path[i]'s chain is the path
   * from i on: that entry at t - i, Lt[rel[i]]), the sum of row updates
   * pulled into registers (the same operations in the same order: x - h y
   * rounds as their x + (-h) y, ss_math.h), then X/D */
  for (int t = 0; t < np; t++) {
    int k = path[t];
    const double *Lt = w->L + (path - w->anc) + t;
    double d = w->L[w->anc_adr[k]];
    if (ncol == 6) {
      ssV2 a0, a1, a2, x0, x1, x2;
      memcpy(&a0, w->S + 6 * k, sizeof a0);
      memcpy(&a1, w->S + 6 * k + 2, sizeof a1);
      memcpy(&a2, w->S + 6 * k + 4, sizeof a2);
      for (int i = 0; i < t; i++) {
        const double *xi = X + 6 * i, h = Lt[rel[i]];
        ssV2 hv = {h, h};
        memcpy(&x0, xi, sizeof x0);
        memcpy(&x1, xi + 2, sizeof x1);
        memcpy(&x2, xi + 4, sizeof x2);
        a0 -= hv * x0;
        a1 -= hv * x1;
        a2 -= hv * x2;
      }
      ssV2 dv = {d, d};
      memcpy(X + 6 * t, &a0, sizeof a0);
      memcpy(X + 6 * t + 2, &a1, sizeof a1);
      memcpy(X + 6 * t + 4, &a2, sizeof a2);
      a0 /= dv;
      a1 /= dv;
      a2 /= dv;
      memcpy(XD + 6 * t, &a0, sizeof a0);
      memcpy(XD + 6 * t + 2, &a1, sizeof a1);
      memcpy(XD + 6 * t + 4, &a2, sizeof a2);
    } else {
      double x = t == 0;
      for (int i = 0; i < t; i++) x -= Lt[rel[i]] * X[i];
      X[t] = x;
      XD[t] = x / d;
    }
  }
  if (!nr) return;
  if (ncol == 6) {
    /* row r = sum over the path of MiKT_kr S_k, its six sums in registers
     * (three pairs, from +0, in the path's order: the bits of row updates
     * of a zeroed W); rows r to r + 2 together, one pass over the path's
     * S (past the last row, the others are the last again, not stored) */
    for (int r = 0; r < nr; r += 3) {
      int r1 = r + 1 < nr, r2 = r + 2 < nr ? 2 : r1;
      ssV2 w0 = {0, 0}, w1 = {0, 0}, w2 = {0, 0}, v0 = {0, 0}, v1 = {0, 0}, v2 = {0, 0};
      ssV2 x0 = {0, 0}, x1 = {0, 0}, x2 = {0, 0};
      for (int i = 0; i < np; i++) {
        size_t k = (size_t)path[i]; /* (its offsets without a sign extension each) */
        const double *Sk = w->S + 6 * k, *mk = w->MiKT + k * nr + r;
        ssV2 m0 = {mk[0], mk[0]}, m1 = {mk[r1], mk[r1]}, m2 = {mk[r2], mk[r2]}, s0, s1, s2;
        memcpy(&s0, Sk, sizeof s0);
        memcpy(&s1, Sk + 2, sizeof s1);
        memcpy(&s2, Sk + 4, sizeof s2);
        w0 += m0 * s0;
        w1 += m0 * s1;
        w2 += m0 * s2;
        v0 += m1 * s0;
        v1 += m1 * s1;
        v2 += m1 * s2;
        x0 += m2 * s0;
        x1 += m2 * s1;
        x2 += m2 * s2;
      }
      memcpy(W + 6 * r, &w0, sizeof w0);
      memcpy(W + 6 * r + 2, &w1, sizeof w1);
      memcpy(W + 6 * r + 4, &w2, sizeof w2);
      if (!r1) break;
      memcpy(W + 6 * r + 6, &v0, sizeof v0);
      memcpy(W + 6 * r + 8, &v1, sizeof v1);
      memcpy(W + 6 * r + 10, &v2, sizeof v2);
      if (r2 < 2) break;
      memcpy(W + 6 * r + 12, &x0, sizeof x0);
      memcpy(W + 6 * r + 14, &x1, sizeof x1);
      memcpy(W + 6 * r + 16, &x2, sizeof x2);
    }
  } else {
    memcpy(W, w->MiKT + (size_t)path[0] * nr, (size_t)nr * sizeof(double));
  }
  closure_forward(w, W, ncol);
}

/* A link's or a dof's probe, reduced on its first use in a step.  Both are
 * inlined into their callers, the pairs' entry points: most calls find the
 * probe ready, and the check costs less than a call returning the Probe
 * through memory (reduce, the rare case, stays a call). */
static inline __attribute__((always_inline)) Probe
link_probe(ssArtWork *w, int b)
{
  size_t lb = (size_t)(b - w->b0), n = (size_t)w->nv, nr = (size_t)w->nrow;
  const int *path = w->anc + w->padr[lb];
  double *X = w->Xp + lb * n * 6, *XD = w->XD + lb * n * 6, *W = w->Wp + lb * nr * 6;
  if (!w->Xok[lb]) {
    reduce(w, path, w->npath[lb], 6, X, XD, W);
    w->Xok[lb] = 1;
  }
  return (Probe){path, w->npath[lb], X, XD, W};
}

static inline __attribute__((always_inline)) Probe
dof_probe(ssArtWork *w, int k)
{
  size_t n = (size_t)w->nv, nr = (size_t)w->nrow;
  const int *path = w->anc + w->anc_adr[k];
  int np = w->anc_adr[k + 1] - w->anc_adr[k];
  double *X = w->Xd + (size_t)k * n, *XD = w->XDd + (size_t)k * n, *W = w->Wd + (size_t)k * nr;
  if (!w->dok[k]) {
    reduce(w, path, np, 1, X, XD, W);
    w->dok[k] = 1;
  }
  return (Probe){path, np, X, XD, W};
}

/* Y_b = P M'^-1 J_b^T (nv x 6) and Lam_b = J_b Y_b, once per step.  The
 * projection P = I - M'^-1 K^T A^-1 K (project) is applied to the six
 * columns at once, and K M'^-1 J_b^T = (J_b MiKT)^T (M' is symmetric)
 * reads only the rows of MiKT on b's path. */
static void body_response(const ssModel *m, ssArtWork *w, int lb)
{
  if (w->Yok[lb]) return;
  int n = w->nv, nr = w->nrow, b = w->b0 + lb;
  double *Y = w->Y + (size_t)lb * n * 6;
  /* J_b^T: the motion subspaces of b's path, the six columns solved at once */
  memset(Y, 0, (size_t)n * 6 * sizeof(double));
  for (int a = b; a >= 0; a = m->body_parent[a]) {
    int nd = m->body_ndof[a];
    if (!nd) continue;
    int k0 = m->body_dofadr[a] - w->v0;
    memcpy(Y + 6 * k0, w->S + 6 * k0, 6 * (size_t)nd * sizeof(double));
  }
  ltdl_solve(w, Y, 6);
  if (nr) {
    /* Z = A^-1 (J_b MiKT)^T, row i = closure row i, from the link's
     * W = L_A^-1 (J_b MiKT)^T (link_probe); then Y -= MiKT Z */
    double *Z = w->Z;
    memcpy(Z, link_probe(w, b).W, 6 * (size_t)nr * sizeof(double));
    closure_backward(w, Z, 6);
    /* each row's sum t = (MiKT Z)_k in registers, three pairs (the same
     * products and sums, in order, as six-wide row updates of t) */
    for (int k = 0; k < n; k++) {
      const double *Mk = w->MiKT + (size_t)k * nr;
      ssV2 t0 = {0, 0}, t1 = {0, 0}, t2 = {0, 0}, z0, z1, z2, y;
      for (int i = 0; i < nr; i++) {
        ssV2 mv = {Mk[i], Mk[i]};
        memcpy(&z0, Z + 6 * i, sizeof z0);
        memcpy(&z1, Z + 6 * i + 2, sizeof z1);
        memcpy(&z2, Z + 6 * i + 4, sizeof z2);
        t0 += mv * z0;
        t1 += mv * z1;
        t2 += mv * z2;
      }
      double *yk = Y + 6 * k;
      memcpy(&y, yk, sizeof y);
      y -= t0;
      memcpy(yk, &y, sizeof y);
      memcpy(&y, yk + 2, sizeof y);
      y -= t1;
      memcpy(yk + 2, &y, sizeof y);
      memcpy(&y, yk + 4, sizeof y);
      y -= t2;
      memcpy(yk + 4, &y, sizeof y);
    }
  }
  double *Lam = w->Lam + 36 * lb;
  memset(Lam, 0, 36 * sizeof(double));
  for (int a = b; a >= 0; a = m->body_parent[a]) {
    int nd = m->body_ndof[a];
    if (!nd) continue;
    int k0 = m->body_dofadr[a] - w->v0;
    for (int k = k0; k < k0 + nd; k++)
      for (int r = 0; r < 6; r++) ss_row_add_scaled(Lam + 6 * r, w->S[6 * k + r], Y + 6 * k, 6);
  }
  w->Yok[lb] = 1;
}

void ss_art_link_block(const ssModel *m, ssData *d, int b, const double **Y,
                       const double **Lam)
{
  ssArtWork *w = d->art[m->body_sys[b]];
  int lb = b - w->b0;
  body_response(m, w, lb);
  *Y = w->Y + (size_t)lb * w->nv * 6;
  *Lam = w->Lam + 36 * lb;
}

/* probe_pair's three rows of a 6 x 6 block, s (nine pairs, row r in
 * s[3 r, 3 r + 3)): s_r += x_r y, or -= with sub, y six wide */
static inline __attribute__((always_inline)) void rows3_sum(ssV2 s[9], const double *x,
                                                           const double *y, const int sub)
{
  ssV2 y0, y1, y2;
  memcpy(&y0, y, sizeof y0);
  memcpy(&y1, y + 2, sizeof y1);
  memcpy(&y2, y + 4, sizeof y2);
  for (int r = 0; r < 3; r++) {
    ssV2 xv = {x[r], x[r]};
    if (sub) {
      s[3 * r] -= xv * y0;
      s[3 * r + 1] -= xv * y1;
      s[3 * r + 2] -= xv * y2;
    } else {
      s[3 * r] += xv * y0;
      s[3 * r + 1] += xv * y1;
      s[3 * r + 2] += xv * y2;
    }
  }
}

/* J_a P M'^-1 J_b^T (ca x cb, row i at out + ldo i; ca, cb: a's and b's
 * column counts, constants at each call so that the row updates unroll) */
static inline __attribute__((always_inline)) void
probe_pair(const ssArtWork *w, Probe a, Probe b, int ca, int cb, double *out, int ldo)
{
  /* the shared part of two paths to the root is the tail of both (from i
   * on in a's, from j on in b's), a common dof's chain, so as long in each:
   * the paths compared aligned at their ends, its first dof is the first
   * match (any dof of both stands as far from either end) */
  int nr = w->nrow, i = a.np > b.np ? a.np - b.np : 0, j = i + b.np - a.np;
  while (i < a.np && a.path[i] != b.path[j]) {
    i++;
    j++;
  }
  if (ca == 6 && cb == 6) {
    /* two links: three rows of the block at a time, their 18 sums in
     * registers (nine pairs, from +0), the same products and sums in the
     * same order as the row updates below (s - x y rounds as their
     * s + (-x) y: ss_math.h) */
    for (int r0 = 0; r0 < 6; r0 += 3) {
      ssV2 s[9] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}};
      for (int k = i, l = j; k < a.np; k++, l++)
        rows3_sum(s, a.X + 6 * k + r0, b.XD + 6 * l, 0);
      for (int k = 0; k < nr; k++) rows3_sum(s, a.W + 6 * k + r0, b.W + 6 * k, 1);
      /* a pair at a time (one copy of a row's three would keep s in
       * memory, zeroed there and stored after each sum) */
      for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++)
          memcpy(out + (size_t)ldo * (r0 + r) + 2 * q, &s[3 * r + q], sizeof s[0]);
    }
    return;
  }
  if (ca == 6 && cb == 1) {
    /* a link and a dof: the six sums in three pairs (from +0), each the
     * same products and sums in the same order as the row updates below */
    ssV2 s[3] = {{0, 0}, {0, 0}, {0, 0}}, xv;
    for (; i < a.np; i++, j++) {
      ssV2 yv = {b.XD[j], b.XD[j]};
      for (int r = 0; r < 3; r++) {
        memcpy(&xv, a.X + 6 * i + 2 * r, sizeof xv);
        s[r] += xv * yv;
      }
    }
    for (int k = 0; k < nr; k++) {
      ssV2 yv = {b.W[k], b.W[k]};
      for (int r = 0; r < 3; r++) {
        memcpy(&xv, a.W + 6 * k + 2 * r, sizeof xv);
        s[r] -= xv * yv;
      }
    }
    for (int r = 0; r < 6; r++) out[(size_t)ldo * r] = s[r / 2][r % 2];
    return;
  }
  double acc[36];
  memset(acc, 0, (size_t)ca * cb * sizeof(double)); /* (the block's entries only) */
  for (; i < a.np; i++, j++) {
    const double *x = a.X + ca * i, *y = b.XD + cb * j;
    for (int r = 0; r < ca; r++) ss_row_add_scaled(acc + cb * r, x[r], y, cb);
  }
  for (int k = 0; k < nr; k++)
    for (int r = 0; r < ca; r++) ss_row_add_scaled(acc + cb * r, -a.W[ca * k + r], b.W + cb * k, cb);
  for (int r = 0; r < ca; r++) memcpy(out + (size_t)ldo * r, acc + cb * r, cb * sizeof(double));
}

void ss_art_link_pair(const ssModel *m, ssData *d, int a, int b, double *out, int ldo)
{
  ssArtWork *w = d->art[m->body_sys[a]];
  probe_pair(w, link_probe(w, a), link_probe(w, b), 6, 6, out, ldo);
}

void ss_art_link_dof_pair(const ssModel *m, ssData *d, int b, int dof, double out[6])
{
  ssArtWork *w = d->art[m->body_sys[b]];
  probe_pair(w, link_probe(w, b), dof_probe(w, dof - w->v0), 6, 1, out, 1);
}

double ss_art_dof_pair(ssData *d, int sys, int dof1, int dof2)
{
  ssArtWork *w = d->art[sys];
  double g;
  probe_pair(w, dof_probe(w, dof1 - w->v0), dof_probe(w, dof2 - w->v0), 1, 1, &g, 1);
  return g;
}

void ss_art_dof_force_add(ssData *d, int sys, int dof, double f)
{
  ssArtWork *w = d->art[sys];
  w->fsum[dof - w->v0] += f;
}

void ss_art_force_add(const ssModel *m, ssData *d, int b, const double F[6])
{
  ssArtWork *w = d->art[m->body_sys[b]];
  for (int a = b; a >= 0; a = m->body_parent[a]) {
    int nd = m->body_ndof[a];
    if (!nd) continue;
    int k0 = m->body_dofadr[a] - w->v0;
    for (int k = k0; k < k0 + nd; k++) w->fsum[k] += dot6(w->S + 6 * k, F);
  }
}

void ss_art_force_apply(const ssModel *m, ssData *d, int sys, double *u)
{
  ssArtWork *w = d->art[sys];
  int n = w->nv;
  double *x = w->fsum;
  ltdl_solve(w, x, 1);
  project(w, x);
  for (int k = 0; k < n; k++) u[k] += x[k];
  memset(x, 0, (size_t)n * sizeof(double));
}

const double *ss_art_origin(const ssData *d, int sys) { return d->art[sys]->org; }

void ss_art_contact_rows(const double p[3], const double frame[9], double X[18])
{
  /* contact-frame velocity of the point from a spatial velocity */
  for (int i = 0; i < 3; i++) {
    const double *f = frame + 3 * i;
    ss_v3_cross(X + 6 * i, p, f);
    memcpy(X + 6 * i + 3, f, 3 * sizeof(double));
  }
}

void ss_art_contact_response(const ssModel *m, ssData *d, int b,
                             const double X[18], double LX[18], double G[9])
{
  const double *Y, *Lam;
  ss_art_link_block(m, d, b, &Y, &Lam);
  for (int i = 0; i < 3; i++) m6v(LX + 6 * i, Lam, X + 6 * i);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) G[3 * i + j] = dot6(X + 6 * i, LX + 6 * j);
}

void ss_art_dof_row(ssData *d, int s, int dof, double sign, double *J, double G[9])
{
  ssArtWork *w = d->art[s];
  int n = w->nv;
  memset(J, 0, 3 * (size_t)n * sizeof(double));
  J[dof - w->v0] = sign;
  memset(G, 0, 9 * sizeof(double));
  G[0] = ss_art_dof_pair(d, s, dof, dof);
}

void ss_art_dof_response(ssData *d, int s, int dof, double sign, double *W)
{
  ssArtWork *w = d->art[s];
  int n = w->nv, k = dof - w->v0;
  double *col = w->x;
  memset(col, 0, (size_t)n * sizeof(double));
  col[k] = 1;
  ltdl_solve(w, col, 1);
  project(w, col);
  memset(W, 0, 3 * (size_t)n * sizeof(double));
  for (int i = 0; i < n; i++) W[3 * i] = sign * col[i];
}

void ss_art_link_velocity(const ssModel *m, const ssData *d, int b,
                          double V[6])
{
  ss_art_link_motion(m, d, b, d->qvel + d->art[m->body_sys[b]]->v0, V);
}

void ss_art_link_motion(const ssModel *m, const ssData *d, int b,
                        const double *u, double V[6])
{
  ss_art_link_motion_cols(m, d, b, u, 1, 1, V, 1);
}

void ss_art_link_motion_cols(const ssModel *m, const ssData *d, int b, const double *U,
                             int ldu, int ncol, double *out, int ldo)
{
  const ssArtWork *w = d->art[m->body_sys[b]];
  const int *path = w->bord + w->padr[b - w->b0];
  int np = w->npath[b - w->b0];
  for (int c = 0; c < ncol; c++) {
    /* each body's dofs in turn from b's (its path in bord: no walk of the
     * bodies), the sums from +0 */
    ssV2 p[3] = {{0, 0}, {0, 0}, {0, 0}};
    for (int t = 0; t < np; t++) {
      int k = path[t];
      ssV2 uk = {U[(size_t)ldu * k + c], U[(size_t)ldu * k + c]}, sk;
      for (int i = 0; i < 3; i++) {
        memcpy(&sk, w->S + 6 * k + 2 * i, sizeof sk);
        p[i] += sk * uk;
      }
    }
    double V[6];
    memcpy(V, p, sizeof V);
    for (int i = 0; i < 6; i++) out[(size_t)ldo * i + c] = V[i];
  }
}

void ss_art_point_velocity(const ssModel *m, const ssData *d, int b,
                           const double pw[3], double v[3])
{
  ss_art_point_velocity_of(m, d, d->qvel, b, pw, v);
}

void ss_art_point_velocity_of(const ssModel *m, const ssData *d, const double *qvel, int b,
                              const double pw[3], double v[3])
{
  double sv[6], wp[3], p[3];
  ss_art_link_motion(m, d, b, qvel + d->art[m->body_sys[b]]->v0, sv);
  ss_v3_sub(p, pw, d->art[m->body_sys[b]]->org);
  ss_v3_cross(wp, sv, p);
  ss_v3_add(v, sv + 3, wp);
}

/* q <- q (+) s du, joint by joint */
static void advance(const ssModel *m, ssData *d, const ssArtWork *w,
                    const double *du, double s)
{
  for (int lb = 0; lb < w->nb; lb++) {
    int b = w->b0 + lb, nd = m->body_ndof[b];
    if (!nd) continue;
    double *q = d->qpos + m->body_qadr[b];
    const double *v = du + m->body_dofadr[b] - w->v0;
    switch (m->body_jnttype[b]) {
    case SS_JOINT_REVOLUTE:
    case SS_JOINT_PRISMATIC:
      q[0] += s * v[0];
      break;
    case SS_JOINT_SPHERICAL: {
      double rv[3], dq[4];
      ss_v3_scale(rv, v, s);
      ss_quat_from_rotvec(dq, rv);
      ss_quat_mul(q, q, dq); /* local angular velocity */
      ss_quat_normalize(q);
      break;
    }
    case SS_JOINT_FLOATING: {
      double rv[3], dq[4];
      ss_v3_addscl(q, v, s);
      ss_v3_scale(rv, v + 3, s);
      ss_quat_from_rotvec(dq, rv);
      ss_quat_mul(q + 3, dq, q + 3); /* world angular velocity */
      ss_quat_normalize(q + 3);
      break;
    }
    default:
      break;
    }
  }
}

double ss_art_closure_error(const ssModel *m, ssData *d, int s)
{
  ssArtWork *w = d->art[s];
  if (!w->nrow) return 0;
  ss_art_forward(m, d, s);
  closures(m, d, w, 0);
  double e = 0;
  for (int r = 0; r < w->nrow; r++) e = fmax(e, fabs(w->phi[r]));
  return e;
}

void ss_art_integrate(const ssModel *m, ssData *d, int s)
{
  ssArtWork *w = d->art[s];
  advance(m, d, w, d->qvel + w->v0, m->opt.timestep);
  if (!w->nrow) return;
  /* remove closure drift: steps du = -M'^-1 K^T A^-1 phi, M' of this step.
   * K and A are first those of the step's start (ss_art_free_velocity
   * factored them; the configuration has moved by one step since): a chord
   * method, each step cutting phi by about the relative change of K over
   * the step, at the cost of a forward pass instead of a factorisation.
   * Where the last step did not cut phi at least fourfold, K and A are
   * refactored at the current configuration (a Newton step). */
  double err = 0, prev = INFINITY, z[64];
  double *zz = w->nrow <= 64 ? z : malloc((size_t)w->nrow * sizeof(double));
  if (!zz) return;
  for (int it = 0; it < 12; it++) {
    /* the bodies phi reads, the others where the loop stops here (the
     * last pass poses all: the loop then moves qpos once more) */
    forward_poses(m, d, s, it < 11);
    closures(m, d, w, 0);
    err = 0;
    for (int r = 0; r < w->nrow; r++) {
      double e = fabs(w->phi[r]);
      err = e > err ? e : err; /* fmax's maximum, without its call */
    }
    if (err < 1e-13) break;
    /* K at these poses only where A is refactored (the chord steps keep
     * the step's K and A; ss_art_free_velocity forms K where the loop
     * leaves it stale: the same rows) */
    if (!(err <= 0.25 * prev)) {
      forward_rest(m, d, s); /* (K reads S) */
      closures(m, d, w, 1);
      factor_closures(w);
    }
    prev = err;
    memcpy(zz, w->phi, (size_t)w->nrow * sizeof(double));
    closure_solve(w, zz, 1);
    double *du = w->rhs;
    mat_vec(w->MiKT, w->nv, w->nrow, zz, du);
    for (int k = 0; k < w->nv; k++) du[k] = -du[k];
    advance(m, d, w, du, 1);
  }
  /* the last poses' centres of mass and subspaces, where a refactoring
   * pass has not formed them (at the poses ss_art_forward would form them
   * at: those of kin_q) */
  if (!w->kin_ok) forward_rest(m, d, s);
  if (err > d->closure_error) d->closure_error = err;
  if (zz != z) free(zz);
}

/* ---------------------------------------------------------------------- */
/* building from a URDF                                                    */

ssArtDef ss_art_def_default(void)
{
  ssArtDef a;
  memset(&a, 0, sizeof a);
  a.quat[0] = 1;
  a.fixed_base = -1;
  return a;
}

int ss_model_find_body(const ssModel *m, int s, const char *name)
{
  for (int b = m->sys_bodyadr[s]; b < m->sys_bodyadr[s] + m->sys_nbody[s]; b++)
    if (!strcmp(m->body_name[b], name)) return b;
  return -1;
}

static void rot_inertia(double out[9], const double q[4], const double v[6])
{
  double I[9] = {v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5]};
  double R[9];
  ss_quat_to_mat(R, q);
  rotate_inertia(out, R, I);
}

/* each mesh geom loads its own copy: scale is baked into the vertices */
static int load_mesh(ssModel *m, const ssUrdfGeom *g, ssError *err)
{
  ssMesh *mesh = NULL;
  if (ss_mesh_load(g->mesh_path, g->mesh_scale, &mesh, err) != SS_OK) return -1;
  int k = ss_model_push_mesh(m, mesh, g->mesh_path, err);
  if (k < 0)
    ss_mesh_free(mesh);
  else
    memcpy(m->mesh_scale + 3 * k, g->mesh_scale, 3 * sizeof(double));
  return k;
}

/* At the initial configuration, every closure must constrain something
 * the earlier ones do not: a closure all of whose rows depend on the rows
 * before it (a duplicate pin, say) is reported.  Rows that are only partly
 * dependent (the out-of-plane row of a pin in a planar linkage) are fine:
 * the solver drops them.  Gram-Schmidt on the rows of K. */
static ssStatus check_closures(ssModel *m, int s, ssError *err)
{
  /* nothing to check without closures: the data below would only be
   * allocated and freed, and a system's workspace (ss_art_work_new) holds
   * dense per-link blocks, links x dofs in size, which made building a
   * 20 000-link chain take 10 s for no result */
  if (sys_closures(m, s, NULL, NULL) == 0) return SS_OK;
  ssData *d = ss_data_new(m);
  if (!d) return ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
  ssArtWork *w = d->art[s];
  ssStatus st = SS_OK;
  if (w->nrow) {
    ss_forward(m, d);
    closures(m, d, w, 1);
    int n = w->nv, r = 0;
    double *Q = calloc((size_t)w->nrow * (n ? n : 1), sizeof(double));
    if (!Q) st = ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
    int nq = 0;
    for (int e = 0; !st && e < w->neq; e++) {
      int k = w->eq[e], rows = m->eq_type[k] == SS_CLOSURE_PIN ? 3 : 1, added = 0;
      for (int i = 0; i < rows; i++, r++) {
        double *v = Q + (size_t)nq * n, norm0 = 0, norm = 0;
        memcpy(v, w->K + (size_t)r * n, (size_t)n * sizeof(double));
        for (int j = 0; j < n; j++) norm0 += v[j] * v[j];
        for (int q = 0; q < nq; q++) {
          const double *b = Q + (size_t)q * n;
          double dot = 0;
          for (int j = 0; j < n; j++) dot += v[j] * b[j];
          for (int j = 0; j < n; j++) v[j] -= dot * b[j];
        }
        for (int j = 0; j < n; j++) norm += v[j] * v[j];
        if (norm0 > 0 && norm > 1e-16 * norm0) {
          norm = sqrt(norm);
          for (int j = 0; j < n; j++) v[j] /= norm;
          nq++;
          added++;
        }
      }
      if (!added)
        st = ss_error_set(err, SS_ERR_VALUE, m->sys_source[s], m->eq_line[k],
                          "articulated system '%s': loop closure %d (%s between "
                          "'%s' and '%s', URDF line %d) is redundant or singular "
                          "at the initial configuration: the joints and the "
                          "closures before it already fix what it constrains",
                          m->sys_name[s], e,
                          m->eq_type[k] == SS_CLOSURE_PIN ? "pin" :
                          m->eq_type[k] == SS_CLOSURE_DISTANCE ? "distance" : "equality",
                          m->body_name[m->eq_body[2 * k]],
                          m->body_name[m->eq_body[2 * k + 1]], m->eq_line[k]);
    }
    free(Q);
  }
  ss_data_free(d);
  return st;
}

int ss_model_add_articulated(ssModel *m, const ssUrdf *u, const ssArtDef *def,
                             ssError *err)
{
  const char *f = m->source_path;
  int line = def->line;
  /* the scene decides the base; without a word from it a URDF rooted at a
   * "world" link does; otherwise it floats.  A URDF's world pose of the
   * root is composed with the scene's placement. */
  int fixed = def->fixed_base >= 0 ? def->fixed_base : u->world_base == SS_URDF_BASE_FIXED;
  double base_pos[3], base_quat[4];
  memcpy(base_pos, def->pos, sizeof base_pos);
  memcpy(base_quat, def->quat, sizeof base_quat);
  ss_quat_normalize(base_quat);
  if (u->world_base != SS_URDF_BASE_NONE) {
    double R[9], off[3];
    ss_quat_to_mat(R, base_quat);
    ss_m3_mulv(off, R, u->base_pos);
    ss_v3_add(base_pos, base_pos, off);
    ss_quat_mul(base_quat, base_quat, u->base_quat);
    ss_quat_normalize(base_quat);
  }
  /* coordinates: the base, then every joint in the URDF's order */
  int nq = fixed ? 0 : 7, nv = fixed ? 0 : 6;
  for (int j = 0; j < u->njoint; j++) {
    switch (u->joint[j].type) {
    case SS_JOINT_REVOLUTE:
    case SS_JOINT_PRISMATIC: nq += 1; nv += 1; break;
    case SS_JOINT_SPHERICAL:
      /* a joint spring is tau = -stiffness (q - spring_mount), one
       * coordinate; on a ball joint it was dropped without a word */
      if (u->joint[j].stiffness > 0) {
        ss_error_set(err, SS_ERR_UNSUPPORTED, u->path, u->joint[j].line,
                     "joint '%s': stiffness %g on a spherical joint is not supported "
                     "(a joint spring acts on a revolute, continuous or prismatic "
                     "joint)", u->joint[j].name, u->joint[j].stiffness);
        return -1;
      }
      nq += 4;
      nv += 3;
      break;
    case SS_JOINT_FIXED: break;
    default:
      ss_error_set(err, SS_ERR_UNSUPPORTED, u->path, u->joint[j].line,
                   "joint '%s': a floating joint is only allowed at the root",
                   u->joint[j].name);
      return -1;
    }
  }
  if (def->qpos && !fixed && def->pose_given) {
    ss_error_set(err, SS_ERR_VALUE, f, line,
                 "articulated_system '%s': %s sets the floating base's pose (its "
                 "first 7 values: position, quaternion w x y z), and so do pos and "
                 "quat: give one or the other", def->name,
                 def->qpos_name ? def->qpos_name : "qpos");
    return -1;
  }
  if (def->qpos && def->nqpos != nq) {
    ss_error_set(err, SS_ERR_VALUE, f, line,
                 "articulated_system '%s': %s has %d values, expected %d",
                 def->name, def->qpos_name ? def->qpos_name : "qpos",
                 def->nqpos, nq);
    return -1;
  }
  if (def->qvel && def->nqvel != nv) {
    ss_error_set(err, SS_ERR_VALUE, f, line,
                 "articulated_system '%s': qvel has %d values, expected %d",
                 def->name, def->nqvel, nv);
    return -1;
  }
  if (def->qpos && !ss_all_within(def->qpos, nq, DBL_MAX)) {
    ss_error_set(err, SS_ERR_VALUE, f, line,
                 "articulated_system '%s': %s values must be finite", def->name,
                 def->qpos_name ? def->qpos_name : "qpos");
    return -1;
  }
  for (int k = 0; def->qvel && k < nv; k++)
    if (!ss_all_within(def->qvel + k, 1, SS_SPEED_MAX)) {
      ss_error_set(err, SS_ERR_VALUE, f, line,
                   "articulated_system '%s': qvel value %d of %d is %g; each "
                   "must be at most 1e5 in magnitude (m/s, rad/s), the largest "
                   "speed a step accepts", def->name, k + 1, nv, def->qvel[k]);
      return -1;
    }
  int mat = ss_model_material(m, def->material);
  if (mat < 0) {
    ss_error_set(err, SS_ERR_NOMEM, f, line, "out of memory");
    return -1;
  }
  /* a failure below removes everything this call added */
  ssModelMark mark = ss_model_mark(m);
  int s = ss_model_push_sys(m, def->name, SS_SYS_ARTICULATED, nq, nv, line, err);
  if (s < 0) return -1;
  m->sys_fixed[s] = fixed;
  free(m->sys_source[s]);
  free(m->sys_resdir[s]);
  m->sys_source[s] = strdup(def->urdf_path ? def->urdf_path : u->path);
  m->sys_resdir[s] = strdup(def->res_dir ? def->res_dir : "");
  int *body_of = malloc((size_t)u->nlink * sizeof(int));
  if (!m->sys_source[s] || !m->sys_resdir[s] || !body_of) {
    free(body_of);
    ss_error_set(err, SS_ERR_NOMEM, f, line, "out of memory");
    ss_model_rollback(m, &mark);
    return -1;
  }
  for (int i = 0; i < u->nlink; i++) body_of[i] = -1;
  int qa = m->sys_qadr[s], va = m->sys_vadr[s];
  double *q0 = nq ? m->qpos0 + m->sys_qadr[s] : NULL;   /* NULL + 0 is UB */

  /* bodies: the root, then each joint's child (parents come first) */
  for (int j = -1; j < u->njoint; j++) {
    const ssUrdfJoint *J = j >= 0 ? &u->joint[j] : NULL;
    int li = J ? J->child : u->root;
    const ssUrdfLink *L = &u->link[li];
    int parent = J ? body_of[J->parent] : -1;
    int b = ss_model_push_body(m, s, L->name, J ? J->name : "", parent, err);
    if (b < 0) goto fail;
    body_of[li] = b;
    m->body_mass[b] = L->mass;
    rot_inertia(m->body_inertia + 9 * b, L->com_quat, L->inertia);
    memcpy(m->body_ipos + 3 * b, L->com, 3 * sizeof(double));
    if (!J) {
      m->body_jnttype[b] = fixed ? SS_JOINT_FIXED : SS_JOINT_FLOATING;
      memcpy(m->body_jntpos + 3 * b, base_pos, 3 * sizeof(double));
      memcpy(m->body_jntquat + 4 * b, base_quat, 4 * sizeof(double));
      if (!fixed) {
        m->body_qadr[b] = qa;
        m->body_dofadr[b] = va;
        m->body_ndof[b] = 6;
        memcpy(q0, base_pos, 3 * sizeof(double));
        memcpy(q0 + 3, m->body_jntquat + 4 * b, 4 * sizeof(double));
        qa += 7;
        va += 6;
      }
    } else {
      m->body_jnttype[b] = J->type;
      memcpy(m->body_jntpos + 3 * b, J->pos, 3 * sizeof(double));
      memcpy(m->body_jntquat + 4 * b, J->quat, 4 * sizeof(double));
      memcpy(m->body_jntaxis + 3 * b, J->axis, 3 * sizeof(double));
      m->body_jntdamping[b] = J->damping;
      m->body_jntstiffness[b] = J->stiffness;
      m->body_jntref[b] = J->spring_mount;
      m->body_jntlimited[b] = J->limited;
      m->body_jntrange[2 * b] = J->lower;
      m->body_jntrange[2 * b + 1] = J->upper;
      int nd = J->type == SS_JOINT_SPHERICAL ? 3 : J->type == SS_JOINT_FIXED ? 0 : 1;
      if (nd) {
        m->body_qadr[b] = qa;
        m->body_dofadr[b] = va;
        m->body_ndof[b] = nd;
        if (nd == 3) m->qpos0[qa] = 1; /* identity quaternion */
        qa += nd == 3 ? 4 : 1;
        va += nd;
      }
    }
    /* colliders and visuals */
    for (int g = 0; g < L->ngeom; g++) {
      const ssUrdfGeom *G = &L->geom[g];
      int mesh = -1;
      double size[3];
      memcpy(size, G->size, sizeof size);
      if (G->type == SS_GEOM_MESH) {
        if ((mesh = load_mesh(m, G, err)) < 0) {
          ssError me = *err;
          ss_error_set(err, me.code, u->path, G->line, "link '%s': mesh %s: %s",
                       L->name, G->mesh_path, me.message);
          goto fail;
        }
        const ssMesh *me = m->mesh[mesh];
        for (int k = 0; k < 3; k++) size[k] = me->hi[k] - me->lo[k];
      }
      if (ss_model_push_geom(m, b, G->type, size, G->pos, G->quat, mat, G->rgba,
                             G->collision ? 1 : 2, mesh, err) < 0)
        goto fail;
    }
  }
  if (def->qpos) {
    memcpy(q0, def->qpos, (size_t)nq * sizeof(double));
    /* a floating base's or ball joint's quaternion in qpos: a zero one is
     * refused, as <state quat> is; any other is normalised (one of unit
     * length to 1e-14 is kept as written, so that exports read back bit
     * for bit), as the base pose is: a rotation that is not orthonormal
     * would scale the links it carries */
    for (int b = m->sys_bodyadr[s]; b < m->sys_bodyadr[s] + m->sys_nbody[s]; b++) {
      int t = m->body_jnttype[b];
      if (t != SS_JOINT_FLOATING && t != SS_JOINT_SPHERICAL) continue;
      double *qq = m->qpos0 + m->body_qadr[b] + (t == SS_JOINT_FLOATING ? 3 : 0);
      double n2 = qq[0] * qq[0] + qq[1] * qq[1] + qq[2] * qq[2] + qq[3] * qq[3];
      if (!(n2 > 0)) {
        ss_error_set(err, SS_ERR_VALUE, f, line,
                     "articulated_system '%s': %s values %d to %d (the %s of link '%s') "
                     "are a quaternion of zero length (w x y z)",
                     def->name, def->qpos_name ? def->qpos_name : "qpos",
                     (int)(qq - q0) + 1, (int)(qq - q0) + 4,
                     t == SS_JOINT_FLOATING ? "floating base's orientation" : "ball joint",
                     m->body_name[b]);
        goto fail;
      }
      if (fabs(n2 - 1) > 1e-14) ss_quat_normalize(qq);
    }
  }
  if (def->qvel) memcpy(m->qvel0 + m->sys_vadr[s], def->qvel, (size_t)nv * sizeof(double));

  /* closures and springs: implicit anchors and lengths come from the
   * initial configuration */
  double *xp = malloc((size_t)m->sys_nbody[s] * 7 * sizeof(double));
  if (!xp) {
    ss_error_set(err, SS_ERR_NOMEM, f, line, "out of memory");
    goto fail;
  }
  double *xq = xp + 3 * m->sys_nbody[s];
  kinematics(m, s, m->qpos0, xp, xq, NULL, NULL, 0);
  int b0 = m->sys_bodyadr[s];
#define WORLD_POINT(b, local, out)                                             \
  do {                                                                         \
    double R_[9];                                                              \
    ss_quat_to_mat(R_, xq + 4 * ((b) - b0));                                   \
    ss_m3_mulv(out, R_, local);                                                \
    ss_v3_add(out, out, xp + 3 * ((b) - b0));                                  \
  } while (0)
#define LOCAL_POINT(b, world, out)                                             \
  do {                                                                         \
    double R_[9], d_[3];                                                       \
    ss_quat_to_mat(R_, xq + 4 * ((b) - b0));                                   \
    ss_v3_sub(d_, world, xp + 3 * ((b) - b0));                                 \
    ss_m3_mulvT(out, R_, d_);                                                  \
  } while (0)
  for (int c = 0; c < u->nclosure; c++) {
    const ssUrdfClosure *C = &u->closure[c];
    double an[6] = {0, 0, 0, 0, 0, 0}, data[2] = {0, 0};
    int b1, b2;
    char name[64];
    snprintf(name, sizeof name, "closure%d", c);
    if (C->type == SS_CLOSURE_EQUALITY) {
      b1 = body_of[u->joint[C->joint1].child];
      b2 = body_of[u->joint[C->joint2].child];
      data[0] = C->ratio;
      data[1] = C->offset;
    } else {
      b1 = body_of[C->body1];
      b2 = body_of[C->body2];
      memcpy(an, C->anchor1, 3 * sizeof(double));
      double p1[3], p2[3];
      WORLD_POINT(b1, an, p1);
      if (C->has_anchor2) {
        memcpy(an + 3, C->anchor2, 3 * sizeof(double));
      } else if (C->type == SS_CLOSURE_PIN) {
        LOCAL_POINT(b2, p1, an + 3);
      }
      WORLD_POINT(b2, an + 3, p2);
      double dv[3];
      ss_v3_sub(dv, p1, p2);
      data[0] = C->type == SS_CLOSURE_DISTANCE && C->length < 0 ? ss_v3_norm(dv) : C->length;
    }
    if (ss_model_push_eq(m, name, C->type, s, b1, b2, an, data, C->line, err) < 0) {
      free(xp);
      goto fail;
    }
  }
  for (int k = 0; k < u->nspring; k++) {
    const ssUrdfSpring *S = &u->spring[k];
    int b1 = body_of[S->body1], b2 = body_of[S->body2];
    double an[6], p1[3], p2[3], dv[3];
    memcpy(an, S->anchor1, 3 * sizeof(double));
    memcpy(an + 3, S->anchor2, 3 * sizeof(double));
    WORLD_POINT(b1, an, p1);
    WORLD_POINT(b2, an + 3, p2);
    ss_v3_sub(dv, p1, p2);
    double par[3] = {S->stiffness, S->damping,
                     S->rest_length < 0 ? ss_v3_norm(dv) : S->rest_length};
    if (ss_model_push_spring(m, S->name, b1, b2, an, par, err) < 0) {
      free(xp);
      goto fail;
    }
  }
#undef WORLD_POINT
#undef LOCAL_POINT
  free(xp);
  free(body_of);
  if (check_closures(m, s, err) != SS_OK) {
    ss_model_rollback(m, &mark);
    return -1;
  }
  return s;
fail:
  free(body_of);
  ss_model_rollback(m, &mark);
  return -1;
}

int ss_model_add_pd(ssModel *m, int s, const char *joint, double kp, double kd,
                    double qt, double vt, double effort, int line, ssError *err)
{
  int b = -1;
  for (int k = m->sys_bodyadr[s]; k < m->sys_bodyadr[s] + m->sys_nbody[s]; k++)
    if (!strcmp(m->body_jntname[k], joint)) b = k;
  if (b < 0) {
    ss_error_set(err, SS_ERR_NOTFOUND, m->source_path, line,
                 "pd: articulated_system '%s' has no joint named '%s'",
                 m->sys_name[s], joint);
    return -1;
  }
  if (m->body_ndof[b] != 1) {
    ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                 "pd: joint '%s' must be revolute, continuous or prismatic",
                 joint);
    return -1;
  }
  if (!isfinite(kp) || kp < 0 || !isfinite(kd) || kd < 0 || !isfinite(qt) ||
      !isfinite(vt) || !isfinite(effort) || effort < 0) {
    ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                 "pd on joint '%s': gains and effort_limit must be finite and "
                 ">= 0, targets finite", joint);
    return -1;
  }
  /* two controllers on one joint would both act, summed, each within its
   * own effort bound: what a second <pd> for the same joint means is
   * unclear, so it is an error rather than a guess */
  for (int k = 0; k < m->npd; k++)
    if (m->pd_body[k] == b) {
      ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                   "pd: joint '%s' of articulated_system '%s' already has a PD "
                   "controller (one per joint)", joint, m->sys_name[s]);
      return -1;
    }
  double gain[3] = {kp, kd, effort}, target[2] = {qt, vt};
  return ss_model_push_pd(m, b, gain, target, err);
}

/* One bounded implicit row per PD controller and one unilateral row per
 * joint at (or within a step of) its limit. */
ssStatus ss_art_rows(const ssModel *m, ssData *d, ssError *err)
{
  const double dt = m->opt.timestep;
  for (int k = 0; k < m->npd; k++) {
    int b = m->pd_body[k], s = m->body_sys[b];
    if (!d->sys_active[s]) continue;
    int nv = m->sys_nv[s], dof = m->body_dofadr[b];
    ssContact *c = ss_contact_new(d, 6L * nv);
    if (!c) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
    const double *g = m->pd_gain + 3 * k, *t = d->pd_target + 2 * k;
    double q = d->qpos[m->body_qadr[b]];
    /* tau(u) = kp (qt - q - dt u) + kd (ut - u), as an impulse over dt */
    c->type = SS_CONTACT_PD;
    c->sys = s;
    c->vadr = m->sys_vadr[s];
    c->nv = nv;
    c->geom = -1;
    c->hfield = -1;
    c->vertex = -1;
    c->dof = dof;
    c->row_a = dt * (g[0] * (t[0] - q) + g[1] * t[1]);
    c->row_b = dt * (g[1] + dt * g[0]);
    c->row_bound = g[2] > 0 ? g[2] * dt : INFINITY;
    ss_art_dof_row(d, s, dof, 1, d->jac + c->jadr, c->G);
  }
  for (int b = 0; b < m->nbody; b++) {
    int s = m->body_sys[b];
    if (!m->body_jntlimited[b] || m->body_ndof[b] != 1 || !d->sys_active[s]) continue;
    if (m->sys_type[s] != SS_SYS_ARTICULATED) continue;
    double q = d->qpos[m->body_qadr[b]], u = d->qvel[m->body_dofadr[b]];
    const double *r = m->body_jntrange + 2 * b;
    for (int side = 0; side < 2; side++) {
      /* gap to the limit, positive inside the range */
      double gap = side == 0 ? q - r[0] : r[1] - q;
      double vin = side == 0 ? u : -u;
      if (gap + dt * vin > 0 && gap > 0) continue;
      int nv = m->sys_nv[s];
      ssContact *c = ss_contact_new(d, 6L * nv);
      if (!c) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
      c->type = SS_CONTACT_LIMIT;
      c->sys = s;
      c->vadr = m->sys_vadr[s];
      c->nv = nv;
      c->geom = -1;
      c->hfield = -1;
      c->vertex = -1;
      c->dof = m->body_dofadr[b];
      c->g0 = gap;
      d->contact_deep += gap < 0;
      /* (past the limit: stop there; the push moves it back,
       * ss_solver_push) */
      c->vn_target = gap >= 0 ? -gap / dt : 0;
      ss_art_dof_row(d, s, c->dof, side == 1 ? -1 : 1, d->jac + c->jadr, c->G);
    }
  }
  return SS_OK;
}
