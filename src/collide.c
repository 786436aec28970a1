/* collide.c -- footprints, exact vertical ray casts, contact candidates and
 * effective widths of box, sphere, cylinder and capsule colliders, and the
 * footprints of point sets (a mesh's vertices) (DESIGN 2.4, 2.6), signed
 * distances and the contact points of two shapes.  Pure
 * functions: no allocation, no printing (one constant table, the
 * footprints' circle, is formed at first use). */
#include "collide.h"

#include <math.h>
#include <threads.h>

#include "sort_runs.h"
#include "ss_math.h"

#define SS_PI 3.14159265358979323846

/* the circle table is built from one quadrant */
_Static_assert(SS_FOOTPRINT_SEGMENTS % 4 == 0, "SS_FOOTPRINT_SEGMENTS must be a multiple of 4");

/* points fed to the hull: two caps of SS_FOOTPRINT_SEGMENTS each at most */
#define HULL_IN_MAX (2 * SS_FOOTPRINT_SEGMENTS)

/* polygons of at most this many vertices (a box's footprint) visit all
 * their edges: cheaper than searching the chains for the few near a row */
#define SMALL_POLY 16

/* room for a convex polygon clipped by four half-planes, plus slack */
#define CLIP_MAX SS_POLY_CLIP_MAX

/* relative tolerance (of the squared extent) below which three hull points
 * count as collinear: removes duplicated and near-duplicated corners */
#define HULL_COLLINEAR_EPS 1e-14

typedef struct pt2 {
  double x, y;
} pt2;

/* ---------------------------------------------------------------------- */
/* convex hull                                                             */

static int pt_less(const pt2 *a, const pt2 *b)
{
  return a->x < b->x || (a->x == b->x && a->y < b->y);
}

/* footprint points by x, then y: they come as a few monotone runs in x
 * (a circle's polygon), so the run-merging sort is nearly linear.  Points
 * equal under pt_less are equal. */
SS_SORT_RUNS(sort_point_runs, pt2, pt_less)

static double cross3(const pt2 *o, const pt2 *a, const pt2 *b)
{
  return (a->x - o->x) * (b->y - o->y) - (a->y - o->y) * (b->x - o->x);
}

/* Andrew's monotone chain into h (room for 2 n + 2), with buf (n) the
 * sort's scratch (the caller's arrays: qsort may allocate; buf and h may
 * be one array, the sort done before the chain begins); strictly
 * convex turns only, so collinear and duplicated points (degenerate
 * projections) are dropped.  Sorts p.  Returns the hull's count:
 * counter-clockwise from the least point (pt_less); a single point where
 * the points do not spread. */
static int hull_chain(pt2 *p, int n, pt2 *buf, pt2 *h)
{
  if (n <= 0) return 0;
  const pt2 *v = sort_point_runs(p, buf, n);
  if (v != p) memcpy(p, v, (size_t)n * sizeof *p);

  /* collinearity tolerance scaled by the point set's extent */
  double ylo = p[0].y, yhi = p[0].y;
  for (int i = 1; i < n; i++) {
    if (p[i].y < ylo) ylo = p[i].y;
    if (p[i].y > yhi) yhi = p[i].y;
  }
  double ext = fmax(p[n - 1].x - p[0].x, yhi - ylo);
  if (!(ext > 0)) {
    h[0] = p[0];
    return 1;
  }
  double tol = HULL_COLLINEAR_EPS * ext * ext;

  /* lower chain left to right, then upper chain right to left */
  int k = 0;
  for (int i = 0; i < n; i++) {
    while (k >= 2 && cross3(&h[k - 2], &h[k - 1], &p[i]) <= tol) k--;
    h[k++] = p[i];
  }
  for (int i = n - 2, lower = k + 1; i >= 0; i--) {
    while (k >= lower && cross3(&h[k - 2], &h[k - 1], &p[i]) <= tol) k--;
    h[k++] = p[i];
  }
  k--; /* the last point repeats the first */
  if (k < 1) k = 1;
  return k;
}

/* hull_chain of the footprint points p (n <= HULL_IN_MAX) into out */
static void convex_hull(pt2 *p, int n, ssPoly2 *out)
{
  pt2 buf[HULL_IN_MAX], h[2 * HULL_IN_MAX + 2];
  int k = hull_chain(p, n, buf, h);
  if (k > SS_POLY_MAX) k = SS_POLY_MAX; /* cannot happen: k <= n */
  out->n = k;
  for (int i = 0; i < k; i++) {
    out->x[i] = h[i].x;
    out->y[i] = h[i].y;
  }
}

/* hull_reduce's order of vertices: least triangle first, then the first
 * in the polygon's order (so that the cut does not depend on how the
 * heap happens to hold them) */
static int tri_before(const double *a, int i, int j)
{
  return a[i] < a[j] || (a[i] == a[j] && i < j);
}

/* the heap hp[0, n) (pos: each vertex's place in it) with its entry at
 * place k moved up or down to where tri_before puts it */
static void heap_fix(int *hp, int *pos, const double *a, int n, int k)
{
  int v = hp[k];
  while (k > 0 && tri_before(a, v, hp[(k - 1) / 2])) {
    hp[k] = hp[(k - 1) / 2];
    pos[hp[k]] = k;
    k = (k - 1) / 2;
  }
  for (;;) {
    int c = 2 * k + 1;
    if (c >= n) break;
    if (c + 1 < n && tri_before(a, hp[c + 1], hp[c])) c++;
    if (!tri_before(a, hp[c], v)) break;
    hp[k] = hp[c];
    pos[hp[k]] = k;
    k = c;
  }
  hp[k] = v;
  pos[v] = k;
}

/* The convex polygon h[0, k) (k <= SS_HULL_POINTS_MAX) cut down to max
 * vertices: the vertex whose triangle with its two neighbours is least
 * removed, one at a time (the first in h's order on ties), and that
 * triangle's area lost.  What remains is convex, counter-clockwise and
 * inside the polygon, and keeps h's order.  The triangles in a heap:
 * O(k log k).  Returns the count. */
static int hull_reduce(pt2 *h, int k, int max)
{
  int prev[SS_HULL_POINTS_MAX], next[SS_HULL_POINTS_MAX];
  int hp[SS_HULL_POINTS_MAX], pos[SS_HULL_POINTS_MAX];
  double a[SS_HULL_POINTS_MAX];
  if (k <= max || k > SS_HULL_POINTS_MAX) return k < max ? k : max;
  for (int i = 0; i < k; i++) {
    prev[i] = i > 0 ? i - 1 : k - 1;
    next[i] = i + 1 < k ? i + 1 : 0;
  }
  for (int i = 0; i < k; i++) {
    a[i] = cross3(&h[prev[i]], &h[i], &h[next[i]]);
    hp[i] = i;
    pos[i] = i;
  }
  for (int i = k / 2 - 1; i >= 0; i--) heap_fix(hp, pos, a, k, i);
  for (int n = k; n > max;) {
    /* the least off the heap (the last entry in its place), its
     * neighbours joined and their triangles formed anew */
    int best = hp[0], l = prev[best], r = next[best];
    hp[0] = hp[--n];
    pos[hp[0]] = 0;
    pos[best] = -1;
    if (n > 0) heap_fix(hp, pos, a, n, 0);
    next[l] = r;
    prev[r] = l;
    a[l] = cross3(&h[prev[l]], &h[l], &h[r]);
    heap_fix(hp, pos, a, n, pos[l]);
    a[r] = cross3(&h[l], &h[r], &h[next[r]]);
    heap_fix(hp, pos, a, n, pos[r]);
  }
  int m = 0;
  for (int i = 0; i < k; i++)
    if (pos[i] >= 0) h[m++] = h[i];
  return m;
}

/* ---------------------------------------------------------------------- */
/* footprints                                                              */

/* Unit circle polygon scaled to the circle's area (radius k > 1) and turned
 * so that its support along +x and -x is exactly 1: the hull of two such
 * polygons translated along y is then exactly 2 wide, so a lying wheel's
 * footprint is 2r x L and a capsule's is pi r^2 + 2 r L.  Quarter symmetry
 * keeps the four quadrants identical. */
static double circle_c[SS_FOOTPRINT_SEGMENTS], circle_s[SS_FOOTPRINT_SEGMENTS];

static void circle_table(void)
{
  double *c = circle_c, *s = circle_s;
  const int n = SS_FOOTPRINT_SEGMENTS, q = SS_FOOTPRINT_SEGMENTS / 4;
  double step = 2 * SS_PI / n;
  double k = sqrt(2 * SS_PI / (n * sin(step)));
  double phi0 = acos(1 / k);
  for (int i = 0; i < q; i++) {
    double ci = k * cos(phi0 + step * i), si = k * sin(phi0 + step * i);
    c[i] = ci;          s[i] = si;
    c[i + q] = -si;     s[i + q] = ci;
    c[i + 2 * q] = -ci; s[i + 2 * q] = -si;
    c[i + 3 * q] = si;  s[i + 3 * q] = -ci;
  }
}

/* the table, formed once per process (33 libm calls: a wheel's footprint
 * formed them at every step); call_once makes the first use safe from
 * any number of threads */
static once_flag circle_once = ONCE_FLAG_INIT;

/* the affine image centre + u c_i + v s_i of the circle table */
static int put_ellipse(pt2 *p, int np, const double c[], const double s[],
                       double ox, double oy, const double u[2], const double v[2])
{
  for (int i = 0; i < SS_FOOTPRINT_SEGMENTS; i++) {
    p[np].x = ox + u[0] * c[i] + v[0] * s[i];
    p[np].y = oy + u[1] * c[i] + v[1] * s[i];
    np++;
  }
  return np;
}

/* Horizontal unit vector w perpendicular to the axis a (any when a is
 * vertical).  Built from the axis alone, so spinning a wheel about its axle
 * leaves its footprint unchanged. */
static void axis_side(const double a[3], double w[3])
{
  double m = fmax(fabs(a[0]), fabs(a[1]));
  if (m > 0) {
    w[0] = -a[1] / m;
    w[1] = a[0] / m;
    w[2] = 0;
    ss_v3_normalize(w);
  } else {
    ss_v3_set(w, 1, 0, 0);
  }
}

/* one copy's points for swept_hull: p[i], or where p is NULL the ellipse
 * (ox, oy) + u c_i + v s_i of the circle table, formed as put_ellipse
 * forms it (only the points the hull gathers) */
