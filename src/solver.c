/* solver.c -- per-contact Gauss-Seidel on the impulse-response blocks.
 *
 * Each sweep visits every contact once.  For contact i the others are held:
 * its velocity without its own impulse is v0 = J u - G lambda_i, and its new
 * impulse solves the contact law at the end-of-step velocity
 * v = v0 + G lambda_i.  Soil points solve the implicit soil law of
 * DESIGN 3.1 (scalar, safeguarded root finding -- never a penalty spring);
 * rigid points a Coulomb cone.  The system velocity u is updated after each
 * contact by W (lambda_new - lambda_old). */
#include "solver.h"
#include "articulated.h"
#include "ss_math.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------- */
/* the soil point                                                          */

/* Normal pressure at end-of-step normal velocity vn (DESIGN 3.1) and its
 * derivative dP/dvn (<= 0). */
static double soil_pressure(const ssSoilMaterial *mat, const ssContact *c,
                            double dt, double vn, double *dP)
{
  double delta = -(c->g0 + dt * vn);
  if (!(delta > 0)) {
    *dP = 0;
    return 0;
  }
  double s = c->sp + delta, n = mat->sinkage_exponent;
  double k = (c->width > 0 ? mat->bekker_kc / c->width : 0) + mat->bekker_kphi;
  /* one power for the envelope and its slope: s^n = s s^(n-1) */
  double sn1 = n == 1.0 ? 1.0 : pow(s, n - 1);
  double pe = mat->elastic_stiffness * delta, py = k * s * sn1;
  double p, slope;
  if (pe <= py) {
    p = pe;
    slope = mat->elastic_stiffness;
  } else {
    p = py;
    slope = k * n * sn1;
  }
  double dpdv = -dt * slope;
  if (vn < 0) {
    p -= mat->damping * vn;
    dpdv -= mat->damping;
  }
  *dP = dpdv;
  return p;
}

/* lambda_n = A dt P(a + g lambda_n): one root, f increasing (g >= 0,
 * P non-increasing).  Bracket [0, A dt P(a)]; Newton with bisection. */
static double solve_normal(const ssSoilMaterial *mat, const ssContact *c,
                           double dt, double a, double g, double guess,
                           double tol, int *iters)
{
  double scale = c->area * dt, dP;
  double hi = scale * soil_pressure(mat, c, dt, a, &dP);
  if (!(hi > 0)) return 0;
  if (!(g > 0)) return hi;
  double lo = 0, x = guess;
  if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
  double ftol = tol * hi;
  for (int it = 0; it < 100; it++) {
    (*iters)++;
    double P = soil_pressure(mat, c, dt, a + g * x, &dP);
    double f = x - scale * P;
    if (fabs(f) <= ftol) return x;
    if (f > 0) hi = x;
    else lo = x;
    double fp = 1 - scale * dP * g;
    double xn = x - f / fp;
    if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);
    if (fabs(xn - x) <= tol * x || hi - lo <= tol * hi) return xn;
    x = xn;
  }
  return x;
}

/* 2x2 helpers on the tangential block */
static void inv2(const double A[4], double R[4])
{
  double det = A[0] * A[3] - A[1] * A[2];
  R[0] = A[3] / det;
  R[1] = -A[1] / det;
  R[2] = -A[2] / det;
  R[3] = A[0] / det;
}

/* The tangential impulse bound of one contact as a function of its slip
 * speed: A dt tau_max(p_n, j + dt sigma) on soil (Janosi buildup), or a
 * constant mu lambda_n for a rigid Coulomb contact (mat == NULL). */
typedef struct ShearBound {
  const ssSoilMaterial *mat;
  double scale, pn, j, dt;
  double constant;
} ShearBound;

/* the bound at slip speed sigma and its derivative in sigma */
static double shear_bound(const ShearBound *b, double sigma, double *slope)
{
  if (!b->mat) {
    *slope = 0;
    return b->constant;
  }
  double tf = b->scale * ss_soil_shear_strength(b->mat, b->pn);
  double K = b->mat->shear_displacement, j = b->j + b->dt * sigma;
  if (!(K > 0)) {
    *slope = 0;
    return tf;
  }
  double e = exp(-(j > 0 ? j : 0) / K);
  *slope = tf * e / K * b->dt;
  return tf * (1 - e);
}

