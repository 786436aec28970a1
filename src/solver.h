/* solver.h -- per-contact Gauss-Seidel on the impulse-response blocks.
 *
 * Every contact couples one dynamic system (or none, for static bodies) to
 * a static support (a soil bed, a rigid height map, a ground plane).  A
 * contact carries its Jacobian J (3 x nv of its system, rows = contact
 * frame n, t1, t2) and W = M^-1 J^T (nv x 3), so the velocity response to
 * an impulse is J W; single rigid bodies and joint rows store J and W.  A
 * contact on an articulated link stores only its spatial rows X (3 x 6):
 * its Jacobian is X J_b and its response Y_b X^T, with the link's block
 * Y_b = P M'^-1 J_b^T (nv x 6, loop closures eliminated) and
 * Lam_b = J_b Y_b (6 x 6) computed once per step per link; beside X it
 * keeps LX (3 x 6, row i = Lam_b X_i^T).  A run of consecutive
 * contacts on one link is swept as a packed group: the link's spatial
 * velocity V = J_b u is updated by Lam_b X^T dl = LX^T dl after each visit
 * (exact block Gauss-Seidel, every other contact held) and the group's
 * accumulated spatial impulse reaches u (Y_b F) once, when the group
 * ends. */
#ifndef SS_SOLVER_H
#define SS_SOLVER_H

#include "soilsim.h"
#include "point.h"

#include <limits.h>
#include <stddef.h>
#include <string.h>

typedef enum ssContactType {
  SS_CONTACT_SOIL = 0, /* one soil quadrature point (DESIGN 3.1) */
  SS_CONTACT_RIGID,    /* Coulomb cone with restitution */
  SS_CONTACT_PD,       /* joint PD controller: one bounded implicit row */
  SS_CONTACT_LIMIT,    /* joint limit: one unilateral row */
  SS_CONTACT_PAIR      /* Coulomb cone between two moving bodies: the
                          first (geom, sys, link, ...) takes lambda, the
                          second (geom2, sys2, link2, ...) -lambda; the
                          frame's normal points from the second into the
                          first */
} ssContactType;

struct ssContact {
  int type;          /* ssContactType */
  int sys;           /* dynamic system, -1 if the body is static */
  int geom;          /* collider */
  int hfield;        /* bed or rigid height map; -1 for a ground plane */
  int vertex;        /* soil: absolute index into the soil arrays; rigid:
                        its cache key (ss_rigid_feature) */
  int vadr, nv;      /* the system's velocity block */
  int link;          /* articulated link whose block serves the contact, or
                        -1 (J and W stored) */
  int run;           /* solver: contacts from this one on the same link */
  int warm_entry;    /* index of its warm-start cache entry in d->warm, -1
                        none: set where the warm start's impulses wait
                        for ss_solver_warm_apply (d->warm_pending) */
  long jadr, jlen;   /* offset and length in ssData.jac: J (3 nv) then
                        W (nv x 3), or X (3 x 6) for a link contact */
  double area;       /* soil: quadrature weight A (m^2) */
  double width;      /* soil: effective width b (m) */
  double g0;         /* separation along n at the step start (m, > 0 above) */
  double sp, j;      /* soil: plastic sinkage and shear before the step */
  double lambda[3];  /* impulse in the contact frame (N s) */
  double mu;         /* rigid: friction coefficient */
  double vn_target;  /* rigid: lowest allowed normal velocity (m/s) */
  double row_a, row_b;/* PD: impulse = row_a - row_b v (before clamping) */
  double row_bound;  /* PD: |impulse| <= row_bound (effort dt) */
  int dof;           /* PD, limit: global velocity index */
  int loaded;        /* soil: 1 if the point carries load at the end */
  int warm_trend;    /* soil: 1 when warm_t is a converged step's traction,
                        so that this step's change can be formed */
  int cache_ready;   /* soil: cache holds a set-up law (ss_point_setup); 0:
                        empty, whatever its bytes */
  int w_ready;       /* joint row: its W formed (ss_art_dof_response, at
                        its first use); 0: not yet */
  int bed_axes;      /* soil: frame is an unturned bed's (rows z, x, y,
                        exactly), so products by it are permutations
                        (ss_contact_frame_mulv, _tmulv); 0: any frame */
  /* From here on ss_contact_new leaves the fields as they were (it zeroes
   * those above): each is written before it is read.  pos and frame: by
   * the soil and rigid contacts' creators, and read only for those
   * contacts; G: by the sweeps' set-up (soil and rigid contacts of moving
   * bodies), by attach (terrain.c) for a static body's, by the joint rows'
   * creators; v: by the solve's end, for every contact; warm_t: by the
   * warm start, and read only where warm_trend says it was; cache: by
   * ss_point_setup, read only where cache_ready says it was; the second
   * body's fields: by a pair contact's creator, read only for those. */
  double pos[3];     /* contact point, world */
  double frame[9];   /* rows n, t1, t2 (world); n = bed +z / surface normal */
  double G[9];       /* impulse response J W (3 x 3) */
  double v[3];       /* contact-frame velocity at the end of the solve */
  double warm_t[3];  /* soil: the cached traction its warm start came from */
  ssPointCache cache;/* soil: the point solve's law and reused values
                        (empty while cache_ready is 0) */
  /* a pair contact's second body, written by its creator and read only
   * for SS_CONTACT_PAIR: its collider, system, velocity block, link (-1:
   * a free body) and Jacobian storage, which follows the first body's in
   * ssData.jac (jadr2 = jadr + the first's length; jlen covers both) */
  int geom2, sys2, vadr2, nv2, link2;
  long jadr2;
};