typedef struct PtSrc {
  const pt2 *p;
  double ox, oy;
  const double *u, *v;
} PtSrc;

static inline pt2 src_point(const PtSrc *src, int i)
{
  if (src->p) return src->p[i];
  pt2 q = {src->ox + src->u[0] * circle_c[i] + src->v[0] * circle_s[i],
           src->oy + src->u[1] * circle_c[i] + src->v[1] * circle_s[i]};
  return q;
}

/* points i = i0, i0 + step, ..., i1 of src onto h from m on, in a run that
 * does not wrap, the box (x least, greatest, y least, greatest) grown over
 * them; returns h's new count */
static inline int gather_run(pt2 *h, int m, const PtSrc *src, int i0, int i1, int step,
                             double box[4])
{
  for (int i = i0;; i += step) {
    pt2 v = src_point(src, i);
    h[m++] = v;
    if (v.x < box[0]) box[0] = v.x;
    if (v.x > box[1]) box[1] = v.x;
    if (v.y < box[2]) box[2] = v.y;
    if (v.y > box[3]) box[3] = v.y;
    if (i == i1) return m;
  }
}

/* swept_hull's chain of one copy src: its points from index a to b,
 * forwards (fwd) or backwards, modulo n, onto h from m on (gather_run; a
 * chain that wraps takes two runs, so that no point tests for the wrap);
 * returns h's new count */
static inline int hull_gather(pt2 *h, int m, const PtSrc *src, int n, int fwd, int a, int b,
                              double box[4])
{
  if (fwd) {
    if (a > b) {
      m = gather_run(h, m, src, a, n - 1, 1, box);
      a = 0;
    }
    return gather_run(h, m, src, a, b, 1, box);
  }
  if (a < b) {
    m = gather_run(h, m, src, a, 0, -1, box);
    a = n - 1;
  }
  return gather_run(h, m, src, a, b, -1, box);
}

/* swept_hull's extents e = tx y - ty x of the points i = i0, i0 + step,
 * ..., i1 of p (a run that does not wrap): the least and greatest so far,
 * *lo and *hi, and the first points that reach them, *kb and *ka */
static inline void extent_run(const pt2 *p, int i0, int i1, int step, double tx, double ty,
                              double *lo, double *hi, int *kb, int *ka)
{
  double l = *lo, h = *hi;
  int b = *kb, a = *ka;
  for (int i = i0;; i += step) {
    double e = tx * p[i].y - ty * p[i].x;
    if (e < l) {
      l = e;
      b = i;
    }
    if (e > h) {
      h = e;
      a = i;
    }
    if (i == i1) break;
  }
  *lo = l;
  *hi = h;
  *kb = b;
  *ka = a;
}

/* The hull of two copies of one convex polygon, p[0, n) and the ellipse
 * (ox, oy) + u c_i + v s_i (put_ellipse's points, formed here only where
 * the hull takes them: the second copy, the first moved by -2t, t = (tx,
 * ty) != 0; points in the order of the circle table, counter-clockwise
 * when ccw, else clockwise), without a
 * sort: it is the polygon swept along t, the first copy's chain between
 * its extreme points across t followed by the second copy's other chain.
 * Collinear and repeated points are dropped with convex_hull's tolerance,
 * and the result starts at its least point (x, then y) as convex_hull's
 * does, so that where convex_hull keeps the same points the polygon is the
 * same, bit for bit.  Returns 0 (out untouched) when the sweep is not
 * cleanly convex; convex_hull then decides. */
static int swept_hull(const pt2 *p, int n, int ccw, double tx, double ty, double ox,
                      double oy, const double u[2], const double v[2], ssPoly2 *out)
{
  /* the points counter-clockwise, read in place: the first copy's k-th is
   * p[i] with i = k d (mod n), d = 1 when ccw, else n - 1 (p[0], then
   * backwards), the second copy's the ellipse's point i; B, A: least and
   * greatest extent along the normal (-ty, tx), the first of them in that
   * order (its runs: p[0, n) when ccw, else p[0], then p[n - 1] down to
   * p[1]) */
  int kb = 0, ka = 0;
  double lo = INFINITY, hi = -INFINITY;
  if (ccw) {
    extent_run(p, 0, n - 1, 1, tx, ty, &lo, &hi, &kb, &ka);
  } else {
    extent_run(p, 0, 0, 1, tx, ty, &lo, &hi, &kb, &ka);
    extent_run(p, n - 1, 1, -1, tx, ty, &lo, &hi, &kb, &ka);
  }
  /* B to A on the first copy (its edges face +t), A to B on the second,
   * and their bounding box (begun at the first point, as they come) */
  pt2 h[HULL_IN_MAX + 2];
  double box[4] = {p[kb].x, p[kb].x, p[kb].y, p[kb].y};
  const PtSrc copy0 = {p, 0, 0, NULL, NULL}, copy1 = {NULL, ox, oy, u, v};
  int m = hull_gather(h, 0, &copy0, n, ccw, kb, ka, box);
  m = hull_gather(h, m, &copy1, n, ccw, ka, kb, box);
  double xlo = box[0], xhi = box[1], ylo = box[2], yhi = box[3];
  double ext = xhi - xlo > yhi - ylo ? xhi - xlo : yhi - ylo;
  if (!(ext > 0)) return 0;
  double tol = HULL_COLLINEAR_EPS * ext * ext;
  /* left turns only, as convex_hull keeps them, around the cycle.  Every
   * turn the stack keeps was tested left when its last point came, so
   * only a test neither left nor not (NaN: a point not finite) leaves
   * the turns to be tested again below (odd) */
  int k = 0, odd = 0;
  for (int i = 0; i < m; i++) {
    while (k >= 2) {
      double t = cross3(&h[k - 2], &h[k - 1], &h[i]);
      if (t > tol) break;
      if (!(t <= tol)) {
        odd = 1; /* neither: a NaN */
        break;
      }
      k--;
    }
    h[k++] = h[i];
  }
  int first = 0;
  for (int changed = 1; changed && k - first >= 3;) {
    changed = 0;
    double t0 = cross3(&h[k - 2], &h[k - 1], &h[first]), t1;
    if (t0 <= tol) {
      k--;
      changed = 1;
    } else if ((t1 = cross3(&h[k - 1], &h[first], &h[first + 1])) <= tol) {
      first++;
      changed = 1;
    } else {
      /* the two turns across the cycle's ends, tested last */
      odd |= !(t0 > tol && t1 > tol);
    }
  }
  const pt2 *c = h + first;
  int cnt = k - first;
  if (cnt < 3) return 0;
  /* every turn left (the filter's stack makes them so, unless a point is
   * not finite: odd): else leave it to convex_hull */
  if (odd) {
    for (int i = 0; i < cnt; i++) {
      int i1 = i + 1 < cnt ? i + 1 : i + 1 - cnt, i2 = i + 2 < cnt ? i + 2 : i + 2 - cnt;
      if (!(cross3(c + i, c + i1, c + i2) > tol)) return 0;
    }
  }
  /* the least point (pt_less), most points failing at their x alone */
  int start = 0;
  for (int i = 1; i < cnt; i++) {
    if (!(c[i].x <= c[start].x)) continue;
    if (c[i].x < c[start].x || c[i].y < c[start].y) start = i;
  }
  /* from the least point to the end, then the rest */
  out->n = cnt;
  for (int i = start; i < cnt; i++) {
    out->x[i - start] = c[i].x;
    out->y[i - start] = c[i].y;
  }
  for (int i = 0; i < start; i++) {
    out->x[cnt - start + i] = c[i].x;
    out->y[cnt - start + i] = c[i].y;
  }
  return 1;
}

void ss_shape_footprint(const ssShape *s, ssPoly2 *out)
{
  pt2 p[HULL_IN_MAX];
  int np = 0;
  const double *R = s->R, *c = s->pos;
  out->n = 0;

  switch (s->type) {
  case SS_GEOM_BOX: {
    /* the 8 corners projected along z */
    double h[3] = {0.5 * s->size[0], 0.5 * s->size[1], 0.5 * s->size[2]};
    for (int i = 0; i < 8; i++) {
      double lx = (i & 1) ? h[0] : -h[0];
      double ly = (i & 2) ? h[1] : -h[1];
      double lz = (i & 4) ? h[2] : -h[2];
      p[np].x = c[0] + R[0] * lx + R[1] * ly + R[2] * lz;
      p[np].y = c[1] + R[3] * lx + R[4] * ly + R[5] * lz;
      np++;
    }
    break;
  }
  case SS_GEOM_SPHERE: {
    double r = s->size[0], u[2] = {r, 0}, v[2] = {0, r};
    call_once(&circle_once, circle_table);
    np = put_ellipse(p, np, circle_c, circle_s, c[0], c[1], u, v);
    break;
  }
  case SS_GEOM_CYLINDER:
  case SS_GEOM_CAPSULE: {
    double a[3] = {R[2], R[5], R[8]}, w[3], b[3], u[2], v[2];
    double r = s->size[0], hl = 0.5 * s->size[1];
    call_once(&circle_once, circle_table);
    axis_side(a, w);
    if (s->type == SS_GEOM_CYLINDER) {
      /* cap discs: in-plane axes w and a x w, projected to xy */
      ss_v3_cross(b, a, w);
      u[0] = r * w[0]; u[1] = r * w[1];
      v[0] = r * b[0]; v[1] = r * b[1];
    } else {
      /* end spheres project to full circles */
      u[0] = r * w[0];  u[1] = r * w[1];
      v[0] = -r * w[1]; v[1] = r * w[0];
    }
    np = put_ellipse(p, np, circle_c, circle_s, c[0] + hl * a[0], c[1] + hl * a[1], u, v);
    /* two copies of one convex polygon: swept, no sort (a wheel's
     * footprint in half the instructions; the second copy formed where
     * the hull takes it), unless the caps are (nearly) edge-on or the axis
     * (nearly) vertical, where the copies' points nearly coincide and only
     * the sort tells them apart */
    double ox = c[0] - hl * a[0], oy = c[1] - hl * a[1];
    double det = u[0] * v[1] - u[1] * v[0], tx = hl * a[0], ty = hl * a[1];
    double lu = hypot(u[0], u[1]), lv = hypot(v[0], v[1]);
    if (fabs(det) > 1e-9 * lu * lv && hypot(tx, ty) > 1e-6 * fmax(lu, lv) &&
        swept_hull(p, SS_FOOTPRINT_SEGMENTS, det > 0, tx, ty, ox, oy, u, v, out))
      return;
    np = put_ellipse(p, np, circle_c, circle_s, ox, oy, u, v);
    break;
  }
  default:
    return;
  }
  convex_hull(p, np, out);
}