/* h(sigma) = |M^-1 ct| - 1 with M = sigma I + T(sigma) G: zero at the slip
 * speed sigma.  Returns h, its derivative *dh, and in lt the impulse
 * -T M^-1 ct at that speed. */
static double slip_residual(const ShearBound *b, const double G[4],
                            const double ct[2], double sigma, double lt[2],
                            double *dh)
{
  double dT;
  double T = shear_bound(b, sigma, &dT);
  double M[4] = {sigma + T * G[0], T * G[1], T * G[2], sigma + T * G[3]};
  double det = M[0] * M[3] - M[1] * M[2];
  if (!(det > 0)) {
    lt[0] = lt[1] = 0;
    *dh = 0;
    return INFINITY;
  }
  double w0 = (M[3] * ct[0] - M[1] * ct[1]) / det;
  double w1 = (-M[2] * ct[0] + M[0] * ct[1]) / det;
  double wn = sqrt(w0 * w0 + w1 * w1);
  lt[0] = -T * w0;
  lt[1] = -T * w1;
  /* d(M^-1 c)/dsigma = -M^-1 (I + T' G) M^-1 c */
  double q0 = w0 + dT * (G[0] * w0 + G[1] * w1);
  double q1 = w1 + dT * (G[2] * w0 + G[3] * w1);
  double d0 = -(M[3] * q0 - M[1] * q1) / det;
  double d1 = -(-M[2] * q0 + M[0] * q1) / det;
  *dh = wn > 0 ? (w0 * d0 + w1 * d1) / wn : 0;
  return wn - 1;
}

/* Tangential impulse of one contact for a fixed normal impulse: stick if
 * the impulse that stops slip lies inside the bound, else the slip speed
 * sigma in (0, |ct|] solving |w(sigma)| = sigma along the 2x2 block
 * (maximum dissipation: the impulse opposes the resulting slip), by Newton
 * on h(sigma) kept inside the bracket (bisection when a step leaves it). */
static void solve_tangent(const ShearBound *b, const double ct[2],
                          const double G[4], double tol, double lt[2],
                          int *iters)
{
  double slope;
  double speed = sqrt(ct[0] * ct[0] + ct[1] * ct[1]);
  lt[0] = lt[1] = 0;
  if (speed == 0) return;
  double gmax = fabs(G[0]) + fabs(G[3]);
  if (!(gmax > 0)) {
    /* no response (static body): the slip is what it is */
    double T = shear_bound(b, speed, &slope);
    lt[0] = -T * ct[0] / speed;
    lt[1] = -T * ct[1] / speed;
    return;
  }
  double Gi[4];
  inv2(G, Gi);
  double ls0 = -(Gi[0] * ct[0] + Gi[1] * ct[1]);
  double ls1 = -(Gi[2] * ct[0] + Gi[3] * ct[1]);
  double T0 = shear_bound(b, 0, &slope);
  if (sqrt(ls0 * ls0 + ls1 * ls1) <= T0) {
    lt[0] = ls0;
    lt[1] = ls1;
    return;
  }
  double lo = 0, hi = speed, x = speed, tmp[2], dh;
  for (int it = 0; it < 100; it++) {
    (*iters)++;
    double h = slip_residual(b, G, ct, x, tmp, &dh);
    if (h > 0) {
      lo = x;
    } else {
      hi = x;
      lt[0] = tmp[0];
      lt[1] = tmp[1];
    }
    if (fabs(h) <= tol) {
      lt[0] = tmp[0];
      lt[1] = tmp[1];
      return;
    }
    double xn = dh < 0 ? x - h / dh : 0.5 * (lo + hi);
    if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);
    if (fabs(xn - x) <= tol * speed) {
      slip_residual(b, G, ct, xn, lt, &dh);
      return;
    }
    x = xn;
  }
}