/* A cached traction from the previous step (warm start).  The next step
 * starts a soil point from traction + rate, the traction extrapolated
 * linearly over one step, scaled and projected into the current bounds.
 * The rate is the traction's change over the last step, kept only where
 * both tractions are converged solutions (the point was matched, and the
 * steps that made them both converged) and the change exceeds the solver
 * tolerance times the traction (1-norms); otherwise 0.  A change of
 * unconverged tractions is mostly solver error, and extrapolating it feeds
 * that error back step after step; a change within the tolerance (a
 * settled body's drift) is no trend either, and extrapolating it costs
 * the point solves an iteration.  A creeping collider's entries keep their
 * rates but are marked (creep; solver.c, CREEP_SLIP): its tractions follow
 * slip directions that turn with velocities of 1e-5 m/s and less, and the
 * warm start extrapolates them only where the Newton phase fails without. */
struct ssWarmEntry {
  int vertex;        /* absolute soil vertex; rigid contacts: their key
                        (ss_rigid_feature, < 0); joint rows: see row_key */
  int geom;
  int creep;         /* 1: its collider crept (solver.c, CREEP_SLIP) and
                        its rate is not 0: the warm start leaves the rate
                        out, unless the Newton phase fails without */
  double traction[3];/* impulse / (area dt), contact frame (Pa); rigid
                        contacts: impulse / dt (N); joint rows: impulse /
                        dt in traction[0] */
  double rate[3];    /* traction change over the last step (Pa); 0 for
                        rigid contacts and rows */
  uint64_t key;      /* the cache's order as one number, from geom and
                        vertex (ss_solver_warm_key), kept for the look-ups
                        and the sort */
};

/* A rigid contact's key in the warm-start cache, in place of a soil
 * vertex: its support s (rigid height map h, ground plane nhfield + p, or
 * another collider nhfield + nplane + g: a static body's, or a pair
 * contact's second body's)
 * and its collider's candidate point k (ss_shape_candidates' order, k <
 * SS_RIGID_CANDIDATES) as INT_MIN + s SS_RIGID_CANDIDATES + k: negative,
 * so never a soil vertex, and ascending in the order a collider's rigid
 * contacts are made.  A candidate is a feature of the collider (a box's
 * corner, a cylinder's lowest rim point at either end or one of its cap
 * points), so its impulse carries over from step to step as a body rests,
 * slides or rolls on its support.  (s < 2^26 - 1: the model's limits on
 * height maps and ground planes keep it there.) */
#define SS_RIGID_CANDIDATES 32
static inline int ss_rigid_feature(int support, int k)
{
  return INT_MIN + support * SS_RIGID_CANDIDATES + k;
}
/* the support and candidate of a rigid contact's key (vertex < 0) */
static inline void ss_rigid_feature_split(int vertex, int *support, int *k)
{
  unsigned u = (unsigned)vertex - 0x80000000u;
  *support = (int)(u / SS_RIGID_CANDIDATES);
  *k = (int)(u % SS_RIGID_CANDIDATES);
}

/* The warm-start cache's order (<0, 0, >0): by collider, then vertex,
 * the joint rows last; checkpoints hold the cache in it (checkpoint.c
 * checks a file's entries with it). */
int ss_solver_warm_cmp(const ssWarmEntry *a, const ssWarmEntry *b);
/* Sets e->key from e->geom and e->vertex: wherever an entry is made (the
 * cache's store, a checkpoint's restore). */
void ss_solver_warm_key(ssWarmEntry *e);

/* Room for one more contact (zeroed up to pos, see ssContact, so its point
 * cache empty; link = -1)
 * with njac doubles of Jacobian storage in d->jac (6 nv for J and W, 36
 * for a link contact's X and LX); NULL when out of memory. */
