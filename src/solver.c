/* solver.c -- per-contact Gauss-Seidel on the impulse-response blocks.
 *
 * Each sweep visits every contact once.  For contact i the others are held:
 * its velocity without its own impulse is v0 = J u - G lambda_i, and its new
 * impulse solves the contact law at the end-of-step velocity
 * v = v0 + G lambda_i (point.c): soil points the implicit soil law of
 * DESIGN 3.1 (scalar, safeguarded root finding -- never a penalty spring),
 * rigid points a Coulomb cone.  The system velocity u is updated after each
 * contact by W (lambda_new - lambda_old). */
#include "solver.h"
#include "articulated.h"
#include "dynamics.h"
#include "sort_runs.h"
#include "ss_math.h"

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

/* the head of a new contact, zeros but link = -1 (no link), is copied
 * from here (ss_contact_add): GCC lowers a memset of its 184 bytes
 * (offsetof(ssContact, pos)) to `rep stos`, whose start-up costs about
 * three times the dozen loads and stores of this copy (10 ns a contact on
 * the benchmark machine, some 7 % of a settled plate point's step) */
const ssContact ss_contact_blank = {.link = -1};

int ss_contact_reserve(ssData *d, int count, long njac)
{
  if (count <= 0) return 1;
  if (d->ncontact > d->cap_contact - count) {
    if (count > INT_MAX / 2 - d->ncontact) return 0;
    int c = d->cap_contact ? d->cap_contact : 256;
    while (c < d->ncontact + count) c *= 2;
    ssContact *p = realloc(d->contact, (size_t)c * sizeof *p);
    if (!p) return 0;
    d->contact = p;
    d->cap_contact = c;
  }
  size_t need = (size_t)ss_contact_jac_end(d) + (size_t)count * (size_t)njac;
  if (need > d->cap_jac) {
    size_t cap = d->cap_jac ? 2 * d->cap_jac : 4096;
    while (cap < need) cap *= 2;
    double *q = realloc(d->jac, cap * sizeof(double));
    if (!q) return 0;
    d->jac = q;
    d->cap_jac = cap;
  }
  return 1;
}