int ss_solver_soil_point(const ssSoilMaterial *mat, double dt, ssContact *c,
                         const double v0[3], double tol)
{
  const double *G = c->G;
  double Gtt[4] = {G[4], G[5], G[7], G[8]};
  int iters = 0;
  double ln = c->lambda[0], lt[2] = {c->lambda[1], c->lambda[2]};
  int coupled = G[1] != 0 || G[2] != 0;
  for (int outer = 0; outer < 50; outer++) {
    double a = v0[0] + G[1] * lt[0] + G[2] * lt[1];
    double ln_new = solve_normal(mat, c, dt, a, G[0], ln, tol, &iters);
    double ct[2] = {v0[1] + G[3] * ln_new, v0[2] + G[6] * ln_new};
    double lt_new[2] = {0, 0};
    if (ln_new > 0) {
      ShearBound b = {mat, c->area * dt, ln_new / (c->area * dt), c->j, dt, 0};
      solve_tangent(&b, ct, Gtt, tol, lt_new, &iters);
    }
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
  return iters;
}

/* ---------------------------------------------------------------------- */
/* the rigid point: Coulomb cone with a normal velocity target            */

static void rigid_point(ssContact *c, const double v0[3], double tol)
{
  const double *G = c->G;
  if (!(G[0] > 0)) return;
  double Gtt[4] = {G[4], G[5], G[7], G[8]};
  double ln = c->lambda[0], lt[2] = {c->lambda[1], c->lambda[2]};
  int iters = 0, coupled = G[1] != 0 || G[2] != 0;
  for (int it = 0; it < 50; it++) {
    double vn = v0[0] + G[1] * lt[0] + G[2] * lt[1];
    double ln_new = (c->vn_target - vn) / G[0];
    if (ln_new < 0) ln_new = 0;
    double ct[2] = {v0[1] + G[3] * ln_new, v0[2] + G[6] * ln_new};
    double lt_new[2] = {0, 0};
    if (ln_new > 0) {
      ShearBound b = {NULL, 0, 0, 0, 0, c->mu * ln_new};
      solve_tangent(&b, ct, Gtt, tol, lt_new, &iters);
    }
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

/* ---------------------------------------------------------------------- */
/* joint rows: PD (bounded, implicit) and limits (unilateral)              */

static void pd_row(ssContact *c, const double v0[3])
{
  /* lambda = a - b (v0 + G lambda), clamped to the effort bound */
  double l = (c->row_a - c->row_b * v0[0]) / (1 + c->row_b * c->G[0]);
  if (l > c->row_bound) l = c->row_bound;
  if (l < -c->row_bound) l = -c->row_bound;
  c->lambda[0] = l;
}

static void limit_row(ssContact *c, const double v0[3])
{
  double l = c->G[0] > 0 ? (c->vn_target - v0[0]) / c->G[0] : 0;
  c->lambda[0] = l > 0 ? l : 0;
}

ssContact *ss_contact_new(ssData *d, long njac)
{
  if (d->ncontact == d->cap_contact) {
    int c = d->cap_contact ? 2 * d->cap_contact : 256;
    ssContact *p = realloc(d->contact, (size_t)c * sizeof *p);
    if (!p) return NULL;
    d->contact = p;
    d->cap_contact = c;
  }
  ssContact *c = d->contact + d->ncontact;
  long jadr = d->ncontact ? d->contact[d->ncontact - 1].jadr +
                                d->contact[d->ncontact - 1].jlen
                          : 0;
  size_t need = (size_t)jadr + (size_t)njac;
  if (need > d->cap_jac) {
    size_t cap = d->cap_jac ? 2 * d->cap_jac : 4096;
    while (cap < need) cap *= 2;
    double *q = realloc(d->jac, cap * sizeof(double));
    if (!q) return NULL;
    d->jac = q;
    d->cap_jac = cap;
  }
  memset(c, 0, sizeof *c);
  c->link = -1;
  c->jadr = jadr;
  c->jlen = njac;
  d->ncontact++;
  return c;
}

/* ---------------------------------------------------------------------- */
/* sweeps                                                                  */

/* contact-frame velocity X V of a link contact from a spatial velocity */
static void rows_velocity(const double *X, const double V[6], double v[3])
{
  for (int k = 0; k < 3; k++) {
    const double *x = X + 6 * k;
    v[k] = x[0] * V[0] + x[1] * V[1] + x[2] * V[2] + x[3] * V[3] + x[4] * V[4] + x[5] * V[5];
  }
}

/* spatial impulse X^T dl of a link contact */
static void rows_impulse(const double *X, const double dl[3], double w[6])
{
  for (int i = 0; i < 6; i++) w[i] = X[i] * dl[0] + X[6 + i] * dl[1] + X[12 + i] * dl[2];
}

/* u += Y w over the system's velocities */
static void link_apply(ssData *d, const ssContact *c, const double *Y,
                       const double w[6])
{
  double *u = d->qvel + c->vadr;
  for (int k = 0; k < c->nv; k++) {
    const double *y = Y + 6 * k;
    u[k] += y[0] * w[0] + y[1] * w[1] + y[2] * w[2] + y[3] * w[3] + y[4] * w[4] + y[5] * w[5];
  }
}

/* the contact's velocity J u, from the full velocity */
static void contact_velocity(const ssModel *m, const ssData *d,
                             const ssContact *c, double v[3])
{
  if (c->link >= 0) {
    double V[6];
    ss_art_link_velocity(m, d, c->link, V);
    rows_velocity(d->jac + c->jadr, V, v);
    return;
  }
  const double *J = d->jac + c->jadr, *u = d->qvel + c->vadr;
  int nv = c->nv;
  if (nv == 6) {
    /* a single rigid body */
    for (int k = 0; k < 3; k++) {
      const double *j = J + 6 * k;
      v[k] = j[0] * u[0] + j[1] * u[1] + j[2] * u[2] + j[3] * u[3] + j[4] * u[4] + j[5] * u[5];
    }
    return;
  }
  for (int k = 0; k < 3; k++) {
    double s = 0;
    for (int i = 0; i < nv; i++) s += J[k * nv + i] * u[i];
    v[k] = s;
  }
}

/* u += W dl, the full velocity update of one contact */
static void apply_impulse(const ssModel *m, ssData *d, const ssContact *c,
                          const double dl[3])
{
  if (c->link >= 0) {
    const double *Y, *Lam;
    double w[6];
    ss_art_link_block(m, d, c->link, &Y, &Lam);
    rows_impulse(d->jac + c->jadr, dl, w);
    link_apply(d, c, Y, w);
    return;
  }
  const double *W = d->jac + c->jadr + 3 * c->nv;
  double *u = d->qvel + c->vadr;
  if (c->nv == 6) {
    for (int i = 0; i < 6; i++)
      u[i] += W[3 * i] * dl[0] + W[3 * i + 1] * dl[1] + W[3 * i + 2] * dl[2];
    return;
  }
  for (int i = 0; i < c->nv; i++)
    u[i] += W[3 * i] * dl[0] + W[3 * i + 1] * dl[1] + W[3 * i + 2] * dl[2];
}

/* A packed group: consecutive contacts on one link swept against the
 * link's spatial velocity; F is the group's spatial impulse not yet in u. */
typedef struct Group {
  const ssContact *first; /* NULL: no group open */
  int end;                /* index of the group's last contact */
  const double *Y, *Lam;  /* the link's block */
  double V[6];            /* J_b u with F applied */
  double F[6];
} Group;

/* a lone contact keeps the full update: opening a group (J_b u) and
 * closing it (Y F) cost what one full visit costs (J_b u, then Y X^T dl),
 * so a group pays from two contacts on */
enum { MIN_GROUP = 2 };

static int group_open(const ssModel *m, ssData *d, Group *g,
                      const ssContact *c, int end)
{
  ss_art_link_block(m, d, c->link, &g->Y, &g->Lam);
  /* a response block that is not finite (a degenerate link) is left to
   * the full update, which reports it through the velocities */
  for (int k = 0; k < 36; k++)
    if (!isfinite(g->Lam[k])) return 0;
  g->first = c;
  g->end = end;
  ss_art_link_velocity(m, d, c->link, g->V);
  memset(g->F, 0, sizeof g->F);
  return 1;
}

static void group_close(ssData *d, Group *g)
{
  if (!g->first) return;
  link_apply(d, g->first, g->Y, g->F);
  g->first = NULL;
}

static int cmp_warm(const void *a, const void *b)
{
  const ssWarmEntry *x = a, *y = b;
  if (x->vertex != y->vertex) return (x->vertex > y->vertex) - (x->vertex < y->vertex);
  return (x->geom > y->geom) - (x->geom < y->geom);
}

/* cache key of a joint row: its dof and kind (PD, or the limit's side) */
static void row_key(const ssData *d, const ssContact *c, ssWarmEntry *k)
{
  int upper = c->type == SS_CONTACT_LIMIT && d->jac[c->jadr + (c->dof - c->vadr)] < 0;
  k->vertex = 2 * c->dof + upper;
  k->geom = c->type == SS_CONTACT_PD ? -2 : -3;
}

/* The cache entry of key, or NULL.  Contacts come in runs of ascending
 * keys (one collider's points in vertex order), so the search walks on
 * from the previous hit (*cursor) while the keys ascend, a few entries at
 * most, and falls back to bisection when they do not. */
static const ssWarmEntry *find_warm(const ssData *d, const ssWarmEntry *key,
                                    int *cursor)
{
  int p = *cursor, n = d->nwarm;
  if (p < n && cmp_warm(d->warm + p, key) <= 0) {
    for (int k = 0; k < 8 && p < n; k++, p++) {
      int c = cmp_warm(d->warm + p, key);
      if (c == 0) {
        *cursor = p + 1;
        return d->warm + p;
      }
      if (c > 0) return NULL; /* passed it: not cached */
    }
  }
  const ssWarmEntry *e = bsearch(key, d->warm, (size_t)n, sizeof *key, cmp_warm);
  if (e) *cursor = (int)(e - d->warm) + 1;
  return e;
}

/* Initial impulses from last step's tractions, scaled by the current area
 * and time step and projected into the current bounds; joint rows start
 * from last step's impulse rate. */
static void warm_start(const ssModel *m, ssData *d)
{
  const double dt = m->opt.timestep;
  Group g = {NULL, 0, NULL, NULL, {0}, {0}};
  int cursor = 0;
  for (int i = 0; i < d->ncontact; i++) {
    ssContact *c = d->contact + i;
    c->lambda[0] = c->lambda[1] = c->lambda[2] = 0;
    if (!m->opt.terrain_warm_start || c->type == SS_CONTACT_RIGID || !d->nwarm)
      continue;
    ssWarmEntry key = {c->vertex, c->geom, {0, 0, 0}};
    if (c->type != SS_CONTACT_SOIL) row_key(d, c, &key);
    const ssWarmEntry *e = find_warm(d, &key, &cursor);
    if (!e) continue;
    if (c->type == SS_CONTACT_PD) {
      double l = e->traction[0] * dt;
      c->lambda[0] = l > c->row_bound ? c->row_bound : l < -c->row_bound ? -c->row_bound : l;
    } else if (c->type == SS_CONTACT_LIMIT) {
      c->lambda[0] = e->traction[0] > 0 ? e->traction[0] * dt : 0;
    } else {
      double scale = c->area * dt;
      double ln = e->traction[0] > 0 ? e->traction[0] * scale : 0;
      double lt0 = e->traction[1] * scale, lt1 = e->traction[2] * scale;
      double lim = scale * ss_soil_shear_strength(&m->hfield_soilmat[c->hfield], ln / scale);
      double mag = sqrt(lt0 * lt0 + lt1 * lt1);
      if (mag > lim) {
        lt0 *= lim / mag;
        lt1 *= lim / mag;
      }
      c->lambda[0] = ln;
      c->lambda[1] = lt0;
      c->lambda[2] = lt1;
    }
    if (!c->nv) continue;
    if (c->link >= 0 && !d->solver_full) {
      /* a link run's impulses reach u once, at the run's end */
      if (!g.first || g.first->link != c->link) {
        group_close(d, &g);
        g.first = c;
        ss_art_link_block(m, d, c->link, &g.Y, &g.Lam);
        memset(g.F, 0, sizeof g.F);
      }
      double w[6];
      rows_impulse(d->jac + c->jadr, c->lambda, w);
      for (int k = 0; k < 6; k++) g.F[k] += w[k];
    } else {
      group_close(d, &g);
      apply_impulse(m, d, c, c->lambda);
    }
  }
  group_close(d, &g);
}

static int cached(const ssContact *c)
{
  return c->type == SS_CONTACT_PD || c->type == SS_CONTACT_LIMIT ||
         (c->type == SS_CONTACT_SOIL && c->lambda[0] > 0);
}

/* keep this step's converged tractions (soil) and impulse rates (joint
 * rows) for the next one */
static ssStatus store_warm(const ssModel *m, ssData *d, ssError *err)
{
  const double dt = m->opt.timestep;
  int n = 0;
  for (int i = 0; i < d->ncontact; i++) n += cached(d->contact + i);
  if (n > d->cap_warm) {
    ssWarmEntry *p = realloc(d->warm, (size_t)n * sizeof *p);
    if (!p) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
    d->warm = p;
    d->cap_warm = n;
  }
  n = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    if (!cached(c)) continue;
    ssWarmEntry *e = d->warm + n++;
    if (c->type == SS_CONTACT_SOIL) {
      double inv = 1.0 / (c->area * dt);
      e->vertex = c->vertex;
      e->geom = c->geom;
      e->traction[0] = c->lambda[0] * inv;
      e->traction[1] = c->lambda[1] * inv;
      e->traction[2] = c->lambda[2] * inv;
    } else {
      row_key(d, c, e);
      e->traction[0] = c->lambda[0] / dt;
      e->traction[1] = e->traction[2] = 0;
    }
  }
  /* one collider's entries come in order already: sort only when the
   * list is not (several colliders, joint rows) */
  int sorted = 1;
  for (int i = 1; i < n && sorted; i++) sorted = cmp_warm(d->warm + i - 1, d->warm + i) < 0;
  if (!sorted) qsort(d->warm, (size_t)n, sizeof *d->warm, cmp_warm);
  d->nwarm = n;
  return SS_OK;
}

/* one Gauss-Seidel visit: new impulse of contact c with the others held;
 * inside an open group g the contact sees and moves the link's spatial
 * velocity only */
static void visit(const ssModel *m, ssData *d, ssContact *c, Group *g,
                  double *dmax, double *lmax)
{
  const double dt = m->opt.timestep, stol = m->opt.scalar_tolerance;
  int packed = g->first != NULL;
  double v[3] = {0, 0, 0}, v0[3], old[3];
  if (packed) rows_velocity(d->jac + c->jadr, g->V, v);
  else if (c->nv) contact_velocity(m, d, c, v);
  memcpy(old, c->lambda, sizeof old);
  ss_m3_mulv(v0, c->G, old);
  ss_v3_sub(v0, v, v0);
  switch (c->type) {
  case SS_CONTACT_SOIL:
    ss_solver_soil_point(&m->hfield_soilmat[c->hfield], dt, c, v0, stol);
    break;
  case SS_CONTACT_RIGID: rigid_point(c, v0, stol); break;
  case SS_CONTACT_PD: pd_row(c, v0); break;
  default: limit_row(c, v0); break;
  }
  double dl[3];
  ss_v3_sub(dl, c->lambda, old);
  if (packed) {
    if (dl[0] != 0 || dl[1] != 0 || dl[2] != 0) {
      double w[6];
      rows_impulse(d->jac + c->jadr, dl, w);
      for (int k = 0; k < 6; k++) g->F[k] += w[k];
      for (int r = 0; r < 6; r++) {
        const double *L = g->Lam + 6 * r;
        g->V[r] += L[0] * w[0] + L[1] * w[1] + L[2] * w[2] + L[3] * w[3] + L[4] * w[4] + L[5] * w[5];
      }
    }
  } else if (c->nv) {
    apply_impulse(m, d, c, dl);
  }
  double dn = fabs(dl[0]) + fabs(dl[1]) + fabs(dl[2]);
  double ln = fabs(c->lambda[0]) + fabs(c->lambda[1]) + fabs(c->lambda[2]);
  if (dn > *dmax) *dmax = dn;
  if (ln > *lmax) *lmax = ln;
}

ssStatus ss_solver_solve(const ssModel *m, ssData *d, ssError *err)
{
  const double dt = m->opt.timestep, tol = m->opt.solver_tolerance;
  ssStepStats *st = &d->stats;
  st->sweeps = 0;
  st->residual = 0;
  st->converged = 1;
  warm_start(m, d);

  /* joint rows (PD, limits) are few, stiff and coupled to everything:
   * they are revisited every 64 contacts, a cheap stand-in for a block
   * solve that keeps the sweep count low */
  int first_row = d->ncontact;
  while (first_row > 0 && (d->contact[first_row - 1].type == SS_CONTACT_PD ||
                           d->contact[first_row - 1].type == SS_CONTACT_LIMIT))
    first_row--;
  int rows = first_row < d->ncontact;

  /* runs of contacts on one link (packed groups) */
  for (int i = first_row - 1; i >= 0; i--) {
    ssContact *c = d->contact + i;
    c->run = 1;
    if (c->link >= 0 && i + 1 < first_row && c[1].link == c->link) c->run += c[1].run;
  }
  int pack = !d->solver_full;

  int sweeps = d->ncontact ? m->opt.solver_max_sweeps : 0;
  Group g = {NULL, 0, NULL, NULL, {0}, {0}};
  for (int sweep = 0; sweep < sweeps; sweep++) {
    double dmax = 0, lmax = 0;
    for (int i = 0; i < d->ncontact; i++) {
      ssContact *c = d->contact + i;
      if (g.first && i > g.end) group_close(d, &g);
      if (!g.first && pack && i < first_row && c->link >= 0 && c->run >= MIN_GROUP) {
        /* a group ends where the joint rows are revisited */
        int end = i + c->run - 1;
        if (rows && end > (i | 63)) end = i | 63;
        if (end - i + 1 >= MIN_GROUP) group_open(m, d, &g, c, end);
      }
      visit(m, d, c, &g, &dmax, &lmax);
      if (i < first_row && rows && (i & 63) == 63) {
        group_close(d, &g);
        for (int r = first_row; r < d->ncontact; r++)
          visit(m, d, d->contact + r, &g, &dmax, &lmax);
      }
    }
    group_close(d, &g);
    st->sweeps = sweep + 1;
    st->residual = lmax > 0 ? dmax / lmax : 0;
    if (st->residual <= tol) break;
  }
  st->converged = st->residual <= tol;

  /* end-of-step contact velocities for the soil update */
  int link = -1;
  double V[6];
  for (int i = 0; i < d->ncontact; i++) {
    ssContact *c = d->contact + i;
    double v[3] = {0, 0, 0};
    if (c->link >= 0) {
      /* one spatial velocity per link run */
      if (c->link != link) ss_art_link_velocity(m, d, c->link, V);
      link = c->link;
      rows_velocity(d->jac + c->jadr, V, v);
    } else if (c->nv) {
      contact_velocity(m, d, c, v);
    }
    memcpy(c->v, v, sizeof v);
    c->loaded = c->type == SS_CONTACT_SOIL && c->lambda[0] > 0 &&
                -(c->g0 + dt * v[0]) > 0;
    if (c->type == SS_CONTACT_SOIL && !c->loaded)
      c->lambda[0] = c->lambda[1] = c->lambda[2] = 0;
  }
  return store_warm(m, d, err);
}