int ss_points_footprint(const double *q, int n, const double R[9], const double o[3],
                        ssPoly2 *out)
{
  /* h is the sort's scratch too (hull_chain) */
  pt2 p[SS_HULL_POINTS_MAX], h[2 * SS_HULL_POINTS_MAX + 2];
  out->n = 0;
  if (n < 0 || n > SS_HULL_POINTS_MAX) return 0;
  /* projected as a box's corners are (ss_shape_footprint) */
  for (int k = 0; k < n; k++) {
    const double *v = q + 3 * k;
    p[k].x = o[0] + R[0] * v[0] + R[1] * v[1] + R[2] * v[2];
    p[k].y = o[1] + R[3] * v[0] + R[4] * v[1] + R[5] * v[2];
  }
  int k = hull_chain(p, n, h, h), nh = k;
  if (k > SS_POLY_MAX) k = hull_reduce(h, k, SS_POLY_MAX);
  out->n = k;
  for (int i = 0; i < k; i++) {
    out->x[i] = h[i].x;
    out->y[i] = h[i].y;
  }
  return nh;
}

/* ---------------------------------------------------------------------- */
/* bounds                                                                  */

void ss_shape_aabb(const ssShape *s, double lo[3], double hi[3])
{
  const double *R = s->R;
  double e[3] = {0, 0, 0};
  switch (s->type) {
  case SS_GEOM_BOX:
    for (int k = 0; k < 3; k++)
      e[k] = 0.5 * (fabs(R[3 * k]) * s->size[0] + fabs(R[3 * k + 1]) * s->size[1] +
                    fabs(R[3 * k + 2]) * s->size[2]);
    break;
  case SS_GEOM_SPHERE:
    e[0] = e[1] = e[2] = s->size[0];
    break;
  case SS_GEOM_CYLINDER:
    /* the cap rim's extent along k is r sqrt(1 - a_k^2) */
    for (int k = 0; k < 3; k++) {
      double ak = R[3 * k + 2];
      e[k] = 0.5 * s->size[1] * fabs(ak) + s->size[0] * sqrt(fmax(0.0, 1 - ak * ak));
    }
    break;
  case SS_GEOM_CAPSULE:
    for (int k = 0; k < 3; k++)
      e[k] = 0.5 * s->size[1] * fabs(R[3 * k + 2]) + s->size[0];
    break;
  default:
    break;
  }
  for (int k = 0; k < 3; k++) {
    lo[k] = s->pos[k] - e[k];
    hi[k] = s->pos[k] + e[k];
  }
}

/* [lo, hi] widened to hold the product of scalar k and interval [a, b] */
static void add_scaled(double k, double a, double b, double *lo, double *hi)
{
  double p = k * a, q = k * b;
  *lo += fmin(p, q);
  *hi += fmax(p, q);
}

int ss_shape_low_bounds(const ssShape *s, double zc, double lo[2], double hi[2])
{
  const double *R = s->R, *c = s->pos;
  double e = fabs(s->size[0]) + fabs(s->size[1]) + fabs(s->size[2]);
  /* slack far above round-off: widens zc, then the bounds */
  zc += 1e-9 * (1 + fabs(zc) + fabs(c[2]) + e);
  double pad = 1e-9 * (1 + fabs(c[0]) + fabs(c[1]) + e);

  switch (s->type) {
  case SS_GEOM_BOX: {
    /* corners at or below zc and the points where edges cross it */
    double p[8][3];
    int any = 0;
    lo[0] = lo[1] = INFINITY;
    hi[0] = hi[1] = -INFINITY;
    for (int i = 0; i < 8; i++) {
      double l[3] = {(i & 1) ? 0.5 * s->size[0] : -0.5 * s->size[0],
                     (i & 2) ? 0.5 * s->size[1] : -0.5 * s->size[1],
                     (i & 4) ? 0.5 * s->size[2] : -0.5 * s->size[2]};
      ss_m3_mulv(p[i], R, l);
      ss_v3_add(p[i], p[i], c);
    }
    for (int i = 0; i < 8; i++) {
      if (p[i][2] <= zc) {
        any = 1;
        for (int k = 0; k < 2; k++) {
          lo[k] = fmin(lo[k], p[i][k]);
          hi[k] = fmax(hi[k], p[i][k]);
        }
      }
      for (int bit = 1; bit < 8; bit <<= 1) {
        int j = i ^ bit;
        if (j < i || (p[i][2] <= zc) == (p[j][2] <= zc)) continue;
        double t = (zc - p[i][2]) / (p[j][2] - p[i][2]);
        for (int k = 0; k < 2; k++) {
          double x = p[i][k] + t * (p[j][k] - p[i][k]);
          lo[k] = fmin(lo[k], x);
          hi[k] = fmax(hi[k], x);
        }
      }
    }
    if (!any) return 0;
    break;
  }
  case SS_GEOM_SPHERE:
  case SS_GEOM_CAPSULE: {
    /* centre segment c + t a (|t| <= hl) swept by a ball of radius r: only
     * segment points within r above zc matter, and the ball's slice below
     * zc is widest about the lowest of them */
    double r = s->size[0], hl = s->type == SS_GEOM_CAPSULE ? 0.5 * s->size[1] : 0;
    double a[3] = {R[2], R[5], R[8]}, t0 = -hl, t1 = hl;
    double lim = zc + r - c[2];
    if (a[2] > 0) t1 = fmin(t1, lim / a[2]);
    else if (a[2] < 0) t0 = fmax(t0, lim / a[2]);
    else if (lim < 0) return 0;
    if (!(t0 <= t1)) return 0;
    double h = c[2] + fmin(t0 * a[2], t1 * a[2]) - zc;
    double rho = h <= 0 ? r : sqrt(fmax(0.0, r * r - h * h));
    for (int k = 0; k < 2; k++) {
      lo[k] = c[k] - rho;
      hi[k] = c[k] + rho;
      add_scaled(a[k], t0, t1, &lo[k], &hi[k]);
    }
    break;
  }
  case SS_GEOM_CYLINDER: {
    /* points c + t a + al w + be b (|t| <= hl, al^2 + be^2 <= r^2) with w
     * horizontal, so their height is c_z + t a_z + be b_z */
    double r = s->size[0], hl = 0.5 * s->size[1];
    double a[3] = {R[2], R[5], R[8]}, w[3], b[3];
    axis_side(a, w);
    ss_v3_cross(b, a, w);
    if (b[2] < 0) ss_v3_scale(b, b, -1);
    double t0 = -hl, t1 = hl, lim = zc + r * b[2] - c[2];
    if (a[2] > 0) t1 = fmin(t1, lim / a[2]);
    else if (a[2] < 0) t0 = fmax(t0, lim / a[2]);
    else if (lim < 0) return 0;
    if (!(t0 <= t1)) return 0;
    /* be stays below bh; al within the disc's chord nearest the centre */
    double bh = r, al = r;
    if (b[2] > 0) {
      bh = fmin(r, (zc - c[2] - fmin(t0 * a[2], t1 * a[2])) / b[2]);
      if (bh < 0) al = sqrt(fmax(0.0, r * r - bh * bh));
      bh = fmax(bh, -r);
    }
    for (int k = 0; k < 2; k++) {
      lo[k] = c[k] - al * fabs(w[k]);
      hi[k] = c[k] + al * fabs(w[k]);
      add_scaled(a[k], t0, t1, &lo[k], &hi[k]);
      add_scaled(b[k], -r, bh, &lo[k], &hi[k]);
    }
    break;
  }
  default:
    return 0;
  }
  for (int k = 0; k < 2; k++) {
    lo[k] -= pad;
    hi[k] += pad;
  }
  return 1;
}

/* ---------------------------------------------------------------------- */
/* polygons                                                                */

double ss_poly_area(const ssPoly2 *p)
{
  if (p->n < 3) return 0;
  /* relative to the first vertex, so distant polygons keep their digits */
  double x0 = p->x[0], y0 = p->y[0], a2 = 0;
  for (int i = 1; i + 1 < p->n; i++)
    a2 += (p->x[i] - x0) * (p->y[i + 1] - y0) - (p->x[i + 1] - x0) * (p->y[i] - y0);
  return 0.5 * a2;
}

/* the point where edge P -> Q crosses c = b, placed exactly on the line */
static inline int put_cut(double *oc, double *oo, int m, double b, double pc,
                          double po, double qc, double qo)
{
  oc[m] = b;
  oo[m] = po + (b - pc) / (qc - pc) * (qo - po);
  return m + 1;
}

/* Sutherland-Hodgman against the slab lo <= c <= hi in one pass (c is x or
 * y, o the other coordinate): each edge P -> Q contributes its part inside
 * the slab.  Input is shifted by (-offc, -offo) as it is read.  Only the
 * edges j (ending at vertex j) in the ascending ranges [rg[2r], rg[2r+1])
 * are visited: the others must contribute nothing, so that the output is
 * that of visiting all n.  An edge begins only with room for its two
 * points (m <= CLIP_MAX - 2), tested per edge where guard is set (clip_slab
 * sets it only where the ranges hold enough edges to fill the room). */