ssContact *ss_contact_new(ssData *d, long njac)
{
  return ss_contact_reserve(d, 1, njac) ? ss_contact_add(d, njac) : NULL;
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

/* The same from the contact's point and frame, where X is not formed (it
 * is only for the sweeps): X^T dl = (p x f; f), f = frame^T dl, p the
 * point from o, its system's origin (ss_art_origin), about which the
 * link's spatial vectors are (the callers load o once for a run of
 * contacts on one link) */
static inline void link_impulse(const double o[3], const ssContact *c, const double dl[3],
                                double w[6])
{
  double p[3];
  ss_v3_sub(p, c->pos, o);
  ss_contact_frame_tmulv(c, w + 3, dl);
  ss_v3_cross(w, p, w + 3);
}

/* and its contact-frame velocity X V = frame (v_o + omega x p) from the
 * link's spatial velocity V = (omega; v_o) */
static inline void link_point_velocity(const double o[3], const ssContact *c, const double V[6],
                                       double v[3])
{
  double w[3], p[3];
  ss_v3_sub(p, c->pos, o);
  ss_v3_cross(w, V, p);
  ss_v3_add(w, w, V + 3);
  ss_contact_frame_mulv(c, v, w);
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

/* a rigid body's contact: J u = frame (v + omega x r), u = (v; omega), r
 * from the centre of mass com, without J (formed only for the sweeps) */
static inline __attribute__((always_inline)) void
body_point_velocity(const ssContact *c, const double com[3], const double u[6], double v[3])
{
  double r[3], w[3];
  ss_v3_sub(r, c->pos, com);
  ss_v3_cross(w, u + 3, r);
  ss_v3_add(w, w, u);
  ss_contact_frame_mulv(c, v, w);
}

/* One body of a contact at its point and frame, from the full velocity:
 * the link's (link >= 0, of system sys) or the free body's of collider
 * geom (velocities at vadr) */
static void side_velocity(const ssModel *m, const ssData *d, const ssContact *c, int link,
                          int sys, int vadr, int geom, double v[3])
{
  if (link >= 0) {
    double V[6];
    ss_art_link_velocity(m, d, link, V);
    link_point_velocity(ss_art_origin(d, sys), c, V, v);
    return;
  }
  body_point_velocity(c, d->body_xipos + 3 * m->geom_body[geom], d->qvel + vadr, v);
}

/* u += W dl on one body of a contact: a link's (its block's Y), or a free
 * body's (W, nv x 3, after its J at jadr) */
static void side_apply(const ssModel *m, ssData *d, const ssContact *c, int link, int sys,
                       int vadr, int nv, long jadr, const double dl[3])
{
  double *u = d->qvel + vadr;
  if (link >= 0) {
    const double *Y, *Lam;
    double w[6];
    ss_art_link_block(m, d, link, &Y, &Lam);
    link_impulse(ss_art_origin(d, sys), c, dl, w);
    for (int k = 0; k < nv; k++) {
      const double *y = Y + 6 * k;
      u[k] += y[0] * w[0] + y[1] * w[1] + y[2] * w[2] + y[3] * w[3] + y[4] * w[4] + y[5] * w[5];
    }
    return;
  }
  const double *W = d->jac + jadr + 3 * nv;
  for (int i = 0; i < nv; i++)
    u[i] += W[3 * i] * dl[0] + W[3 * i + 1] * dl[1] + W[3 * i + 2] * dl[2];
}

/* a pair contact's velocity: its first body's less its second's */
static void pair_velocity(const ssModel *m, const ssData *d, const ssContact *c, double v[3])
{
  double v2[3];
  side_velocity(m, d, c, c->link, c->sys, c->vadr, c->geom, v);
  side_velocity(m, d, c, c->link2, c->sys2, c->vadr2, c->geom2, v2);
  ss_v3_sub(v, v, v2);
}

/* One body's rows and response of a contact (of a pair contact, either
 * body), for the sweeps: a link's X and LX (J, 36 values), or a free
 * body's J and W (6 nv), and its G (3 x 3) */
static void side_rows(const ssModel *m, ssData *d, const ssContact *c, int link, int sys,
                           int geom, int nv, double *J, double G[9])
{
  if (link >= 0) {
    double p[3];
    ss_v3_sub(p, c->pos, ss_art_origin(d, sys));
    ss_art_contact_rows(p, c->frame, J);
    ss_art_contact_response(m, d, link, J, J + 18, G);
    return;
  }
  int b = m->geom_body[geom];
  ss_dyn_contact_jacobian(d, b, c->pos, c->frame, J);
  ss_dyn_contact_response(m, d, b, J, J + 3 * nv, G);
}

/* the contact's velocity J u, from the full velocity */
static inline __attribute__((always_inline)) void
contact_velocity(const ssModel *m, const ssData *d, const ssContact *c, double v[3])
{
  if (c->type == SS_CONTACT_PAIR) {
    pair_velocity(m, d, c, v);
    return;
  }
  if (c->link >= 0) {
    double V[6];
    ss_art_link_velocity(m, d, c->link, V);
    link_point_velocity(ss_art_origin(d, c->sys), c, V, v);
    return;
  }
  const double *u = d->qvel + c->vadr;
  if (c->type == SS_CONTACT_SOIL || c->type == SS_CONTACT_RIGID) {
    body_point_velocity(c, d->body_xipos + 3 * m->geom_body[c->geom], u, v);
    return;
  }
  /* a joint row: J (3 x nv) stored */
  const double *J = d->jac + c->jadr;
  for (int k = 0; k < 3; k++) {
    double s = 0;
    for (int i = 0; i < c->nv; i++) s += J[k * c->nv + i] * u[i];
    v[k] = s;
  }
}

/* A joint row (PD, limit) has one row: J's first row and W's first column
 * (the other two are zero), so its visit reads and moves only that one;
 * that row is +-1 at the joint's dof and zero elsewhere
 * (ss_art_dof_row), so J u is one product. */
static double row_velocity(const ssData *d, const ssContact *c)
{
  int k = c->dof - c->vadr;
  return d->jac[c->jadr + k] * d->qvel[c->dof];
}

/* a joint row's W, formed at its first use in the step (ss_art_dof_row
 * leaves it out: the Newton phase does not need it) */
static const double *row_response(ssData *d, ssContact *c)
{
  double *W = d->jac + c->jadr + 3 * c->nv;
  if (!c->w_ready) {
    ss_art_dof_response(d, c->sys, c->dof, d->jac[c->jadr + (c->dof - c->vadr)], W);
    c->w_ready = 1;
  }
  return W;
}

static void row_apply(ssData *d, ssContact *c, double dl)
{
  const double *W = row_response(d, c);
  double *u = d->qvel + c->vadr;
  for (int i = 0; i < c->nv; i++) u[i] += W[3 * i] * dl;
}

/* u += W dl, the full velocity update of one contact */
static void apply_impulse(const ssModel *m, ssData *d, ssContact *c,
                          const double dl[3])
{
  if (c->type == SS_CONTACT_PAIR) {
    /* dl on the first body, -dl on the second */
    const double ml[3] = {-dl[0], -dl[1], -dl[2]};
    side_apply(m, d, c, c->link, c->sys, c->vadr, c->nv, c->jadr, dl);
    side_apply(m, d, c, c->link2, c->sys2, c->vadr2, c->nv2, c->jadr2, ml);
    return;
  }
  if (c->link >= 0) {
    const double *Y, *Lam;
    double w[6];
    ss_art_link_block(m, d, c->link, &Y, &Lam);
    link_impulse(ss_art_origin(d, c->sys), c, dl, w);
    link_apply(d, c, Y, w);
    return;
  }
  const double *W = c->type == SS_CONTACT_PD || c->type == SS_CONTACT_LIMIT
                         ? row_response(d, c)
                         : d->jac + c->jadr + 3 * c->nv;
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
  const double *Y, *Lam;  /* the link's block */
  double V[6];            /* J_b u with F applied */
  double F[6];
  double o[3];            /* the link's system's origin (ss_art_origin) */
} Group;

/* a lone contact keeps the full update: opening a group (J_b u) and
 * closing it (Y F) cost what one full visit costs (J_b u, then Y X^T dl),
 * so a group pays from two contacts on */
enum { MIN_GROUP = 2 };

/* With joint rows present, a run is swept in balanced pieces of at most
 * PIECE contacts and the rows are revisited after each piece.  The wheel
 * PD rows and the steering rack are coupled to their patches through the
 * wheel's spin and the tie rods; measured on the buggy (sweeps per step
 * over 2000 steps at tolerance 1e-9): one revisit per run 114, pieces of
 * <= 110: 34, <= 64: 33, <= 40: 24, <= 32: 23.6, <= 20: 31; buggy_turn
 * 34 -> 28 and plate_arm 72 -> 69 from 64 to 32. */
enum { PIECE = 32 };

static int group_open(const ssModel *m, ssData *d, Group *g, const ssContact *c)
{
  ss_art_link_block(m, d, c->link, &g->Y, &g->Lam);
  /* a response block that is not finite (a degenerate link) is left to
   * the full update, which reports it through the velocities */
  for (int k = 0; k < 36; k++)
    if (!isfinite(g->Lam[k])) return 0;
  g->first = c;
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

/* The cache's order: by collider, then vertex; the joint rows (geom < 0,
 * taken as unsigned) after every collider.  Each collider's points come
 * in vertex order and the colliders in order, so a step's entries arrive
 * sorted or in a few runs (one per bed), and the warm start's look-ups
 * walk the cache forwards without skipping other colliders' entries.
 * The key (geom, vertex) as one number: the geom taken as unsigned, then
 * the vertex with its sign bit flipped (signed order as unsigned). */
static inline uint64_t warm_key(int geom, int vertex)
{
  return (uint64_t)(uint32_t)geom << 32 | ((uint32_t)vertex ^ 0x80000000u);
}

static inline uint64_t entry_key(const ssWarmEntry *e)
{
  return e->key;
}

void ss_solver_warm_key(ssWarmEntry *e)
{
  e->key = warm_key(e->geom, e->vertex);
}

/* (from the fields: it checks a checkpoint's entries as they were read) */
int ss_solver_warm_cmp(const ssWarmEntry *a, const ssWarmEntry *b)
{
  uint64_t ka = warm_key(a->geom, a->vertex), kb = warm_key(b->geom, b->vertex);
  return (ka > kb) - (ka < kb);
}

/* cache key of a joint row: its dof and kind (PD, or the limit's side) */
static void row_key(const ssData *d, const ssContact *c, int *geom, int *vertex)
{
  int upper = c->type == SS_CONTACT_LIMIT && d->jac[c->jadr + (c->dof - c->vadr)] < 0;
  *vertex = 2 * c->dof + upper;
  *geom = c->type == SS_CONTACT_PD ? -2 : -3;
}

/* The cache entry of key (geom, vertex), or NULL.  Contacts come in runs
 * of ascending keys (one collider's points in vertex order, the colliders
 * in order), so the search walks on from the previous hit while the keys
 * ascend, a few entries at most, answers NULL at once for a key between
 * the previous hit and the entry after it (the cache is sorted), and
 * falls back to bisection otherwise (a new bed, the joint rows, a gap of
 * more than 8 entries no longer loaded).  *cursor: the entry after the
 * previous hit (warm at the start), a pointer (an index took a product
 * by the entry's size at each look-up).  (Inlined where it is used: the
 * call added a tenth to a settled plate point's warm start.) */
static inline __attribute__((always_inline)) const ssWarmEntry *
find_warm(const ssWarmEntry *warm, int n, int geom, int vertex, const ssWarmEntry **cursor)
{
  const ssWarmEntry *p = *cursor, *end = warm + n;
  const uint64_t key = warm_key(geom, vertex);
  if (p < end && entry_key(p) <= key) {
    for (int k = 0; k < 8 && p < end; k++, p++) {
      uint64_t ek = entry_key(p);
      if (ek == key) {
        *cursor = p + 1;
        return p;
      }
      if (ek > key) return NULL; /* passed it: not cached */
    }
  } else if (p > warm && entry_key(p - 1) < key) {
    /* between the previous hit (the cursor's last entry) and the entry
     * after it, or past the last: not cached, without the bisection (a
     * point new to the patch) */
    return NULL;
  }
  /* the first entry not below the key */
  int a = 0, b = n;
  while (a < b) {
    int mid = a + (b - a) / 2;
    if (entry_key(warm + mid) < key) a = mid + 1;
    else b = mid;
  }
  if (a == n || entry_key(warm + a) != key) return NULL;
  *cursor = warm + a + 1;
  return warm + a;
}

/* A rigid body's run of contacts in the warm start: the sum of their
 * J^T lambda (force; torque about the centre of mass), applied at the
 * run's end */
typedef struct BodyRun {
  int body; /* -1: none open */
  double F[6];
} BodyRun;

static void body_run_close(const ssModel *m, ssData *d, BodyRun *r)
{
  if (r->body < 0) return;
  ss_dyn_body_impulse(m, d, r->body, r->F);
  r->body = -1;
  memset(r->F, 0, sizeof r->F);
}

/* The warm start's velocity change, accumulated over the contacts in
 * order: a link run's and a rigid body's impulses reach u once, at the
 * run's end */
typedef struct WarmApply {
  Group g;
  BodyRun br;
} WarmApply;

/* the tangential impulse (t0, t1) scaled back into the disc of radius lim
 * where it lies outside (a warm start's projection into its bound) */
static inline void disc_clip(double *t0, double *t1, double lim)
{
  double mag = sqrt(*t0 * *t0 + *t1 * *t1);
  if (mag > lim) {
    double s = lim / mag;
    *t0 *= s;
    *t1 *= s;
  }
}

/* soil point c's warm impulse from its cache entry e (with the creeping
 * colliders' rates or without) into lam; dt the time step, mats the beds'
 * soils (m->hfield_soilmat) */
static inline __attribute__((always_inline)) void
warm_soil_impulse(const ssSoilMaterial *mats, double dt, const ssContact *c,
                  const ssWarmEntry *e, int creep_rates, double lam[3])
{
  double scale = c->area * dt, t[3];
  static const double none[3] = {0, 0, 0};
  const double *rate = e->creep && !creep_rates ? none : e->rate;
  for (int k = 0; k < 3; k++) t[k] = e->traction[k] + rate[k];
  double ln = t[0] > 0 ? t[0] * scale : 0;
  double lt0 = t[1] * scale, lt1 = t[2] * scale;
  /* the bound at zero slip as the laws form it (point.c, newton.c):
   * A dt c + mu lambda_n, the strength tau_f(p_n) times A dt */
  const ssSoilMaterial *mat = &mats[c->hfield];
  disc_clip(&lt0, &lt1, scale * mat->cohesion + mat->friction_coefficient * ln);
  lam[0] = ln;
  lam[1] = lt0;
  lam[2] = lt1;
}

/* rigid contact c's warm impulse from its cache entry e: last step's
 * force times this step's dt, projected into its Coulomb cone (normal
 * impulse >= 0, |tangential| <= mu normal) */
static void rigid_warm_impulse(const ssContact *c, const ssWarmEntry *e, double dt,
                               double lam[3])
{
  double ln = e->traction[0] > 0 ? e->traction[0] * dt : 0;
  double lt0 = e->traction[1] * dt, lt1 = e->traction[2] * dt;
  disc_clip(&lt0, &lt1, c->mu * ln);
  lam[0] = ln;
  lam[1] = lt0;
  lam[2] = lt1;
}

/* contact c's warm impulse from its cache entry e into lam, whose entries
 * a joint row leaves as they are (0) */
static inline __attribute__((always_inline)) void
warm_impulse(const ssModel *m, const ssContact *c, const ssWarmEntry *e, int creep_rates,
             double lam[3])
{
  const double dt = m->opt.timestep;
  if (c->type == SS_CONTACT_PD) {
    double l = e->traction[0] * dt;
    lam[0] = l > c->row_bound ? c->row_bound : l < -c->row_bound ? -c->row_bound : l;
  } else if (c->type == SS_CONTACT_LIMIT) {
    lam[0] = e->traction[0] > 0 ? e->traction[0] * dt : 0;
  } else if (c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_PAIR) {
    rigid_warm_impulse(c, e, dt, lam);
  } else {
    warm_soil_impulse(m->hfield_soilmat, dt, c, e, creep_rates, lam);
  }
}

/* a rigid body's soil point c: J^T lam = (f; r x f), f = frame^T lam, r
 * from the centre of mass com (J is formed only for the sweeps), added to
 * the run's sums F */
static inline __attribute__((always_inline)) void
body_run_add(const ssContact *c, const double com[3], const double lam[3], double F[6])
{
  double f[3], r[3], t[3];
  ss_contact_frame_tmulv(c, f, lam);
  ss_v3_sub(r, c->pos, com);
  ss_v3_cross(t, r, f);
  for (int k = 0; k < 3; k++) {
    F[k] += f[k];
    F[3 + k] += t[k];
  }
}

/* a rigid body b's run opens where the last contacts' group or another
 * body's run was open (closed first), or goes on */
static inline void body_run_open(const ssModel *m, ssData *d, WarmApply *a, int b)
{
  group_close(d, &a->g);
  if (a->br.body != b) {
    body_run_close(m, d, &a->br);
    a->br.body = b;
  }
}

/* One body's warm impulse lam of pair contact c: a link's through its
 * block (Y), a free body's as J^T lam (ss_dyn_body_impulse), neither
 * from the rows in ssData.jac, which the warm start comes before */
static void warm_side(const ssModel *m, ssData *d, const ssContact *c, int link, int sys,
                      int vadr, int nv, int geom, const double lam[3])
{
  if (link >= 0) {
    side_apply(m, d, c, link, sys, vadr, nv, -1, lam);
    return;
  }
  int b = m->geom_body[geom];
  double F[6] = {0};
  body_run_add(c, d->body_xipos + 3 * b, lam, F);
  ss_dyn_body_impulse(m, d, b, F);
}

/* contact c's warm impulse, and its velocity change into a */
static inline __attribute__((always_inline)) void
warm_one(const ssModel *m, ssData *d, ssContact *c, const ssWarmEntry *e, int creep_rates,
         WarmApply *a)
{
  warm_impulse(m, c, e, creep_rates, c->lambda);
  if (!c->nv) return;
  Group *g = &a->g;
  BodyRun *br = &a->br;
  if (c->type == SS_CONTACT_PAIR) {
    /* on two bodies, each from the contact's point and frame (its rows
     * and responses are formed only for the sweeps, after the warm
     * start): lambda on the first, -lambda on the second */
    group_close(d, g);
    body_run_close(m, d, br);
    const double ml[3] = {-c->lambda[0], -c->lambda[1], -c->lambda[2]};
    warm_side(m, d, c, c->link, c->sys, c->vadr, c->nv, c->geom, c->lambda);
    warm_side(m, d, c, c->link2, c->sys2, c->vadr2, c->nv2, c->geom2, ml);
  } else if (c->link < 0 && (c->type == SS_CONTACT_SOIL || c->type == SS_CONTACT_RIGID)) {
    /* a rigid body's run likewise, as J^T lambda (its J and W are formed
     * only for the sweeps, after the warm start) */
    int b = m->geom_body[c->geom];
    body_run_open(m, d, a, b);
    body_run_add(c, d->body_xipos + 3 * b, c->lambda, br->F);
  } else if (c->link >= 0 && !d->solver_full) {
    body_run_close(m, d, br);
    if (!g->first || g->first->link != c->link) {
      group_close(d, g);
      g->first = c;
      ss_art_link_block(m, d, c->link, &g->Y, &g->Lam);
      memset(g->F, 0, sizeof g->F);
      ss_v3_copy(g->o, ss_art_origin(d, c->sys));
    }
    double w[6];
    link_impulse(g->o, c, c->lambda, w);
    for (int k = 0; k < 6; k++) g->F[k] += w[k];
  } else {
    group_close(d, g);
    body_run_close(m, d, br);
    apply_impulse(m, d, c, c->lambda);
  }
}

static void warm_close(const ssModel *m, ssData *d, WarmApply *a)
{
  group_close(d, &a->g);
  body_run_close(m, d, &a->br);
}

/* soil point c's cache entry e kept: the traction its warm start comes
 * from (warm_t, and warm_trend: the cache's rates need them whatever the
 * solve starts from); returns 1 where the warm start leaves e's rate out */
static inline int warm_keep(ssContact *c, const ssWarmEntry *e, int converged, int creep_rates)
{
  /* (element by element: a memcpy's stores may alias anything, as the
   * compiler sees it, and the callers' loops read their invariants again
   * after one) */
  c->warm_t[0] = e->traction[0];
  c->warm_t[1] = e->traction[1];
  c->warm_t[2] = e->traction[2];
  c->warm_trend = converged;
  return e->creep && !creep_rates;
}

/* contact c's cache entry (NULL: none) from the nwarm of warm, its
 * impulse zeroed and a soil point's entry kept (warm_keep, counted in
 * *left) */
static inline __attribute__((always_inline)) const ssWarmEntry *
warm_match(const ssData *d, ssContact *c, const ssWarmEntry *warm, int nwarm,
           const ssWarmEntry **cursor, int converged, int creep_rates, int *left)
{
  c->lambda[0] = c->lambda[1] = c->lambda[2] = 0;
  if (!nwarm) return NULL;
  int geom = c->geom, vertex = c->vertex;
  if (c->type == SS_CONTACT_PD || c->type == SS_CONTACT_LIMIT) row_key(d, c, &geom, &vertex);
  const ssWarmEntry *e = find_warm(warm, nwarm, geom, vertex, cursor);
  if (e && c->type == SS_CONTACT_SOIL) *left += warm_keep(c, e, converged, creep_rates);
  return e;
}

/* warm_body_run's point c of collider geom: its cache entry matched
 * (*cur, as find_warm's cursor), kept (warm_keep, counted in *nleft) and
 * its impulse into c->lambda and lam; 0 where it has no entry (its
 * impulse 0) */
static inline __attribute__((always_inline)) int
warm_body_point(const ssSoilMaterial *mats, double dt, ssContact *c, const ssWarmEntry *warm,
                int nwarm, int geom, int converged, int creep_rates, const ssWarmEntry **cur,
                int *nleft,
                double lam[3])
{
  const ssWarmEntry *e = find_warm(warm, nwarm, geom, c->vertex, cur);
  if (!e) {
    c->lambda[0] = c->lambda[1] = c->lambda[2] = 0;
    return 0;
  }
  *nleft += warm_keep(c, e, converged, creep_rates);
  warm_soil_impulse(mats, dt, c, e, creep_rates, lam);
  c->lambda[0] = lam[0];
  c->lambda[1] = lam[1];
  c->lambda[2] = lam[2];
  return 1;
}

/* The warm start (not deferred) of the soil points from contact i on that
 * lie on collider geom of a rigid body, up to the first contact that does
 * not; returns its index.  Each point as warm_start and warm_one take it,
 * their sums into a->br in the same order, but with the collider, the
 * type tests and the body's centre of mass known for the run, and the
 * run's sums in locals (the contacts' stores could alias them, as the
 * compiler sees it).  The points up to the first with an entry, where
 * the body's run opens (a call), and those after it are two loops: the
 * second calls nothing, so the contacts, the soils and the loop's bounds
 * stay in registers instead of being read again after each point. */
static int warm_body_run(const ssModel *m, ssData *d, int i, int nwarm, int converged,
                         int creep_rates, const ssWarmEntry **cursor, int *left, WarmApply *a)
{
  const ssWarmEntry *warm = d->warm;
  ssContact *const contact = d->contact;
  const ssSoilMaterial *const mats = m->hfield_soilmat;
  const int ncontact = d->ncontact, geom = contact[i].geom, b = m->geom_body[geom];
  const double dt = m->opt.timestep;
  const double com[3] = {d->body_xipos[3 * b], d->body_xipos[3 * b + 1],
                         d->body_xipos[3 * b + 2]};
  double F[6], lam[3];
  const ssWarmEntry *cur = *cursor;
  int open = 0, nleft = 0;
  for (; i < ncontact; i++) {
    ssContact *c = contact + i;
    if (c->type != SS_CONTACT_SOIL || c->geom != geom) break;
    if (!warm_body_point(mats, dt, c, warm, nwarm, geom, converged, creep_rates, &cur, &nleft,
                         lam))
      continue;
    /* the run's first impulse: the body's run opens (or goes on) */
    body_run_open(m, d, a, b);
    memcpy(F, a->br.F, sizeof F);
    body_run_add(c, com, lam, F);
    open = 1;
    i++;
    break;
  }
  for (; open && i < ncontact; i++) {
    ssContact *c = contact + i;
    if (c->type != SS_CONTACT_SOIL || c->geom != geom) break;
    if (warm_body_point(mats, dt, c, warm, nwarm, geom, converged, creep_rates, &cur, &nleft,
                        lam))
      body_run_add(c, com, lam, F);
  }
  if (open) memcpy(a->br.F, F, sizeof F);
  *cursor = cur;
  *left += nleft;
  return i;
}

/* The deferred warm start's matching (warm_start): each contact's cache
 * entry (c->warm_entry, -1: none) from the nwarm of warm, its impulse
 * zeroed and a soil point's entry kept (warm_match); returns how many
 * matched entries' rates were left out.  Inlined into one copy for each
 * value of creep_rates (warm_match_all). */
static inline __attribute__((always_inline)) int
match_all(const ssData *d, const ssWarmEntry *warm, int nwarm, int converged,
          const int creep_rates)
{
  ssContact *const contact = d->contact;
  const int ncontact = d->ncontact;
  const ssWarmEntry *cursor = warm;
  int left = 0;
  for (int i = 0; i < ncontact; i++) {
    ssContact *c = contact + i;
    const ssWarmEntry *e =
      warm_match(d, c, warm, nwarm, &cursor, converged, creep_rates, &left);
    c->warm_entry = e ? (int)(e - warm) : -1;
  }
  return left;
}

/* match_all, a function of its own, not inlined: inside warm_start the
 * loop shared its registers with the other path's, and read converged,
 * creep_rates and its count from the stack at each point */
static __attribute__((noinline)) int
warm_match_all(const ssData *d, const ssWarmEntry *warm, int nwarm, int converged,
               int creep_rates)
{
  return creep_rates ? match_all(d, warm, nwarm, converged, 1)
                     : match_all(d, warm, nwarm, converged, 0);
}

/* Initial impulses from last step's tractions extrapolated by their rate
 * (ssWarmEntry), scaled by the current area and time step and projected
 * into the current bounds; joint rows start from last step's impulse
 * rate.  converged: the cached tractions are a converged solve's (the
 * previous step's stats), so this step may form their rate.  A creeping
 * collider's entries (creep) are extrapolated only with creep_rates.  On
 * entry d->qvel is the free velocity; returns how many matched entries'
 * rates were left out.
 * Where the Newton phase may start from its prediction instead
 * (ss_newton_may_predict; on the rolling buggy, most steps), only the
 * cache entries are matched (c->warm_entry) and the tractions they came
 * from kept (warm_t, warm_trend: the cache's rates need them whatever the
 * solve starts from); the impulses stay 0 and d->qvel free until
 * ss_solver_warm_apply, which the Newton phase calls only where it starts
 * from the warm start after all, and the solve before any sweep. */
static int warm_start(const ssModel *m, ssData *d, int converged, int creep_rates)
{
  int left = 0, defer = !d->solver_warm_eager && ss_newton_may_predict(m, d);
  WarmApply a = {{NULL, NULL, NULL, {0}, {0}, {0}}, {-1, {0}}};
  d->warm_creep_rates = creep_rates;
  /* (the loop's invariants in locals: the contacts' stores could alias
   * them, as the compiler sees it) */
  const ssWarmEntry *warm = d->warm;
  const int nwarm = m->opt.terrain_warm_start ? d->nwarm : 0, ncontact = d->ncontact;
  const ssWarmEntry *cursor = warm;
  if (defer) {
    left = warm_match_all(d, warm, nwarm, converged, creep_rates);
  } else {
    for (int i = 0; i < ncontact;) {
      ssContact *c = d->contact + i;
      if (nwarm && c->type == SS_CONTACT_SOIL && c->link < 0 && c->nv) {
        /* a rigid body's soil points, as one run */
        i = warm_body_run(m, d, i, nwarm, converged, creep_rates, &cursor, &left, &a);
        continue;
      }
      const ssWarmEntry *e =
        warm_match(d, c, warm, nwarm, &cursor, converged, creep_rates, &left);
      if (e) warm_one(m, d, c, e, creep_rates, &a);
      i++;
    }
    warm_close(m, d, &a);
  }
  d->warm_pending = defer;
  return left;
}

void ss_solver_warm_lambda(const ssModel *m, const ssData *d, int i, double lam[3])
{
  const ssContact *c = d->contact + i;
  memcpy(lam, c->lambda, 3 * sizeof(double));
  if (d->warm_pending && c->warm_entry >= 0)
    warm_impulse(m, c, d->warm + c->warm_entry, d->warm_creep_rates, lam);
}

void ss_solver_warm_apply(const ssModel *m, ssData *d)
{
  if (!d->warm_pending) return;
  d->warm_pending = 0;
  WarmApply a = {{NULL, NULL, NULL, {0}, {0}, {0}}, {-1, {0}}};
  for (int i = 0; i < d->ncontact; i++) {
    ssContact *c = d->contact + i;
    if (c->warm_entry >= 0) warm_one(m, d, c, d->warm + c->warm_entry, d->warm_creep_rates, &a);
  }
  warm_close(m, d, &a);
}

/* the contacts the cache keeps: the joint rows, and soil points and rigid
 * contacts (the other two types) that carry load */
static int cached(const ssContact *c)
{
  return c->type == SS_CONTACT_PD || c->type == SS_CONTACT_LIMIT || c->lambda[0] > 0;
}

/* Sort the n cache entries of a by key (warm_key), b being as large;
 * returns whichever of a and b ends holding them.  The contacts come in a
 * few ascending runs (one per bed,
 * then the joint rows: the PD rows in the model's order, then the
 * limits), so neighbouring runs are merged pairwise until one is left: a
 * few passes, no general sort, none where the entries came sorted, and a
 * short tail (the buggy's one PD row out of dof order) inserted in place
 * (sort_runs.h). */
static int warm_less(const ssWarmEntry *a, const ssWarmEntry *b)
{
  return entry_key(a) < entry_key(b);
}
SS_SORT_RUNS(sort_runs, ssWarmEntry, warm_less)

/* A collider whose loaded soil points all slip slower than CREEP_SLIP
 * (m/s) while its patch carries shear (tangential impulses above
 * CREEP_SHEAR of the normal ones, both summed) creeps: its slip directions
 * are set by velocities so small that a traction's next value is mostly
 * no extrapolation of its last two, and an extrapolated warm start (rates
 * in ssWarmEntry) is further from the answer than the last tractions
 * themselves.  Its cache entries are marked (creep): the warm start leaves
 * their rates out, and only where the Newton phase then declines does it
 * start again from the extrapolation.  (plate_arm.xml, whose plate creeps
 * at 1e-7 to 1e-5 m/s under the lift's pull: with the rates always, 27
 * sweeps per step; without them, 4.7, nearly all in steps 201-500 where
 * the plate also sinks at 1e-3 m/s and its trend is real; with them where
 * Newton fails without, 0.4, and no step over 20 sweeps in 301-1000.)  A
 * sinking body carries no shear and keeps its rates; a rolling wheel's
 * patch slips far faster.  Which start suits is not known before: the
 * first residuals of both are about 1e-3 there, whichever converges. */
#define CREEP_SLIP 1e-4
#define CREEP_SHEAR 1e-6

/* The entries of ss_solver_store_warm, in contact order from next on;
 * returns the end of those made, and in *run the end of their first run
 * of ascending keys (-1: they came sorted).  Inlined into one copy for
 * each case of law (the Newton phase's impulses, or NULL: the contacts')
 * and converged (0 or 1), which ss_solver_store_warm picks once: each
 * point's law select, its index and the test of converged leave the
 * loop (a tenth of the buggy's store, an eighth of the settled
 * plate's). */
static inline __attribute__((always_inline)) ssWarmEntry *
store_entries(const ssModel *m, const ssData *d, ssWarmEntry *next, const double *law,
              const int converged, int *run)
{
  /* (the loop's invariants in locals: the entries' stores could alias
   * them, as the compiler sees it) */
  const double dt = m->opt.timestep, tol = m->opt.solver_tolerance;
  const int ncontact = d->ncontact;
  const ssContact *contact = d->contact;
  double *patch = d->geom_patch;
  ssWarmEntry *end = next;
  int first = -1;
  uint64_t last = 0;
  for (int i = 0; i < ncontact; i++) {
    const ssContact *c = contact + i;
    if (!cached(c)) continue;
    ssWarmEntry *e = end++;
    e->creep = 0;
    int geom, vertex;
    if (c->type == SS_CONTACT_SOIL) {
      double inv = 1.0 / (c->area * dt);
      geom = c->geom;
      vertex = c->vertex;
      /* (the soil points come first, as the Newton phase needs) */
      const double *l = law ? law + 3 * i : c->lambda;
      /* (the 1-norms start from their first terms: 0 + |x| is |x|,
       * whatever x, and they are only compared) */
      double ch = 0, size = 0;
      for (int k = 0; k < 3; k++) {
        e->traction[k] = l[k] * inv;
        e->rate[k] = c->warm_trend && converged ? e->traction[k] - c->warm_t[k] : 0;
        ch = k ? ch + fabs(e->rate[k]) : fabs(e->rate[k]);
        size = k ? size + fabs(e->traction[k]) : fabs(e->traction[k]);
      }
      /* a change within the solver's tolerance is not a trend: the
       * tractions are known to about that (a settled body's drift) */
      if (ch <= tol * size) {
        e->rate[0] = e->rate[1] = e->rate[2] = 0;
      } else {
        /* (a patch whose fastest slip reached CREEP_SLIP does not creep,
         * whatever its later points and sums: those are left out, and
         * its sums, scratch, are not read) */
        double *g = patch + 3 * geom;
        if (g[0] < CREEP_SLIP * CREEP_SLIP) {
          double v2 = c->v[1] * c->v[1] + c->v[2] * c->v[2];
          if (v2 > g[0]) g[0] = v2;
          g[1] += c->lambda[0];
          g[2] += fabs(c->lambda[1]) + fabs(c->lambda[2]);
        }
      }
    } else if (c->type != SS_CONTACT_PD && c->type != SS_CONTACT_LIMIT) {
      /* a rigid or pair contact: its force, to be scaled by the next
       * step's dt; no rate */
      geom = c->geom;
      vertex = c->vertex;
      for (int k = 0; k < 3; k++) {
        e->traction[k] = c->lambda[k] / dt;
        e->rate[k] = 0;
      }
    } else {
      row_key(d, c, &geom, &vertex);
      e->traction[0] = c->lambda[0] / dt;
      e->traction[1] = e->traction[2] = 0;
      e->rate[0] = e->rate[1] = e->rate[2] = 0;
    }
    /* an impulse over a tiny step can overflow as a force (a heavy body's
     * impact at dt = 1e-300): no start is better than an infinite one,
     * which the next step could not use nor a checkpoint hold */
    if (!(isfinite(e->traction[0]) && isfinite(e->traction[1]) && isfinite(e->traction[2]) &&
          isfinite(e->rate[0]) && isfinite(e->rate[1]) && isfinite(e->rate[2]))) {
      end--;
      continue;
    }
    e->vertex = vertex;
    e->geom = geom;
    uint64_t key = warm_key(geom, vertex);
    e->key = key;
    if (key < last && first < 0) first = (int)(e - next);
    last = key;
  }
  *run = first;
  return end;
}

/* keep this step's converged tractions (soil) and impulse rates (joint
 * rows) for the next one */
ssStatus ss_solver_store_warm(const ssModel *m, ssData *d, ssError *err)
{
  /* room for every contact (those cached are fewer: no pass to count them) */
  int n = d->ncontact;
  if (n > d->cap_warm) {
    ssWarmEntry *p = realloc(d->warm, (size_t)n * sizeof *p);
    if (!p) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
    d->warm = p;
    d->cap_warm = n;
  }
  if (n > d->cap_warm_next) {
    ssWarmEntry *q = realloc(d->warm_next, (size_t)n * sizeof *q);
    if (!q) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
    d->warm_next = q;
    d->cap_warm_next = n;
  }
  /* the entries in contact order into warm_next (the old cache is not
   * needed any more), then sorted into warm; end walks past the last one
   * made (a pointer: from a count, each entry's address took three
   * instructions more) */
  ssWarmEntry *next = d->warm_next;
  /* A step whose warm start stood as it came (the Newton phase found a
   * settled body's warm impulses within the tolerance of its laws there)
   * keeps the laws' impulses at its velocities instead: as close to the
   * answer, and ahead of the warm impulses by the step's drift.  Kept
   * back, that drift (a settled plate's slow creep, each step's change
   * below the tolerance, so no rate follows it) piles up over the steps
   * until the warm start fails its check, and every few steps pay for
   * the apply and check a converged Newton solve needs (the settled
   * plate: every other step). */
  const double *law = d->solver_settled ? ss_newton_law(d) : NULL;
  /* each collider's patch, over its points that keep a rate: the largest
   * squared slip, and sums of normal and tangential impulses (1-norms),
   * for CREEP_SLIP */
  double *patch = d->geom_patch;
  memset(patch, 0, 3 * (size_t)m->ngeom * sizeof *patch);
  /* the end of the entries' first run of ascending keys, -1 where they
   * came sorted, for the sort (the soil points come in runs, see
   * warm_key) */
  int run;
  /* (one copy of the loop for each case, store_entries) */
  ssWarmEntry *end = law ? d->stats.converged ? store_entries(m, d, next, law, 1, &run)
                                              : store_entries(m, d, next, law, 0, &run)
                    : d->stats.converged ? store_entries(m, d, next, NULL, 1, &run)
                                         : store_entries(m, d, next, NULL, 0, &run);
  n = (int)(end - next);
  /* a creeping collider's points keep no rates */
  int creeping = 0;
  for (int g = 0; g < m->ngeom; g++) {
    double *p = patch + 3 * g;
    p[0] = p[1] > 0 && p[0] < CREEP_SLIP * CREEP_SLIP && p[2] > CREEP_SHEAR * p[1];
    creeping |= p[0] != 0;
  }
  for (int k = 0; k < n && creeping; k++) {
    ssWarmEntry *e = next + k;
    e->creep = e->geom >= 0 && patch[3 * e->geom] != 0 &&
               (e->rate[0] != 0 || e->rate[1] != 0 || e->rate[2] != 0);
  }
  if (run < 0 || sort_runs_from(next, d->warm, n, run) == next) {
    /* sorted in warm_next: the buffers change places (and capacities) */
    int cap = d->cap_warm;
    d->warm_next = d->warm;
    d->warm = next;
    d->cap_warm = d->cap_warm_next;
    d->cap_warm_next = cap;
  }
  d->nwarm = n;
  ss_newton_keep(d);
  return SS_OK;
}

/* one Gauss-Seidel visit: new impulse of contact c with the others held;
 * inside an open group g the contact sees and moves the link's spatial
 * velocity only */
/* contact c's velocity as a visit sees it: in an open group g from the
 * link's spatial velocity, else from the system's */
static inline void visit_velocity(const ssModel *m, ssData *d, const ssContact *c,
                                  const Group *g, int row, double v[3])
{
  v[0] = v[1] = v[2] = 0;
  if (g->first) rows_velocity(d->jac + c->jadr, g->V, v);
  else if (row) v[0] = row_velocity(d, c);
  else if (c->nv) contact_velocity(m, d, c, v);
}

/* contact c's impulse changed by dl: into the open group g (the link's
 * spatial impulse and velocity), or into the system's velocity */
static inline void visit_apply(const ssModel *m, ssData *d, ssContact *c, Group *g, int row,
                               const double dl[3])
{
  if (g->first) {
    if (dl[0] != 0 || dl[1] != 0 || dl[2] != 0) {
      double w[6], dV[6];
      const double *X = d->jac + c->jadr;
      rows_impulse(X, dl, w);
      rows_impulse(X + 18, dl, dV); /* Lam X^T dl, from LX */
      for (int k = 0; k < 6; k++) {
        g->F[k] += w[k];
        g->V[k] += dV[k];
      }
    }
  } else if (row) {
    if (dl[0] != 0) row_apply(d, c, dl[0]);
  } else if (c->nv) {
    apply_impulse(m, d, c, dl);
  }
}

/* the sweeps' measure: a contact's change dl and impulse l (1-norms) into
 * the largest so far */
static inline void measure_add(const double dl[3], const double l[3], double *dmax,
                               double *lmax)
{
  double dn = fabs(dl[0]) + fabs(dl[1]) + fabs(dl[2]);
  double ln = fabs(l[0]) + fabs(l[1]) + fabs(l[2]);
  if (dn > *dmax) *dmax = dn;
  if (ln > *lmax) *lmax = ln;
}

static void visit(const ssModel *m, ssData *d, ssContact *c, Group *g,
                  double *dmax, double *lmax)
{
  const double stol = m->opt.scalar_tolerance;
  int row = c->type == SS_CONTACT_PD || c->type == SS_CONTACT_LIMIT;
  double v[3], v0[3], old[3];
  visit_velocity(m, d, c, g, row, v);
  memcpy(old, c->lambda, sizeof old);
  ss_m3_mulv(v0, c->G, old);
  ss_v3_sub(v0, v, v0);
  switch (c->type) {
  case SS_CONTACT_SOIL:
    ss_point_soil(c, v0, stol);
    break;
  case SS_CONTACT_RIGID:
  case SS_CONTACT_PAIR: ss_point_rigid(c, v0, stol); break;
  case SS_CONTACT_PD: pd_row(c, v0); break;
  default: limit_row(c, v0); break;
  }
  double dl[3];
  ss_v3_sub(dl, c->lambda, old);
  visit_apply(m, d, c, g, row, dl);
  measure_add(dl, c->lambda, dmax, lmax);
}

/* contact c's end-of-step velocity v kept, and whether it is loaded (a
 * soil point pressed by its impulse and still below the surface at the
 * step's end: the soil update's); an unloaded soil point's impulse 0 */
static inline __attribute__((always_inline)) void
contact_end(ssContact *c, const double v[3], double dt)
{
  /* (one store each: a memcpy went through a copy on the stack) */
  c->v[0] = v[0];
  c->v[1] = v[1];
  c->v[2] = v[2];
  c->loaded = c->type == SS_CONTACT_SOIL && c->lambda[0] > 0 && -(c->g0 + dt * v[0]) > 0;
  if (c->type == SS_CONTACT_SOIL && !c->loaded)
    c->lambda[0] = c->lambda[1] = c->lambda[2] = 0;
}

/* The end of the solve (contact_end) for the run of soil points from c on
 * (before end) that lie on c's collider, a rigid body's; returns the
 * contact after the run.  The body's velocity and centre of mass are
 * known for the run (in locals: the contacts' stores could alias them, as
 * the compiler sees it). */
static ssContact *body_run_end(const ssModel *m, const ssData *d, ssContact *c,
                               const ssContact *end)
{
  const double dt = m->opt.timestep;
  const int geom = c->geom;
  const double *x = d->body_xipos + 3 * m->geom_body[geom], *q = d->qvel + c->vadr;
  const double com[3] = {x[0], x[1], x[2]}, u[6] = {q[0], q[1], q[2], q[3], q[4], q[5]};
  for (; c < end && c->type == SS_CONTACT_SOIL && c->geom == geom; c++) {
    double v[3];
    body_point_velocity(c, com, u, v);
    contact_end(c, v, dt);
  }
  return c;
}

/* The same for the run of contacts from c on (before end) that lie on
 * c's link: the link's spatial velocity formed once for the run, in
 * locals (as body_run_end's), and each point's velocity kept from
 * registers instead of through a stack copy. */
static ssContact *link_run_end(const ssModel *m, const ssData *d, ssContact *c,
                               const ssContact *end)
{
  const double dt = m->opt.timestep;
  const int link = c->link;
  double S[6];
  ss_art_link_velocity(m, d, link, S);
  const double V[6] = {S[0], S[1], S[2], S[3], S[4], S[5]};
  const double *org = ss_art_origin(d, c->sys), o[3] = {org[0], org[1], org[2]};
  for (; c < end && c->link == link && c->type != SS_CONTACT_PAIR; c++) {
    double v[3];
    link_point_velocity(o, c, V, v);
    contact_end(c, v, dt);
  }
  return c;
}

/* Whether contact b joins rigid contact a's block: a rigid contact of the
 * same collider (next to it in the contacts, on the same link or body),
 * or a pair contact of the same two colliders */
static inline int same_block(const ssContact *a, const ssContact *b)
{
  return b->type == a->type && b->geom == a->geom &&
         (a->type == SS_CONTACT_RIGID || (a->type == SS_CONTACT_PAIR && b->geom2 == a->geom2));
}

/* Visits contacts lo..hi once, backwards where back is set */
static void visit_span(const ssModel *m, ssData *d, int lo, int hi, int back, Group *g,
                       double *dmax, double *lmax)
{
  if (back)
    for (int k = hi; k >= lo; k--) visit(m, d, d->contact + k, g, dmax, lmax);
  else
    for (int k = lo; k <= hi; k++) visit(m, d, d->contact + k, g, dmax, lmax);
}

/* A collider's rigid contacts on one body or link (two rim points of a
 * wheel, four corners of a box) are solved as one block within each
 * sweep: after its first pass (which counts in the sweep's measure: it
 * is the block's answer to every other contact's change since its last
 * visit), the block's own solve (block_solve) and a pass that checks it,
 * again, alternating direction, until the block's own largest change in a
 * pass is within the tolerance of its largest impulse, or RIGID_PASSES
 * passes (the solve before the first BLOCK_TRIES of them, on blocks of at
 * most BLOCK_MAX contacts).  Such contacts are redundant or nearly (a
 * wheel's two rim points on flat ground, with its camber and its steer
 * held by the suspension's linkage, hold the same motions as the other
 * wheels' do through the chassis; four corners of a box on the ground):
 * the split of the load between them is set only by small differences,
 * which one pass a sweep moves slowly.  Measured on buggy_rigid.xml (2000
 * steps, tolerance 1e-9, the warm start on): one pass a sweep, 177 sweeps
 * a step over its last 500 steps and 416 of them at the 200-sweep cap;
 * passes alone up to 64, 41 sweeps a step and none capped after its drop.
 * Turning (the rack at 3 cm, 6000 steps): one pass a sweep, every step
 * from 1 s on at the cap; passes alone, 172 sweeps a step from 2 s on,
 * three steps in five capped, the passes at their own cap; with the
 * block's solve, 38-40 sweeps a step and one step in 25 capped (README,
 * Rigid contacts).  A block's solve keeps its arrays on the stack, about
 * 60 KB at BLOCK_MAX. */
enum { RIGID_PASSES = 64, BLOCK_MAX = 16, BLOCK_TRIES = 6 };

/* X_a LX_b^T, the 3 x 3 of two link contacts' rows (6 wide each) */
static void rows_product(const double *Xa, const double *LXb, double G[9])
{
  for (int r = 0; r < 3; r++)
    for (int k = 0; k < 3; k++) {
      const double *x = Xa + 6 * r, *y = LXb + 6 * k;
      G[3 * r + k] = x[0] * y[0] + x[1] * y[1] + x[2] * y[2] + x[3] * y[3] + x[4] * y[4] +
                     x[5] * y[5];
    }
}

/* The response of contact a's velocity to contact b's impulse through one
 * body both act on, from their rows at ja and jb: the same link's X_a LX_b
 * (link >= 0), or the same free body's J_a W_b (nv velocities) */
static void side_response(const ssData *d, int link, int nv, long ja, long jb, double G[9])
{
  const double *Xa = d->jac + ja;
  if (link >= 0) {
    rows_product(Xa, d->jac + jb + 18, G);
    return;
  }
  const double *Wb = d->jac + jb + 3 * nv;
  for (int r = 0; r < 3; r++)
    for (int k = 0; k < 3; k++) {
      double s = 0;
      for (int i = 0; i < nv; i++) s += Xa[r * nv + i] * Wb[3 * i + k];
      G[3 * r + k] = s;
    }
}

/* G_ab, the response of contact a's velocity to contact b's impulse (3 x 3,
 * row-major), both on one link (X_a Lam X_b^T = X_a . LX_b), on two links
 * of a system (through P, their pair block), on one free body (J_a W_b),
 * or two pair contacts of the same colliders, from the rows the sweeps'
 * set-up formed */
static void block_response(const ssData *d, const ssContact *a, const ssContact *b,
                           const double *P, double G[9])
{
  if (a->type == SS_CONTACT_PAIR) {
    /* two pair contacts of the same two colliders: both bodies' parts
     * (the second's with the sign its velocity counts with, twice) */
    double G2[9];
    side_response(d, a->link, a->nv, a->jadr, b->jadr, G);
    side_response(d, a->link2, a->nv2, a->jadr2, b->jadr2, G2);
    for (int k = 0; k < 9; k++) G[k] += G2[k];
    return;
  }
  if (a->link >= 0 && a->link != b->link) {
    /* X_a (J_a Y_b) X_b^T, P = J_a Y_b the links' pair block */
    const double *Xb = d->jac + b->jadr;
    double LX[18];
    for (int k = 0; k < 3; k++)
      for (int r = 0; r < 6; r++) {
        const double *p = P + 6 * r, *x = Xb + 6 * k;
        LX[6 * k + r] = p[0] * x[0] + p[1] * x[1] + p[2] * x[2] + p[3] * x[3] + p[4] * x[4] +
                        p[5] * x[5];
      }
    rows_product(d->jac + a->jadr, LX, G);
    return;
  }
  side_response(d, a->link, a->nv, a->jadr, b->jadr, G);
}

/* Solves the n x n system A x = b in place (row-major, n <= 3 BLOCK_MAX),
 * regularised towards xc: (A + e I) x = b + e xc, e 1e-10 of A's largest
 * diagonal entry, by the Newton phase's LU (ss_lu_factor).  A block's
 * contacts may be exactly redundant (four corners of a box on the ground
 * hold six motions with twelve rows): of the answers then, the one nearest
 * the impulses it starts from, so that a block already solved stays as it
 * is (a pass after it changes nothing).  0 where a pivot falls below 1e-14
 * of that diagonal entry or the answer is not finite. */
static int block_linear(double *A, double *b, const double *xc, int n)
{
  double s = 0;
  for (int i = 0; i < n; i++) s = fmax(s, fabs(A[i * n + i]));
  if (!(s > 0)) return 0;
  for (int i = 0; i < n; i++) {
    A[i * n + i] += 1e-10 * s;
    b[i] += 1e-10 * s * xc[i];
  }
  int piv[3 * BLOCK_MAX];
  if (!ss_lu_factor(A, piv, n)) return 0;
  for (int k = 0; k < n; k++)
    if (!(fabs(A[k * n + k]) > 1e-14 * s)) return 0;
  ss_lu_solve(A, piv, n, b);
  for (int k = 0; k < n; k++)
    if (!isfinite(b[k])) return 0;
  return 1;
}

/* A block for block_solve: its rigid contacts c, their responses G (3n x
 * 3n) and their velocities without the block's own impulses v0, and each
 * contact's assumed state, kind: 0 unloaded, 1 sticking, 2 sliding, its
 * tangential impulse on the cone against its slip (-mu lambda_n v_t /
 * |v_t|) linearised about the slip vk (speed sk, direction u) and the
 * normal impulse lk of the last answer, or, where sk or lk is 0, held
 * along -u; 3 a PD row (system_blocks), one unknown within its effort
 * bound, lambda + b v = a (pd_row), its second and third rows and columns
 * of G zero. */
typedef struct Block {
  int n;
  int island;  /* free bodies' contacts joined by pair contacts
                  (island_blocks): responses by island_response */
  ssContact *c[BLOCK_MAX];
  double G[3 * BLOCK_MAX][3 * BLOCK_MAX], v0[3 * BLOCK_MAX];
  int kind[BLOCK_MAX];
  double u[BLOCK_MAX][2], vk[BLOCK_MAX][2], sk[BLOCK_MAX], lk[BLOCK_MAX];
  double lmax; /* the largest normal impulse of the answer being judged */
} Block;

/* A correction of one contact's state (block_admissible): to which state,
 * a sliding one's direction u, and how far the answer is from admissible
 * in it, as an impulse (a velocity through the contact's own response) */
typedef struct Fix {
  int i, kind;
  double u[2], viol;
} Fix;

/* unknowns of contact i in its state: none, its impulse (3), or a sliding
 * contact's normal impulse alone where its direction is held (1) */
static inline int block_unknowns(const Block *B, int i)
{
  if (!B->kind[i]) return 0;
  if (B->kind[i] == 1) return 3;
  if (B->kind[i] == 3) return 1;
  return B->sk[i] > 0 && B->lk[i] > 0 && B->c[i]->mu > 0 ? 3 : 1;
}

/* The impulses nl (3n) of block B's contacts in their states: the loaded
 * ones at their normal targets (vn_target), the sticking ones stopped,
 * the sliding ones' on their cones against their slip (a Newton step on
 * (sk / (mu lk)) (lambda_t + mu lambda_n u) + P_u (v_t - vk) = 0, P_u = I
 * - u u^T the slip's change across u: the impulse's direction follows the
 * slip's; or, held, lambda_t = -mu lambda_n u).  Each equation is a
 * combination cr of the block's velocity rows plus terms own in its
 * contact's unknowns.  lam: the impulses the solve starts from
 * (block_linear).  0 where the system cannot be solved. */
static int block_impulses(const Block *B, const double *lam, double nl[3 * BLOCK_MAX])
{
  enum { N = 3 * BLOCK_MAX };
  const int n = B->n;
  int col[BLOCK_MAX], nun[BLOCK_MAX], neq = 0;
  for (int i = 0; i < n; i++) {
    col[i] = neq;
    neq += nun[i] = block_unknowns(B, i);
  }
  for (int i = 0; i < 3 * n; i++) nl[i] = 0;
  if (neq == 0) return 1;
  /* a held sliding contact's impulse per unit normal impulse */
  double E[BLOCK_MAX][3];
  for (int j = 0; j < n; j++) {
    E[j][0] = 1;
    E[j][1] = -B->c[j]->mu * B->u[j][0];
    E[j][2] = -B->c[j]->mu * B->u[j][1];
  }
  double A[N * N], x[N], xc[N];
  for (int i = 0; i < n; i++) {
    const ssContact *ci = B->c[i];
    for (int a = 0; a < nun[i]; a++) xc[col[i] + a] = lam[3 * i + a];
    for (int a = 0; a < nun[i]; a++) {
      int r = col[i] + a;
      double *Ar = A + r * neq, cr[3] = {0, 0, 0}, own[3] = {0, 0, 0}, rhs = 0;
      if (B->kind[i] == 3) {
        /* lambda + b v = a */
        cr[0] = ci->row_b;
        own[0] = 1;
        rhs = ci->row_a;
      } else if (B->kind[i] == 2 && a > 0) {
        double al = B->sk[i] / (ci->mu * B->lk[i]);
        const double *u = B->u[i];
        for (int b = 0; b < 2; b++) {
          double P = (a - 1 == b) - u[a - 1] * u[b];
          cr[1 + b] = P;
          rhs += P * B->vk[i][b];
        }
        own[a] = al;
        own[0] = al * ci->mu * u[a - 1];
      } else {
        cr[a] = 1;
        rhs = a == 0 ? ci->vn_target : 0;
      }
      /* (the combination's rows are contact i's own three) */
      const int R = 3 * i;
      x[r] = rhs - (cr[0] * B->v0[R] + cr[1] * B->v0[R + 1] + cr[2] * B->v0[R + 2]);
      for (int j = 0; j < n; j++) {
        for (int k = 0; k < nun[j]; k++) {
          double g[3];
          for (int q = 0; q < 3; q++)
            g[q] = nun[j] == 3 ? B->G[R + q][3 * j + k]
                               : B->G[R + q][3 * j] * E[j][0] + B->G[R + q][3 * j + 1] * E[j][1] +
                                     B->G[R + q][3 * j + 2] * E[j][2];
          Ar[col[j] + k] = cr[0] * g[0] + cr[1] * g[1] + cr[2] * g[2];
        }
      }
      for (int k = 0; k < nun[i]; k++) Ar[col[i] + k] += own[k];
    }
  }
  if (!block_linear(A, x, xc, neq)) return 0;
  for (int i = 0; i < n; i++) {
    double *l = nl + 3 * i;
    if (nun[i] == 3) {
      l[0] = x[col[i]];
      l[1] = x[col[i] + 1];
      l[2] = x[col[i] + 2];
    } else if (nun[i] == 1) {
      for (int k = 0; k < 3; k++) l[k] = E[i][k] * x[col[i]];
    }
  }
  return 1;
}

/* sliding contact i linearised at normal impulse ln and slip vt (its
 * direction kept where vt is 0) */
static void block_slide_at(Block *B, int i, double ln, const double vt[2])
{
  double s = hypot(vt[0], vt[1]);
  B->kind[i] = 2;
  B->vk[i][0] = vt[0];
  B->vk[i][1] = vt[1];
  B->sk[i] = s;
  B->lk[i] = ln > 0 ? ln : 0;
  if (s > 0) {
    B->u[i][0] = vt[0] / s;
    B->u[i][1] = vt[1] / s;
  }
}

/* contact i's state from its impulse l and velocity v: sliding where its
 * tangential impulse lies on its cone */
static void block_state(Block *B, int i, const double l[3], const double v[3])
{
  const ssContact *c = B->c[i];
  double ln = l[0], lt = hypot(l[1], l[2]);
  B->u[i][0] = B->u[i][1] = 0;
  B->sk[i] = B->lk[i] = 0;
  if (c->type == SS_CONTACT_PD) {
    B->kind[i] = 3;
    return;
  }
  B->kind[i] = !(ln > 0) ? 0 : lt < c->mu * ln * (1 - 1e-6) ? 1 : 2;
  if (B->kind[i] != 2) return;
  /* against its impulse where it has no slip */
  if (lt > 0) {
    B->u[i][0] = -l[1] / lt;
    B->u[i][1] = -l[2] / lt;
  }
  block_slide_at(B, i, ln, v + 1);
}

/* Whether contact i's answer nl (with the block's G and v0) is admissible
 * in its state, and where it slides also settled (its slip along the
 * direction the step assumed, its impulse on the cone against it to 1e-9
 * of the block's largest normal impulse, B->lmax, the scale of the sweeps'
 * measure; against its own, a lightly loaded contact never settled where
 * the regularisation of block_linear moves its impulse by more): 1.
 * -1 where its state is wrong, with the correction in *f (a loaded
 * contact pulled: unloaded; an unloaded one closing past its target:
 * sticking; a sticking one beyond its cone: sliding against that impulse;
 * a sliding one whose slip stopped or turned back: sticking).  0 where a
 * sliding contact is linearised again at its new slip (done).  -2 for a PD
 * row past its effort bound: the solve has no state for it. */
static int block_admissible(Block *B, int i, const double *nl, Fix *f)
{
  const ssContact *c = B->c[i];
  const double *l = nl + 3 * i;
  if (B->kind[i] == 3) return fabs(l[0]) < c->row_bound ? 1 : -2;
  double v[3];
  for (int a = 0; a < 3; a++) {
    v[a] = B->v0[3 * i + a];
    for (int j = 0; j < 3 * B->n; j++) v[a] += B->G[3 * i + a][j] * nl[j];
  }
  /* a velocity's violation as an impulse, through the contact's own
   * response (positive for a contact on a moving body) */
  const double gn = B->G[3 * i][3 * i];
  const double gt = 0.5 * (B->G[3 * i + 1][3 * i + 1] + B->G[3 * i + 2][3 * i + 2]);
  int kind = B->kind[i];
  f->i = i;
  f->u[0] = B->u[i][0];
  f->u[1] = B->u[i][1];
  f->viol = 0;
  if (kind && !(l[0] >= 0)) {
    kind = 0;
    f->viol = -l[0];
  } else if (!kind) {
    double dv = c->vn_target - v[0];
    if (dv > 1e-9 * fabs(c->vn_target)) {
      kind = 1;
      f->viol = gn > 0 ? dv / gn : dv;
    }
  } else if (kind == 1) {
    double lt = hypot(l[1], l[2]);
    if (!(lt <= c->mu * l[0] * (1 + 1e-9)) && lt > 0) {
      kind = 2;
      f->u[0] = -l[1] / lt;
      f->u[1] = -l[2] / lt;
      f->viol = lt - c->mu * l[0];
    }
  } else {
    double s = hypot(v[1], v[2]), dot = v[1] * f->u[0] + v[2] * f->u[1];
    if (!(dot > 0)) {
      kind = 1;
      f->viol = gt > 0 ? -dot / gt : -dot;
    } else {
      double on = fabs(l[1] + c->mu * l[0] * v[1] / s) + fabs(l[2] + c->mu * l[0] * v[2] / s);
      if (!(dot >= (1 - 1e-12) * s && on <= 1e-9 * (c->mu * B->lmax))) {
        block_slide_at(B, i, l[0], v + 1);
        return 0;
      }
    }
  }
  f->kind = kind;
  return kind == B->kind[i] ? 1 : -1;
}

/* The responses that involve block B's PD rows (row[i] set; system_blocks,
 * so g holds no open group) into B->G, by trial: an impulse on each row
 * that changes its own velocity by about 1 (1 / G, its own response)
 * applied to the system's velocity, every member's velocity read against
 * v (theirs now), the velocity then put back bit for bit.  That column also gives
 * the row's line: the response is symmetric (J M^-1 J^T; the two agree to
 * round-off in the velocities, 1e-7 of the smallest entries, 3e-8, on
 * the turning buggy).  The rows' responses to one another are not formed
 * anywhere else, nor a row's to a link's contact.  0 where the system has
 * more than 256 dofs. */
static int block_row_responses(const ssModel *m, ssData *d, Block *B, const Group *g,
                               const int *row, const double *v)
{
  const int n = B->n;
  const ssContact *c0 = B->c[0];
  double *u = d->qvel + c0->vadr, keep[256];
  if (g->first || c0->nv > 256) return 0;
  memcpy(keep, u, (size_t)c0->nv * sizeof(double));
  for (int r = 0; r < n; r++) {
    if (!row[r]) continue;
    double s = B->c[r]->G[0] > 0 ? 1 / B->c[r]->G[0] : 1;
    row_apply(d, B->c[r], s);
    for (int i = 0; i < n; i++) {
      double w[3];
      visit_velocity(m, d, B->c[i], g, row[i], w);
      for (int a = 0; a < 3; a++) {
        double gi = row[i] && a ? 0 : (w[a] - v[3 * i + a]) / s;
        B->G[3 * i + a][3 * r] = gi;
        if (!row[i]) B->G[3 * r][3 * i + a] = gi;
      }
    }
    memcpy(u, keep, (size_t)c0->nv * sizeof(double));
  }
  return 1;
}

/* The bodies of a free body's contact (rigid or pair): each one's body,
 * its rows J (3 x 6) and response W (6 x 3) at jadr and jadr + 18 in the
 * contact's storage, and the sign its impulse takes there */
typedef struct Side {
  int body;
  long jadr;
  double sign;
} Side;

static int contact_sides(const ssModel *m, const ssContact *c, Side s[2])
{
  s[0] = (Side){m->geom_body[c->geom], c->jadr, 1};
  if (c->type != SS_CONTACT_PAIR) return 1;
  s[1] = (Side){m->geom_body[c->geom2], c->jadr2, -1};
  return 2;
}

/* G_ab between two contacts of free bodies (an island's, island_blocks):
 * over the bodies they share, J_a W_b with their signs */
static void island_response(const ssModel *m, const ssContact *a, const ssContact *b,
                            const double *jac, double G[9])
{
  Side sa[2], sb[2];
  int na = contact_sides(m, a, sa), nb = contact_sides(m, b, sb);
  memset(G, 0, 9 * sizeof(double));
  for (int p = 0; p < na; p++)
    for (int q = 0; q < nb; q++) {
      if (sa[p].body != sb[q].body) continue;
      const double *J = jac + sa[p].jadr, *W = jac + sb[q].jadr + 18;
      const double s = sa[p].sign * sb[q].sign;
      for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++) {
          double t = 0;
          for (int i = 0; i < 6; i++) t += J[6 * r + i] * W[3 * i + k];
          G[3 * r + k] += s * t;
        }
    }
}

/* One solve of block B's contacts (B->n and B->c set), every other contact
 * held: the linear system of their states (block_impulses), from the
 * states their impulses show, the states corrected and the sliding
 * contacts linearised again (block_admissible) until an admissible,
 * settled answer, at most 2n + 8 solves.  One state is corrected a round
 * (changed together, the states of redundant contacts cycle): that of the
 * largest violation, unless it leads back to a set of states tried in
 * this solve, then the next largest; none left, the solve gives up.  (The
 * first inadmissible contact's, as it was, let a wheel's two rim points
 * on rigid ground and a second wheel's trade states in a cycle of four
 * while a third contact's violation, a thousand times larger, waited:
 * turning on buggy_rigid.xml, 61 of steps 2001-4000 stopped at the sweep
 * cap, 13 after, 14 with the PD rows in the system's solve.)  Where a
 * pass moves the load between nearly redundant contacts only a little,
 * this moves it at once; the pass after it checks the answer.  Velocities are read and moved through the open
 * group g, or the system's where none is open.  Returns 1 where it
 * applied an answer. */
static int block_solve(const ssModel *m, ssData *d, Block *B, Group *g)
{
  const int n = B->n;
  double lam[3 * BLOCK_MAX], v[3 * BLOCK_MAX], nl[3 * BLOCK_MAX];
  enum { LINKS = 8 };
  int links[LINKS], nlinks = 0, li[BLOCK_MAX], row[BLOCK_MAX], nrow = 0;
  double P[LINKS * LINKS][36];
  unsigned char have[LINKS * LINKS] = {0};
  for (int i = 0; i < n; i++) {
    row[i] = B->c[i]->type == SS_CONTACT_PD;
    nrow += row[i];
    if (row[i]) continue;
    int k = 0;
    while (k < nlinks && links[k] != B->c[i]->link) k++;
    if (k == nlinks) {
      if (nlinks == LINKS) return 0;
      links[nlinks++] = B->c[i]->link;
    }
    li[i] = k;
  }
  for (int i = 0; i < n; i++) {
    visit_velocity(m, d, B->c[i], g, row[i], v + 3 * i);
    memcpy(lam + 3 * i, B->c[i]->lambda, sizeof B->c[i]->lambda);
    for (int j = 0; j < n; j++) {
      /* (a row's entries: block_row_responses) */
      double Gij[9] = {0};
      if (B->island) {
        island_response(m, B->c[i], B->c[j], d->jac, Gij);
      } else if (!row[i] && !row[j]) {
        const double *Pij = NULL;
        if (B->c[i]->link >= 0 && li[i] != li[j]) {
          int q = li[i] * LINKS + li[j];
          if (!have[q]) ss_art_link_pair(m, d, links[li[i]], links[li[j]], P[q], 6);
          have[q] = 1;
          Pij = P[q];
        }
        block_response(d, B->c[i], B->c[j], Pij, Gij);
      }
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) B->G[3 * i + a][3 * j + b] = Gij[3 * a + b];
    }
  }
  if (nrow && !block_row_responses(m, d, B, g, row, v)) return 0;
  for (int i = 0; i < 3 * n; i++) {
    B->v0[i] = v[i];
    for (int j = 0; j < 3 * n; j++) B->v0[i] -= B->G[i][j] * lam[j];
  }
  for (int i = 0; i < n; i++) block_state(B, i, lam + 3 * i, v + 3 * i);
  /* the states tried, 2 bits a contact (BLOCK_MAX <= 32), one a round */
  uint64_t key = 0, seen[2 * BLOCK_MAX + 9];
  for (int i = 0; i < n; i++) key |= (uint64_t)B->kind[i] << (2 * i);
  seen[0] = key;
  int ok = 0, nseen = 1;
  for (int round = 0; round < 2 * n + 8 && !ok; round++) {
    if (!block_impulses(B, lam, nl)) return 0;
    B->lmax = 0;
    for (int i = 0; i < n; i++) B->lmax = fmax(B->lmax, nl[3 * i]);
    /* the corrections, largest violation first */
    Fix fix[BLOCK_MAX];
    int nfix = 0;
    ok = 1;
    for (int i = 0; i < n; i++) {
      Fix f;
      int a = block_admissible(B, i, nl, &f);
      if (a == -2) return 0;
      ok &= a > 0;
      if (a >= 0) continue;
      int k = nfix++;
      for (; k > 0 && !(fix[k - 1].viol >= f.viol); k--) fix[k] = fix[k - 1];
      fix[k] = f;
    }
    if (!nfix) continue;
    /* one a round, the first that leads to a state not tried */
    int k = 0;
    uint64_t next = 0;
    for (; k < nfix; k++) {
      int i = fix[k].i, s = 0;
      next = (key & ~((uint64_t)3 << (2 * i))) | (uint64_t)fix[k].kind << (2 * i);
      while (s < nseen && seen[s] != next) s++;
      if (s == nseen) break;
    }
    if (k == nfix) return 0;
    const Fix *f = fix + k;
    B->kind[f->i] = f->kind;
    B->u[f->i][0] = f->u[0];
    B->u[f->i][1] = f->u[1];
    B->sk[f->i] = B->lk[f->i] = 0;
    key = next;
    seen[nseen++] = key;
  }
  if (!ok) return 0;
  for (int i = 0; i < n; i++) {
    ssContact *c = B->c[i];
    double dl[3];
    ss_v3_sub(dl, nl + 3 * i, c->lambda);
    visit_apply(m, d, c, g, row[i], dl);
    memcpy(c->lambda, nl + 3 * i, sizeof c->lambda);
  }
  return 1;
}

/* the largest change a visit of each of the n rigid contacts cs would make
 * (none made), over their largest impulse: the sweeps' measure on them,
 * with the full velocity (outside any group) */
static double rigid_residual(const ssModel *m, ssData *d, ssContact *const *cs, int n)
{
  double dmax = 0, lmax = 0;
  for (int i = 0; i < n; i++) {
    ssContact *c = cs[i];
    double v[3] = {0, 0, 0}, v0[3], old[3], dl[3];
    int row = c->type == SS_CONTACT_PD;
    if (row) v[0] = row_velocity(d, c);
    else contact_velocity(m, d, c, v);
    ss_m3_mulv(v0, c->G, c->lambda);
    ss_v3_sub(v0, v, v0);
    /* the law's answer taken and the impulse put back (ss_point_rigid and
     * pd_row write only the impulse) */
    memcpy(old, c->lambda, sizeof old);
    if (row) pd_row(c, v0);
    else ss_point_rigid(c, v0, m->opt.scalar_tolerance);
    ss_v3_sub(dl, c->lambda, old);
    measure_add(dl, c->lambda, &dmax, &lmax);
    memcpy(c->lambda, old, sizeof old);
  }
  return lmax > 0 ? dmax / lmax : 0;
}

/* Block B solved (block_solve, no group open) and its answer kept only
 * where it lowers B's measure (rigid_residual), its changes then into
 * the sweep's measure; else B's impulses and the velocities of the nsys
 * systems sys it moves put back.  (Systems of more than 256 velocities
 * in all keep the sweeps alone.) */
static void block_try(const ssModel *m, ssData *d, Block *B, const int *sys, int nsys,
                      double *dmax, double *lmax)
{
  Group none = {NULL, NULL, NULL, {0}, {0}, {0}};
  double keep[3 * BLOCK_MAX], u0[256];
  int nu = 0;
  for (int s = 0; s < nsys; s++) nu += m->sys_nv[sys[s]];
  if (nu > 256) return;
  for (int j = 0; j < B->n; j++) memcpy(keep + 3 * j, B->c[j]->lambda, sizeof B->c[j]->lambda);
  for (int s = 0, k = 0; s < nsys; k += m->sys_nv[sys[s]], s++)
    memcpy(u0 + k, d->qvel + m->sys_vadr[sys[s]], (size_t)m->sys_nv[sys[s]] * sizeof(double));
  double before = rigid_residual(m, d, B->c, B->n);
  if (!block_solve(m, d, B, &none)) return;
  double after = rigid_residual(m, d, B->c, B->n);
  if (!(after < before)) {
    for (int j = 0; j < B->n; j++) memcpy(B->c[j]->lambda, keep + 3 * j, sizeof B->c[j]->lambda);
    for (int s = 0, k = 0; s < nsys; k += m->sys_nv[sys[s]], s++)
      memcpy(d->qvel + m->sys_vadr[sys[s]], u0 + k, (size_t)m->sys_nv[sys[s]] * sizeof(double));
    return;
  }
  for (int j = 0; j < B->n; j++) {
    double dl[3];
    ss_v3_sub(dl, B->c[j]->lambda, keep + 3 * j);
    measure_add(dl, B->c[j]->lambda, dmax, lmax);
  }
}

/* Every SYSTEM_EVERY sweeps, after the sweep: each articulated system's
 * rigid contacts on more than one collider solved together (block_solve,
 * the links' responses to one another from the factors, ss_art_link_pair),
 * those that carry load or lie within 0.1 mm of their support, with its PD
 * rows within their effort bounds (below); the answer
 * kept only where it lowers their measure (rigid_residual), else the
 * impulses and velocities put back.  The collider blocks settle each wheel
 * or foot; what stays slow is their coupling through the body they hold
 * (a wheel's load and the chassis' roll), which this solves at once.
 * Measured on buggy_rigid.xml (tolerance 1e-9), straight, steps 1001-2000:
 * collider blocks alone 42 sweeps a step, with this after every sweep 5.5,
 * every second 7.2, every fourth 9.3, every eighth 15; 0.36 s for 2000
 * steps alone, 0.20-0.24 s with it.  Turning (rack at 3 cm), steps
 * 2001-6000: alone 39 sweeps a step and 179 capped, 1.01 s for 6000 steps;
 * every sweep 14.5 and 117 capped, 1.90 s; every fourth 18.5 and 117, 1.05
 * s.  Its rounds cost what its sweeps save only at the fourth.  Without the
 * measure's check it took 147 sweeps a step over the first 500 steps
 * (states cycling between its answer and the passes').  Since block_solve
 * picks its corrections by violation: turning, every second sweep 8.9
 * sweeps a step and 24 capped, every fourth 11.1 and 23, every eighth 16.0
 * and 22, each about 0.6 s for 6000 steps.  The system's PD rows within
 * their effort bounds join it (block_row_responses): a driven wheel's
 * spin and the steering rack are held by them and by the contacts at
 * once, and alternating between the two took most of the sweeps left.
 * With them, every fourth sweep: straight (steps 21-2000) 5.1 sweeps a
 * step against 9.5, 0.17 s against 0.22 s; turning 7.3 against 11.1 and
 * 36 capped against 23, 0.45 s against 0.53 s; the rack at 1, 2 or 4 cm
 * left or 3 cm right (steps 1001-5000) 5.6 to 6.8 against 10.3 to 10.9,
 * 8 to 29 capped against 4 to 24, a fifth quicker.  Every second sweep:
 * straight 3.1, turning 4.5 and 24 capped, the other racks 3.6 to 4.3
 * and 10 to 21, the same times or a little less (the benchmark, straight:
 * 0.042 ms a step against 0.048); every sweep 2.3, 3.8 and 23, 3.2 to 3.5
 * and 10 to 16, a quarter slower; every third or eighth, more sweeps and
 * no quicker. */
enum { SYSTEM_EVERY = 2 };

static void system_blocks(const ssModel *m, ssData *d, int first_row, double *dmax,
                          double *lmax)
{
  for (int i = 0; i < first_row;) {
    ssContact *c = d->contact + i;
    if (c->type != SS_CONTACT_RIGID || c->link < 0) {
      i++;
      continue;
    }
    Block B;
    int sys = c->sys, ngeom = 0, lastg = -1, k = i;
    B.n = 0;
    B.island = 0;
    for (; k < first_row; k++) {
      ssContact *e = d->contact + k;
      if (e->sys != sys) break;
      if (e->type != SS_CONTACT_RIGID) continue;
      if (e->lambda[0] == 0 && e->g0 > 1e-4) continue;
      if (B.n == BLOCK_MAX) {
        B.n = 0;
        break;
      }
      B.c[B.n++] = e;
      if (e->geom != lastg) ngeom++;
      lastg = e->geom;
    }
    i = k > i ? k : i + 1;
    if (!B.n || ngeom < 2) continue;
    /* and its PD rows within their bounds (rows come last) */
    for (int r = first_row; r < d->ncontact && B.n < BLOCK_MAX; r++) {
      ssContact *e = d->contact + r;
      if (e->type == SS_CONTACT_PD && e->sys == sys && fabs(e->lambda[0]) < e->row_bound)
        B.c[B.n++] = e;
    }
    /* (a system of more than 256 dofs keeps the collider blocks alone) */
    block_try(m, d, &B, &sys, 1, dmax, lmax);
  }
}

/* Every SYSTEM_EVERY sweeps, after the sweep (with system_blocks): the
 * contacts of each island of free bodies that pair contacts join (a box
 * on a box on the ground, a ball against a cylinder on a slope) solved
 * together as one block, as system_blocks solves an articulated
 * system's: their rigid contacts and the pair contacts between them, those
 * that carry load or lie within 0.1 mm; the answer kept only where it
 * lowers their measure.  The collider blocks settle each body on its
 * supports and each pair's contacts; what stays slow is the load passed
 * along the chain of bodies, which Gauss-Seidel moves a step a sweep.
 * An island of more than ISLAND_BODIES bodies or BLOCK_MAX such contacts
 * keeps the sweeps alone; so does one that holds a link. */
enum { ISLAND_BODIES = 8, ISLAND_PAIRS = 64 };

static int in_list(const int *v, int n, int x)
{
  for (int k = 0; k < n; k++)
    if (v[k] == x) return 1;
  return 0;
}

static void island_blocks(const ssModel *m, ssData *d, int first_row, double *dmax,
                          double *lmax)
{
  int done[ISLAND_PAIRS], ndone = 0;
  for (int i = 0; i < first_row; i++) {
    ssContact *c = d->contact + i;
    if (c->type != SS_CONTACT_PAIR || c->link >= 0 || c->link2 >= 0 || in_list(done, ndone, i))
      continue;
    /* the island: the bodies (systems) pair contacts join to c's */
    int sys[ISLAND_BODIES] = {c->sys, c->sys2}, nsys = 2, grown = 1, whole = 1;
    while (grown && whole) {
      grown = 0;
      for (int k = 0; k < first_row && whole; k++) {
        const ssContact *e = d->contact + k;
        if (e->type != SS_CONTACT_PAIR) continue;
        int a = in_list(sys, nsys, e->sys), b = in_list(sys, nsys, e->sys2);
        if (a == b) continue;
        if (e->link >= 0 || e->link2 >= 0 || nsys == ISLAND_BODIES) {
          whole = 0;
          break;
        }
        sys[nsys++] = a ? e->sys2 : e->sys;
        grown = 1;
      }
    }
    /* its contacts: the bodies' rigid contacts, the pairs between them */
    Block B;
    B.n = 0;
    B.island = 1;
    for (int k = 0; k < first_row && whole; k++) {
      ssContact *e = d->contact + k;
      int in = e->type == SS_CONTACT_PAIR ? in_list(sys, nsys, e->sys)
               : e->type == SS_CONTACT_RIGID ? e->link < 0 && in_list(sys, nsys, e->sys)
                                             : 0;
      if (!in) continue;
      if (e->type == SS_CONTACT_PAIR && ndone < ISLAND_PAIRS) done[ndone++] = k;
      if (e->lambda[0] == 0 && e->g0 > 1e-4) continue;
      if (B.n == BLOCK_MAX) whole = 0;
      else B.c[B.n++] = e;
    }
    if (!whole || B.n < 2) continue;
    block_try(m, d, &B, sys, nsys, dmax, lmax);
  }
}

static void rigid_block(const ssModel *m, ssData *d, int lo, int hi, int back, Group *g,
                        double *dmax, double *lmax)
{
  const double tol = m->opt.solver_tolerance;
  Block B;
  B.island = 0;
  B.n = hi - lo + 1 <= BLOCK_MAX ? hi - lo + 1 : 0;
  for (int i = 0; i < B.n; i++) B.c[i] = d->contact + lo + i;
  visit_span(m, d, lo, hi, back, g, dmax, lmax);
  for (int pass = 1; pass < RIGID_PASSES; pass++) {
    if (pass <= BLOCK_TRIES && B.n) block_solve(m, d, &B, g);
    double dm = 0, lm = 0;
    back = !back;
    visit_span(m, d, lo, hi, back, g, &dm, &lm);
    if (dm <= tol * lm) break;
  }
}

/* Visits contacts i..end (a piece of a link's run, or a free body's rigid
 * contacts on one collider), backwards where back is set; its rigid
 * contacts by collider as blocks (rigid_block) */
static void visit_piece(const ssModel *m, ssData *d, int i, int end, int back, Group *g,
                        double *dmax, double *lmax)
{
  for (int n = 0; n <= end - i;) {
    int k = back ? end - n : i + n, lo = k, hi = k;
    ssContact *c = d->contact + k;
    if (c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_PAIR) {
      /* k is the block's first contact in this direction */
      if (back)
        while (lo > i && same_block(c, d->contact + lo - 1)) lo--;
      else
        while (hi < end && same_block(c, d->contact + hi + 1)) hi++;
    }
    if (hi > lo) rigid_block(m, d, lo, hi, back, g, dmax, lmax);
    else visit(m, d, c, g, dmax, lmax);
    n += hi - lo + 1;
  }
}

/* The creeping solve (ss_newton_creep) for a step the Newton phase and
 * its first sweeps leave unconverged, where the contacts suit it.  Every
 * CREEP_EVERY sweeps the sweeps' rate over the last CREEP_EVERY, rho =
 * (r / r_before)^(1/CREEP_EVERY), says how many more they need to reach
 * the tolerance, log(tol / r) / log(rho); where that is more than
 * CREEP_WORTH (or the residual did not fall), the creeping solve moves
 * them on to its answer, which the next sweep checks.  Its pass over the
 * points costs about a third of a sweep of an articulated link's points
 * and one of a free body's, and it takes 60 to 200 of them: a step that
 * the sweeps settle in a few tens more is left to them.  At most
 * CREEP_TRIES a step: one that fails twice (a soil so stiff that its
 * laws turn rounding into their answer) is left to the sweeps, at their
 * cost alone. */
enum { CREEP_EVERY = 10, CREEP_WORTH = 40, CREEP_TRIES = 2 };

static int creep_due(double r, double r_before, double tol)
{
  if (!(r < r_before) || !(r_before > 0)) return 1;
  double rho_log = log(r / r_before) / CREEP_EVERY;
  return log(tol / r) / rho_log > CREEP_WORTH;
}

ssStatus ss_solver_solve(const ssModel *m, ssData *d, ssError *err)
{
  const double dt = m->opt.timestep, tol = m->opt.solver_tolerance;
  ssStepStats *st = &d->stats;
  st->sweeps = 0;
  st->residual = 0;
  int converged = st->converged; /* the previous step's */
  st->converged = 1;
  st->newton = 0;
  st->newton_sticking = 0;
  st->newton_linear = 0;
  st->creep = 0;
  d->solver_settled = 0;
  d->newton_rec[2].step = -1;
  if (m->nv) memcpy(d->qvel_free, d->qvel, (size_t)m->nv * sizeof(double));
  int left = warm_start(m, d, converged, 0);

  /* joint rows (PD, limits) are few, stiff and coupled to everything:
   * they are revisited after every piece of a link run (PIECE) and every
   * 64 other contacts, a cheap stand-in for a block solve that keeps the
   * sweep count low */
  int first_row = d->ncontact;
  while (first_row > 0 && (d->contact[first_row - 1].type == SS_CONTACT_PD ||
                           d->contact[first_row - 1].type == SS_CONTACT_LIMIT))
    first_row--;
  int rows = first_row < d->ncontact;

  int pack = !d->solver_full;

  /* Newton on the contact links' velocities, where it applies: its answer
   * stands when its check meets the tolerance, else the sweeps go on from
   * it */
  int sweeps = d->ncontact ? m->opt.solver_max_sweeps : 0;
  if (!d->solver_gs_only) {
    double res;
    int done = ss_newton_solve(m, d, first_row, &st->newton, &st->newton_sticking, &res);
    int ok = done && res <= tol;
    if (!done && left) {
      /* declined from the creeping colliders' last tractions: again from
       * their extrapolation (CREEP_SLIP).  (An answer that only missed
       * the check is kept: the sweeps finish it.) */
      int it = st->newton;
      if (m->nv) memcpy(d->qvel, d->qvel_free, (size_t)m->nv * sizeof(double));
      warm_start(m, d, converged, 1);
      done = ss_newton_solve(m, d, first_row, &st->newton, &st->newton_sticking, &res);
      ok = done && res <= tol;
      st->newton += it;
    }
    if (ok) {
      st->residual = res;
      sweeps = 0;
      d->solver_settled = done == 2;
    }
  }
  /* the sweeps start from the warm start, or from the Newton phase's
   * answer (which left nothing pending) */
  ss_solver_warm_apply(m, d);

  /* what only the sweeps use: the runs of contacts on one link (packed
   * groups), the body contacts' responses (a rigid body's J, W and G, a
   * link contact's X, LX and G), and the soil points' laws (the Newton
   * phase has its own) */
  for (int i = first_row - 1; i >= 0 && sweeps > 0; i--) {
    ssContact *c = d->contact + i;
    c->run = 1;
    /* (a pair contact is visited alone: it moves two bodies) */
    if (c->link >= 0 && i + 1 < first_row && c[1].link == c->link &&
        c->type != SS_CONTACT_PAIR && c[1].type != SS_CONTACT_PAIR)
      c->run += c[1].run;
  }
  int link_rigid = 0; /* rigid contacts on articulated links (system_blocks) */
  int free_pairs = 0; /* pair contacts between free bodies (island_blocks) */
  for (int i = 0; i < d->ncontact && sweeps > 0; i++) {
    ssContact *c = d->contact + i;
    double *J = d->jac + c->jadr;
    link_rigid |= c->type == SS_CONTACT_RIGID && c->link >= 0;
    free_pairs |= c->type == SS_CONTACT_PAIR && c->link < 0 && c->link2 < 0;
    if (c->type == SS_CONTACT_PAIR) {
      /* each body's rows and response; G their sum (the second body
       * takes -lambda and its velocity counts negative) */
      double G2[9];
      side_rows(m, d, c, c->link, c->sys, c->geom, c->nv, J, c->G);
      side_rows(m, d, c, c->link2, c->sys2, c->geom2, c->nv2, d->jac + c->jadr2, G2);
      for (int k = 0; k < 9; k++) c->G[k] += G2[k];
    } else if (c->link >= 0 ||
               (c->nv > 0 && (c->type == SS_CONTACT_SOIL || c->type == SS_CONTACT_RIGID))) {
      side_rows(m, d, c, c->link, c->sys, c->geom, c->nv, J, c->G);
    }
    if (c->type == SS_CONTACT_SOIL)
      ss_point_setup(&m->hfield_soilmat[c->hfield], ss_solver_pow_table(m, d, c->hfield), dt, c);
  }
  Group g = {NULL, NULL, NULL, {0}, {0}, {0}};
  double r_before = 0; /* the residual CREEP_EVERY sweeps before */
  int creep_tries = 0;
  for (int sweep = 0; sweep < sweeps; sweep++) {
    double dmax = 0, lmax = 0;
    int since = 0, pending = 1;
    for (int i = 0; i < first_row;) {
      ssContact *c = d->contact + i;
      int end = i;
      if (c->link >= 0 && c->run >= MIN_GROUP) {
        /* a run in balanced pieces of at most PIECE contacts (c->run
         * counts the run's contacts from c on, so later pieces divide
         * what is left the same way) */
        int pieces = rows ? (c->run + PIECE - 1) / PIECE : 1;
        end = i + (c->run + pieces - 1) / pieces - 1;
      } else if (c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_PAIR) {
        /* a free body's rigid contacts on one collider, or the pair
         * contacts of two colliders: one block */
        while (end + 1 < first_row && same_block(c, d->contact + end + 1)) end++;
      }
      if (end > i) {
        /* (a pair's block moves two bodies: never in a link's group) */
        if (pack && c->link >= 0 && c->type != SS_CONTACT_PAIR) group_open(m, d, &g, c);
        /* symmetric Gauss-Seidel within a piece: every other sweep visits
         * it backwards, so a correction travels across the contact patch
         * both ways; the same order packed or not */
        visit_piece(m, d, i, end, sweep & 1, &g, &dmax, &lmax);
        group_close(d, &g);
      } else {
        visit(m, d, c, &g, &dmax, &lmax);
      }
      since += end - i + 1;
      pending = 1;
      /* the joint rows after every piece of a run and every 64 other
       * contacts */
      if (rows && (end > i || since >= 64)) {
        for (int r = first_row; r < d->ncontact; r++)
          visit(m, d, d->contact + r, &g, &dmax, &lmax);
        since = pending = 0;
      }
      i = end + 1;
    }
    if (pending)
      for (int r = first_row; r < d->ncontact; r++)
        visit(m, d, d->contact + r, &g, &dmax, &lmax);
    group_close(d, &g);
    if (link_rigid && sweep % SYSTEM_EVERY == SYSTEM_EVERY - 1)
      system_blocks(m, d, first_row, &dmax, &lmax);
    if (free_pairs && sweep % SYSTEM_EVERY == SYSTEM_EVERY - 1)
      island_blocks(m, d, first_row, &dmax, &lmax);
    st->sweeps = sweep + 1;
    st->residual = lmax > 0 ? dmax / lmax : 0;
    if (st->residual <= tol) break;
    /* the sweeps crawl: the creeping solve, where it applies */
    if ((sweep + 1) % CREEP_EVERY == 0 && !d->solver_gs_only && creep_tries < CREEP_TRIES) {
      if (sweep + 1 > CREEP_EVERY && creep_due(st->residual, r_before, tol)) {
        int passes = 0;
        creep_tries++;
        ss_newton_creep(m, d, first_row, tol, &passes);
        st->creep += passes;
        st->newton += passes;
      }
      r_before = st->residual;
    }
  }
  st->converged = st->residual <= tol;

  /* end-of-step contact velocities for the soil update */
  /* (no contacts: the array may not exist yet, and no arithmetic on its
   * NULL) */
  const ssContact *end = d->ncontact ? d->contact + d->ncontact : d->contact;
  for (ssContact *c = d->contact; c < end;) {
    double v[3] = {0, 0, 0};
    if (c->type == SS_CONTACT_PAIR) {
      pair_velocity(m, d, c, v);
      contact_end(c, v, dt);
      c++;
      continue;
    }
    if (c->link >= 0) {
      /* one spatial velocity per link run */
      c = link_run_end(m, d, c, end);
      continue;
    } else if (c->nv) {
      if (c->type == SS_CONTACT_SOIL) {
        /* a rigid body's soil points, as one run */
        c = body_run_end(m, d, c, end);
        continue;
      }
      if (c->type == SS_CONTACT_PD || c->type == SS_CONTACT_LIMIT)
        /* a joint row's one row, as its visits take it (row_velocity),
         * instead of J u's three sums over every velocity: its other
         * rows are zero, and the sums gave the same up to the sign of a
         * zero (or which NaN, where u is not finite); no reader takes a
         * row's v (the soil update and the cache read soil points') */
        v[0] = row_velocity(d, c);
      else
        contact_velocity(m, d, c, v);
    }
    contact_end(c, v, dt);
    c++;
  }
  return SS_OK;
}

/* ---------------------------------------------------------------------- */
/* the push out of penetrations                                            */

/* The push's sweeps: its answer moves positions only, by rigid_erp of a
 * penetration, so a relative change of 1e-6 is far below what anyone
 * sees (a micrometre of a metre's penetration); the cap bounds a step
 * whose rigid contacts couple stiffly (a vehicle's wheels through its
 * suspension), where the push is then partly made and the next step's
 * makes the rest. */
enum { PUSH_SWEEPS = 50 };
#define PUSH_TOL 1e-6
/* The fastest a penetration is pushed out (m/s, or rad/s for a revolute
 * joint past its limit), Box2D's default contactPushMaxVelocity: a deep
 * one is moved out over many steps, never in one.  Unbounded, a buggy
 * started 5 m under a ground plane took rigid_erp of it in one step
 * (1000 m/s), which moved its wheels through their suspension's travel
 * before any joint limit had a row to hold them, and its linkage threw
 * it upwards at 2000 m/s^2. */
#define PUSH_SPEED_MAX 3.0

/* (solver.h) */
int ss_solver_push(const ssModel *m, ssData *d)
{
  /* (none penetrating: nothing to look at, as most steps on soil) */
  if (!d->contact_deep) return 0;
  /* a moving system's rigid contacts and joint limits, any of them
   * penetrating */
  int n = 0, deep = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    if ((c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_PAIR ||
         c->type == SS_CONTACT_LIMIT) && c->nv > 0) {
      n++;
      deep |= c->g0 < 0;
    }
  }
  if (!deep) return 0;
  int *idx = malloc((size_t)n * sizeof *idx);
  double *p = calloc((size_t)n, sizeof *p);
  if (!idx || !p) {
    free(idx);
    free(p);
    return -1;
  }
  n = 0;
  for (int i = 0; i < d->ncontact; i++) {
    const ssContact *c = d->contact + i;
    if ((c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_PAIR ||
         c->type == SS_CONTACT_LIMIT) && c->nv > 0)
      idx[n++] = i;
  }
  /* the sweeps on a velocity of their own, from rest: d->qvel holds the
   * push while they run, the step's velocity waits in qvel_push */
  const size_t nv = (size_t)m->nv;
  memcpy(d->qvel_push, d->qvel, nv * sizeof(double));
  memset(d->qvel, 0, nv * sizeof(double));
  const double erp_dt = m->opt.rigid_erp / m->opt.timestep;
  for (int sweep = 0; sweep < PUSH_SWEEPS; sweep++) {
    double dmax = 0, lmax = 0;
    for (int k = 0; k < n; k++) {
      ssContact *c = d->contact + idx[k];
      if (!(c->G[0] > 0)) continue;
      double v[3];
      if (c->type == SS_CONTACT_LIMIT)
        v[0] = row_velocity(d, c);
      else
        contact_velocity(m, d, c, v);
      /* out by rigid_erp of the penetration; a contact not penetrating
       * is not pushed into its support */
      double target = c->g0 < 0 ? -erp_dt * c->g0 : 0;
      if (target > PUSH_SPEED_MAX) target = PUSH_SPEED_MAX;
      double pn = p[k] + (target - v[0]) / c->G[0];
      if (!(pn > 0)) pn = 0;
      double dl[3] = {pn - p[k], 0, 0};
      p[k] = pn;
      if (dl[0] != 0) apply_impulse(m, d, c, dl);
      dmax = fabs(dl[0]) > dmax ? fabs(dl[0]) : dmax;
      lmax = pn > lmax ? pn : lmax;
    }
    if (!(dmax > PUSH_TOL * lmax)) break;
  }
  /* the push into qvel_push, the step's velocity back */
  for (size_t k = 0; k < nv; k++) {
    double t = d->qvel[k];
    d->qvel[k] = d->qvel_push[k];
    d->qvel_push[k] = t;
  }
  free(idx);
  free(p);
  return 1;
}

/* the soil beds' tables of powers (solver.h) */
void ss_solver_pow_tables(const ssModel *m, ssData *d)
{
  for (int h = 0; h < m->nhfield; h++) {
    double a = m->hfield_soilmat[h].sinkage_exponent - 1;
    ssPowTable *t = d->hfield_pow + h;
    if (m->hfield_soil[h] && a != 0 && t->ser.a != a)
      ss_pow_table_init(t, a);
  }
}

const ssPowTable *ss_solver_pow_table(const ssModel *m, const ssData *d, int h)
{
  const ssPowTable *t = d->hfield_pow + h;
  double a = m->hfield_soilmat[h].sinkage_exponent - 1;
  return t->ok && t->ser.a == a ? t : NULL;
}