ssContact *ss_contact_new(ssData *d, long njac);
/* The same in two parts, for a loop that makes many: room for count more
 * contacts of njac doubles each (0 when out of memory), then each one
 * taken without a check (ss_contact_add, at most count of them). */
int ss_contact_reserve(ssData *d, int count, long njac);
extern const ssContact ss_contact_blank;
/* end of the Jacobian storage in use */
static inline long ss_contact_jac_end(const ssData *d)
{
  return d->ncontact ? d->contact[d->ncontact - 1].jadr + d->contact[d->ncontact - 1].jlen : 0;
}
/* v = frame w and f = frame^T l of contact c: on an unturned bed's axes
 * (bed_axes) the permutations themselves, the same values as the products
 * by the frame's ones and zeros (up to the sign of a zero) */
static inline void ss_contact_frame_mulv(const ssContact *c, double v[3], const double w[3])
{
  if (c->bed_axes) {
    v[0] = w[2];
    v[1] = w[0];
    v[2] = w[1];
    return;
  }
  ss_m3_mulv(v, c->frame, w);
}
static inline void ss_contact_frame_tmulv(const ssContact *c, double f[3], const double l[3])
{
  if (c->bed_axes) {
    f[0] = l[1];
    f[1] = l[2];
    f[2] = l[0];
    return;
  }
  ss_m3_mulvT(f, c->frame, l);
}

static inline ssContact *ss_contact_add(ssData *d, long njac)
{
  ssContact *c = d->contact + d->ncontact;
  long jadr = ss_contact_jac_end(d);
  memcpy(c, &ss_contact_blank, offsetof(ssContact, pos));
  c->jadr = jadr;
  c->jlen = njac;
  d->ncontact++;
  return c;
}

/* ss_contact_add for a loop that makes many soil points of one collider:
 * the head copied from the caller's template (ss_contact_blank's with the
 * fields they share set once: type, collider, system, link, jlen, ...)
 * but for the soil quantities area, width, g0, sp and j, which the caller
 * sets (copied, they would be stored twice), the Jacobian storage at jadr
 * (the caller's running ss_contact_jac_end, each contact's jlen on).
 * Room as for ss_contact_add (ss_contact_reserve). */
/* (the five lie together, just before lambda) */
_Static_assert(offsetof(ssContact, lambda) - offsetof(ssContact, area) == 5 * sizeof(double),
               "ss_contact_add_head skips area, width, g0, sp and j as one block");
static inline ssContact *ss_contact_add_head(ssData *d, const ssContact *head, long jadr)
{
  ssContact *c = d->contact + d->ncontact;
  memcpy(c, head, offsetof(ssContact, area));
  memcpy(c->lambda, head->lambda, offsetof(ssContact, pos) - offsetof(ssContact, lambda));
  c->jadr = jadr;
  d->ncontact++;
  return c;
}

/* Solve all contacts in d->contact; d->qvel holds the free velocity on entry
 * and the end-of-step velocity on return.  Fills d->stats.  The warm-start
 * cache is not touched: ss_solver_store_warm keeps this step's tractions
 * once the step has passed its checks. */
ssStatus ss_solver_solve(const ssModel *m, ssData *d, ssError *err);
/* The warm start's impulses into the contacts and their velocity change
 * into d->qvel, where they are still pending (d->warm_pending): where the
 * Newton phase may start from its prediction (ss_newton_may_predict), the
 * solve matches the cache first and applies the impulses only where a
 * solve starts from them after all; the prediction's answer replaces
 * both. */
void ss_solver_warm_apply(const ssModel *m, ssData *d);
/* Contact i's warm-start impulse, applied yet or not (the Newton phase's
 * points that stick at its start take their tangential impulses from it) */
void ss_solver_warm_lambda(const ssModel *m, const ssData *d, int i, double lam[3]);
ssStatus ss_solver_store_warm(const ssModel *m, ssData *d, ssError *err);
/* The push out of penetrations (split impulse), after the solve: the
 * velocity that moves the solve's rigid contacts and joint limits out of
 * their supports by rigid_erp of their penetration in one step (and no
 * other of them in), found by sweeps of normal impulses on a velocity of
 * its own, from rest, into d->qvel_push; d->qvel is left as the solve
 * left it.  The step moves the positions by d->qvel + d->qvel_push, and
 * the push (at most 3 m/s at a contact) leaves no velocity behind: a body
 * started inside the ground is moved out over a few steps instead of
 * being thrown from it (the
 * solve itself only stops a penetrating contact, and bounces it by its
 * restitution).  Returns 1 with a push, 0 where nothing penetrates
 * (qvel_push untouched), -1 out of memory (d->qvel as it was). */