static inline int clip_ranges(const double *ic, const double *io, int n, const int *rg,
                              int nr, double offc, double offo, double *oc, double *oo,
                              double lo, double hi, int guard)
{
  int m = 0;
  for (int r = 0; r < nr; r++) {
    int j = rg[2 * r], pj = j > 0 ? j - 1 : n - 1;
    double pc = ic[pj] - offc, po = io[pj] - offo;
    for (; j < rg[2 * r + 1]; j++) {
      if (guard && m > CLIP_MAX - 2) break;
      double qc = ic[j] - offc, qo = io[j] - offo;
      if (qc >= lo && qc <= hi) {
        /* entering (unless Q itself is the entry), then Q */
        if (pc < lo && qc > lo) m = put_cut(oc, oo, m, lo, pc, po, qc, qo);
        else if (pc > hi && qc < hi) m = put_cut(oc, oo, m, hi, pc, po, qc, qo);
        oc[m] = qc;
        oo[m] = qo;
        m++;
      } else if (qc < lo) {
        /* leaving below (unless P itself was the exit), maybe crossing all */
        if (pc > hi) {
          m = put_cut(oc, oo, m, hi, pc, po, qc, qo);
          m = put_cut(oc, oo, m, lo, pc, po, qc, qo);
        } else if (pc > lo) {
          m = put_cut(oc, oo, m, lo, pc, po, qc, qo);
        }
      } else {
        /* leaving above, likewise */
        if (pc < lo) {
          m = put_cut(oc, oo, m, lo, pc, po, qc, qo);
          m = put_cut(oc, oo, m, hi, pc, po, qc, qo);
        } else if (pc < hi) {
          m = put_cut(oc, oo, m, hi, pc, po, qc, qo);
        }
      }
      pc = qc;
      po = qo;
    }
  }
  return m;
}

/* clip_ranges, its room test per edge only where it can fail: an edge adds
 * at most two points, so that with e edges in all the last begins with at
 * most 2 (e - 1) <= CLIP_MAX - 2 when e <= CLIP_MAX / 2 */
static int clip_slab(const double *ic, const double *io, int n, const int *rg,
                     int nr, double offc, double offo, double *oc, double *oo,
                     double lo, double hi)
{
  if (n <= 0) return 0;
  int e = 0;
  for (int r = 0; r < nr; r++) e += rg[2 * r + 1] - rg[2 * r];
  if (e <= CLIP_MAX / 2)
    return clip_ranges(ic, io, n, rg, nr, offc, offo, oc, oo, lo, hi, 0);
  return clip_ranges(ic, io, n, rg, nr, offc, offo, oc, oo, lo, hi, 1);
}

/* whether co never falls (rise) or never rises (!rise) along the vertices
 * a, a + 1, ..., b of the polygon (co, n), indices modulo n: the run to the
 * array's end, its edge n - 1 -> 0, then the run from 0, so that no step
 * tests for the wrap */
static inline int chain_monotone(const double *co, int n, int a, int b, int rise)
{
  if (a > b) {
    for (int i = a; i < n - 1; i++)
      if (rise ? co[i + 1] < co[i] : co[i + 1] > co[i]) return 0;
    if (rise ? co[0] < co[n - 1] : co[0] > co[n - 1]) return 0;
    a = 0;
  }
  for (int i = a; i < b; i++)
    if (rise ? co[i + 1] < co[i] : co[i + 1] > co[i]) return 0;
  return 1;
}

/* the two chains of the polygon (co, n) monotone in the coordinate co */
static int mono_chains(const double *co, int n, ssPolyChains *c)
{
  int l = 0, r = 0;
  if (n < 3) return 0;
  for (int i = 1; i < n; i++) {
    if (co[i] < co[l]) l = i;
    if (co[i] > co[r]) r = i;
  }
  if (l == r) return 0;
  /* co must not fall from l to r, nor rise from r back to l */
  if (!chain_monotone(co, n, l, r, 1) || !chain_monotone(co, n, r, l, 0)) return 0;
  c->l = l;
  c->r = r;
  for (int k = 0; k < 4; k++) c->hint[k] = -1;
  return 1;
}

int ss_poly_ychains(const ssPoly2 *p, ssPolyChains *c)
{
  return mono_chains(p->y, p->n, c);
}

/* whether sgn (v[k] - val) >= 0 (> 0 when strict), as a comparison of
 * v[k] with val: the same outcome for a finite val, as the slabs' bounds
 * are (a difference of doubles is then 0 only for equal ones, infinite
 * only with v[k], and a NaN fails both; an infinite val would compare
 * equal to itself where the difference is a NaN) */
static inline int run_pred(const double *v, int k, double val, double sgn, int strict)
{
  if (sgn > 0) return strict ? v[k] > val : v[k] >= val;
  return strict ? v[k] < val : v[k] <= val;
}

/* first k in [from, cnt) where run_pred holds on the plain array v (it
 * holds at none before from); cnt when none.  sgn v is non-decreasing
 * along it, so the predicate is monotone and the answer unique: galloping
 * from h to bracket it, then bisecting, finds the one bisection alone
 * finds. */
static inline int run_search(const double *v, int from, int cnt, double val, double sgn,
                             int strict, int h)
{
  int a = from, b = cnt;
  if (h >= from && h < cnt) {
    if (run_pred(v, h, val, sgn, strict)) {
      b = h;
      for (int step = 1;; step *= 2) {
        int k = b - step;
        if (k < from) break;
        if (!run_pred(v, k, val, sgn, strict)) {
          a = k + 1;
          break;
        }
        b = k;
      }
    } else {
      a = h + 1;
      for (int step = 1;; step *= 2) {
        int k = a - 1 + step;
        if (k >= cnt) break;
        if (run_pred(v, k, val, sgn, strict)) {
          b = k;
          break;
        }
        a = k + 1;
      }
    }
  }
  while (a < b) {
    int mid = (int)((unsigned)(a + b) / 2);
    if (run_pred(v, mid, val, sgn, strict)) b = mid;
    else a = mid + 1;
  }
  return a;
}

/* first k in [from, cnt) where sgn (x[start + k] - v) >= 0 (> 0 when
 * strict; it holds at none before from), indices modulo n; cnt when none;
 * *hint (where to start) receives it.  A chain that wraps past n - 1 is
 * searched in the one of its two plain runs that holds the answer (its
 * first run's last entry tells which), so that no step forms an index
 * modulo n. */
static inline int chain_search(const double *x, int n, int start, int from, int cnt,
                               double v, double sgn, int strict, int *hint)
{
  int len1 = n - start, h = *hint, k;
  if (cnt <= len1) k = run_search(x + start, from, cnt, v, sgn, strict, h);
  else if (from < len1 && run_pred(x + start, len1 - 1, v, sgn, strict))
    k = run_search(x + start, from, len1, v, sgn, strict, h);
  else
    k = len1 + run_search(x, from > len1 ? from - len1 : 0, cnt - len1, v, sgn, strict,
                          h - len1);
  *hint = k;
  return k;
}

/* the edges (index of their end vertex) of chain start -> start + cnt of
 * the polygon (co, n) whose range in the coordinate co meets [x0, x1], as
 * up to two ascending index ranges */
static inline int chain_edges(const double *co, int n, int start, int cnt, double sgn,
                              double x0, double x1, int hint[2], int *rg)
{
  int s1 = start + 1 < n ? start + 1 : 0;
  /* sgn = 1: co rises along the chain; edge k runs from vertex k to k + 1 */
  double enter = sgn > 0 ? x0 : x1, leave = sgn > 0 ? x1 : x0;
  int k0 = chain_search(co, n, s1, 0, cnt, enter, sgn, 0, hint);
  if (k0 >= cnt) return 0;
  /* vertices start .. start + k0 come before the enter bound, so before
   * the leave bound: k1 > k0, searched from k0 + 1 on (one test, where
   * the edge k0 leaves the slab) */
  hint[1] = k0 + 1;
  int k1 = chain_search(co, n, start, k0 + 1, cnt, leave, sgn, 1, hint + 1);
  int a = s1 + k0;
  if (a >= n) a -= n;
  int b = a + (k1 - k0);
  if (b <= n) {
    rg[0] = a;
    rg[1] = b;
    return 1;
  }
  rg[0] = a;
  rg[1] = n;
  rg[2] = 0;
  rg[3] = b - n;
  return 2;
}

/* area of the polygon (x, y) (n > 2, kept about (mx, my)) and, when cx
 * and cy are not NULL and the area is not 0, its centroid */
static double shoelace(const double *x, const double *y, int n, double mx, double my,
                       double *cx, double *cy)
{
  double a2 = 0, sx = 0, sy = 0;
  for (int i = 0, j = n - 1; i < n; j = i++) {
    double cr = x[j] * y[i] - x[i] * y[j];
    a2 += cr;
    sx += (x[j] + x[i]) * cr;
    sy += (y[j] + y[i]) * cr;
  }
  if (a2 == 0) return 0;
  if (cx && cy) {
    *cx = mx + sx / (3 * a2);
    *cy = my + sy / (3 * a2);
  }
  return fabs(0.5 * a2);
}

/* The edges of the polygon (co, n) whose range in co meets the slab
 * [c0, c1] widened far beyond round-off (every edge a clip against the
 * slab would take something from: it compares co - m with c0 - m), as
 * ascending index ranges in rg (room for 4), found along its chains c
 * monotone in co (ss_poly_ychains).  Returns their
 * count. */
static int slab_edges(const double *co, int n, ssPolyChains *c, double c0, double c1,
                      int rg[8])
{
  int l = c->l, r = c->r, nr = 0;
  double tol = 1e-9 * (fabs(c0) + fabs(c1));
  double lo = c0 - tol, hi = c1 + tol;
  /* the chains' edge counts, (r - l) and (l - r) modulo n (0 <= l, r < n:
   * one of them takes n, without a division) */
  int up = r - l, down = l - r;
  if (up < 0) up += n;
  else down += n;
  nr += chain_edges(co, n, l, up, 1, lo, hi, c->hint, rg);
  nr += chain_edges(co, n, r, down, -1, lo, hi, c->hint + 2, rg + 2 * nr);
  /* ascending, as the clip visits them */
  for (int i = 1; i < nr; i++)
    for (int k = i; k > 0 && rg[2 * k - 2] > rg[2 * k]; k--) {
      int a = rg[2 * k - 2], b = rg[2 * k - 1];
      rg[2 * k - 2] = rg[2 * k];
      rg[2 * k - 1] = rg[2 * k + 1];
      rg[2 * k] = a;
      rg[2 * k + 1] = b;
    }
  return nr;
}

double ss_poly_rect_area(const ssPoly2 *p, double x0, double x1, double y0,
                         double y1, double *cx, double *cy)
{
  if (p->n < 3 || !(x1 > x0) || !(y1 > y0)) return 0;
  double ax[CLIP_MAX], ay[CLIP_MAX], bx[CLIP_MAX], by[CLIP_MAX];
  int all[2] = {0, p->n};
  /* x first, then y, about the rectangle's centre: small numbers, exact
   * corners */
  double mx = 0.5 * (x0 + x1), my = 0.5 * (y0 + y1);
  int n = clip_slab(p->x, p->y, p->n, all, 1, mx, my, ax, ay, x0 - mx, x1 - mx);
  if (n < 3) return 0;
  all[1] = n;
  n = clip_slab(ay, ax, n, all, 1, 0, 0, by, bx, y0 - my, y1 - my);
  if (n < 3) return 0;
  return shoelace(bx, by, n, mx, my, cx, cy);
}

/* one chain of a band: m vertices in x order (within round-off) */
typedef struct BandChain {
  int m, k;
  const double *x, *y;
} BandChain;

/* The integrals of y, x y and y^2 dx along chain c from x = a to x = b
 * (in its x order), x taken about sh, times 2, 6 and 3: each edge piece is
 * linear, so the trapezoid rule is exact for y and Simpson's for x y and
 * y^2; their factors 1/2, 1/6 and 1/3 are left to the caller, which needs
 * one division a cell instead of six (they sat on the edge cells' chain
 * of dependent operations).  c->k, the first edge that may reach past a,
 * moves on as the cells do.  An edge piece is the edge from s = max(xa, a)
 * to t = min(xb, b): its ends' y are the vertices' own where the edge is
 * not cut (xa >= a, xb <= b: the piece is the whole edge, of positive
 * width), and only a cut edge needs its slope and a test of its width. */
static inline void chain_integrals(BandChain *c, double a, double b, double sh, double I[3])
{
  const double *x = c->x, *y = c->y;
  const int m = c->m;
  int k = c->k;
  if (x[k] > a) k = 0; /* (k = 0 again where it is 0: no test for it) */
  while (k < m - 2 && x[k + 1] <= a) k++;
  c->k = k;
  /* the sums in locals, stored once: stored as they grow, each would be
   * read back after every store (a double's store may alias them) */
  double i0 = 0, i1 = 0, i2 = 0;
  for (; k < m - 1 && x[k] < b; k++) {
    double xa = x[k], xb = x[k + 1];
    if (!(xb > xa)) continue; /* an edge along y adds nothing */
    double ya = y[k], yb = y[k + 1];
    double s = xa, t = xb, ys = ya, yt = yb;
    if (xa < a || xb > b) {
      double slope = (yb - ya) / (xb - xa);
      if (xa < a) {
        s = a;
        ys = ya + (a - xa) * slope;
      }
      if (xb > b) {
        t = b;
        yt = ya + (b - xa) * slope;
      }
      if (!(t > s)) continue;
    }
    double w = t - s, su = s - sh, tu = t - sh;
    i0 += w * (ys + yt);
    i1 += w * (su * (2 * ys + yt) + tu * (ys + 2 * yt));
    i2 += w * (ys * ys + ys * yt + yt * yt);
  }
  I[0] = i0;
  I[1] = i1;
  I[2] = i2;
}

/* vertices i = i0, i0 + step, ..., i1 of (x, y) into the band b from its
 * m-th on, in a run that does not wrap (a chain that does takes two, so
 * that no vertex tests for the wrap); returns the band's new count */
static inline int band_put(ssPolyBand *b, int m, const double *x, const double *y, int i0,
                           int i1, int step)
{
  for (int i = i0;; i += step) {
    b->x[m] = x[i];
    b->y[m++] = y[i];
    if (i == i1) return m;
  }
}

int ss_poly_band(const ssPoly2 *p, ssPolyChains *yc, double y0, double y1, double ox,
                 ssPolyBand *b)
{
  b->n = b->l = 0;
  b->ox = ox;
  b->oy = 0.5 * (y0 + y1);
  if (p->n < 3 || !(y1 > y0)) return 1;
  int rg[8] = {0, p->n}, nr = p->n <= SMALL_POLY ? 1 : slab_edges(p->y, p->n, yc, y0, y1, rg);
  if (nr == 0) return 1;
  double x[SS_POLY_CLIP_MAX], y[SS_POLY_CLIP_MAX];
  int n = clip_slab(p->y, p->x, p->n, rg, nr, b->oy, ox, y, x, y0 - b->oy, y1 - b->oy);
  if (n < 3) return 1;
  /* its two chains monotone in x, both from the least x to the greatest:
   * the one the polygon runs along (x, y) from l to r, and the one it
   * runs back along, reversed */
  ssPolyChains c;
  if (!mono_chains(x, n, &c)) return 0;
  int m = 0;
  if (c.l <= c.r) {
    m = band_put(b, m, x, y, c.l, c.r, 1);
  } else {
    m = band_put(b, m, x, y, c.l, n - 1, 1);
    m = band_put(b, m, x, y, 0, c.r, 1);
  }
  b->l = m;
  if (c.l >= c.r) {
    m = band_put(b, m, x, y, c.l, c.r, -1);
  } else {
    m = band_put(b, m, x, y, c.l, 0, -1);
    m = band_put(b, m, x, y, n - 1, c.r, -1);
  }
  b->n = m;
  b->k[0] = b->k[1] = 0;
  return 1;
}

double ss_poly_band_area(ssPolyBand *b, double x0, double x1, double *cx, double *cy)
{
  if (b->n == 0 || !(x1 > x0)) return 0;
  /* Green's theorem: area, int x dA and int y dA of the cell's part are
   * -(closed) integrals of y, x y and y^2 / 2 dx along its boundary, whose
   * parts along the cell's sides (dx = 0) add nothing: the chain the
   * polygon runs forwards (lower, when counter-clockwise) counts
   * negatively, the other (run backwards here) positively */
  double mx = 0.5 * (x0 + x1), sh = mx - b->ox, a = x0 - b->ox, e = x1 - b->ox;
  double If[3], Ir[3];
  /* each chain's place stored as soon as its integrals are done: one value
   * fewer held in a register across the other chain's */
  {
    BandChain f = {b->l, b->k[0], b->x, b->y};
    chain_integrals(&f, a, e, sh, If);
    b->k[0] = f.k;
  }
  {
    BandChain r = {b->n - b->l, b->k[1], b->x + b->l, b->y + b->l};
    chain_integrals(&r, a, e, sh, Ir);
    b->k[1] = r.k;
  }
  /* (the integrals of chain_integrals times 2, 6 and 3: area A, then
   * int x dA / A and int y dA / A = (1/2) int y^2 dx / A both over 6 A) */
  double A = 0.5 * (Ir[0] - If[0]);
  if (A == 0) return 0;
  if (cx && cy) {
    double k = 1 / (6 * A);
    *cx = mx + (Ir[1] - If[1]) * k;
    *cy = b->oy + (Ir[2] - If[2]) * k;
  }
  return fabs(A);
}

/* the chord at height y over the edges in the ascending ranges rg (edge
 * i ends at vertex i); the others must not reach y */
static int chord_of(const ssPoly2 *p, const int *rg, int nr, double y, double *x0,
                    double *x1)
{
  double lo = INFINITY, hi = -INFINITY;
  for (int r = 0; r < nr; r++)
    for (int i = rg[2 * r]; i < rg[2 * r + 1]; i++) {
      int j = i > 0 ? i - 1 : p->n - 1;
      double ya = p->y[j], yb = p->y[i];
      if ((ya > y && yb > y) || (ya < y && yb < y)) continue;
      /* fmin and fmax as comparisons, bit for bit theirs (glibc's: a
       * NaN argument loses, and of equal ones the second wins; lo and hi
       * are never NaN), without a call each */
      double x;
      if (ya == yb) {
        /* an edge along the line: both ends */
        double xi = p->x[i], xj = p->x[j];
        double e0 = xi < xj || xj != xj ? xi : xj, e1 = xi > xj || xj != xj ? xi : xj;
        if (e0 <= lo) lo = e0;
        if (e1 >= hi) hi = e1;
        continue;
      }
      x = p->x[j] + (y - ya) / (yb - ya) * (p->x[i] - p->x[j]);
      if (x <= lo) lo = x;
      if (x >= hi) hi = x;
    }
  if (!(hi >= lo)) return 0;
  *x0 = lo;
  *x1 = hi;
  return 1;
}

int ss_poly_chord(const ssPoly2 *p, double y, double *x0, double *x1)
{
  int all[2] = {0, p->n};
  return chord_of(p, all, 1, y, x0, x1);
}

int ss_poly_chord_y(const ssPoly2 *p, ssPolyChains *yc, double y, double *x0, double *x1)
{
  if (!yc || p->n <= SMALL_POLY) return ss_poly_chord(p, y, x0, x1);
  int rg[8], nr = slab_edges(p->y, p->n, yc, y, y, rg);
  return chord_of(p, rg, nr, y, x0, x1);
}

int ss_poly_contains(const ssPoly2 *p, double x, double y)
{
  if (p->n < 3) return 0;
  /* inside a convex polygon of either orientation: no edge sees the point
   * on its other side; "on" allows a rounding-level distance, scaled by the
   * edge so that points at a vertex count too */
  int pos = 0, neg = 0;
  for (int i = 0, j = p->n - 1; i < p->n; j = i++) {
    double ex = p->x[i] - p->x[j], ey = p->y[i] - p->y[j];
    double rx = x - p->x[j], ry = y - p->y[j];
    double cr = ex * ry - ey * rx;
    double el = fabs(ex) + fabs(ey);
    double tol = 1e-12 * el * (el + fabs(rx) + fabs(ry));
    if (cr > tol) pos = 1;
    else if (cr < -tol) neg = 1;
    if (pos && neg) return 0;
  }
  return 1;
}

/* ---------------------------------------------------------------------- */
/* vertical ray casts                                                      */