int ss_solver_push(const ssModel *m, ssData *d);

/* The Newton phase (newton.c): when every contact is a soil point on an
 * articulated link or a PD row and every loaded point slips, solve the
 * step's contacts by Newton's method on the contact links' spatial
 * velocities and the rows' velocities.  On entry d->qvel_free holds the
 * free velocity, the contacts their first impulses and d->qvel the matching
 * velocity, or, with d->warm_pending, the warm start waits to be applied
 * (ss_solver_warm_apply: the phase applies it where it starts from it,
 * not where it starts from its prediction); contacts [first_row,
 * ncontact) are the joint rows.  Returns 1 when Newton converged: the
 * contacts hold its impulses, d->qvel their velocity, and *residual the
 * check of that answer against every contact's law at that velocity (the
 * sweeps' measure: max |change| / max |impulse|); 2 when the first
 * impulses passed that check as they came (a settled body: contacts and
 * d->qvel untouched); 0 when it declined: everything as on entry (the
 * warm start perhaps applied), unless an answer it applied failed its
 * check first (apply_linear's, or one at 10 tol): then the contacts hold
 * that answer and d->qvel its velocity, a consistent start for the
 * sweeps.  *iterations: the Newton iterations spent
 * either way; *sticking: the soil points it solved in impulse form
 * (sticking or nearly, newton.c). */
typedef struct ssNewtonWork ssNewtonWork;
int ss_newton_solve(const ssModel *m, ssData *d, int first_row, int *iterations,
                    int *sticking, double *residual);
/* 1 where this step's Newton phase may start from its last two answers
 * extrapolated (their records are the two steps before this one's, and
 * neither the warm start nor the prediction is switched off); whether it
 * does depends on its unknowns too (newton.c, predict) */
int ss_newton_may_predict(const ssModel *m, const ssData *d);
/* After ss_newton_solve returned 2 (and until it is called again): the
 * soil points' impulses by their laws at d->qvel, three for each of the
 * contacts before first_row (the contact frame's n, t1, t2) */
const double *ss_newton_law(const ssData *d);
/* Keep this step's answer of the Newton phase (d->newton_rec) as the start
 * of the next steps; once the step has passed its checks, with the cache
 * (ss_solver_store_warm) */
void ss_newton_keep(ssData *d);
void ss_newton_work_free(ssNewtonWork *w);

/* The creeping solve (newton.c): the step's contacts as the minimum of
 * their laws' convex potential in the Newton phase's unknowns (the shear
 * kink smoothed, the smoothing taken down to where no sweep can see it),
 * by Newton's method with a line search; its last step by the laws'
 * linear model.  For the steps the Newton phase and the first sweeps
 * leave unconverged (a creeping patch, stick and slip mixed), where the
 * contacts suit the Newton phase.  On entry the impulses and d->qvel are
 * consistent.  Returns 1 when it applied an answer (the contacts'
 * impulses, d->qvel their velocity; the sweeps then check it), 0 when
 * not (everything as it was).  *count: its passes over the points,
 * added. */
int ss_newton_creep(const ssModel *m, ssData *d, int first_row, double tol, int *count);

/* Dense LU with partial pivoting of the n x n matrix A (row-major), in
 * place, the row swaps in piv; 0 where a column has no nonzero pivot left
 * (singular).  Then x <- A^-1 x from the factors.  (newton.c: the Newton
 * phase's matrix and the rigid blocks' systems, solver.c.) */
int ss_lu_factor(double *A, int *piv, int n);
void ss_lu_solve(const double *A, const int *piv, int n, double *x);

/* Each soil bed's table of s^(n-1) (ss_math.h's ssPowTable in
 * d->hfield_pow), formed again wherever its material's exponent is not
 * the one it was formed for; before each step's contacts (step.c).  The
 * first power of every loaded point in a step (the Newton phase's first
 * evaluation, the sweeps' first visit, the soil update) comes from it
 * instead of libm's pow. */
void ss_solver_pow_tables(const ssModel *m, ssData *d);
/* bed h's table, NULL where none holds (n = 1 or beyond the series) */
const ssPowTable *ss_solver_pow_table(const ssModel *m, const ssData *d, int h);

/* The per-point soil solve (exposed for tests and benchmarks): given the
 * contact's state and the velocity v0 it would have with lambda = 0 from
 * this contact (others held), find lambda.  Returns the number of inner
 * iterations.  c->lambda is the first guess (zero: cold) and c->cache
 * the values of the last visit (zero: none); a cold start from scratch
 * zeroes both. */
int ss_solver_soil_point(const ssSoilMaterial *mat, double dt, ssContact *c,
                         const double v0[3], double tol);

#endif