void ss_shape_cast_init(ssShapeCast *c, const ssShape *s)
{
  const double *R = s->R;
  /* every field written below */
  c->type = s->type;
  ss_v3_copy(c->pos, s->pos);
  c->r = s->size[0];
  for (int k = 0; k < 3; k++) {
    /* the line (x, y, pos_z) + t e_z in the shape frame: o + t d with
     * o = R^T (x - pos_x, y - pos_y, 0) */
    c->ox[k] = R[k];
    c->oy[k] = R[3 + k];
    c->d[k] = R[6 + k];
    c->par[k] = c->d[k] == 0;
    c->id[k] = c->par[k] ? 0 : 1 / c->d[k];
    /* a box's half sizes; a cylinder's or capsule's half length (its
     * caps' slab is the third) */
    double h = s->type == SS_GEOM_BOX ? 0.5 * s->size[k] : 0.5 * s->size[1];
    c->h[k] = h;
    c->e[k] = copysign(h, c->d[k]);
    c->ne[k] = -c->e[k];
  }
  /* the lateral surface: a t^2 + 2 b t + c = 0 with a fixed */
  c->a = c->d[0] * c->d[0] + c->d[1] * c->d[1];
  c->ia = c->a > 0 ? 1 / c->a : 0;
  c->rr = c->r * c->r;
  double hl = 0.5 * s->size[1];
  for (int e = 0; e < 2; e++) {
    double sg = e ? 1 : -1;
    c->end[e][0] = s->pos[0] + sg * hl * R[2];
    c->end[e][1] = s->pos[1] + sg * hl * R[5];
    c->end[e][2] = s->pos[2] + sg * hl * R[8];
  }
}

int ss_shape_lowest_z(const ssShape *s, double x, double y, double *z)
{
  ssShapeCast c;
  ssCastRow r;
  ss_shape_cast_init(&c, s);
  ss_shape_cast_row(&c, y, &r);
  return ss_shape_cast_lowest_z(&c, &r, x, z);
}

/* ---------------------------------------------------------------------- */
/* candidates and widths                                                   */

static void put_point(double pts[][3], int *k, int max, const double p[3])
{
  if (*k < max) ss_v3_copy(pts[*k], p);
  if (*k < max) (*k)++;
}

int ss_shape_candidates(const ssShape *s, const double n[3], double pts[][3],
                        int max)
{
  const double *R = s->R, *c = s->pos;
  double p[3];
  int k = 0;
  if (max <= 0) return 0;

  switch (s->type) {
  case SS_GEOM_BOX:
    for (int i = 0; i < 8; i++) {
      double l[3] = {(i & 1) ? 0.5 * s->size[0] : -0.5 * s->size[0],
                     (i & 2) ? 0.5 * s->size[1] : -0.5 * s->size[1],
                     (i & 4) ? 0.5 * s->size[2] : -0.5 * s->size[2]};
      ss_m3_mulv(p, R, l);
      ss_v3_add(p, p, c);
      put_point(pts, &k, max, p);
    }
    break;
  case SS_GEOM_SPHERE:
    ss_v3_copy(p, c);
    ss_v3_addscl(p, n, -s->size[0]);
    put_point(pts, &k, max, p);
    break;
  case SS_GEOM_CAPSULE:
    for (int e = -1; e <= 1; e += 2) {
      ss_v3_set(p, c[0] + e * 0.5 * s->size[1] * R[2],
                c[1] + e * 0.5 * s->size[1] * R[5],
                c[2] + e * 0.5 * s->size[1] * R[8]);
      ss_v3_addscl(p, n, -s->size[0]);
      put_point(pts, &k, max, p);
    }
    break;
  case SS_GEOM_CYLINDER: {
    static const double c8[8] = {1, 0.70710678118654752, 0, -0.70710678118654752,
                                 -1, -0.70710678118654752, 0, 0.70710678118654752};
    double a[3] = {R[2], R[5], R[8]}, u[3] = {R[0], R[3], R[6]}, m[3];
    double r = s->size[0], hl = 0.5 * s->size[1];

    /* rim direction lowest along n: -n with its axial part removed */
    ss_v3_scale(m, n, -1);
    ss_v3_addscl(m, a, ss_v3_dot(n, a));
    if (ss_v3_normalize(m) < 1e-12) ss_v3_copy(m, u);

    /* the two lowest rim points first, then 7 more per cap at 45-degree
     * steps from the lowest.  The ring turns with the lowest direction m,
     * not with the body: a ring fixed on the body brought a rim point
     * down onto the support every eighth of a turn of a rolling wheel,
     * whose speculative contact (its approach taken linear over the
     * step) braked it, 13 % of the speed of a cylinder rolling at 1.33
     * m/s lost in 10 s on flat ground at 1 ms */
    double mp[3];
    ss_v3_cross(mp, a, m);
    for (int e = -1; e <= 1; e += 2) {
      ss_v3_copy(p, c);
      ss_v3_addscl(p, a, e * hl);
      ss_v3_addscl(p, m, r);
      put_point(pts, &k, max, p);
    }
    for (int e = -1; e <= 1; e += 2)
      for (int i = 1; i < 8; i++) {
        ss_v3_copy(p, c);
        ss_v3_addscl(p, a, e * hl);
        ss_v3_addscl(p, m, r * c8[i]);
        ss_v3_addscl(p, mp, r * c8[(i + 6) & 7]);
        put_point(pts, &k, max, p);
      }
    break;
  }
  default:
    break;
  }
  return k;
}

double ss_shape_width(const ssShape *s, const double n[3])
{
  const double *R = s->R;
  switch (s->type) {
  case SS_GEOM_BOX: {
    /* drop the axis most nearly along n; the shorter of the other two */
    int drop = 0;
    double best = -1;
    for (int k = 0; k < 3; k++) {
      double dk = fabs(n[0] * R[k] + n[1] * R[3 + k] + n[2] * R[6 + k]);
      if (dk > best) {
        best = dk;
        drop = k;
      }
    }
    return fmin(s->size[(drop + 1) % 3], s->size[(drop + 2) % 3]);
  }
  case SS_GEOM_CYLINDER: {
    /* axle within 45 degrees of the bed plane: a wheel, b = tread width */
    double an = fabs(n[0] * R[2] + n[1] * R[5] + n[2] * R[8]);
    if (an * an <= 0.5 * ss_v3_dot(n, n)) return s->size[1];
    return 2 * s->size[0];
  }
  case SS_GEOM_SPHERE:
  case SS_GEOM_CAPSULE:
    return 2 * s->size[0];
  default:
    return 0;
  }
}

/* ---------------------------------------------------------------------- */
/* signed distances and contacts between two shapes                        */

double ss_shape_sdf(const ssShape *s, const double p[3], double n[3])
{
  const double *R = s->R;
  double w[3], l[3], nl[3] = {0, 0, 0}, d;
  ss_v3_sub(w, p, s->pos);
  switch (s->type) {
  case SS_GEOM_SPHERE: {
    /* in the frame itself: no rotation to round through */
    double len = ss_v3_norm(w);
    if (len > 0) {
      ss_v3_set(n, w[0] / len, w[1] / len, w[2] / len);
    } else {
      ss_v3_set(n, 0, 0, 1);
    }
    return len - s->size[0];
  }
  case SS_GEOM_BOX: {
    ss_m3_mulvT(l, R, w);
    /* outside: from the box's nearest point (l clamped to it) */
    double e[3];
    int outside = 0;
    for (int k = 0; k < 3; k++) {
      double h = 0.5 * s->size[k];
      double c = l[k] < -h ? -h : (l[k] > h ? h : l[k]);
      e[k] = l[k] - c;
      outside |= e[k] != 0;
    }
    d = outside ? ss_v3_norm(e) : 0;
    if (d > 0) {
      /* division, not the reciprocal's product: the normal is then
       * e / |e| rounded once per component */
      ss_v3_set(nl, e[0] / d, e[1] / d, e[2] / d);
    } else {
      /* inside or on: the nearest face (the greatest |l_k| - h_k, <= 0),
       * the first axis on ties and the positive face at l_k = 0, so that
       * the same point always leaves by the same face */
      int best = 0;
      d = fabs(l[0]) - 0.5 * s->size[0];
      for (int k = 1; k < 3; k++) {
        double q = fabs(l[k]) - 0.5 * s->size[k];
        if (q > d) {
          d = q;
          best = k;
        }
      }
      nl[best] = l[best] >= 0 ? 1 : -1;
    }
    ss_m3_mulv(n, R, nl);
    return d;
  }
  case SS_GEOM_CAPSULE: {
    ss_m3_mulvT(l, R, w);
    /* from the nearest point of the axis segment */
    double hl = 0.5 * s->size[1];
    double t = l[2] < -hl ? -hl : (l[2] > hl ? hl : l[2]);
    double v[3] = {l[0], l[1], l[2] - t};
    double len = ss_v3_norm(v);
    if (len > 0) {
      ss_v3_set(nl, v[0] / len, v[1] / len, v[2] / len);
    } else {
      nl[0] = 1; /* on the segment: every way out as near; local +x */
    }
    ss_m3_mulv(n, R, nl);
    return len - s->size[0];
  }
  case SS_GEOM_CYLINDER: {
    ss_m3_mulvT(l, R, w);
    /* the 2-D problem in (radial distance q, axial z) against the
     * rectangle [0, r] x [-h, h] */
    double r = s->size[0], h = 0.5 * s->size[1];
    double q = hypot(l[0], l[1]);
    double rad[3] = {1, 0, 0}; /* on the axis: local +x */
    if (q > 0) ss_v3_set(rad, l[0] / q, l[1] / q, 0);
    double az = l[2] >= 0 ? 1 : -1;
    double dr = q - r, dz = fabs(l[2]) - h;
    if (dr > 0 && dz > 0) {
      /* beyond the rim: from the rim's nearest point */
      d = hypot(dr, dz);
      ss_v3_set(nl, rad[0] * dr / d, rad[1] * dr / d, az * dz / d);
    } else if (dr > 0 || (!(dz > 0) && dr > dz)) {
      /* outside the side, or inside nearer the side than a cap */
      d = dr;
      ss_v3_copy(nl, rad);
    } else {
      /* outside a cap, or inside as near a cap as the side or nearer */
      d = dz;
      nl[2] = az;
    }
    ss_m3_mulv(n, R, nl);
    return d;
  }
  default:
    return NAN;
  }
}

/* types ss_shape_pair_points takes */
static int pair_type(int t)
{
  return t == SS_GEOM_BOX || t == SS_GEOM_SPHERE || t == SS_GEOM_CYLINDER ||
         t == SS_GEOM_CAPSULE;
}

/* a shape's bounding radius about its centre: the scale of its
 * coordinates, for ss_shape_pair_points' tolerance */
static double shape_extent(const ssShape *s)
{
  switch (s->type) {
  case SS_GEOM_BOX:
    return 0.5 * ss_v3_norm(s->size);
  case SS_GEOM_CYLINDER:
    return hypot(s->size[0], 0.5 * s->size[1]);
  case SS_GEOM_CAPSULE:
    return s->size[0] + 0.5 * s->size[1];
  default:
    return s->size[0];
  }
}

/* The sphere of radius r (0: the point) at c tested against o: with
 * d = sdf_o(c) and o's normal m there, the point c - r m at gap d - r,
 * normal m (flip: -m, for b's candidates tested against a).  Writes *out
 * and returns 1 when the gap is within margin (NaN never is). */
static int sphere_contact(const ssShape *o, const double c[3], double r, int flip, int id,
                          double margin, ssPairPoint *out)
{
  double m[3];
  double gap = ss_shape_sdf(o, c, m) - r;
  if (!(gap <= margin)) return 0;
  ss_v3_copy(out->pos, c);
  if (r != 0) ss_v3_addscl(out->pos, m, -r);
  if (flip) ss_v3_scale(out->n, m, -1);
  else ss_v3_copy(out->n, m);
  out->gap = gap;
  out->id = id;
  return 1;
}

/* The candidates of s against o within margin, into out (room for 16) in
 * order of id (ids from base: 0 for a's, 16 for b's, whose normals are
 * flipped to run from b towards a).  Returns the count. */
static int side_contacts(const ssShape *s, const ssShape *o, int base, double margin,
                         ssPairPoint *out)
{
  static const double up[3] = {0, 0, 1}; /* a box's corners need no n */
  const double *R = s->R;
  const int flip = base != 0;
  double pts[16][3];
  int k = 0;
  switch (s->type) {
  case SS_GEOM_SPHERE:
    k += sphere_contact(o, s->pos, s->size[0], flip, base, margin, out + k);
    break;
  case SS_GEOM_CAPSULE: {
    double a[3] = {R[2], R[5], R[8]}, c[3], len = s->size[1], hl = 0.5 * len;
    for (int e = 0; e < 2; e++) {
      ss_v3_copy(c, s->pos);
      ss_v3_addscl(c, a, e ? hl : -hl);
      k += sphere_contact(o, c, s->size[0], flip, base + e, margin, out + k);
    }
    /* the segment's point nearest o's centre, where it is not an end's:
     * a capsule across a face touches it there, between two ends that may
     * both hang free */
    double w[3];
    ss_v3_sub(w, o->pos, s->pos);
    double t = ss_v3_dot(w, a), tol = 1e-9 * len;
    if (t + hl > tol && hl - t > tol) {
      ss_v3_copy(c, s->pos);
      ss_v3_addscl(c, a, t);
      k += sphere_contact(o, c, s->size[0], flip, base + 2, margin, out + k);
    }
    break;
  }
  case SS_GEOM_BOX:
  case SS_GEOM_CYLINDER: {
    /* a cylinder's rim placed from o's normal at its centre, towards o */
    double m[3];
    const double *dir = up;
    if (s->type == SS_GEOM_CYLINDER) {
      ss_shape_sdf(o, s->pos, m);
      dir = m;
    }
    int np = ss_shape_candidates(s, dir, pts, 16);
    for (int i = 0; i < np; i++)
      k += sphere_contact(o, pts[i], 0, flip, base + i, margin, out + k);
    break;
  }
  default:
    break;
  }
  return k;
}

/* 1 when q (one of b's) lies at p (one of a's kept) with the same normal
 * (tol: a length; normals to 1e-9): one contact found from both sides, as
 * where the two touch at a point both sides' candidates give (a sphere
 * resting on a box's corner) */
static int same_contact(const ssPairPoint *p, const ssPairPoint *q, double tol)
{
  for (int k = 0; k < 3; k++)
    if (!(fabs(p->n[k] - q->n[k]) <= 1e-9) || !(fabs(p->pos[k] - q->pos[k]) <= tol))
      return 0;
  return 1;
}

/* The closest points of the lines p + s da and q + t db, as s and t; 0
 * where the lines are parallel (the sine of their angle 1e-6 or less:
 * there corners, rims and ends meet) */
static int lines_closest(const double p[3], const double da[3], const double q[3],
                         const double db[3], double *s, double *t)
{
  double r[3];
  ss_v3_sub(r, p, q);
  double A = ss_v3_dot(da, da), B = ss_v3_dot(da, db), E = ss_v3_dot(db, db);
  double C = ss_v3_dot(da, r), F = ss_v3_dot(db, r), den = A * E - B * B;
  if (!(den > 1e-12 * A * E)) return 0;
  *s = (B * F - C * E) / den;
  *t = (A * F - B * C) / den;
  return 1;
}

/* Box edges: e = 4 i + bits, i the local axis the edge runs along, bit 0
 * the sign of its place on axis (i + 1) % 3, bit 1 on axis (i + 2) % 3
 * (set: +).  Its start p0 (at -size[i]/2 along i) and its vector d (to
 * its other end), in the frame. */
static void box_edge(const ssShape *s, int e, double p0[3], double d[3])
{
  int i = e >> 2, j = (i + 1) % 3, k = (i + 2) % 3;
  double l[3];
  l[i] = -0.5 * s->size[i];
  l[j] = (e & 1 ? 0.5 : -0.5) * s->size[j];
  l[k] = (e & 2 ? 0.5 : -0.5) * s->size[k];
  ss_m3_mulv(p0, s->R, l);
  ss_v3_add(p0, p0, s->pos);
  ss_v3_set(d, s->size[i] * s->R[i], s->size[i] * s->R[3 + i], s->size[i] * s->R[6 + i]);
}

/* a box's half extent along the unit u: sum of h_k |u . axis_k| */
static double box_radius(const ssShape *s, const double u[3])
{
  const double *R = s->R;
  double r = 0;
  for (int k = 0; k < 3; k++)
    r += 0.5 * s->size[k] * fabs(u[0] * R[k] + u[1] * R[3 + k] + u[2] * R[6 + k]);
  return r;
}

/* A colour 0..3 of each box edge (box_edge's numbering) such that the 4
 * edges of every face have 4 different colours: with the crossing's side
 * (below) it tells apart the up to 8 edge crossings of two faces. */
static const int edge_colour[12] = {0, 1, 2, 3, 2, 1, 3, 0, 3, 1, 0, 2};

/* The edge-edge contacts of two boxes (ss_shape_pair_points' rule), into
 * out (room for 8) in order of id (8..15).  Returns the count. */
static int edge_contacts(const ssShape *a, const ssShape *b, double margin, double eps,
                         ssPairPoint *out)
{
  const double tol = 1e-9; /* of an edge's length: its ends are corners' */
  double dc[3];
  ss_v3_sub(dc, a->pos, b->pos);
  /* the best separation S of the two along the 15 axes of the separating
   * axis test (the 6 face normals, the 9 cross products of an edge of
   * each): an edge pair is a contact only where it separates them within
   * eps as well as the best axis */
  double S = -INFINITY;
  for (int side = 0; side < 2; side++) {
    const ssShape *s = side ? b : a;
    for (int k = 0; k < 3; k++) {
      double u[3] = {s->R[k], s->R[3 + k], s->R[6 + k]};
      double sep = fabs(ss_v3_dot(dc, u)) - box_radius(a, u) - box_radius(b, u);
      if (sep > S) S = sep;
    }
  }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double ua[3] = {a->R[i], a->R[3 + i], a->R[6 + i]};
      double ub[3] = {b->R[j], b->R[3 + j], b->R[6 + j]}, u[3];
      ss_v3_cross(u, ua, ub);
      double len = ss_v3_norm(u);
      if (!(len > 1e-6)) continue; /* parallel: the face axes cover it */
      ss_v3_set(u, u[0] / len, u[1] / len, u[2] / len);
      double sep = fabs(ss_v3_dot(dc, u)) - box_radius(a, u) - box_radius(b, u);
      if (sep > S) S = sep;
    }
  ssPairPoint slot[8];
  int used[8] = {0};
  for (int ea = 0; ea < 12; ea++) {
    double pa0[3], da[3];
    box_edge(a, ea, pa0, da);
    for (int eb = 0; eb < 12; eb++) {
      double pb0[3], db[3], c[3], s, t;
      box_edge(b, eb, pb0, db);
      /* the closest points of the two lines (none where parallel: no
       * edge-edge normal, faces and corners meet there); a pair counts
       * only where both lie strictly inside their edges, where the
       * clamped segments' closest points are these same points */
      if (!lines_closest(pa0, da, pb0, db, &s, &t)) continue;
      if (!(s > tol && s < 1 - tol && t > tol && t < 1 - tol)) continue;
      ss_v3_cross(c, da, db);
      double cc = ss_v3_dot(c, c);
      double pa[3], pb[3], n[3];
      ss_v3_copy(pa, pa0);
      ss_v3_addscl(pa, da, s);
      ss_v3_copy(pb, pb0);
      ss_v3_addscl(pb, db, t);
      double cn = sqrt(cc);
      ss_v3_set(n, c[0] / cn, c[1] / cn, c[2] / cn);
      if (ss_v3_dot(dc, n) < 0) ss_v3_scale(n, n, -1);
      double w[3];
      ss_v3_sub(w, pa, pb);
      double gap = ss_v3_dot(w, n);
      if (!(gap <= margin)) continue;
      /* each edge within margin of its box's extreme along the normal:
       * a's lowest along n, b's highest */
      if (!(ss_v3_dot(pa, n) - (ss_v3_dot(a->pos, n) - box_radius(a, n)) <= margin + eps) ||
          !(ss_v3_dot(b->pos, n) + box_radius(b, n) - ss_v3_dot(pb, n) <= margin + eps))
        continue;
      /* no axis separates them better */
      if (!(gap >= S - eps)) continue;
      /* the midpoint within margin of both boxes: the two points meet */
      double mid[3], m[3];
      ss_v3_add(mid, pa, pb);
      ss_v3_scale(mid, mid, 0.5);
      if (!(ss_shape_sdf(a, mid, m) <= margin + eps) || !(ss_shape_sdf(b, mid, m) <= margin + eps))
        continue;
      /* the side of b's edge a's edge crosses it from: b's outward
       * direction at its edge across the normal, o = db x n turned away
       * from b's centre, against a's edge direction */
      double o[3], q[3];
      ss_v3_cross(o, db, n);
      ss_v3_sub(q, pb, b->pos);
      if (ss_v3_dot(o, q) < 0) ss_v3_scale(o, o, -1);
      int k = edge_colour[ea] + (ss_v3_dot(da, o) > 0 ? 4 : 0);
      if (used[k] && !(gap < slot[k].gap)) continue;
      used[k] = 1;
      ss_v3_copy(slot[k].pos, mid);
      ss_v3_copy(slot[k].n, n);
      slot[k].gap = gap;
      slot[k].id = 8 + k;
    }
  }
  int cnt = 0;
  for (int k = 0; k < 8; k++)
    if (used[k]) out[cnt++] = slot[k];
  return cnt;
}

/* The crossings of box x's edges with round y's side (a cylinder's or a
 * capsule's; ss_shape_pair_points' rule), into out (room for 4) in order
 * of id (base + 8 + colour: the box's ids past its corners); flip as
 * side_contacts' for the box's candidates.  Returns the count. */
static int edge_side_contacts(const ssShape *x, const ssShape *y, int base, double margin,
                              ssPairPoint *out)
{
  const double tol = 1e-9; /* of the edge's and the axis's lengths */
  const double a[3] = {y->R[2], y->R[5], y->R[8]}, hl = 0.5 * y->size[1];
  ssPairPoint slot[4];
  int used[4] = {0};
  for (int e = 0; e < 12; e++) {
    double p0[3], d[3], sp, t;
    box_edge(x, e, p0, d);
    /* the closest points of the edge's line, p0 + sp d, and the axis's,
     * pos + t a (|a| = 1) */
    if (!lines_closest(p0, d, y->pos, a, &sp, &t)) continue;
    if (!(sp > tol && sp < 1 - tol && fabs(t) <= hl + margin)) continue;
    double p[3];
    ss_v3_copy(p, p0);
    ss_v3_addscl(p, d, sp);
    ssPairPoint c;
    int k = edge_colour[e];
    if (!sphere_contact(y, p, 0, base != 0, base + 8 + k, margin, &c)) continue;
    if (used[k] && !(c.gap < slot[k].gap)) continue;
    used[k] = 1;
    slot[k] = c;
  }
  int cnt = 0;
  for (int k = 0; k < 4; k++)
    if (used[k]) out[cnt++] = slot[k];
  return cnt;
}

static int is_round(int t)
{
  return t == SS_GEOM_CYLINDER || t == SS_GEOM_CAPSULE;
}

/* The closest points of round shapes a's and b's axis lines, a->pos + s
 * ua and b->pos + t ub (their unit local z), as s and t, with ua x ub in
 * c; 0 where the axes are parallel (the sine of their angle 1e-6 or
 * less: there the rims and ends meet) */
static int axes_closest(const ssShape *a, const ssShape *b, double *s, double *t, double c[3])
{
  const double ua[3] = {a->R[2], a->R[5], a->R[8]}, ub[3] = {b->R[2], b->R[5], b->R[8]};
  ss_v3_cross(c, ua, ub);
  return lines_closest(a->pos, ua, b->pos, ub, s, t);
}

/* The contact of two round shapes' sides (cylinders' or capsules') where
 * their axes cross (ss_shape_pair_points' rule): 1 with it in *out, its
 * point on b's side where on_b, else on a's; 0 where there is none. */
static int axis_contact(const ssShape *a, const ssShape *b, double margin, int on_b,
                        ssPairPoint *out)
{
  const double tol = 1e-9; /* of the half lengths */
  const double ua[3] = {a->R[2], a->R[5], a->R[8]}, ub[3] = {b->R[2], b->R[5], b->R[8]};
  const double ha = 0.5 * a->size[1], hb = 0.5 * b->size[1];
  double c[3], r[3], sa, tb;
  if (!axes_closest(a, b, &sa, &tb, c)) return 0;
  if (!(fabs(sa) < ha * (1 - tol) && fabs(tb) < hb * (1 - tol))) return 0;
  ss_v3_sub(r, a->pos, b->pos);
  double cc = ss_v3_dot(c, c), pa[3], pb[3], w[3], n[3];
  ss_v3_copy(pa, a->pos);
  ss_v3_addscl(pa, ua, sa);
  ss_v3_copy(pb, b->pos);
  ss_v3_addscl(pb, ub, tb);
  ss_v3_sub(w, pa, pb);
  /* the common normal of the axes, from b's towards a's (where they
   * meet, towards a's centre) */
  double cn = sqrt(cc), side = ss_v3_dot(w, c);
  if (side == 0) side = ss_v3_dot(r, c);
  ss_v3_scale(n, c, side < 0 ? -1 / cn : 1 / cn);
  double gap = ss_v3_dot(w, n) - a->size[0] - b->size[0];
  if (!(gap <= margin)) return 0;
  if (on_b) {
    ss_v3_copy(out->pos, pb);
    ss_v3_addscl(out->pos, n, b->size[0]);
  } else {
    ss_v3_copy(out->pos, pa);
    ss_v3_addscl(out->pos, n, -a->size[0]);
  }
  ss_v3_copy(out->n, n);
  out->gap = gap;
  return 1;
}

/* The contact of round shape x lying across cylinder y's cap (ss_shape_
 * pair_points' rule): where the closest points of the two axes' lines
 * lie strictly between x's ends and past y's end by at most r_x + margin,
 * x's surface point from the closest point on x's axis towards y's cap
 * (against the cap's normal, taken across x's axis), as x's candidate
 * against y (flip as side_contacts' for x's candidates).  1 with it in
 * *out (its id not set), 0 where there is none. */
static int cap_contact(const ssShape *x, const ssShape *y, double margin, int flip,
                       ssPairPoint *out)
{
  const double tol = 1e-9; /* of the half lengths */
  const double ux[3] = {x->R[2], x->R[5], x->R[8]}, uy[3] = {y->R[2], y->R[5], y->R[8]};
  const double hx = 0.5 * x->size[1], hy = 0.5 * y->size[1], rx = x->size[0];
  double c[3], sx, ty;
  if (!axes_closest(x, y, &sx, &ty, c)) return 0;
  if (!(fabs(sx) < hx * (1 - tol) && fabs(ty) >= hy * (1 - tol) && fabs(ty) <= hy + rx + margin))
    return 0;
  /* the cap's normal, across x's axis */
  double nc[3], d[3], p[3];
  ss_v3_scale(nc, uy, ty > 0 ? 1 : -1);
  ss_v3_copy(d, nc);
  ss_v3_addscl(d, ux, -ss_v3_dot(nc, ux));
  if (!(ss_v3_normalize(d) > 1e-6)) return 0;
  ss_v3_copy(p, x->pos);
  ss_v3_addscl(p, ux, sx);
  ss_v3_addscl(p, d, -rx);
  return sphere_contact(y, p, 0, flip, 0, margin, out);
}

/* p into all[0..*k), kept in order of id: where no contact holds its id
 * and none is the same point with the same normal (same_contact) */
static void put_extra(ssPairPoint *all, int *k, const ssPairPoint *p, double tol)
{
  int at = *k;
  for (int i = 0; i < *k; i++) {
    if (all[i].id == p->id || same_contact(&all[i], p, tol)) return;
    if (all[i].id > p->id && at == *k) at = i;
  }
  for (int i = *k; i > at; i--) all[i] = all[i - 1];
  all[at] = *p;
  (*k)++;
}

int ss_shape_pair_points(const ssShape *a, const ssShape *b, double margin,
                         ssPairPoint *out, int max)
{
  if (max <= 0 || !pair_type(a->type) || !pair_type(b->type)) return 0;
  /* (one more: two cylinders' 32 candidates and their sides' contact) */
  ssPairPoint all[SS_PAIR_POINTS_MAX + 1], bs[16];
  int k = side_contacts(a, b, 0, margin, all), ka = k;
  /* two boxes: their edges' crossings (ids 8..15, after a's corners) */
  if (a->type == SS_GEOM_BOX && b->type == SS_GEOM_BOX)
    k += edge_contacts(a, b, margin, 1e-9 * (shape_extent(a) + shape_extent(b)), all + k);
  /* a box and a cylinder or a capsule: the box's edges across the
   * other's side (ids 8..11 after a box's corners, 24..27 after b's) */
  if (a->type == SS_GEOM_BOX && is_round(b->type))
    k += edge_side_contacts(a, b, 0, margin, all + k);
  /* two spheres touch at one point, which a's candidate gives exactly */
  if (!(a->type == SS_GEOM_SPHERE && b->type == SS_GEOM_SPHERE)) {
    int nb = side_contacts(b, a, 16, margin, bs);
    double tol = 1e-9 * (shape_extent(a) + shape_extent(b));
    for (int j = 0; j < nb; j++) {
      int dup = 0;
      for (int i = 0; i < ka && !dup; i++) dup = same_contact(&all[i], &bs[j], tol);
      if (!dup) all[k++] = bs[j];
    }
    if (b->type == SS_GEOM_BOX && is_round(a->type))
      k += edge_side_contacts(b, a, 16, margin, all + k);
    /* two round shapes: their sides where the axes cross, on a's side
     * with a capsule a's id 3 or a cylinder a's id 5 (its rim point
     * farthest from b, which gives way to it), but on a capsule b's side
     * (id 19) against a cylinder a */
    ssPairPoint x;
    int cyl_a = a->type == SS_GEOM_CYLINDER, cyl_b = b->type == SS_GEOM_CYLINDER;
    int on_b = cyl_a && !cyl_b, id = -1;
    if (is_round(a->type) && is_round(b->type)) {
      if (axis_contact(a, b, margin, on_b, &x))
        id = on_b ? 19 : cyl_a ? 5 : 3;
      /* else one lying across the other's cap (a log across a post's
       * top), on the one lying: a's slot 3 or 5, b's 19 or 21 */
      else if (cyl_b && cap_contact(a, b, margin, 0, &x))
        id = cyl_a ? 5 : 3;
      else if (cyl_a && cap_contact(b, a, margin, 1, &x))
        id = cyl_b ? 21 : 19;
    }
    if (id >= 0) {
      x.id = id;
      /* a cylinder's slot (5, 21) is its farthest rim point's, which gives
       * way to it */
      if (id == 5 || id == 21)
        for (int i = 0; i < k; i++)
          if (all[i].id == id) all[i] = x;
      put_extra(all, &k, &x, tol);
    }
  }
  if (k > max) k = max;
  for (int i = 0; i < k; i++) out[i] = all[i];
  return k;
}
