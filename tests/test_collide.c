/* test_collide.c -- footprints, cell quadrature weights, exact vertical ray
 * casts, contact candidates, widths and bounds of the collider shapes
 * (DESIGN 2.4, 2.6), checked against closed forms. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "collide.h"
#include "sort_runs.h"
#include "ss_math.h"
#include "tap.h"

#define PI 3.14159265358979323846

/* deterministic xorshift64* so every run sees the same scenes */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static double urand(double lo, double hi)
{
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  uint64_t v = rng_state * 0x2545f4914f6cdd1dull;
  return lo + (hi - lo) * ((double)(v >> 11) / 9007199254740992.0);
}

static void rot_z(double R[9], double a)
{
  double c = cos(a), s = sin(a);
  double t[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
  memcpy(R, t, sizeof t);
}

static void rot_x(double R[9], double a)
{
  double c = cos(a), s = sin(a);
  double t[9] = {1, 0, 0, 0, c, -s, 0, s, c};
  memcpy(R, t, sizeof t);
}

static void rot_y(double R[9], double a)
{
  double c = cos(a), s = sin(a);
  double t[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
  memcpy(R, t, sizeof t);
}

static void rot_random(double R[9])
{
  double q[4];
  do {
    for (int i = 0; i < 4; i++) q[i] = urand(-1, 1);
  } while (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 1);
  ss_quat_normalize(q);
  ss_quat_to_mat(R, q);
}

/* a wheel: axis (local z) horizontal along heading psi, spun by phi */
static void rot_wheel(double R[9], double psi, double phi)
{
  double A[9], B[9], C[9];
  rot_z(A, phi);          /* spin about the axle */
  rot_x(B, -0.5 * PI);    /* local z -> frame y */
  ss_m3_mul(C, B, A);
  rot_z(A, psi);          /* heading */
  ss_m3_mul(R, A, C);
}

/* axis tilted by phi from vertical (towards frame x), then a yaw */
static void rot_tilt(double R[9], double phi, double psi)
{
  double A[9], B[9];
  rot_y(A, phi);
  rot_z(B, psi);
  ss_m3_mul(R, B, A);
}

static ssShape make_shape(int type, double s0, double s1, double s2,
                          double x, double y, double z, const double R[9])
{
  ssShape s;
  s.type = type;
  s.size[0] = s0; s.size[1] = s1; s.size[2] = s2;
  s.pos[0] = x; s.pos[1] = y; s.pos[2] = z;
  memcpy(s.R, R, sizeof s.R);
  return s;
}

/* the sum of cell weights over a vertex grid of spacing dx, dy whose
 * origin is (gx, gy); also the area-weighted centroid */
static double grid_sum(const ssPoly2 *p, double dx, double dy, double gx,
                       double gy, double *mx, double *my)
{
  double xlo = p->x[0], xhi = p->x[0], ylo = p->y[0], yhi = p->y[0];
  for (int i = 1; i < p->n; i++) {
    xlo = fmin(xlo, p->x[i]); xhi = fmax(xhi, p->x[i]);
    ylo = fmin(ylo, p->y[i]); yhi = fmax(yhi, p->y[i]);
  }
  int i0 = (int)floor((xlo - gx) / dx) - 1, i1 = (int)ceil((xhi - gx) / dx) + 1;
  int j0 = (int)floor((ylo - gy) / dy) - 1, j1 = (int)ceil((yhi - gy) / dy) + 1;
  double sum = 0, sx = 0, sy = 0;
  for (int j = j0; j <= j1; j++)
    for (int i = i0; i <= i1; i++) {
      double x = gx + i * dx, y = gy + j * dy, cx = 0, cy = 0;
      double a = ss_poly_rect_area(p, x - 0.5 * dx, x + 0.5 * dx, y - 0.5 * dy,
                                   y + 0.5 * dy, &cx, &cy);
      sum += a;
      sx += a * cx;
      sy += a * cy;
    }
  if (mx) *mx = sum > 0 ? sx / sum : 0;
  if (my) *my = sum > 0 ? sy / sum : 0;
  return sum;
}

/* 1 if the polygon is strictly convex and counter-clockwise */
static int poly_ccw_convex(const ssPoly2 *p)
{
  if (p->n < 3) return 0;
  for (int i = 0; i < p->n; i++) {
    int j = (i + 1) % p->n, k = (i + 2) % p->n;
    double cr = (p->x[j] - p->x[i]) * (p->y[k] - p->y[j]) -
                (p->y[j] - p->y[i]) * (p->x[k] - p->x[j]);
    if (!(cr > 0)) return 0;
  }
  return 1;
}

/* the extent of a polygon along the unit direction (ux, uy) */
static double poly_extent(const ssPoly2 *p, double ux, double uy)
{
  double lo = INFINITY, hi = -INFINITY;
  for (int i = 0; i < p->n; i++) {
    double t = p->x[i] * ux + p->y[i] * uy;
    lo = fmin(lo, t);
    hi = fmax(hi, t);
  }
  return hi - lo;
}

static double rel(double got, double want)
{
  return fabs(got - want) / fabs(want);
}

/* a plate's loaded area is its true area for any placement and heading */
static void test_plate_quadrature(void)
{
  double worst = 0, worst_c = 0;
  int n4 = 1;
  for (int trial = 0; trial < 40; trial++) {
    double R[9];
    rot_z(R, urand(-PI, PI));
    double cx = urand(-3, 3), cy = urand(-3, 3);
    ssShape s = make_shape(SS_GEOM_BOX, 0.4, 0.6, 0.05, cx, cy, urand(0, 1), R);
    ssPoly2 p;
    ss_shape_footprint(&s, &p);
    if (p.n != 4) n4 = 0;
    double dx = urand(0.01, 0.05), dy = urand(0.01, 0.05), mx, my;
    double a = grid_sum(&p, dx, dy, urand(-1, 1), urand(-1, 1), &mx, &my);
    worst = fmax(worst, rel(a, 0.24));
    worst_c = fmax(worst_c, fmax(fabs(mx - cx), fabs(my - cy)));
  }
  ok(n4, "a flat plate at any heading has a 4-gon footprint");
  ok(worst <= 1e-12, "plate 0.4x0.6, 40 random placements/headings/grids: "
     "sum of cell weights = 0.24 (worst rel err %.3g)", worst);
  ok(worst_c <= 1e-12, "the weighted centroid of the cells is the plate centre "
     "(worst err %.3g m)", worst_c);

  /* edges exactly on cell boundaries */
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  ssShape s = make_shape(SS_GEOM_BOX, 0.4, 0.6, 0.05, 0.025, 0.025, 0.1, I);
  ssPoly2 p;
  ss_shape_footprint(&s, &p);
  close_enough(grid_sum(&p, 0.05, 0.05, 0, 0, NULL, NULL), 0.24, 0.24e-13,
               "plate with edges on cell boundaries (5 cm): area");
  close_enough(grid_sum(&p, 0.01, 0.02, 0, 0.015, NULL, NULL), 0.24, 0.24e-13,
               "plate with edges on cell boundaries (1x2 cm): area");
}

/* box footprints: exact hull of the 8 projected corners */
static void test_box_footprint(void)
{
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, R[9];
  ssPoly2 p;
  ssShape s = make_shape(SS_GEOM_BOX, 0.3, 0.5, 0.2, 1, 2, 3, I);
  ss_shape_footprint(&s, &p);
  ok(p.n == 4 && poly_ccw_convex(&p), "axis-aligned box: CCW 4-gon (n = %d)", p.n);
  close_enough(ss_poly_area(&p), 0.15, 1e-15, "axis-aligned box: footprint area");

  /* tilted about x only: corners collapse pairwise onto the x = +-hx sides */
  rot_x(R, 0.4);
  R[1] = R[2] = R[3] = R[6] = 0;
  s = make_shape(SS_GEOM_BOX, 0.3, 0.5, 0.2, 0, 0, 0, R);
  ss_shape_footprint(&s, &p);
  ok(p.n == 4 && poly_ccw_convex(&p), "box tilted about x: collinear corners removed (n = %d)", p.n);
  close_enough(ss_poly_area(&p), 0.3 * (0.5 * cos(0.4) + 0.2 * sin(0.4)), 1e-15,
               "box tilted about x: footprint area");

  /* random orientation: projected area of a box = sum of face areas |n_z| */
  double worst = 0;
  int convex = 1, inside = 1;
  for (int trial = 0; trial < 200; trial++) {
    rot_random(R);
    double sx = urand(0.05, 1), sy = urand(0.05, 1), sz = urand(0.05, 1);
    s = make_shape(SS_GEOM_BOX, sx, sy, sz, urand(-5, 5), urand(-5, 5), 0, R);
    ss_shape_footprint(&s, &p);
    double want = sy * sz * fabs(R[6]) + sx * sz * fabs(R[7]) + sx * sy * fabs(R[8]);
    worst = fmax(worst, rel(ss_poly_area(&p), want));
    if (!poly_ccw_convex(&p) || p.n > 6) convex = 0;
    for (int i = 0; i < 8; i++) {
      double l[3] = {(i & 1) ? sx / 2 : -sx / 2, (i & 2) ? sy / 2 : -sy / 2,
                     (i & 4) ? sz / 2 : -sz / 2}, w[3];
      ss_m3_mulv(w, R, l);
      if (!ss_poly_contains(&p, s.pos[0] + w[0], s.pos[1] + w[1])) inside = 0;
    }
  }
  ok(worst <= 1e-13, "random boxes: footprint area = projected area (worst rel %.3g)", worst);
  ok(convex, "random boxes: footprints are strictly convex CCW with <= 6 vertices");
  ok(inside, "random boxes: every projected corner lies in the footprint");
}

/* the regular nside-gon prism of circumradius r and height hz, centred:
 * its corners (bottom, top alternating) into v (2 nside x 3) */
static void prism_points(double *v, int nside, double r, double hz)
{
  for (int i = 0; i < nside; i++)
    for (int t = 0; t < 2; t++) {
      double *p = v + 3 * (2 * i + t);
      p[0] = r * cos(2 * PI * i / nside);
      p[1] = r * sin(2 * PI * i / nside);
      p[2] = t ? 0.5 * hz : -0.5 * hz;
    }
}

/* point-set footprints (a mesh's, ss_points_footprint): the hull of the
 * projected points, exact; more than SS_POLY_MAX hull vertices cut down
 * inside the hull */
static void test_points_footprint(void)
{
  static double v[3 * (SS_HULL_POINTS_MAX + 1)];
  double R[9], o[3] = {0.7, -1.3, 0.2};
  ssPoly2 p, q;
  /* its own random stream: the tests after it see the draws they saw
   * before it came */
  const uint64_t rng_saved = rng_state;
  rng_state = 0x2545f4914f6cdd1dull;

  /* a box's 8 corners at random orientations: the box's own footprint */
  double worst = 0;
  int convex = 1;
  for (int trial = 0; trial < 200; trial++) {
    rot_random(R);
    double sx = urand(0.05, 1), sy = urand(0.05, 1), sz = urand(0.05, 1);
    for (int i = 0; i < 8; i++) {
      v[3 * i] = (i & 1) ? sx / 2 : -sx / 2;
      v[3 * i + 1] = (i & 2) ? sy / 2 : -sy / 2;
      v[3 * i + 2] = (i & 4) ? sz / 2 : -sz / 2;
    }
    ssShape s = make_shape(SS_GEOM_BOX, sx, sy, sz, o[0], o[1], o[2], R);
    ss_shape_footprint(&s, &q);
    int nh = ss_points_footprint(v, 8, R, o, &p);
    worst = fmax(worst, rel(ss_poly_area(&p), ss_poly_area(&q)));
    if (!poly_ccw_convex(&p) || p.n != q.n || nh != p.n) convex = 0;
  }
  ok(worst <= 1e-13, "box corners as points, random orientations: the box's footprint area "
     "(worst rel %.3g)", worst);
  ok(convex, "  strictly convex CCW, as many vertices as the box's footprint");

  /* a 64-gon prism standing, any heading, with points inside it: the
   * 64-gon (top and bottom project onto each other) */
  const int ns = 64;
  double r = 0.2, want = 0.5 * ns * r * r * sin(2 * PI / ns);
  worst = 0;
  int n64 = 1;
  for (int trial = 0; trial < 50; trial++) {
    prism_points(v, ns, r, 0.1);
    int n = 2 * ns;
    for (int k = 0; k < 20; k++, n++) {
      double a = urand(-PI, PI), t = urand(0, 0.95 * r * cos(PI / ns));
      v[3 * n] = t * cos(a);
      v[3 * n + 1] = t * sin(a);
      v[3 * n + 2] = urand(-0.05, 0.05);
    }
    rot_z(R, urand(-PI, PI));
    int nh = ss_points_footprint(v, n, R, o, &p);
    worst = fmax(worst, rel(ss_poly_area(&p), want));
    if (nh != ns || p.n != ns || !poly_ccw_convex(&p)) n64 = 0;
  }
  ok(n64, "64-gon prism with inner points, any heading: a convex CCW 64-gon");
  ok(worst <= 1e-13, "  its area is the 64-gon's (worst rel %.3g)", worst);

  /* a 256-gon prism standing: the hull's 256 vertices cut down to
   * SS_POLY_MAX, every one kept a hull vertex, losing a little area */
  const int nb = 256;
  prism_points(v, nb, r, 0.1);
  rot_z(R, 0.3);
  int nh = ss_points_footprint(v, 2 * nb, R, o, &p);
  double big = 0.5 * nb * r * r * sin(2 * PI / nb);
  int on_hull = 1;
  for (int i = 0; i < p.n; i++)
    if (fabs(hypot(p.x[i] - o[0], p.y[i] - o[1]) - r) > 1e-12) on_hull = 0;
  ok(nh == nb && p.n == SS_POLY_MAX && poly_ccw_convex(&p) && on_hull,
     "256-gon prism: a hull of %d vertices cut down to %d (SS_POLY_MAX %d), convex CCW, "
     "its vertices the hull's", nh, p.n, SS_POLY_MAX);
  double lost = (big - ss_poly_area(&p)) / big;
  ok(lost > 0 && lost < 2e-4, "  it loses %.3g of the area (< 2e-4)", lost);

  /* more points than the buffers take: refused, an empty polygon */
  nh = ss_points_footprint(v, SS_HULL_POINTS_MAX + 1, R, o, &p);
  ok(nh == 0 && p.n == 0, "more than SS_HULL_POINTS_MAX points: refused (an empty polygon)");
  /* all on one vertical line: a single point, no area */
  for (int i = 0; i < 5; i++) {
    v[3 * i] = v[3 * i + 1] = 0;
    v[3 * i + 2] = i;
  }
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  nh = ss_points_footprint(v, 5, I, o, &p);
  ok(nh == 1 && p.n == 1 && ss_poly_area(&p) == 0 &&
         ss_poly_rect_area(&p, -10, 10, -10, 10, NULL, NULL) == 0,
     "points on one vertical line: one point, no area");
  rng_state = rng_saved;
}

/* round shapes: area-matched polygons, exact tread width */
static void test_round_footprints(void)
{
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, R[9];
  ssPoly2 p;
  double r = 0.3, L = 0.25;

  ssShape s = make_shape(SS_GEOM_SPHERE, r, 0, 0, 0.7, -0.2, 1, I);
  ss_shape_footprint(&s, &p);
  ok(p.n == SS_FOOTPRINT_SEGMENTS && poly_ccw_convex(&p),
     "sphere footprint: CCW %d-gon (n = %d)", SS_FOOTPRINT_SEGMENTS, p.n);
  ok(rel(ss_poly_area(&p), PI * r * r) <= 1e-14, "sphere footprint area = pi r^2 "
     "(rel %.3g)", rel(ss_poly_area(&p), PI * r * r));
  ok(rel(grid_sum(&p, 0.013, 0.021, 0.3, 0.1, NULL, NULL), PI * r * r) <= 1e-12,
     "sphere: cell weights sum to pi r^2");
  ok(ss_poly_contains(&p, 0.7, -0.2) && !ss_poly_contains(&p, 0.7 + 1.01 * r, -0.2),
     "sphere footprint contains its centre, not a point at 1.01 r");

  /* a lying wheel: a 2r x L rectangle whatever its heading and spin */
  double worst = 0, worst_w = 0, a0 = -1, spin_var = 0;
  int small = 1;
  for (int trial = 0; trial < 50; trial++) {
    double psi = urand(-PI, PI);
    rot_wheel(R, psi, urand(-PI, PI));
    s = make_shape(SS_GEOM_CYLINDER, r, L, 0, urand(-2, 2), urand(-2, 2), r, R);
    ss_shape_footprint(&s, &p);
    if (p.n != 4 || !poly_ccw_convex(&p)) small = 0;
    double a = ss_poly_area(&p);
    worst = fmax(worst, rel(a, 2 * r * L));
    /* frame y of the wheel is the axle; across it the width is 2r */
    worst_w = fmax(worst_w, rel(poly_extent(&p, cos(psi), sin(psi)), 2 * r));
    worst_w = fmax(worst_w, rel(poly_extent(&p, -sin(psi), cos(psi)), L));
    if (a0 < 0) a0 = a;
    spin_var = fmax(spin_var, rel(a, a0));
  }
  ok(worst <= 1e-12, "lying wheel: footprint area = 2 r L (worst rel %.3g)", worst);
  ok(worst_w <= 1e-12, "lying wheel: footprint is 2r across, L along the axle "
     "(worst rel %.3g)", worst_w);
  ok(spin_var <= 1e-13, "lying wheel: area does not change with heading or spin");
  ok(small, "lying wheel: the footprint is a CCW 4-gon");

  /* standing cylinder: a disc */
  s = make_shape(SS_GEOM_CYLINDER, r, L, 0, 0, 0, 0, I);
  ss_shape_footprint(&s, &p);
  ok(rel(ss_poly_area(&p), PI * r * r) <= 1e-13 && p.n == SS_FOOTPRINT_SEGMENTS,
     "standing cylinder: a disc of area pi r^2 (n = %d)", p.n);

  /* tilted by phi: pi r^2 |cos phi| + 2 r L sin phi */
  worst = 0;
  small = 1;
  for (int trial = 0; trial < 50; trial++) {
    double phi = urand(0, PI), psi = urand(-PI, PI);
    rot_tilt(R, phi, psi);
    s = make_shape(SS_GEOM_CYLINDER, r, L, 0, urand(-2, 2), urand(-2, 2), 0, R);
    ss_shape_footprint(&s, &p);
    if (p.n > SS_POLY_MAX || !poly_ccw_convex(&p)) small = 0;
    worst = fmax(worst, rel(ss_poly_area(&p),
                            PI * r * r * fabs(cos(phi)) + 2 * r * L * sin(phi)));
  }
  ok(small, "tilted cylinders: convex CCW footprints, <= SS_POLY_MAX vertices");
  ok(worst <= 1e-12, "tilted cylinders: area = pi r^2 |cos| + 2 r L sin (worst rel %.3g)", worst);

  /* nearly lying (a wheel's camber, 1e-2 to 1e-7 rad): thin caps, the
   * footprint swept along the axle (collide.c, swept_hull) */
  worst = 0;
  small = 1;
  for (int trial = 0; trial < 60; trial++) {
    double eps = pow(10, -2 - 5 * urand(0, 1)) * (trial % 2 ? 1 : -1);
    double phi = 0.5 * PI + eps, psi = urand(-PI, PI);
    rot_tilt(R, phi, psi);
    s = make_shape(SS_GEOM_CYLINDER, r, L, 0, urand(-2, 2), urand(-2, 2), r, R);
    ss_shape_footprint(&s, &p);
    if (p.n > SS_POLY_MAX || !poly_ccw_convex(&p)) small = 0;
    worst = fmax(worst, rel(ss_poly_area(&p),
                            PI * r * r * fabs(cos(phi)) + 2 * r * L * sin(phi)));
  }
  ok(small && worst <= 1e-12,
     "nearly lying cylinders: convex CCW footprints, area = pi r^2 |cos| + 2 r L sin "
     "(worst rel %.3g)", worst);

  /* capsules */
  rot_wheel(R, 0.3, 1.1);
  s = make_shape(SS_GEOM_CAPSULE, r, L, 0, 0.2, 0.1, r, R);
  ss_shape_footprint(&s, &p);
  ok(rel(ss_poly_area(&p), PI * r * r + 2 * r * L) <= 1e-13,
     "lying capsule: area = pi r^2 + 2 r L (rel %.3g)",
     rel(ss_poly_area(&p), PI * r * r + 2 * r * L));
  ok(rel(grid_sum(&p, 0.02, 0.03, 0.01, 0, NULL, NULL), PI * r * r + 2 * r * L) <= 1e-12,
     "lying capsule: cell weights sum to its area");
  s = make_shape(SS_GEOM_CAPSULE, r, L, 0, 0, 0, 0, I);
  ss_shape_footprint(&s, &p);
  ok(rel(ss_poly_area(&p), PI * r * r) <= 1e-13 && p.n == SS_FOOTPRINT_SEGMENTS,
     "standing capsule: a disc (n = %d)", p.n);
  worst = 0;
  for (int trial = 0; trial < 50; trial++) {
    double phi = urand(0, PI);
    rot_tilt(R, phi, urand(-PI, PI));
    s = make_shape(SS_GEOM_CAPSULE, r, L, 0, urand(-2, 2), urand(-2, 2), 0, R);
    ss_shape_footprint(&s, &p);
    worst = fmax(worst, rel(ss_poly_area(&p), PI * r * r + 2 * r * L * sin(phi)));
  }
  ok(worst <= 1e-12, "tilted capsules: area = pi r^2 + 2 r L sin (worst rel %.3g)", worst);
}

/* clipping against cells */
static void test_poly_clip(void)
{
  ssPoly2 sq = {4, {0, 1, 1, 0}, {0, 0, 1, 1}};
  ssPoly2 tri = {3, {0, 1, 0}, {0, 0, 1}};
  ssPoly2 cw = {4, {0, 0, 1, 1}, {0, 1, 1, 0}};
  double cx = -9, cy = -9, a;

  close_enough(ss_poly_area(&sq), 1, 0, "CCW unit square: area +1");
  close_enough(ss_poly_area(&cw), -1, 0, "CW unit square: area -1");

  a = ss_poly_rect_area(&sq, 0.5, 1.5, 0.25, 0.75, &cx, &cy);
  ok(a == 0.25 && cx == 0.75 && cy == 0.5, "square and an overlapping cell: 0.25 at "
     "(0.75, 0.5) (got %.17g at %.17g, %.17g)", a, cx, cy);
  a = ss_poly_rect_area(&tri, 0, 1, 0, 1, &cx, &cy);
  ok(fabs(a - 0.5) <= 1e-16 && fabs(cx - 1.0 / 3) <= 1e-16 && fabs(cy - 1.0 / 3) <= 1e-16,
     "triangle inside a cell: 0.5 at (1/3, 1/3)");
  a = ss_poly_rect_area(&tri, 0.4, 0.7, 0.4, 0.7, &cx, &cy);
  ok(fabs(a - 0.02) <= 1e-16 && fabs(cx - (0.4 + 0.2 / 3)) <= 1e-15 &&
     fabs(cy - (0.4 + 0.2 / 3)) <= 1e-15,
     "hypotenuse cutting a cell's corner: 0.02 at (0.4 + 0.2/3, same) (got %.17g)", a);
  a = ss_poly_rect_area(&sq, 0.2, 0.3, 0.6, 0.9, &cx, &cy);
  ok(fabs(a - 0.03) <= 1e-17 && fabs(cx - 0.25) <= 1e-16 && fabs(cy - 0.75) <= 1e-16,
     "cell inside the polygon: full cell area at its centre");
  ok(ss_poly_rect_area(&sq, 1.5, 2, 0, 1, NULL, NULL) == 0, "disjoint cell: 0");
  ok(ss_poly_rect_area(&sq, 1, 2, 0, 1, NULL, NULL) == 0, "cell touching an edge: 0");
  ok(ss_poly_rect_area(&sq, 0.5, 0.5, 0, 1, NULL, NULL) == 0, "empty cell: 0");
  close_enough(ss_poly_rect_area(&cw, 0.5, 1.5, 0, 1, NULL, NULL), 0.5, 1e-16,
               "a CW polygon still gives a positive area");

  ok(ss_poly_contains(&sq, 0.5, 0.5), "contains: interior point");
  ok(ss_poly_contains(&sq, 1, 0.5) && ss_poly_contains(&sq, 0, 0), "contains: edge and vertex");
  ok(!ss_poly_contains(&sq, 1.001, 0.5) && !ss_poly_contains(&sq, -0.5, -0.5),
     "contains: outside points");
  ok(!ss_poly_contains(&tri, 0.6, 0.6), "contains: outside the hypotenuse");

  /* chords: the full-cell shortcut of the soil quadrature */
  double x0 = -9, x1 = -9;
  ok(ss_poly_chord(&tri, 0.25, &x0, &x1) && x0 == 0 && x1 == 0.75,
     "chord of the triangle at y = 0.25: [0, 0.75]");
  ok(ss_poly_chord(&cw, 1, &x0, &x1) && x0 == 0 && x1 == 1,
     "chord along an edge of a CW square: the edge");
  ok(ss_poly_chord(&tri, 1, &x0, &x1) && x0 == 0 && x1 == 0, "chord through a vertex: a point");
  ok(!ss_poly_chord(&sq, 1.5, &x0, &x1) && !ss_poly_chord(&sq, -0.1, &x0, &x1),
     "lines that miss: no chord");
  ssPoly2 dia = {4, {0, 1, 0, -1}, {-1, 0, 1, 0}};
  ok(ss_poly_chord(&dia, 0.5, &x0, &x1) && fabs(x0 + 0.5) <= 1e-16 && fabs(x1 - 0.5) <= 1e-16,
     "chord of a diamond at y = 0.5: [-0.5, 0.5]");
}

/* A row band's cells (ss_poly_band_area) against the full clip
 * (ss_poly_rect_area) on footprints of every shape, on cells straddling,
 * touching and missing them.  Both are exact but for rounding, on
 * coordinates of the cell's size about its middle (tens of roundings of
 * relative 1.1e-16 each): areas must agree within 1e-12 of the cell's and,
 * where a cell is at least a thousandth covered, centroids within 1e-10 of
 * its size (an error e in the moments moves the centroid by e / area).  A
 * wrong integral is off by a good part of the cell.  The cells visited
 * again backwards (the chains' places start over) give the first pass's
 * values bit for bit. */
static void test_poly_band(void)
{
  double R[9];
  int bad_area = 0, bad_centre = 0, differ = 0, cells = 0, hits = 0, split = 0, whole = 0,
      thin = 0, chords = 0, chords_differ = 0;
  double worst_a = 0, worst_c = 0;
  for (int t = 0; t < 60; t++) {
    int type = t % 4;
    rot_random(R);
    if (t % 3 == 0) rot_wheel(R, urand(0, PI), urand(0, PI));
    ssShape s = make_shape(type, 0.3, 0.5, 0.2, urand(-1, 1), urand(-1, 1), 0.2, R);
    ssPoly2 p;
    ssPolyChains yc;
    ss_shape_footprint(&s, &p);
    if (!ss_poly_ychains(&p, &yc)) continue;
    split++;
    double lo[3], hi[3], dx = urand(0.005, 0.05), dy = urand(0.005, 0.05);
    ss_shape_aabb(&s, lo, hi);
    /* chords along the chains: at every vertex's height, between, and
     * beyond the polygon */
    for (int v = 0; v < p.n; v++) {
      double a0 = 7, a1 = 7, b0 = 7, b1 = 7;
      for (int k = 0; k < 3; k++) {
        double y = k == 0 ? p.y[v] : k == 1 ? 0.5 * (p.y[v] + p.y[(v + 1) % p.n])
                                            : p.y[v] + (v % 2 ? 1 : -1) * 0.3;
        int ra = ss_poly_chord(&p, y, &a0, &a1), rb = ss_poly_chord_y(&p, &yc, y, &b0, &b1);
        chords++;
        if (ra != rb || (ra && (memcmp(&a0, &b0, sizeof a0) || memcmp(&a1, &b1, sizeof a1))))
          chords_differ++;
      }
    }
    for (double y = lo[1] - dy; y < hi[1] + dy; y += dy) {
      ssPolyBand b;
      double xs = lo[0] - dx;
      if (!ss_poly_band(&p, &yc, y, y + dy, xs, &b)) {
        thin++;
        continue;
      }
      whole++;
      enum { MAXC = 512 };
      double A[MAXC], CX[MAXC], CY[MAXC];
      int nc = 0;
      for (double x = xs; x < hi[0] + dx && nc < MAXC; x += dx, nc++) {
        double ax = 7, ay = 7, bx = 7, by = 7;
        double ra = ss_poly_rect_area(&p, x, x + dx, y, y + dy, &ax, &ay);
        double ba = ss_poly_band_area(&b, x, x + dx, &bx, &by);
        A[nc] = ba;
        CX[nc] = bx;
        CY[nc] = by;
        cells++;
        hits += ra > 0;
        double ea = fabs(ba - ra) / (dx * dy);
        worst_a = ea > worst_a ? ea : worst_a;
        if (!(ea <= 1e-12)) bad_area++;
        if (ra >= 1e-3 * dx * dy) {
          double ec = (fabs(bx - ax) + fabs(by - ay)) / (dx + dy);
          worst_c = ec > worst_c ? ec : worst_c;
          if (!(ec <= 1e-10)) bad_centre++;
        }
      }
      for (int k = nc - 1; k >= 0; k--) {
        /* the first pass's x, which it stepped to by repeated addition */
        double x = xs, bx = 7, by = 7;
        for (int q = 0; q < k; q++) x += dx;
        double ba = ss_poly_band_area(&b, x, x + dx, &bx, &by);
        if (memcmp(&ba, A + k, sizeof ba) ||
            (ba > 0 && (memcmp(&bx, CX + k, sizeof bx) || memcmp(&by, CY + k, sizeof by))))
          differ++;
      }
    }
  }
  ok(split == 60 && whole > 500 && thin == 0 && hits > 1000 && bad_area == 0 &&
     bad_centre == 0,
     "row bands: the full clip's areas and centroids to round-off (%d of %d cells "
     "off in area, worst %.2g of the cell; %d off in centroid, worst %.2g of its size; "
     "%d covered; %d of 60 footprints split, %d bands, %d not)", bad_area, cells, worst_a,
     bad_centre, worst_c, hits, split, whole, thin);
  ok(chords_differ == 0 && chords > 5000, "chords along the y chains: the full scan's "
     "bit for bit (%d of %d differ)", chords_differ, chords);
  ok(differ == 0, "row bands: cells visited backwards give the same values bit for bit "
     "(%d differ)", differ);

  ssPoly2 sq = {4, {0, 1, 1, 0}, {0, 0, 1, 1}}, cw = {4, {0, 0, 1, 1}, {0, 1, 1, 0}};
  ssPoly2 tri = {3, {0, 1, 0}, {0, 0, 1}};
  ssPolyChains c = {-1, -1, {0, 0, 0, 0}};
  ok(ss_poly_ychains(&sq, &c) && c.l == 0 && c.r == 2 && ss_poly_ychains(&cw, &c),
     "y chains of a square either way round");
  ssPolyBand b;
  double cx = -9, cy = -9, a;
  ss_poly_ychains(&sq, &c);
  ok(ss_poly_band(&sq, &c, 0.25, 0.75, 0.5, &b), "the band of a square");
  a = ss_poly_band_area(&b, 0.5, 1.5, &cx, &cy);
  ok(a == 0.25 && cx == 0.75 && cy == 0.5, "band: square and an overlapping cell: 0.25 at "
     "(0.75, 0.5) (got %.17g at %.17g, %.17g)", a, cx, cy);
  ok(ss_poly_band_area(&b, 1.5, 2, NULL, NULL) == 0 &&
     ss_poly_band_area(&b, 1, 2, NULL, NULL) == 0 &&
     ss_poly_band_area(&b, 0.5, 0.5, NULL, NULL) == 0,
     "band: a disjoint, a touching and an empty cell: 0");
  ss_poly_ychains(&tri, &c);
  ss_poly_band(&tri, &c, 0.4, 0.7, 0.4, &b);
  a = ss_poly_band_area(&b, 0.4, 0.7, &cx, &cy);
  ok(fabs(a - 0.02) <= 1e-16 && fabs(cx - (0.4 + 0.2 / 3)) <= 1e-15 &&
     fabs(cy - (0.4 + 0.2 / 3)) <= 1e-15,
     "band: hypotenuse cutting a cell's corner: 0.02 at (0.4 + 0.2/3, same) (got %.17g "
     "at %.17g, %.17g)", a, cx, cy);
  ss_poly_ychains(&cw, &c);
  ss_poly_band(&cw, &c, 0, 1, 0.5, &b);
  a = ss_poly_band_area(&b, 0.5, 1.5, &cx, &cy);
  ok(a == 0.5 && cx == 0.75 && cy == 0.5, "band: a CW polygon still gives a positive "
     "area, its centroid where a CCW one has it");
  ss_poly_ychains(&sq, &c);
  ok(ss_poly_band(&sq, &c, 1.5, 2, 0, &b) && b.n == 0 &&
     ss_poly_band_area(&b, 0, 1, NULL, NULL) == 0, "a band missing the polygon: empty");
}

/* vertical ray casts against closed forms */
static void test_lowest_z(void)
{
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, R[9], z = 0, worst;
  int miss;

  /* box tilted about x by theta: its bottom face plane */
  double th = 0.3, hx = 0.2, hy = 0.3, hz = 0.05, c[3] = {0.4, -0.3, 0.6};
  rot_x(R, th);
  ssShape s = make_shape(SS_GEOM_BOX, 2 * hx, 2 * hy, 2 * hz, c[0], c[1], c[2], R);
  worst = 0;
  miss = 0;
  for (int i = 0; i < 500; i++) {
    double u = urand(-hx, hx), v = urand(-hy, hy);
    double x = c[0] + u, y = c[1] + v * cos(th) + hz * sin(th);
    double want = c[2] + (sin(th) * (y - c[1]) - hz) / cos(th);
    if (!ss_shape_lowest_z(&s, x, y, &z)) miss++;
    else worst = fmax(worst, fabs(z - want));
  }
  ok(miss == 0 && worst <= 1e-14, "box tilted about x: bottom face plane "
     "(%d misses, worst %.3g m)", miss, worst);
  ok(!ss_shape_lowest_z(&s, c[0] + hx + 1e-9, c[1], &z) &&
     !ss_shape_lowest_z(&s, c[0], c[1] + hy * cos(th) + hz * sin(th) + 1e-9, &z),
     "box tilted about x: lines just outside miss");

  /* axis-aligned box: rays parallel to every slab */
  s = make_shape(SS_GEOM_BOX, 0.4, 0.6, 0.1, 1, 2, 3, I);
  ok(ss_shape_lowest_z(&s, 1.1, 2.25, &z) && z == 2.95, "axis-aligned box: z = c - hz (%.17g)", z);
  z = 42;
  ok(!ss_shape_lowest_z(&s, 1.3, 2, &z) && z == 42, "axis-aligned box: miss returns 0, z untouched");

  /* sphere */
  double r = 0.25;
  s = make_shape(SS_GEOM_SPHERE, r, 0, 0, -0.5, 0.5, 0.2, I);
  worst = 0;
  miss = 0;
  for (int i = 0; i < 500; i++) {
    double rho = r * sqrt(urand(0, 1)), al = urand(-PI, PI);
    double x = -0.5 + rho * cos(al), y = 0.5 + rho * sin(al);
    double want = 0.2 - sqrt(r * r - ((x + 0.5) * (x + 0.5) + (y - 0.5) * (y - 0.5)));
    if (!ss_shape_lowest_z(&s, x, y, &z)) miss++;
    else worst = fmax(worst, fabs(z - want));
  }
  ok(miss == 0 && worst <= 1e-15, "sphere: z = c - sqrt(r^2 - rho^2) (worst %.3g)", worst);
  ok(!ss_shape_lowest_z(&s, -0.5 + 1.0001 * r, 0.5, &z), "sphere: miss outside r");

  /* lying cylinder, random heading and spin: z = c - sqrt(r^2 - d^2) */
  double L = 0.2;
  worst = 0;
  miss = 0;
  int outside = 0;
  for (int i = 0; i < 500; i++) {
    double psi = urand(-PI, PI), cz = urand(0, 1);
    rot_wheel(R, psi, urand(-PI, PI));
    s = make_shape(SS_GEOM_CYLINDER, r, L, 0, 0.1, 0.2, cz, R);
    /* frame y of the wheel (-sin psi, cos psi) is the axle */
    double along = urand(-0.5, 0.5) * L * 0.999, d = urand(-1, 1) * r * 0.999;
    double x = 0.1 - sin(psi) * along + cos(psi) * d;
    double y = 0.2 + cos(psi) * along + sin(psi) * d;
    if (!ss_shape_lowest_z(&s, x, y, &z)) miss++;
    else worst = fmax(worst, fabs(z - (cz - sqrt(r * r - d * d))));
    /* beyond the caps, beyond the tread */
    double e = 0.5 * L * 1.001;
    if (ss_shape_lowest_z(&s, 0.1 - sin(psi) * e, 0.2 + cos(psi) * e, &z)) outside++;
    if (ss_shape_lowest_z(&s, 0.1 + cos(psi) * 1.001 * r, 0.2 + sin(psi) * 1.001 * r, &z))
      outside++;
  }
  ok(miss == 0 && worst <= 1e-13, "lying cylinder: z = c - sqrt(r^2 - d^2) "
     "(%d misses, worst %.3g m)", miss, worst);
  ok(outside == 0, "lying cylinder: lines past the caps or tread miss (%d hits)", outside);

  /* exact axis permutation: the ray is parallel to the cap planes */
  double P[9] = {0, 0, 1, 1, 0, 0, 0, 1, 0};
  s = make_shape(SS_GEOM_CYLINDER, r, L, 0, 0, 0, 1, P);
  ok(ss_shape_lowest_z(&s, 0.05, 0.15, &z) && fabs(z - (1 - sqrt(r * r - 0.15 * 0.15))) <= 1e-15,
     "cylinder with axis exactly along x: lateral surface");
  ok(!ss_shape_lowest_z(&s, 0.11, 0.0, &z), "cylinder with axis exactly along x: miss past a cap");

  /* standing cylinder: the ray is parallel to the lateral surface */
  s = make_shape(SS_GEOM_CYLINDER, r, L, 0, 0, 0, 1, I);
  ok(ss_shape_lowest_z(&s, 0.1, -0.2, &z) && z == 1 - 0.5 * L, "standing cylinder: bottom cap");
  ok(!ss_shape_lowest_z(&s, 0.2, -0.2, &z), "standing cylinder: miss outside r");

  /* capsule lying along frame x: cylinder part and end spheres */
  s = make_shape(SS_GEOM_CAPSULE, r, L, 0, 0, 0, 1, P);
  ok(ss_shape_lowest_z(&s, 0.05, 0.15, &z) && fabs(z - (1 - sqrt(r * r - 0.15 * 0.15))) <= 1e-15,
     "lying capsule: cylinder part z = c - sqrt(r^2 - d^2)");
  double ex = 0.5 * L + 0.1, dd = 0.1 * 0.1 + 0.12 * 0.12;
  ok(ss_shape_lowest_z(&s, ex, 0.12, &z) && fabs(z - (1 - sqrt(r * r - dd))) <= 1e-15,
     "lying capsule: end sphere z = c - sqrt(r^2 - rho^2)");
  ok(!ss_shape_lowest_z(&s, 0.5 * L + r * 1.0001, 0, &z), "lying capsule: miss past an end");

  /* standing capsule: the lower end sphere */
  s = make_shape(SS_GEOM_CAPSULE, r, L, 0, 0, 0, 1, I);
  ok(ss_shape_lowest_z(&s, 0.1, 0.1, &z) && fabs(z - (1 - 0.5 * L - sqrt(r * r - 0.02))) <= 1e-15,
     "standing capsule: z = c - L/2 - sqrt(r^2 - rho^2)");

  /* any orientation: a surface point whose outward normal points down is
   * where the upward line through it enters */
  const char *names[4] = {"box", "sphere", "cylinder", "capsule"};
  for (int type = 0; type < 4; type++) {
    worst = 0;
    miss = 0;
    int tested = 0;
    for (int i = 0; i < 4000; i++) {
      rot_random(R);
      double sz[3] = {urand(0.05, 0.5), urand(0.05, 0.5), urand(0.05, 0.5)};
      s = make_shape(type, sz[0], sz[1], sz[2], urand(-1, 1), urand(-1, 1), urand(-1, 1), R);
      double lp[3], ln[3];
      if (type == SS_GEOM_BOX) {
        int f = (int)urand(0, 6);
        for (int k = 0; k < 3; k++) lp[k] = urand(-0.5, 0.5) * sz[k];
        ss_v3_set(ln, 0, 0, 0);
        lp[f % 3] = (f < 3 ? 0.5 : -0.5) * sz[f % 3];
        ln[f % 3] = f < 3 ? 1 : -1;
      } else {
        double al = urand(-PI, PI), hl = type == SS_GEOM_SPHERE ? 0 : 0.5 * sz[1];
        int part = type == SS_GEOM_SPHERE ? 1 : (int)urand(0, 3);
        if (part == 0) { /* lateral surface */
          ss_v3_set(ln, cos(al), sin(al), 0);
          ss_v3_set(lp, sz[0] * ln[0], sz[0] * ln[1], urand(-hl, hl));
        } else if (type == SS_GEOM_CYLINDER) { /* a cap disc */
          double e = part == 1 ? 1 : -1, rho = sz[0] * sqrt(urand(0, 1));
          ss_v3_set(ln, 0, 0, e);
          ss_v3_set(lp, rho * cos(al), rho * sin(al), e * hl);
        } else { /* a sphere, or a capsule's end hemisphere */
          double e = part == 1 ? 1 : -1, ct = urand(-1, 1), st = sqrt(1 - ct * ct);
          ss_v3_set(ln, st * cos(al), st * sin(al), ct);
          if (type == SS_GEOM_CAPSULE) ln[2] = e * fabs(ct);
          ss_v3_set(lp, sz[0] * ln[0], sz[0] * ln[1], e * hl + sz[0] * ln[2]);
        }
      }
      double wp[3], wn[3];
      ss_m3_mulv(wp, R, lp);
      ss_v3_add(wp, wp, s.pos);
      ss_m3_mulv(wn, R, ln);
      if (wn[2] > -0.05) continue;
      tested++;
      if (!ss_shape_lowest_z(&s, wp[0], wp[1], &z)) miss++;
      else worst = fmax(worst, fabs(z - wp[2]));
    }
    ok(tested > 500 && miss == 0 && worst <= 1e-13, "%s, random orientations: lowest z = "
       "downward-facing surface point (%d points, %d misses, worst %.3g m)",
       names[type], tested, miss, worst);
  }

  /* lines outside the bounds always miss */
  miss = 0;
  for (int i = 0; i < 2000; i++) {
    rot_random(R);
    int type = i % 4;
    s = make_shape(type, urand(0.05, 0.5), urand(0.05, 0.5), urand(0.05, 0.5), 0, 0, 0, R);
    double lo[3], hi[3], al = urand(-PI, PI);
    ss_shape_aabb(&s, lo, hi);
    double rad = 1e-9 + sqrt(fmax(hi[0] * hi[0], lo[0] * lo[0]) + fmax(hi[1] * hi[1], lo[1] * lo[1]));
    if (ss_shape_lowest_z(&s, rad * cos(al), rad * sin(al), &z)) miss++;
  }
  ok(miss == 0, "lines outside every shape's bounds miss (%d hits)", miss);
}

/* contact candidates */
static void test_candidates(void)
{
  double R[9], pts[32][3], n[3] = {0, 0, 1};
  rot_random(R);
  ssShape s = make_shape(SS_GEOM_BOX, 0.3, 0.4, 0.5, 1, 2, 3, R);
  int k = ss_shape_candidates(&s, n, pts, 32), found = 0;
  for (int i = 0; i < 8; i++) {
    double l[3] = {(i & 1) ? 0.15 : -0.15, (i & 2) ? 0.2 : -0.2, (i & 4) ? 0.25 : -0.25}, w[3];
    ss_m3_mulv(w, R, l);
    ss_v3_add(w, w, s.pos);
    for (int j = 0; j < k; j++) {
      double d[3];
      ss_v3_sub(d, pts[j], w);
      if (ss_v3_norm(d) <= 1e-15) { found++; break; }
    }
  }
  ok(k == 8 && found == 8, "box candidates are its 8 corners (k = %d, matched %d)", k, found);
  ok(ss_shape_candidates(&s, n, pts, 3) == 3, "candidates respect max");

  /* a tilted surface normal */
  double nt[3] = {0.3, -0.2, 1};
  ss_v3_normalize(nt);
  s = make_shape(SS_GEOM_SPHERE, 0.2, 0, 0, 1, 2, 3, R);
  k = ss_shape_candidates(&s, nt, pts, 32);
  ok(k == 1 && fabs(pts[0][0] - (1 - 0.2 * nt[0])) <= 1e-15 &&
     fabs(pts[0][2] - (3 - 0.2 * nt[2])) <= 1e-15, "sphere candidate: c - r n");

  s = make_shape(SS_GEOM_CAPSULE, 0.2, 0.6, 0, 1, 2, 3, R);
  k = ss_shape_candidates(&s, nt, pts, 32);
  double a[3] = {R[2], R[5], R[8]};
  double lowest = fmin(ss_v3_dot(nt, pts[0]), ss_v3_dot(nt, pts[1]));
  ok(k == 2 && fabs(lowest - (ss_v3_dot(nt, s.pos) - 0.3 * fabs(ss_v3_dot(nt, a)) - 0.2)) <= 1e-14,
     "capsule candidates: two points, the lowest is the support along -n");

  /* cylinder: lowest candidate is the true support; all lie on the rims */
  double worst = 0, off = 0;
  int count_ok = 1;
  for (int t = 0; t < 100; t++) {
    rot_random(R);
    s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, urand(-1, 1), 0, 1, R);
    k = ss_shape_candidates(&s, nt, pts, 32);
    if (k != 16) count_ok = 0;
    ss_v3_set(a, R[2], R[5], R[8]);
    double na = ss_v3_dot(nt, a), lo = INFINITY;
    for (int j = 0; j < k; j++) {
      double d[3];
      lo = fmin(lo, ss_v3_dot(nt, pts[j]));
      ss_v3_sub(d, pts[j], s.pos);
      double ax = ss_v3_dot(d, a);
      ss_v3_addscl(d, a, -ax);
      off = fmax(off, fmax(fabs(fabs(ax) - 0.1), fabs(ss_v3_norm(d) - 0.3)));
    }
    double want = ss_v3_dot(nt, s.pos) - 0.1 * fabs(na) - 0.3 * sqrt(1 - na * na);
    worst = fmax(worst, fabs(lo - want));
  }
  ok(count_ok, "cylinder candidates: 2 lowest rim points + 7 more per cap");
  ok(worst <= 1e-14, "cylinder candidates: the lowest is the support along -n (worst %.3g)", worst);
  ok(off <= 1e-14, "cylinder candidates lie on the cap rims (worst %.3g)", off);

  /* standing on its end: the rim, not the cap centre */
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0, I);
  k = ss_shape_candidates(&s, n, pts, 32);
  int rim = 0;
  for (int j = 0; j < k; j++)
    if (fabs(pts[j][2] + 0.1) <= 1e-15 && fabs(hypot(pts[j][0], pts[j][1]) - 0.3) <= 1e-15) rim++;
  ok(rim == 8, "standing cylinder: 8 candidates on the bottom rim (%d)", rim);

  /* a wheel spun about its axle offers the same candidates: the ring
   * turns with the lowest direction, not with the body, so that rolling
   * brings no rim point down onto the support */
  double R0[9], moved = 0;
  rot_wheel(R0, 0.3, 0);
  s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0.3, R0);
  double p0[32][3];
  int k0 = ss_shape_candidates(&s, n, p0, 32);
  for (int t = 0; t < 50; t++) {
    rot_wheel(R, 0.3, urand(-PI, PI));
    s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0.3, R);
    k = ss_shape_candidates(&s, n, pts, 32);
    if (k != k0) moved = INFINITY;
    for (int j = 0; j < k && j < k0; j++) {
      double dd[3];
      ss_v3_sub(dd, pts[j], p0[j]);
      moved = fmax(moved, ss_v3_norm(dd));
    }
  }
  ok(moved <= 1e-14, "rolling wheel: the same candidates at every spin angle (worst %.3g)", moved);

  /* and so a cylinder rolling on a plane keeps its speed: it lost 13 %
   * in 10 s at 1 ms (1.333 -> 1.159 m/s), braked by the body-fixed ring's
   * points meeting the ground */
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/>"
      "<cylinder name=\"c\" mass=\"2\"><dim radius=\"0.05\" height=\"0.2\"/>"
      "<state pos=\"0 0 0.05\" quat=\"0.70710678118654752 0.70710678118654752 0 0\" "
      "lin_vel=\"2 0 0\"/></cylinder></objects><material><default friction=\"0.3\" "
      "restitution=\"0\" restitution_threshold=\"0\"/></material></raisim>";
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  int good = ss_scene_load_buffer(xml, strlen(xml), "roll.xml", &m, &d, &e) == SS_OK;
  for (int t = 0; good && t < 10000; t++) good = ss_step(m, d, &e) == SS_OK;
  ok(good && fabs(d->qvel[0] - 4.0 / 3) < 1e-4 && fabs(d->qpos[2] - 0.05) < 1e-9,
     "cylinder sliding onto its side rolls on at 2/3 of 2 m/s for 10 s (%.6f m/s, %s)",
     good ? d->qvel[0] : 0, good ? "stepped" : e.message);
  ss_data_free(d);
  ss_model_free(m);
}

/* A ball on a rigid height map that rises 0.25 m a metre along x (14
 * degrees) rolls down it without slipping: its centre stays r from the
 * slope and accelerates at 5/7 g sin(a) along it (the horizontal part
 * 5/7 g sin(a) cos(a) = 1.6487 m/s^2).  Its candidate point was the
 * lowest along the map's up, directly below the centre: the ball sank
 * r (1/cos(a) - 1) = 3.1 mm into the slope and, pushed there, did not
 * roll (x stayed at 0.30002 m). */
static void test_ball_on_slope(void)
{
  char xml[4096], *q = xml;
  q += sprintf(q, "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
                  "<heightmap name=\"h\" x_size=\"4\" y_size=\"4\" x_sample=\"11\" "
                  "y_sample=\"11\" center_x=\"0\" center_y=\"0\" height=\"");
  for (int j = 0; j < 11; j++)
    for (int i = 0; i < 11; i++) q += sprintf(q, "%s%.1f", i || j ? " " : "", 0.1 * (i - 5));
  sprintf(q, "\"/><sphere name=\"ball\" mass=\"2\"><dim radius=\"0.1\"/>"
             "<state pos=\"0.3 0.2 0.3\"/></sphere></objects><material><default "
             "friction=\"0.8\" restitution=\"0\" restitution_threshold=\"0\"/></material>"
             "</raisim>");
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  int good = ss_scene_load_buffer(xml, strlen(xml), "slope.xml", &m, &d, &e) == SS_OK;
  /* landed and rolling by 0.3 s; then v_x at two times */
  double gap = 0, v1 = 0, v2 = 0, t1 = 0, t2 = 0;
  const double c = sqrt(1.0625);
  for (int t = 0; good && t < 900; t++) {
    good = ss_step(m, d, &e) == SS_OK;
    if (t + 1 >= 300) gap = fmax(gap, fabs((d->qpos[2] - 0.25 * d->qpos[0]) / c - 0.1));
    if (t + 1 == 400) v1 = d->qvel[0], t1 = d->time;
    if (t + 1 == 900) v2 = d->qvel[0], t2 = d->time;
  }
  double a = good ? (v2 - v1) / (t2 - t1) : 0, want = -5.0 / 7 * 9.81 * 0.25 / 1.0625;
  ok(good && gap <= 1e-9 && fabs(a - want) <= 1e-9 * fabs(want),
     "ball on a 14-degree rigid slope: centre r from it (worst %.3g m), rolls at %.10f m/s^2 "
     "horizontally (5/7 g sin cos: %.10f)%s%s", gap, a, want, good ? "" : ": ",
     good ? "" : e.message);
  ss_data_free(d);
  ss_model_free(m);
}

/* Restitution acts on a contact's approach before the step's loads: a
 * box dropped onto the ground with restitution 0.5 (threshold 0) leaves
 * it at half its impact speed, and once its bounces have died it rests
 * at z = 0.05 exactly.  With gravity's g dt in the approach, the resting
 * box met the ground at g dt every step and hopped for ever (z between
 * 51.99 and 52.00 mm). */
static void test_restitution_rest(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/><box name=\"b\" mass=\"2\">"
      "<dim x=\"0.2\" y=\"0.3\" z=\"0.1\"/><state pos=\"0 0 0.25\"/></box></objects>"
      "<material><default friction=\"0.8\" restitution=\"0.5\" "
      "restitution_threshold=\"0\"/></material></raisim>";
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  int good = ss_scene_load_buffer(xml, strlen(xml), "bounce.xml", &m, &d, &e) == SS_OK;
  double vin = 0, vout = 0, zlo = INFINITY, zhi = -INFINITY;
  for (int t = 0; good && t < 3000; t++) {
    double v = d->qvel[2];
    good = ss_step(m, d, &e) == SS_OK;
    if (!vout && d->qvel[2] > 0) vin = v, vout = d->qvel[2];
    if (t >= 2000) zlo = fmin(zlo, d->qpos[2]), zhi = fmax(zhi, d->qpos[2]);
  }
  ok(good && vin < -1.9 && fabs(vout / vin + 0.5) <= 1e-12 && zlo == 0.05 && zhi == 0.05,
     "box with restitution 0.5: leaves the ground at %.12f of its %.4f m/s impact, rests "
     "at z %.9f-%.9f m after 2 s", vin ? -vout / vin : 0, vin, zlo, zhi);
  ss_data_free(d);
  ss_model_free(m);
}

/* A box started 2 cm into the ground is moved out by rigid_erp (0.2) of
 * its penetration a step, but never faster than 3 m/s (3 mm a step: the
 * first two steps), and keeps no speed from it (the push out of
 * penetrations moves positions only, ss_solver_push).  The solve used to remove the penetration by velocity:
 * 0.2 * 0.02 m / 1 ms = 4 m/s upwards, which stayed, and the box flew
 * 0.85 m high.  Tolerances: the push's sweeps stop at a relative change
 * of 1e-6 of its 4 mm (4e-9 m); the solve's velocities are at its 1e-9. */
static void test_penetration_push(void)
{
  const char *xml =
      "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
      "<ground name=\"g\" height=\"0\"/><box name=\"b\" mass=\"2\">"
      "<dim x=\"0.2\" y=\"0.2\" z=\"0.1\"/><state pos=\"0 0 0.03\"/></box></objects>"
      "</raisim>";
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  int good = ss_scene_load_buffer(xml, strlen(xml), "sunk.xml", &m, &d, &e) == SS_OK;
  double worst = 0, vmax = 0, zmax = 0, left = 0.02;
  for (int t = 0; good && t < 1000; t++) {
    good = ss_step(m, d, &e) == SS_OK;
    left -= fmin(0.2 * left, 0.003);
    if (good && t < 60) worst = fmax(worst, fabs(d->qpos[2] - (0.05 - left)));
    for (int k = 0; good && k < 6; k++) vmax = fmax(vmax, fabs(d->qvel[k]));
    zmax = fmax(zmax, d->qpos[2]);
  }
  ok(good && worst <= 1e-8 && vmax <= 1e-6 && zmax <= 0.05 + 1e-9,
     "box started 2 cm into the ground: out by 0.2 of the penetration a step, at most 3 mm "
     "(worst %.3g m from that over 60 steps), no speed from it (largest %.3g), never above its "
     "rest (highest z %.9f m)%s%s", worst, vmax, zmax, good ? "" : ": ", good ? "" : e.message);
  ss_data_free(d);
  ss_model_free(m);
}

/* A 1 x 1 x 0.1 m slab dropped onto a rigid height map (2 x 2 m, 0.1 m
 * spacing) that is flat but for a 0.2 m mesa in its middle (3 x 3
 * vertices at 0.2, its sides sloping to 0 over one spacing) rests on the
 * mesa, its bottom at 0.2 m (centre z = 0.25).  Only the slab's corners
 * were tested against the map: they landed on the flat ground around the
 * mesa, which passed through the slab (centre z = 0.05).  Tolerance: the
 * solve stops the contacts to its 1e-9 and the push leaves what the
 * landing made times 0.8^k, far below 1e-6 m after 2 s. */
static void test_mesa_box(void)
{
  char xml[8192], *q = xml;
  q += sprintf(q, "<raisim version=\"1.0\"><timeStep value=\"0.001\"/><objects>"
                  "<heightmap name=\"h\" x_size=\"2\" y_size=\"2\" x_sample=\"21\" "
                  "y_sample=\"21\" center_x=\"0\" center_y=\"0\" height=\"");
  for (int j = 0; j < 21; j++)
    for (int i = 0; i < 21; i++)
      q += sprintf(q, "%s%s", i || j ? " " : "", abs(i - 10) <= 1 && abs(j - 10) <= 1 ? "0.2" : "0");
  sprintf(q, "\"/><box name=\"slab\" mass=\"10\"><dim x=\"1\" y=\"1\" z=\"0.1\"/>"
             "<state pos=\"0 0 0.5\"/></box></objects></raisim>");
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  int good = ss_scene_load_buffer(xml, strlen(xml), "mesa.xml", &m, &d, &e) == SS_OK;
  for (int t = 0; good && t < 2000; t++) good = ss_step(m, d, &e) == SS_OK;
  double z = good ? d->qpos[2] : NAN, v = 0;
  for (int k = 0; good && k < 6; k++) v = fmax(v, fabs(d->qvel[k]));
  ok(good && fabs(z - 0.25) <= 1e-6 && v <= 1e-6,
     "a slab dropped onto a rigid mesa rests on it: centre z %.9f m (0.25), speed %.3g%s%s", z,
     v, good ? "" : ": ", good ? "" : e.message);
  ss_data_free(d);
  ss_model_free(m);
}

/* ss_quat_normalize keeps the direction of a quaternion whose squares
 * overflow or underflow: (1e300, 1e300, 0, 0) came out as zeros (its norm
 * inf) and (1e-200, 1e-200, 0, 0) as the identity (its squares 0); an
 * ordinary one keeps its bits, a zero one becomes the identity */
static void test_quat_normalize(void)
{
  const double h = 0.70710678118654752;
  double big[4] = {1e300, 1e300, 0, 0}, tiny[4] = {1e-200, -1e-200, 0, 0};
  double q[4] = {0.3, -0.4, 0.5, 0.1}, q2[4], z[4] = {0, 0, 0, 0};
  double n = sqrt(0.3 * 0.3 + 0.4 * 0.4 + 0.5 * 0.5 + 0.1 * 0.1);
  for (int k = 0; k < 4; k++) q2[k] = q[k] / n;
  double nb = ss_quat_normalize(big), nt = ss_quat_normalize(tiny), nq = ss_quat_normalize(q);
  ss_quat_normalize(z);
  ok(fabs(big[0] - h) < 1e-15 && fabs(big[1] - h) < 1e-15 && big[2] == 0 && big[3] == 0 &&
         fabs(nb / 1.4142135623730951e300 - 1) < 1e-15,
     "a quaternion of 1e300 entries keeps its direction (%.17g %.17g, norm %.6g)", big[0],
     big[1], nb);
  ok(fabs(tiny[0] - h) < 1e-15 && fabs(tiny[1] + h) < 1e-15 &&
         fabs(nt / 1.4142135623730951e-200 - 1) < 1e-15,
     "... and one of 1e-200 entries (%.17g %.17g)", tiny[0], tiny[1]);
  ok(!memcmp(q, q2, sizeof q) && nq == n && z[0] == 1 && z[1] == 0 && z[2] == 0 && z[3] == 0,
     "... an ordinary one is divided by its norm as before, a zero one is the identity");
}

/* effective width b: DESIGN 2.4, invariant under yaw */
static void test_width(void)
{
  double R[9], A[9], B[9], n[3] = {0, 0, 1};
  int same = 1;
  double b0;

  /* flat plate: the shorter horizontal side */
  for (int t = 0; t < 50; t++) {
    rot_z(R, urand(-PI, PI));
    ssShape s = make_shape(SS_GEOM_BOX, 0.4, 0.6, 0.05, 0, 0, 0, R);
    if (ss_shape_width(&s, n) != 0.4) same = 0;
    s.size[0] = 0.7;
    if (ss_shape_width(&s, n) != 0.6) same = 0;
  }
  ok(same, "flat plate: b = shorter horizontal side at every heading");

  /* a box on its side: local x vertical */
  rot_y(A, 0.5 * PI);
  same = 1;
  b0 = -1;
  for (int t = 0; t < 50; t++) {
    rot_z(B, urand(-PI, PI));
    ss_m3_mul(R, B, A);
    ssShape s = make_shape(SS_GEOM_BOX, 0.05, 0.5, 0.3, 0, 0, 0, R);
    double b = ss_shape_width(&s, n);
    if (b0 < 0) b0 = b;
    if (b != b0) same = 0;
  }
  ok(same && b0 == 0.3, "box standing on its thin side: b = 0.3 (got %g)", b0);

  /* wheels: tread width whatever heading and spin; standing: diameter */
  same = 1;
  for (int t = 0; t < 50; t++) {
    rot_wheel(R, urand(-PI, PI), urand(-PI, PI));
    ssShape s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0, R);
    if (ss_shape_width(&s, n) != 0.2) same = 0;
  }
  ok(same, "lying wheel: b = tread width at every heading and spin");
  rot_tilt(R, 0.5 * PI - 0.6, 1.0);  /* axle 0.6 rad (< 45 deg) out of the plane */
  ssShape s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0, R);
  ok(ss_shape_width(&s, n) == 0.2, "cylinder with axle 34 deg out of the plane: tread width");
  rot_tilt(R, 0.5 * PI - 0.9, 1.0);
  s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0, R);
  ok(ss_shape_width(&s, n) == 0.6, "cylinder with axle 52 deg out of the plane: diameter");

  s = make_shape(SS_GEOM_SPHERE, 0.3, 0, 0, 0, 0, 0, R);
  ok(ss_shape_width(&s, n) == 0.6, "sphere: b = diameter");
  s = make_shape(SS_GEOM_CAPSULE, 0.3, 1.0, 0, 0, 0, 0, R);
  ok(ss_shape_width(&s, n) == 0.6, "capsule: b = diameter");

  /* a tilted bed: the same plate tilted with it keeps its width */
  double nt[3];
  rot_x(A, 0.4);
  ss_v3_set(nt, A[2], A[5], A[8]);
  same = 1;
  for (int t = 0; t < 20; t++) {
    rot_z(B, urand(-PI, PI));
    ss_m3_mul(R, A, B);
    s = make_shape(SS_GEOM_BOX, 0.4, 0.6, 0.05, 0, 0, 0, R);
    if (ss_shape_width(&s, nt) != 0.4) same = 0;
  }
  ok(same, "plate on a tilted bed: b = 0.4 at every heading");

  /* the public ss_geom_width: a mesh takes its bounding box's rule
   * (DESIGN 2.4), as the box it is shaped like; it gave 0 */
  const char *top = getenv("top_srcdir");
  char xml[1024];
  snprintf(xml, sizeof xml,
           "<raisim version=\"1.0\"><objects>"
           "<mesh name=\"slab\" mass=\"20\" file_name=\"%s/tests/data/urdf/meshes/cube.obj\" "
           "scale=\"0.4 0.6 0.05\"><state pos=\"0 0 0.025\"/></mesh>"
           "<box name=\"plate\" mass=\"20\"><dim x=\"0.4\" y=\"0.6\" z=\"0.05\"/>"
           "<state pos=\"1 0 0.025\"/></box></objects></raisim>", top ? top : ".");
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  if (ss_scene_load_buffer(xml, strlen(xml), "widths.xml", &m, &d, &e) != SS_OK) {
    ok(0, "mesh and box scene loads (%s)", e.message);
    return;
  }
  same = 1;
  double up[3] = {0, 0, 1};
  for (int t = 0; t < 20; t++) {
    rot_z(B, urand(-PI, PI));
    for (int g = 0; g < 2; g++) {
      double b = ss_geom_width(m, g, B, up);
      if (b != 0.4) same = 0;
    }
  }
  ok(m->geom_type[0] == SS_GEOM_MESH && same,
     "ss_geom_width: a box-shaped mesh and the box both 0.4 at every heading (mesh %g)",
     ss_geom_width(m, 0, B, up));
  ss_data_free(d);
  ss_model_free(m);
}

/* tight bounds */
static void test_aabb(void)
{
  double R[9], lo[3], hi[3];
  double worst = 0;
  for (int t = 0; t < 100; t++) {
    rot_random(R);
    ssShape s = make_shape(SS_GEOM_BOX, 0.3, 0.4, 0.5, 1, 2, 3, R);
    ss_shape_aabb(&s, lo, hi);
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 8; i++) {
      double l[3] = {(i & 1) ? 0.15 : -0.15, (i & 2) ? 0.2 : -0.2, (i & 4) ? 0.25 : -0.25}, w[3];
      ss_m3_mulv(w, R, l);
      for (int k = 0; k < 3; k++) {
        clo[k] = fmin(clo[k], s.pos[k] + w[k]);
        chi[k] = fmax(chi[k], s.pos[k] + w[k]);
      }
    }
    for (int k = 0; k < 3; k++) worst = fmax(worst, fmax(fabs(lo[k] - clo[k]), fabs(hi[k] - chi[k])));
  }
  ok(worst <= 1e-15, "box bounds = extremes of its corners (worst %.3g)", worst);

  ssShape s = make_shape(SS_GEOM_SPHERE, 0.3, 0, 0, 1, 2, 3, R);
  ss_shape_aabb(&s, lo, hi);
  ok(lo[0] == 0.7 && hi[1] == 2.3 && lo[2] == 2.7, "sphere bounds = c +- r");

  /* cylinder and capsule: sampled surfaces touch but never pass the bounds */
  for (int type = SS_GEOM_CYLINDER; type <= SS_GEOM_CAPSULE; type++) {
    double over = 0, gap = 0;
    for (int t = 0; t < 20; t++) {
      rot_random(R);
      s = make_shape(type, 0.3, 0.5, 0, 1, 2, 3, R);
      ss_shape_aabb(&s, lo, hi);
      double slo[3] = {INFINITY, INFINITY, INFINITY}, shi[3] = {-INFINITY, -INFINITY, -INFINITY};
      for (int i = 0; i < 20000; i++) {
        double l[3], w[3];
        if (type == SS_GEOM_CYLINDER) {
          double al = 2 * PI * i / 10000.0;
          ss_v3_set(l, 0.3 * cos(al), 0.3 * sin(al), i < 10000 ? 0.25 : -0.25);
        } else {
          /* a fine latitude-longitude grid of both end spheres */
          double al = 2 * PI * (i % 200) / 200.0, be = PI * ((i / 200) % 50) / 49.0;
          ss_v3_set(l, 0.3 * sin(be) * cos(al), 0.3 * sin(be) * sin(al), 0.3 * cos(be));
          l[2] += i < 10000 ? 0.25 : -0.25;
        }
        ss_m3_mulv(w, R, l);
        for (int k = 0; k < 3; k++) {
          slo[k] = fmin(slo[k], s.pos[k] + w[k]);
          shi[k] = fmax(shi[k], s.pos[k] + w[k]);
        }
      }
      for (int k = 0; k < 3; k++) {
        over = fmax(over, fmax(lo[k] - slo[k], shi[k] - hi[k]));
        gap = fmax(gap, fmax(slo[k] - lo[k], hi[k] - shi[k]));
      }
    }
    ok(over <= 1e-15 && gap <= 2e-3, "%s bounds contain the surface and are tight "
       "(overshoot %.3g, gap %.3g)", type == SS_GEOM_CYLINDER ? "cylinder" : "capsule",
       over, gap);
  }
  {
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    s = make_shape(SS_GEOM_CYLINDER, 0.3, 0.5, 0, 0, 0, 0, I);
    ss_shape_aabb(&s, lo, hi);
    ok(hi[0] == 0.3 && hi[1] == 0.3 && hi[2] == 0.25, "standing cylinder bounds");
    s.type = SS_GEOM_CAPSULE;
    ss_shape_aabb(&s, lo, hi);
    ok(hi[0] == 0.3 && hi[2] == 0.55, "standing capsule bounds");
  }
}

/* the bounds of a shape's part below a height hold every vertical line
 * through the shape that reaches that low, and are tight for a wheel */
static void test_low_bounds(void)
{
  double R[9], lo[2], hi[2];
  for (int type = SS_GEOM_BOX; type <= SS_GEOM_CAPSULE; type++) {
    int outside = 0, empty_wrong = 0;
    for (int t = 0; t < 40; t++) {
      rot_random(R);
      if (t < 10) rot_wheel(R, urand(0, PI), urand(0, PI));
      ssShape s = make_shape(type, 0.3, 0.5, 0.2, 1, 2, 3, R);
      double alo[3], ahi[3];
      ss_shape_aabb(&s, alo, ahi);
      double zc = urand(alo[2] - 0.05, ahi[2]);
      int any = ss_shape_low_bounds(&s, zc, lo, hi);
      for (int i = 0; i < 4000; i++) {
        double x = urand(alo[0], ahi[0]), y = urand(alo[1], ahi[1]), z;
        if (!ss_shape_lowest_z(&s, x, y, &z) || z > zc) continue;
        if (!any) empty_wrong++;
        else if (x < lo[0] || x > hi[0] || y < lo[1] || y > hi[1]) outside++;
      }
    }
    ok(outside == 0 && empty_wrong == 0, "type %d: points at or below zc lie in "
       "the low bounds (%d outside, %d missed)", type, outside, empty_wrong);
  }
  /* a wheel of radius 0.3 rolling along x, 1 cm below zc: chord 2 sqrt(0.3^2 - 0.29^2) */
  rot_wheel(R, 0, 0.7);
  ssShape w = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0, 0, 0.3, R);
  int any = ss_shape_low_bounds(&w, 0.01, lo, hi);
  double half = sqrt(0.3 * 0.3 - 0.29 * 0.29), l0 = fmin(hi[0] - lo[0], hi[1] - lo[1]);
  double l1 = fmax(hi[0] - lo[0], hi[1] - lo[1]);
  ok(any && fabs(l0 - 2 * half) < 1e-6 && fabs(l1 - 0.2) < 1e-6,
     "wheel's low bounds: its contact chord by its tread (%.6g x %.6g)", l0, l1);
  ok(!ss_shape_low_bounds(&w, -0.01, lo, hi), "wheel above zc: no low bounds");
}

/* SS_SORT_RUNS on inputs made of runs (ascending, descending, with ties,
 * as the colliders' contacts come) and on random ones: the result must be
 * the stable order, the one a stable insertion sort gives, element for
 * element (key and original position), and an already sorted input must
 * come back in place. */
typedef struct {
  int key, pos;
} SortItem;
static int item_less(const SortItem *a, const SortItem *b) { return a->key < b->key; }
enum { SORT_N = 97 }; /* the longest input */
SS_SORT_RUNS(sort_items, SortItem, item_less)

/* sort v[0, n) (t: its scratch) and compare with the stable insertion
 * sort, element for element (key and original position); in_place: the
 * result must also come back in v */
static int sorts_stably(SortItem *v, SortItem *t, int n, int in_place)
{
  SortItem want[SORT_N];
  memcpy(want, v, sizeof(SortItem) * (size_t)n);
  for (int i = 1; i < n; i++)
    for (int j = i; j > 0 && want[j].key < want[j - 1].key; j--) {
      SortItem s = want[j];
      want[j] = want[j - 1];
      want[j - 1] = s;
    }
  SortItem *r = sort_items(v, t, n);
  int same = 1;
  for (int i = 0; i < n; i++) same &= r[i].key == want[i].key && r[i].pos == want[i].pos;
  return same && (!in_place || r == v);
}

static void test_sort_runs(void)
{
  enum { N = SORT_N };
  SortItem v[N], t[N];
  uint32_t seed = 12345;
  int bad = 0, cases = 0;
  for (int c = 0; c < 400; c++) {
    int n = c % N + 1;
    int mode = c % 4, key = 0, dir = 1;
    for (int i = 0; i < n; i++) {
      seed = seed * 1664525u + 1013904223u;
      int r = (int)(seed >> 24);
      if (mode == 0) key = r % 7; /* random with many ties */
      else {
        if (r % 11 == 0) dir = mode == 1 ? 1 : -dir; /* a new run */
        if (r % 11 == 0) key = r % 20;
        key += dir * (mode == 3 ? (r & 1) : 1); /* mode 3: ties in runs */
      }
      v[i] = (SortItem){key, i};
    }
    int was_sorted = 1;
    for (int i = 1; i < n; i++) was_sorted &= v[i - 1].key <= v[i].key;
    bad += !sorts_stably(v, t, n, was_sorted);
    cases++;
  }
  ok(bad == 0, "SS_SORT_RUNS: %d of %d inputs (runs up and down, ties) in the stable order", cases - bad, cases);
  /* a sorted run with ties, then a tail of 1 to SS_SORT_RUNS_TAIL + 2
   * keys (ties with the run and among themselves, below and above it):
   * the stable order, and in place where the tail is inserted */
  bad = cases = 0;
  for (int c = 0; c < 300; c++) {
    int tail = c % (SS_SORT_RUNS_TAIL + 2) + 1, n = tail + 1 + (c * 7) % (N - tail);
    for (int i = 0; i < n; i++) {
      seed = seed * 1664525u + 1013904223u;
      int r = (int)(seed >> 24);
      v[i] = (SortItem){i < n - tail ? i / 3 : r % (n / 3 + 3) - 1, i};
    }
    int e0 = 1;
    while (e0 < n && v[e0 - 1].key <= v[e0].key) e0++;
    bad += !sorts_stably(v, t, n, n - e0 <= SS_SORT_RUNS_TAIL);
    cases++;
  }
  ok(bad == 0, "SS_SORT_RUNS: %d of %d runs with a short tail in the stable order, in place", cases - bad, cases);
  SortItem one[1] = {{3, 0}}, scratch[1];
  ok(sort_items(one, scratch, 1) == one && sort_items(one, scratch, 0) == one, "SS_SORT_RUNS: 0 and 1 elements stay in place");
}

/* ---------------------------------------------------------------------- */
/* signed distances and pair contacts                                      */

/* p = pos + R l */
static void put_local(const ssShape *s, const double l[3], double p[3])
{
  ss_m3_mulv(p, s->R, l);
  ss_v3_add(p, p, s->pos);
}

/* n + 1 evenly spaced values from a to b, ends included (the i-th) */
static double lerp_n(double a, double b, int i, int n) { return a + (b - a) * i / n; }

/* samples of the sphere of radius r about local (0, 0, zc), polar angle
 * from t0 to t1, arc spacing at most h each way; returns the new count */
static int sample_sphere(const ssShape *s, double r, double zc, double t0, double t1,
                         double h, double (*v)[3], int k)
{
  int nt = (int)ceil((t1 - t0) * r / h);
  for (int i = 0; i <= nt; i++) {
    double t = lerp_n(t0, t1, i, nt), st = sin(t);
    int np = (int)ceil(2 * PI * r * st / h);
    if (np < 1) np = 1;
    for (int j = 0; j < np; j++) {
      double f = 2 * PI * j / np;
      double l[3] = {r * st * cos(f), r * st * sin(f), zc + r * cos(t)};
      put_local(s, l, v[k++]);
    }
  }
  return k;
}

/* samples of a cylinder's side (radius r, |z| <= hl) and, when caps, its
 * two discs; spacing at most h along the surface each way */
static int sample_cylinder(const ssShape *s, double r, double hl, int caps, double h,
                           double (*v)[3], int k)
{
  int nf = (int)ceil(2 * PI * r / h), nz = (int)ceil(2 * hl / h);
  for (int i = 0; i <= nz; i++)
    for (int j = 0; j < nf; j++) {
      double f = 2 * PI * j / nf, l[3] = {r * cos(f), r * sin(f), lerp_n(-hl, hl, i, nz)};
      put_local(s, l, v[k++]);
    }
  if (!caps) return k;
  int nr = (int)ceil(r / h);
  for (int e = -1; e <= 1; e += 2)
    for (int i = 0; i <= nr; i++) {
      double rho = r * i / nr;
      int np = (int)ceil(2 * PI * rho / h);
      if (np < 1) np = 1;
      for (int j = 0; j < np; j++) {
        double f = 2 * PI * j / np, l[3] = {rho * cos(f), rho * sin(f), e * hl};
        put_local(s, l, v[k++]);
      }
    }
  return k;
}

/* points on the surface of s, no two neighbours more than h apart along
 * it (each way), in the frame; returns the count */
static int surface_samples(const ssShape *s, double h, double (*v)[3])
{
  int k = 0;
  switch (s->type) {
  case SS_GEOM_BOX:
    /* each face a grid with its edges, so that edges and corners are in */
    for (int ax = 0; ax < 3; ax++) {
      int u = (ax + 1) % 3, w = (ax + 2) % 3;
      int nu = (int)ceil(s->size[u] / h), nw = (int)ceil(s->size[w] / h);
      for (int e = -1; e <= 1; e += 2)
        for (int i = 0; i <= nu; i++)
          for (int j = 0; j <= nw; j++) {
            double l[3];
            l[ax] = e * 0.5 * s->size[ax];
            l[u] = lerp_n(-0.5 * s->size[u], 0.5 * s->size[u], i, nu);
            l[w] = lerp_n(-0.5 * s->size[w], 0.5 * s->size[w], j, nw);
            put_local(s, l, v[k++]);
          }
    }
    break;
  case SS_GEOM_SPHERE:
    k = sample_sphere(s, s->size[0], 0, 0, PI, h, v, k);
    break;
  case SS_GEOM_CYLINDER:
    k = sample_cylinder(s, s->size[0], 0.5 * s->size[1], 1, h, v, k);
    break;
  case SS_GEOM_CAPSULE:
    /* the side, and each end sphere's outer half only (the inner is not
     * on the surface) */
    k = sample_cylinder(s, s->size[0], 0.5 * s->size[1], 0, h, v, k);
    k = sample_sphere(s, s->size[0], 0.5 * s->size[1], 0, 0.5 * PI, h, v, k);
    k = sample_sphere(s, s->size[0], -0.5 * s->size[1], 0.5 * PI, PI, h, v, k);
    break;
  default:
    break;
  }
  return k;
}

/* 1 when p is inside s or on it, tested in the local frame without the
 * distance function */
static int inside_shape(const ssShape *s, const double p[3])
{
  double w[3], l[3];
  ss_v3_sub(w, p, s->pos);
  ss_m3_mulvT(l, s->R, w);
  double r = s->size[0], hl = 0.5 * s->size[1];
  switch (s->type) {
  case SS_GEOM_BOX:
    return fabs(l[0]) <= 0.5 * s->size[0] && fabs(l[1]) <= 0.5 * s->size[1] &&
           fabs(l[2]) <= 0.5 * s->size[2];
  case SS_GEOM_SPHERE:
    return ss_v3_dot(l, l) <= r * r;
  case SS_GEOM_CYLINDER:
    return l[0] * l[0] + l[1] * l[1] <= r * r && fabs(l[2]) <= hl;
  case SS_GEOM_CAPSULE: {
    double z = fabs(l[2]) > hl ? fabs(l[2]) - hl : 0;
    return l[0] * l[0] + l[1] * l[1] + z * z <= r * r;
  }
  default:
    return 0;
  }
}

/* ss_shape_sdf of each shape type at a random pose against brute force:
 * 2000 random points in and around it, |sdf| the distance to the nearest
 * of dense surface samples (spacing h): no less than it (the samples are
 * on the surface; 1e-12 for round-off) and no more than h beyond (every
 * surface point lies within h / sqrt 2 of a sample); the sign as an inside
 * test says; p - sdf n on the surface (its own sdf within 1e-12 of the
 * size: a few roundings of coordinates near 1); n a unit vector */
static double sdf_samples[40000][3];

static void test_shape_sdf(void)
{
  static const double sizes[4][3] = {
      [SS_GEOM_BOX] = {0.4, 0.3, 0.2},
      [SS_GEOM_SPHERE] = {0.25, 0, 0},
      [SS_GEOM_CYLINDER] = {0.2, 0.3, 0},
      [SS_GEOM_CAPSULE] = {0.1, 0.3, 0},
  };
  static const char *names[4] = {"box", "sphere", "cylinder", "capsule"};
  const double h = 0.01, tol = 1e-12;
  for (int type = 0; type < 4; type++) {
    double R[9];
    rot_random(R);
    ssShape s = make_shape(type, sizes[type][0], sizes[type][1], sizes[type][2],
                           urand(-1, 1), urand(-1, 1), urand(-1, 1), R);
    int ns = surface_samples(&s, h, sdf_samples);
    /* the local half extents, 0.15 wider around */
    double e[3];
    if (type == SS_GEOM_BOX) {
      for (int k = 0; k < 3; k++) e[k] = 0.5 * s.size[k];
    } else {
      e[0] = e[1] = s.size[0];
      e[2] = type == SS_GEOM_SPHERE ? s.size[0]
             : type == SS_GEOM_CYLINDER ? 0.5 * s.size[1]
                                        : 0.5 * s.size[1] + s.size[0];
    }
    double ext = ss_v3_norm(e);
    int bad_d = 0, bad_sign = 0, bad_surf = 0, bad_unit = 0, nin = 0;
    double worst_d = 0, worst_surf = 0;
    for (int i = 0; i < 2000; i++) {
      double l[3], p[3], n[3];
      for (int k = 0; k < 3; k++) l[k] = urand(-e[k] - 0.15, e[k] + 0.15);
      put_local(&s, l, p);
      double d = ss_shape_sdf(&s, p, n);
      double dmin = INFINITY;
      for (int j = 0; j < ns; j++) {
        double w[3];
        ss_v3_sub(w, p, sdf_samples[j]);
        dmin = fmin(dmin, ss_v3_dot(w, w));
      }
      dmin = sqrt(dmin);
      double ad = fabs(d);
      if (!(dmin >= ad - tol && dmin <= ad + h)) bad_d++;
      worst_d = fmax(worst_d, fabs(dmin - ad));
      int in = inside_shape(&s, p);
      nin += in;
      if ((d < -tol && !in) || (d > tol && in) || !isfinite(d)) bad_sign++;
      double q[3], nq[3];
      ss_v3_copy(q, p);
      ss_v3_addscl(q, n, -d);
      double dq = fabs(ss_shape_sdf(&s, q, nq));
      worst_surf = fmax(worst_surf, dq);
      if (!(dq <= tol * ext)) bad_surf++;
      if (!(fabs(ss_v3_norm(n) - 1) <= tol)) bad_unit++;
    }
    ok(bad_d == 0, "sdf %s: |sdf| within the sample spacing of the nearest of %d surface samples (%d of 2000 off, worst difference %.3g)",
       names[type], ns, bad_d, worst_d);
    ok(bad_sign == 0 && nin > 100 && nin < 1900, "sdf %s: negative inside, positive outside (%d inside, %d wrong)",
       names[type], nin, bad_sign);
    ok(bad_surf == 0, "sdf %s: p - sdf n on the surface (%d off, worst |sdf| %.3g)", names[type],
       bad_surf, worst_surf);
    ok(bad_unit == 0, "sdf %s: n a unit vector (%d not)", names[type], bad_unit);
  }
  /* where the way out is not unique: the documented choices */
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, n[3], c[3] = {0, 0, 0};
  ssShape sp = make_shape(SS_GEOM_SPHERE, 0.2, 0, 0, 0, 0, 0, I);
  double d = ss_shape_sdf(&sp, c, n);
  ok(d == -0.2 && n[0] == 0 && n[1] == 0 && n[2] == 1, "sdf: a sphere's centre leaves along +z at -r");
  ssShape bx = make_shape(SS_GEOM_BOX, 0.4, 0.4, 0.4, 0, 0, 0, I);
  d = ss_shape_sdf(&bx, c, n);
  ok(d == -0.2 && n[0] == 1 && n[1] == 0 && n[2] == 0, "sdf: a cube's centre leaves by its +x face");
  ssShape cy = make_shape(SS_GEOM_CYLINDER, 0.2, 1, 0, 0, 0, 0, I);
  d = ss_shape_sdf(&cy, c, n);
  ok(d == -0.2 && n[0] == 1 && n[1] == 0 && n[2] == 0, "sdf: a long cylinder's centre leaves along its local +x");
  ssShape cp = make_shape(SS_GEOM_CAPSULE, 0.2, 1, 0, 0, 0, 0, I);
  double pe[3] = {0, 0, 0.3};
  d = ss_shape_sdf(&cp, pe, n);
  ok(d == -0.2 && n[0] == 1 && n[1] == 0 && n[2] == 0, "sdf: a point of a capsule's segment leaves along its local +x");
  ssShape me = make_shape(SS_GEOM_MESH, 1, 1, 1, 0, 0, 0, I);
  double keep[3] = {7, 8, 9};
  ok(isnan(ss_shape_sdf(&me, c, keep)) && keep[0] == 7 && keep[1] == 8 && keep[2] == 9,
     "sdf: a mesh gives NaN and leaves n untouched");
}

/* the contact of id among out[0, n), or NULL */
static const ssPairPoint *pair_find(const ssPairPoint *out, int n, int id)
{
  for (int i = 0; i < n; i++)
    if (out[i].id == id) return &out[i];
  return NULL;
}

static int near3(const double a[3], const double b[3], double tol)
{
  return fabs(a[0] - b[0]) <= tol && fabs(a[1] - b[1]) <= tol && fabs(a[2] - b[2]) <= tol;
}

/* 1 when p and q are the same bits, field by field (not memcmp of the
 * structs: their padding after id is not theirs to set) */
static int pair_same(const ssPairPoint *p, const ssPairPoint *q)
{
  return memcmp(p->pos, q->pos, sizeof p->pos) == 0 && memcmp(p->n, q->n, sizeof p->n) == 0 &&
         memcmp(&p->gap, &q->gap, sizeof p->gap) == 0 && p->id == q->id;
}

/* the contacts of (a, b) and of (b, a): the same, each with its id moved
 * to the other side, its normal negated, its gap and point the same bits;
 * and a second call the same bits as the first */
static int pair_swaps(const ssShape *a, const ssShape *b, double margin)
{
  ssPairPoint p[SS_PAIR_POINTS_MAX], q[SS_PAIR_POINTS_MAX], r[SS_PAIR_POINTS_MAX];
  int np = ss_shape_pair_points(a, b, margin, p, SS_PAIR_POINTS_MAX);
  int nq = ss_shape_pair_points(b, a, margin, q, SS_PAIR_POINTS_MAX);
  int nr = ss_shape_pair_points(a, b, margin, r, SS_PAIR_POINTS_MAX);
  if (np != nq || np != nr || np == 0) return 0;
  for (int i = 0; i < np; i++) {
    if (!pair_same(&p[i], &r[i])) return 0;
    const ssPairPoint *o = pair_find(q, nq, p[i].id < 16 ? p[i].id + 16 : p[i].id - 16);
    if (!o || o->gap != p[i].gap || memcmp(o->pos, p[i].pos, sizeof o->pos) != 0) return 0;
    for (int k = 0; k < 3; k++)
      if (o->n[k] != -p[i].n[k]) return 0;
  }
  return 1;
}

/* every contact's normal +z and gap want (to tol) */
static int all_up_at(const ssPairPoint *out, int n, double want, double tol)
{
  const double up[3] = {0, 0, 1};
  for (int i = 0; i < n; i++)
    if (!near3(out[i].n, up, 1e-12) || !(fabs(out[i].gap - want) <= tol)) return 0;
  return n > 0;
}

/* no edge-side contact (ids 8..15 or 24..31) among out[0..n) */
static int edge_side_none(const ssPairPoint *out, int n)
{
  for (int i = 0; i < n; i++)
    if ((out[i].id >= 8 && out[i].id < 16) || out[i].id >= 24) return 0;
  return 1;
}

static void test_pair_points(void)
{
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, up[3] = {0, 0, 1}, tol = 1e-12;
  ssPairPoint out[SS_PAIR_POINTS_MAX];
  double R[9];

  /* two spheres 0.05 into each other along a random direction */
  double u[3] = {urand(-1, 1), urand(-1, 1), urand(-1, 1)};
  ss_v3_normalize(u);
  double cb[3] = {urand(-1, 1), urand(-1, 1), urand(-1, 1)}, ca[3];
  ss_v3_copy(ca, cb);
  ss_v3_addscl(ca, u, 0.45);
  ssShape sa = make_shape(SS_GEOM_SPHERE, 0.3, 0, 0, ca[0], ca[1], ca[2], I);
  ssShape sb = make_shape(SS_GEOM_SPHERE, 0.2, 0, 0, cb[0], cb[1], cb[2], I);
  int n = ss_shape_pair_points(&sa, &sb, 0, out, SS_PAIR_POINTS_MAX);
  double w[3];
  if (n == 1) ss_v3_sub(w, out[0].pos, ca);
  ok(n == 1 && out[0].id == 0 && fabs(out[0].gap + 0.05) <= tol && near3(out[0].n, u, tol) &&
         fabs(ss_v3_norm(w) - 0.3) <= tol && fabs(ss_v3_dot(w, u) + 0.3) <= tol,
     "pair: two spheres 0.05 into each other: one contact, gap %.12g, along the centre line, on a's surface",
     n ? out[0].gap : NAN);

  /* a sphere of r 0.1 over a 1 x 1 x 0.2 box's top face (at z = 0) */
  ssShape slab = make_shape(SS_GEOM_BOX, 1, 1, 0.2, 0, 0, -0.1, I);
  ssShape ball = make_shape(SS_GEOM_SPHERE, 0.1, 0, 0, 0, 0, 0.095, I);
  n = ss_shape_pair_points(&ball, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  double want_pos[3] = {0, 0, -0.005};
  ok(n == 1 && out[0].id == 0 && all_up_at(out, n, -0.005, tol) && near3(out[0].pos, want_pos, tol),
     "pair: a ball 5 mm into a box's face: one contact (the ball's), gap -0.005, n +z");
  ok(pair_swaps(&ball, &slab, 0.01), "pair: ball and box swapped: the same contact, id 16, n -z");
  /* over the box's edge (x = 0.5, z = 0), 0.09 from it along (0.6, 0, 0.8) */
  ball.pos[0] = 0.5 + 0.054;
  ball.pos[2] = 0.072;
  n = ss_shape_pair_points(&ball, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  double ne[3] = {0.6, 0, 0.8};
  ok(n == 1 && out[0].id == 0 && fabs(out[0].gap + 0.01) <= tol && near3(out[0].n, ne, tol),
     "pair: a ball over a box's edge: gap %.12g = 0.09 - 0.1 from the edge, n along the way to the edge",
     n ? out[0].gap : NAN);
  /* over its corner (0.5, 0.5, 0), 0.098 from it along (2, 3, 6) / 7:
   * the ball's contact and the corner's (id 16 + 7), one normal and gap */
  double nc[3] = {2.0 / 7, 3.0 / 7, 6.0 / 7};
  ss_v3_set(ball.pos, 0.5, 0.5, 0);
  ss_v3_addscl(ball.pos, nc, 0.098);
  n = ss_shape_pair_points(&ball, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  const ssPairPoint *pc = pair_find(out, n, 23);
  ok(n == 2 && out[0].id == 0 && fabs(out[0].gap + 0.002) <= tol && near3(out[0].n, nc, tol) &&
         pc && fabs(pc->gap + 0.002) <= tol && near3(pc->n, nc, tol),
     "pair: a ball 2 mm into a box's corner: gap %.12g from the corner, the corner's own contact the same gap and normal",
     n ? out[0].gap : NAN);
  /* resting on the corner (gap 0): the two are one point, the corner's
   * dropped */
  ss_v3_set(ball.pos, 0.5, 0.5, 0);
  ss_v3_addscl(ball.pos, nc, 0.1);
  n = ss_shape_pair_points(&ball, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(n == 1 && out[0].id == 0 && fabs(out[0].gap) <= tol,
     "pair: a ball resting on a box's corner: one contact (the corner's the same point, dropped)");

  /* a 0.2 x 0.2 x 0.1 box 1 mm into the slab's top face, aligned */
  ssShape top = make_shape(SS_GEOM_BOX, 0.2, 0.2, 0.1, 0.1, -0.05, 0.049, I);
  n = ss_shape_pair_points(&top, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(n == 4 && out[0].id == 0 && out[1].id == 1 && out[2].id == 2 && out[3].id == 3 &&
         all_up_at(out, n, -0.001, tol),
     "pair: a box 1 mm into another's face: its 4 bottom corners (ids 0-3), gap -0.001, n +z, none of the big box's");
  rot_z(R, 30 * PI / 180);
  memcpy(top.R, R, sizeof R);
  n = ss_shape_pair_points(&top, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  int at_corner = n == 4;
  for (int i = 0; i < n && at_corner; i++) at_corner = fabs(out[i].pos[2] + 0.001) <= tol && out[i].id < 4;
  ok(at_corner && all_up_at(out, n, -0.001, tol),
     "pair: turned 30 degrees about z: the same 4 bottom corners at gap -0.001, n +z");
  ok(pair_swaps(&top, &slab, 0.01), "pair: the two boxes swapped: the same corners, ids 16-19, n -z, same gaps");
  /* a random heading and a 3-degree tilt, the lowest corner 1 mm in:
   * every contact's gap its corner's height over the face */
  rot_tilt(R, 3 * PI / 180, urand(0, 2 * PI));
  memcpy(top.R, R, sizeof R);
  top.pos[2] = 0;
  double cn[8][3], zlo = INFINITY;
  ss_shape_candidates(&top, up, cn, 8);
  for (int i = 0; i < 8; i++) zlo = fmin(zlo, cn[i][2]);
  top.pos[2] = -0.001 - zlo;
  ss_shape_candidates(&top, up, cn, 8);
  int want_n = 0, lowest = -1;
  zlo = INFINITY;
  for (int i = 0; i < 8; i++) {
    want_n += cn[i][2] <= 0.005;
    if (cn[i][2] < zlo) {
      zlo = cn[i][2];
      lowest = i;
    }
  }
  n = ss_shape_pair_points(&top, &slab, 0.005, out, SS_PAIR_POINTS_MAX);
  int heights = n == want_n;
  for (int i = 0; i < n && heights; i++)
    heights = out[i].id < 8 && fabs(out[i].gap - out[i].pos[2]) <= tol &&
              near3(out[i].pos, cn[out[i].id], 0) && near3(out[i].n, up, tol);
  pc = pair_find(out, n, lowest);
  ok(heights && pc && fabs(pc->gap + 0.001) <= tol,
     "pair: a box tilted 3 degrees: %d corners within the margin, each gap its height over the face, the lowest's %.12g",
     n, pc ? pc->gap : NAN);

  /* a capsule (r 0.05, 0.4 long) lying flat across the slab, 2 mm in:
   * both ends and the middle */
  rot_wheel(R, urand(0, 2 * PI), 0);
  ssShape cap = make_shape(SS_GEOM_CAPSULE, 0.05, 0.4, 0, 0.1, 0.05, 0.048, R);
  n = ss_shape_pair_points(&cap, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(n == 3 && out[0].id == 0 && out[1].id == 1 && out[2].id == 2 && all_up_at(out, n, -0.002, tol),
     "pair: a capsule lying across a box: both ends and the middle, gap -0.002, n +z");
  ok(pair_swaps(&cap, &slab, 0.01), "pair: capsule and box swapped: the same three, ids 16-18, n -z");

  /* a cylinder (r 0.3, 0.2 long) on its side, 3 mm in: its rim's lowest
   * points, one per cap, at the cylinder's lowest point's height */
  rot_wheel(R, urand(0, 2 * PI), urand(0, 2 * PI));
  ssShape wheel = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, -0.1, 0.1, 0.297, R);
  n = ss_shape_pair_points(&wheel, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(n == 2 && out[0].id == 0 && out[1].id == 1 && all_up_at(out, n, 0.297 - 0.3, tol),
     "pair: a cylinder on its side: its two lowest rim points (ids 0, 1), gap %.12g = its lowest point's height",
     n ? out[0].gap : NAN);
  ok(pair_swaps(&wheel, &slab, 0.01), "pair: cylinder on its side and box swapped: the same, n -z");
  /* standing on its end, 2 mm in: the 8 rim points of its bottom cap */
  rot_z(R, urand(0, 2 * PI));
  ssShape post = make_shape(SS_GEOM_CYLINDER, 0.3, 0.2, 0, 0.05, 0, 0.098, R);
  n = ss_shape_pair_points(&post, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  int rim = n == 8 && out[0].id == 0;
  for (int i = 1; i < n && rim; i++) rim = out[i].id == i + 1;
  ok(rim && all_up_at(out, n, -0.002, tol),
     "pair: a cylinder standing on its end: its bottom cap's 8 rim points (ids 0, 2-8), gap -0.002");
  ok(pair_swaps(&post, &slab, 0.01), "pair: standing cylinder and box swapped: the same, n -z");

  /* a box (0.3 x 0.3 x 0.2) across a log (r 0.2, 2 long, its axis along
   * y through the origin), turned 10-20 degrees about z, its bottom 2 mm
   * into the log's top: its corners and the log's rims are far (no
   * contact), but the two bottom edges that cross the log's top line do,
   * each at its point over the axis, gap -0.002, n +z (ids 8..11).  It
   * found none: a crate sank into a log until its corners met it. */
  rot_wheel(R, 0, 0);
  ssShape log_ = make_shape(SS_GEOM_CYLINDER, 0.2, 2, 0, 0, 0, 0, R);
  rot_z(R, urand(10, 20) * PI / 180);
  ssShape crate = make_shape(SS_GEOM_BOX, 0.3, 0.3, 0.2, 0, 0, 0.298, R);
  n = ss_shape_pair_points(&crate, &log_, 0.01, out, SS_PAIR_POINTS_MAX);
  int across = n == 2 && all_up_at(out, n, -0.002, tol);
  for (int i = 0; i < n && across; i++)
    across = out[i].id >= 8 && out[i].id < 12 && fabs(out[i].pos[0]) <= tol &&
             fabs(out[i].pos[2] - 0.198) <= tol;
  ok(across && out[0].pos[1] * out[1].pos[1] < 0,
     "pair: a box across a cylinder's side: the two bottom edges over the axis (ids 8-11), "
     "gap -0.002, n +z (%d contacts)", n);
  ok(pair_swaps(&crate, &log_, 0.01), "pair: box across a cylinder swapped: the same, ids 24-27, n -z");
  /* a log (r 0.1, 2 long) across a 1 m wide box, 1 mm in: the box's two
   * top edges under it, at y = +-0.5 (the log's rims overhang) */
  rot_wheel(R, 0, urand(0, 2 * PI));
  log_ = make_shape(SS_GEOM_CYLINDER, 0.1, 2, 0, 0.1, 0, 0.099, R);
  n = ss_shape_pair_points(&log_, &slab, 0.01, out, SS_PAIR_POINTS_MAX);
  across = n == 2 && all_up_at(out, n, -0.001, tol);
  for (int i = 0; i < n && across; i++)
    across = out[i].id >= 24 && out[i].id < 28 && fabs(fabs(out[i].pos[1]) - 0.5) <= tol &&
             fabs(out[i].pos[0] - 0.1) <= tol && fabs(out[i].pos[2]) <= tol;
  ok(across, "pair: a cylinder across a narrower box: the box's two top edges under it (ids 24-27), "
     "gap -0.001, n +z (%d contacts)", n);
  /* the same box across a capsule of the same radius and segment: the
   * same two edges (ids 8..11), and the swap */
  rot_wheel(R, 0, 0);
  ssShape caplog = make_shape(SS_GEOM_CAPSULE, 0.2, 2, 0, 0, 0, 0, R);
  n = ss_shape_pair_points(&crate, &caplog, 0.01, out, SS_PAIR_POINTS_MAX);
  int on_cap = 0;
  for (int i = 0; i < n; i++)
    on_cap += out[i].id >= 8 && out[i].id < 12 && fabs(out[i].gap + 0.002) <= tol &&
              near3(out[i].n, up, tol) && fabs(out[i].pos[2] - 0.198) <= tol;
  ok(on_cap == 2 && pair_swaps(&crate, &caplog, 0.01),
     "pair: a box across a capsule's side: the two bottom edges over the axis, gap -0.002, n +z; "
     "swapped the same");
  /* two logs crossed: b (r 0.2) along y through the origin, a (r 0.1)
   * along x over it, 1 mm in: one contact of their sides where the axes
   * cross, a's id 5, gap -0.001, n +z (b to a), on a's surface; the rims
   * are far.  It found none: the upper log fell into the lower. */
  rot_wheel(R, 0, urand(0, 2 * PI));
  ssShape low = make_shape(SS_GEOM_CYLINDER, 0.2, 2, 0, 0, 0, 0, R);
  rot_wheel(R, 0.5 * PI, urand(0, 2 * PI));
  ssShape high = make_shape(SS_GEOM_CYLINDER, 0.1, 2, 0, 0.2, 0.3, 0.299, R);
  double at_a[3] = {0, 0.3, 0.199}, at_b[3] = {0, 0.3, 0.2}, down[3] = {0, 0, -1};
  n = ss_shape_pair_points(&high, &low, 0.01, out, SS_PAIR_POINTS_MAX);
  int crossed = n == 1 && out[0].id == 5 && all_up_at(out, n, -0.001, tol) && near3(out[0].pos, at_a, tol);
  n = ss_shape_pair_points(&low, &high, 0.01, out, SS_PAIR_POINTS_MAX);
  crossed = crossed && n == 1 && out[0].id == 5 && fabs(out[0].gap + 0.001) <= tol &&
            near3(out[0].n, down, tol) && near3(out[0].pos, at_b, tol);
  ok(crossed, "pair: two cylinders crossed, 1 mm in: their sides' one contact where the axes "
     "cross (a's id 5), gap -0.001, n from b to a, on a's surface either way round");
  /* a capsule (r 0.1) crossing the lower log at 30 degrees from x, its
   * centre off the log's axis: the sides' contact (the capsule's id 3, 19
   * as b) where the axes cross, not only its middle point's towards the
   * log's centre */
  double A30[9], W[9];
  rot_wheel(W, 0.5 * PI, 0);
  rot_z(A30, PI / 6);
  ss_m3_mul(R, A30, W);
  ssShape capx = make_shape(SS_GEOM_CAPSULE, 0.1, 2, 0, 0, 0.3, 0.299, R);
  n = ss_shape_pair_points(&capx, &low, 0.01, out, SS_PAIR_POINTS_MAX);
  pc = pair_find(out, n, 3);
  ok(pc && fabs(pc->gap + 0.001) <= tol && near3(pc->n, up, tol) && near3(pc->pos, at_a, tol) &&
         pair_swaps(&capx, &low, 0.01),
     "pair: a capsule across a cylinder: their sides' contact where the axes cross (id 3), "
     "gap %.12g, n +z; swapped, id 19", pc ? pc->gap : NAN);
  /* two capsules crossed at 60 degrees away from both centres (the
   * upper one's centre 0.4 along its axis from the crossing, the lower
   * one's 0.3): their sides' contact where the axes cross (a's id 3),
   * which their middle points (towards each other's centres) miss */
  rot_wheel(R, 0, 0);
  ssShape capy = make_shape(SS_GEOM_CAPSULE, 0.2, 2, 0, 0, 0, 0, R);
  ss_m3_mul(R, A30, W);
  ssShape capu = make_shape(SS_GEOM_CAPSULE, 0.1, 2, 0, 0.4 * cos(PI / 6),
                            0.3 + 0.4 * sin(PI / 6), 0.299, R);
  double at_c[3] = {0, 0.3, 0.199};
  n = ss_shape_pair_points(&capu, &capy, 0.01, out, SS_PAIR_POINTS_MAX);
  pc = pair_find(out, n, 3);
  ok(pc && fabs(pc->gap + 0.001) <= tol && near3(pc->n, up, tol) && near3(pc->pos, at_c, tol),
     "pair: two capsules crossed away from their centres: their sides' contact where the axes "
     "cross (a's id 3), gap %.12g, n +z", pc ? pc->gap : NAN);
  /* a log (r 0.05) across a post's top (a cylinder standing, r 0.3, its
   * cap at z = 0.5), 1 mm in, turned off the rim's 8 points: the log's
   * point over the post's axis, on the cap, a's id 5, gap -0.001, n +z;
   * swapped, on b's side, id 21 */
  rot_z(R, 0);
  ssShape post2 = make_shape(SS_GEOM_CYLINDER, 0.3, 0.5, 0, 0, 0, 0.25, R);
  rot_wheel(R, PI / 8, 0);
  ssShape lg = make_shape(SS_GEOM_CYLINDER, 0.05, 1.2, 0, 0, 0, 0.549, R);
  double at_cap[3] = {0, 0, 0.499}, down2[3] = {0, 0, -1};
  n = ss_shape_pair_points(&lg, &post2, 0.01, out, SS_PAIR_POINTS_MAX);
  int capped = n == 1 && out[0].id == 5 && all_up_at(out, n, -0.001, tol) &&
               near3(out[0].pos, at_cap, tol);
  n = ss_shape_pair_points(&post2, &lg, 0.01, out, SS_PAIR_POINTS_MAX);
  capped = capped && n == 1 && out[0].id == 21 && fabs(out[0].gap + 0.001) <= tol &&
           near3(out[0].n, down2, tol) && near3(out[0].pos, at_cap, tol);
  ok(capped, "pair: a cylinder lying across another's cap, off its rim points: one contact "
     "over the axis on the cap (id 5; 21 swapped), gap -0.001 (%d)", n);
  /* parallel to the axis: no edge contact (the rims and corners hold it) */
  rot_wheel(R, 0, 0);
  log_ = make_shape(SS_GEOM_CYLINDER, 0.2, 2, 0, 0, 0, 0, R);
  double Rq[9];
  rot_y(Rq, 0.25 * PI);
  ssShape ridge = make_shape(SS_GEOM_BOX, 0.3, 0.3, 0.3, 0, 0, 0.2 + 0.15 * sqrt(2) - 0.001, Rq);
  n = ss_shape_pair_points(&ridge, &log_, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(edge_side_none(out, n), "pair: a box's edge along a cylinder's axis: no edge contact (%d)", n);

  /* the margin: a gap of half the margin kept, of 1.5 margins dropped */
  memcpy(top.R, I, sizeof I);
  top.pos[2] = 0.051; /* 1 mm above */
  n = ss_shape_pair_points(&top, &slab, 0.002, out, SS_PAIR_POINTS_MAX);
  ok(n == 4 && all_up_at(out, n, 0.001, tol), "pair: gaps of half the margin kept (%d)", n);
  n = ss_shape_pair_points(&top, &slab, 0.001 / 1.5, out, SS_PAIR_POINTS_MAX);
  ok(n == 0, "pair: gaps of 1.5 margins dropped (%d)", n);

  /* max: the first in id order; nothing past max written */
  top.pos[2] = 0.049;
  ssPairPoint all[SS_PAIR_POINTS_MAX];
  int na = ss_shape_pair_points(&top, &slab, 0.01, all, SS_PAIR_POINTS_MAX);
  memset(out, 0x5a, sizeof out);
  ssPairPoint fill;
  memset(&fill, 0x5a, sizeof fill);
  n = ss_shape_pair_points(&top, &slab, 0.01, out, 2);
  ok(na == 4 && n == 2 && pair_same(&out[0], &all[0]) && pair_same(&out[1], &all[1]) &&
         memcmp(&out[2], &fill, sizeof fill) == 0 &&
         ss_shape_pair_points(&top, &slab, 0.01, out, 0) == 0,
     "pair: max 2 of 4: count 2, the first two in id order, nothing more written; max 0: none");

  /* a mesh: no contacts */
  ssShape me = make_shape(SS_GEOM_MESH, 1, 1, 1, 0, 0, 0, I);
  ok(ss_shape_pair_points(&me, &ball, 1, out, SS_PAIR_POINTS_MAX) == 0 &&
         ss_shape_pair_points(&ball, &me, 1, out, SS_PAIR_POINTS_MAX) == 0,
     "pair: a mesh on either side: no contacts");
}


/* the edge contacts (ids 8..15) of out[0..n): their count; ids rising */
static int edge_count(const ssPairPoint *out, int n)
{
  int c = 0, last = -1;
  for (int i = 0; i < n; i++) {
    if (out[i].id < last) return -1;
    last = out[i].id;
    c += out[i].id >= 8 && out[i].id < 16;
  }
  return c;
}

/* (a, b) and (b, a) give the same edge contacts: same count, each with the
 * same point and gap (to tol) and the negated normal */
static int edge_swaps(const ssShape *a, const ssShape *b, double margin, double tol)
{
  ssPairPoint p[SS_PAIR_POINTS_MAX], q[SS_PAIR_POINTS_MAX];
  int np = ss_shape_pair_points(a, b, margin, p, SS_PAIR_POINTS_MAX);
  int nq = ss_shape_pair_points(b, a, margin, q, SS_PAIR_POINTS_MAX);
  if (edge_count(p, np) != edge_count(q, nq) || edge_count(p, np) <= 0) return 0;
  for (int i = 0; i < np; i++) {
    if (p[i].id < 8 || p[i].id >= 16) continue;
    int found = 0;
    for (int j = 0; j < nq && !found; j++) {
      double mn[3];
      ss_v3_scale(mn, q[j].n, -1);
      found = q[j].id >= 8 && q[j].id < 16 && fabs(q[j].gap - p[i].gap) <= tol &&
              near3(q[j].pos, p[i].pos, tol) && near3(mn, p[i].n, tol);
    }
    if (!found) return 0;
  }
  return 1;
}

/* Random overlapping pairs of every kind ss_shape_pair_points takes
 * (box, sphere, cylinder, capsule, random sizes and poses): at most
 * SS_PAIR_POINTS_MAX contacts, their ids in [0, 32) strictly rising (a
 * contact's warm-start key is its id: two of one id would share one),
 * unit normals, gaps within the margin, points finite. */
static void test_pair_random(void)
{
  static const int types[4] = {SS_GEOM_BOX, SS_GEOM_SPHERE, SS_GEOM_CYLINDER, SS_GEOM_CAPSULE};
  const double margin = 0.01;
  int bad = 0, with = 0, most = 0;
  for (int t = 0; t < 4000; t++) {
    ssShape sh[2];
    for (int k = 0; k < 2; k++) {
      double R[9];
      rot_random(R);
      sh[k] = make_shape(types[(t >> (2 * k)) & 3], urand(0.05, 0.5), urand(0.05, 2),
                         urand(0.05, 0.5), urand(-0.3, 0.3), urand(-0.3, 0.3), urand(-0.3, 0.3), R);
    }
    ssPairPoint out[SS_PAIR_POINTS_MAX];
    int n = ss_shape_pair_points(&sh[0], &sh[1], margin, out, SS_PAIR_POINTS_MAX);
    with += n > 0;
    most = n > most ? n : most;
    for (int i = 0; i < n; i++) {
      const ssPairPoint *q = out + i;
      int good = q->id >= 0 && q->id < 32 && (i == 0 || q->id > out[i - 1].id) &&
                 fabs(ss_v3_norm(q->n) - 1) <= 1e-12 && q->gap <= margin &&
                 isfinite(q->pos[0] + q->pos[1] + q->pos[2]);
      bad += !good;
    }
  }
  ok(bad == 0 && with > 1000 && most <= SS_PAIR_POINTS_MAX,
     "pair: 4000 random pairs of boxes, spheres, cylinders and capsules (%d touching, at most %d "
     "contacts): ids rising within [0, 32), unit normals, gaps within the margin (%d bad)", with,
     most, bad);
}

static void test_pair_edges(void)
{
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, up[3] = {0, 0, 1}, tol = 1e-12;
  ssPairPoint out[SS_PAIR_POINTS_MAX];
  double R[9];

  /* two 1 x 0.2 x 0.2 bars crossed at 90 degrees, the upper 1 mm into the
   * lower's top (z = 0): no corner of either lies over the other (each
   * 0.4 beyond it), so the corners alone gave nothing; now the square where
   * the two faces overlap is held at its 4 corners, each a crossing of an
   * edge of each bar: 4 edge contacts at (+-0.1, +-0.1, -0.0005), gap
   * -0.001, n +z, ids 8 + (a's edge's colour 0, 1) + (4 by the side) */
  ssShape lo = make_shape(SS_GEOM_BOX, 1, 0.2, 0.2, 0, 0, -0.1, I);
  rot_z(R, 0.5 * PI);
  ssShape hi = make_shape(SS_GEOM_BOX, 1, 0.2, 0.2, 0, 0, 0.099, R);
  int n = ss_shape_pair_points(&hi, &lo, 0.01, out, SS_PAIR_POINTS_MAX);
  int sq = n == 4 && edge_count(out, n) == 4 && all_up_at(out, n, -0.001, tol);
  for (int i = 0; i < n && sq; i++)
    sq = fabs(fabs(out[i].pos[0]) - 0.1) <= tol && fabs(fabs(out[i].pos[1]) - 0.1) <= tol &&
         fabs(out[i].pos[2] + 0.0005) <= tol;
  for (int i = 1; i < n && sq; i++)
    sq = out[i].pos[0] != out[0].pos[0] || out[i].pos[1] != out[0].pos[1];
  ok(sq && out[0].id == 8 && out[1].id == 9 && out[2].id == 12 && out[3].id == 13,
     "pair edges: two bars crossed at 90 degrees, 1 mm in: the overlap square's 4 corners, edge crossings, gap -0.001, n +z (%d)",
     n);
  ok(edge_swaps(&hi, &lo, 0.01, tol), "pair edges: the crossed bars swapped: the same 4, n -z");
  /* two 1 x 1 x 0.2 slabs, the upper turned 45 degrees: their faces
   * overlap in an octagon, no corner over the other: its 8 vertices,
   * ids 8..15 each once */
  ssShape sl = make_shape(SS_GEOM_BOX, 1, 1, 0.2, 0, 0, -0.1, I);
  rot_z(R, 0.25 * PI);
  ssShape oc = make_shape(SS_GEOM_BOX, 1, 1, 0.2, 0, 0, 0.099, R);
  n = ss_shape_pair_points(&oc, &sl, 0.01, out, SS_PAIR_POINTS_MAX);
  int octo = n == 8 && edge_count(out, n) == 8 && all_up_at(out, n, -0.001, tol);
  for (int i = 0; i < n && octo; i++)
    octo = out[i].id == 8 + i &&
           fabs(fmax(fabs(out[i].pos[0]), fabs(out[i].pos[1])) - 0.5) <= tol &&
           fabs((fabs(out[i].pos[0]) + fabs(out[i].pos[1])) - 0.5 * sqrt(2.0)) <= tol;
  ok(octo, "pair edges: two slabs turned 45 degrees: the overlap octagon's 8 vertices, ids 8-15 (%d)", n);

  /* true edge on edge: a (1 x 0.2 x 0.2) turned 45 degrees about x, its
   * lowest edge along x at z = za - 0.1 sqrt 2; b (0.2 x 1 x 0.2) turned 45
   * degrees about y, its highest along y at z = 0.1 sqrt 2; 3 mm into each
   * other: one contact at the crossing, gap -0.003, n +z, the point midway */
  const double d = 0.003, h = 0.1 * sqrt(2.0);
  rot_x(R, 0.25 * PI);
  ssShape ea = make_shape(SS_GEOM_BOX, 1, 0.2, 0.2, 0, 0, 2 * h - d, R);
  rot_y(R, 0.25 * PI);
  ssShape eb = make_shape(SS_GEOM_BOX, 0.2, 1, 0.2, 0, 0, 0, R);
  n = ss_shape_pair_points(&ea, &eb, 0.01, out, SS_PAIR_POINTS_MAX);
  double wp[3] = {0, 0, h - 0.5 * d};
  ok(n == 1 && out[0].id >= 8 && out[0].id < 16 && fabs(out[0].gap + d) <= tol &&
         near3(out[0].n, up, tol) && near3(out[0].pos, wp, tol),
     "pair edges: two edges crossed 3 mm into each other: one contact, gap %.12g, n +z, at the crossing",
     n ? out[0].gap : NAN);
  ok(edge_swaps(&ea, &eb, 0.01, 1e-15), "pair edges: the two swapped: the same contact, n -z, same gap");
  /* moved along the edges (a by 0.2 along x, b by -0.3 along y): still
   * one contact, now at (0, 0, ...) of the frame: the crossing moves
   * with neither (both edges run through the origin's vertical) */
  ea.pos[0] = 0.2;
  eb.pos[1] = -0.3;
  n = ss_shape_pair_points(&ea, &eb, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(n == 1 && out[0].id >= 8 && fabs(out[0].gap + d) <= tol && near3(out[0].pos, wp, tol),
     "pair edges: slid along their edges: the same crossing (%d)", n);
  /* separated by 0.02: none at margin 0.01; at margin 0.03 the one, gap 0.02 */
  ea.pos[2] = 2 * h + 0.02;
  n = ss_shape_pair_points(&ea, &eb, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(n == 0, "pair edges: 0.02 apart, margin 0.01: none (%d)", n);
  n = ss_shape_pair_points(&ea, &eb, 0.03, out, SS_PAIR_POINTS_MAX);
  ok(n == 1 && out[0].id >= 8 && fabs(out[0].gap - 0.02) <= tol && near3(out[0].n, up, tol),
     "pair edges: 0.02 apart, margin 0.03: one at gap %.12g", n ? out[0].gap : NAN);
  /* slid until a's edge ends where it crosses b's (the crossing at an end
   * of a's edge: a corner's place, left to the corners), and a little
   * further: no edge contact */
  ea.pos[2] = 2 * h - d;
  ea.pos[0] = 0.5;
  n = ss_shape_pair_points(&ea, &eb, 0.01, out, SS_PAIR_POINTS_MAX);
  int ne0 = edge_count(out, n);
  ea.pos[0] = 0.5 + 1e-6;
  n = ss_shape_pair_points(&ea, &eb, 0.01, out, SS_PAIR_POINTS_MAX);
  ok(ne0 == 0 && edge_count(out, n) == 0,
     "pair edges: the crossing at an edge's end, and past it: no edge contact (corners' place)");
  /* the crossed bars with the upper's end face at the lower's side face
   * (y = 0.1): its bottom edges meet the lower's top edges only at their
   * ends (none of those); what touches is the end face's two vertical
   * edges across the lower's top edge, at gap 0 along +y, the axis that
   * separates the bars best (by 0 against 0.001 down): 2 edge contacts
   * at (+-0.1, 0.1, 0), n +y, gap 0 */
  hi.pos[1] = 0.6;
  n = ss_shape_pair_points(&hi, &lo, 0.01, out, SS_PAIR_POINTS_MAX);
  const double ey[3] = {0, 1, 0};
  int ends = edge_count(out, n) == 2;
  for (int i = 0; i < n && ends; i++)
    if (out[i].id >= 8 && out[i].id < 16)
      ends = near3(out[i].n, ey, tol) && fabs(out[i].gap) <= tol &&
             fabs(fabs(out[i].pos[0]) - 0.1) <= tol && fabs(out[i].pos[1] - 0.1) <= tol &&
             fabs(out[i].pos[2]) <= tol;
  ok(ends, "pair edges: a bar's end at the other's side: not its bottom edges (ends); its end's vertical edges across the top edge, gap 0, n +y");

  /* random poses: every edge contact's two points pos -+ gap n / 2 lie on
   * the two boxes' edges (sdf 0 to 1e-12 of the size), its normal is unit
   * and across both edges, gap <= margin, the point within margin of both */
  const double margin = 0.01;
  int pairs = 0, with = 0, total = 0, good = 1, sym = 1, asym = 0;
  for (int it = 0; it < 2000; it++) {
    double Ra[9], Rb[9];
    rot_random(Ra);
    rot_random(Rb);
    ssShape a = make_shape(SS_GEOM_BOX, urand(0.1, 1), urand(0.1, 1), urand(0.1, 1), 0, 0, 0, Ra);
    ssShape b = make_shape(SS_GEOM_BOX, urand(0.1, 1), urand(0.1, 1), urand(0.1, 1),
                           urand(-0.4, 0.4), urand(-0.4, 0.4), urand(-0.4, 0.4), Rb);
    double sz = ss_v3_norm(a.size) + ss_v3_norm(b.size);
    /* overlapping: a's centre pushed out of b along a random direction to
     * near the touching distance */
    double u[3] = {urand(-1, 1), urand(-1, 1), urand(-1, 1)};
    ss_v3_normalize(u);
    double lo_t = 0, hi_t = 2 * sz, w[3], m[3];
    for (int k = 0; k < 60; k++) {
      /* bisect for the distance where a's nearest corner leaves b */
      double t = 0.5 * (lo_t + hi_t);
      ss_v3_copy(a.pos, b.pos);
      ss_v3_addscl(a.pos, u, t);
      double lo3[3], hi3[3];
      ss_shape_aabb(&a, lo3, hi3);
      ss_shape_aabb(&b, w, m);
      int apart = lo3[0] > m[0] || hi3[0] < w[0] || lo3[1] > m[1] || hi3[1] < w[1] ||
                  lo3[2] > m[2] || hi3[2] < w[2];
      if (apart) hi_t = t;
      else lo_t = t;
    }
    ss_v3_copy(a.pos, b.pos);
    ss_v3_addscl(a.pos, u, lo_t * urand(0.5, 1));
    n = ss_shape_pair_points(&a, &b, margin, out, SS_PAIR_POINTS_MAX);
    int ne = edge_count(out, n);
    pairs++;
    if (ne < 0 || ne > 8) good = 0;
    if (ne > 0) with++;
    total += ne > 0 ? ne : 0;
    for (int i = 0; i < n; i++) {
      if (out[i].id < 8 || out[i].id >= 16) continue;
      const ssPairPoint *c = &out[i];
      double pa[3], pb[3];
      ss_v3_copy(pa, c->pos);
      ss_v3_addscl(pa, c->n, 0.5 * c->gap);
      ss_v3_copy(pb, c->pos);
      ss_v3_addscl(pb, c->n, -0.5 * c->gap);
      /* on an edge: on the surface, and on 2 faces: the local point's
       * two coordinates at their faces */
      double la[3], lb[3];
      ss_v3_sub(w, pa, a.pos);
      ss_m3_mulvT(la, a.R, w);
      ss_v3_sub(w, pb, b.pos);
      ss_m3_mulvT(lb, b.R, w);
      int fa = 0, fb = 0;
      for (int k = 0; k < 3; k++) {
        fa += fabs(fabs(la[k]) - 0.5 * a.size[k]) <= 1e-12 * sz;
        fb += fabs(fabs(lb[k]) - 0.5 * b.size[k]) <= 1e-12 * sz;
      }
      if (!(fabs(ss_v3_norm(c->n) - 1) <= 1e-12) || !(c->gap <= margin) ||
          !(fabs(ss_shape_sdf(&a, pa, m)) <= 1e-12 * sz) ||
          !(fabs(ss_shape_sdf(&b, pb, m)) <= 1e-12 * sz) || fa != 2 || fb != 2 ||
          !(ss_shape_sdf(&a, c->pos, m) <= margin + 1e-9 * sz) ||
          !(ss_shape_sdf(&b, c->pos, m) <= margin + 1e-9 * sz)) {
        if (good) diag("it %d id %d gap %g fa %d fb %d", it, c->id, c->gap, fa, fb);
        good = 0;
      }
      /* the normal across both edges: the edge's axis is the local one
       * not at a face */
      for (int k = 0; k < 3; k++) {
        if (!(fabs(fabs(la[k]) - 0.5 * a.size[k]) <= 1e-12 * sz)) {
          double ax[3] = {a.R[k], a.R[3 + k], a.R[6 + k]};
          if (!(fabs(ss_v3_dot(ax, c->n)) <= 1e-9)) good = 0;
        }
        if (!(fabs(fabs(lb[k]) - 0.5 * b.size[k]) <= 1e-12 * sz)) {
          double ax[3] = {b.R[k], b.R[3 + k], b.R[6 + k]};
          if (!(fabs(ss_v3_dot(ax, c->n)) <= 1e-9)) good = 0;
        }
      }
    }
    if (ne > 0 && !edge_swaps(&a, &b, margin, 1e-12 * sz)) {
      diag("swapped pair %d: not the same edge contacts", it);
      asym++;
    }
  }
  /* (a deep overlap can tie two edge pairs on one id, or two axes within
   * the 1e-9 of the best: then which is kept depends on the order, and a
   * compiler's rounding of the ties (clang's -O1 in the sanitized build
   * met one in 2000): at most one pair in a hundred may differ) */
  sym = asym <= with / 100;
  ok(good && with >= 100,
     "pair edges: %d random overlapping box pairs, %d with edge contacts (%d): points on both edges, unit normals across both, gaps within margin",
     pairs, with, total);
  ok(sym, "pair edges: random pairs swapped: the same edge contacts, normals negated (%d of "
     "%d differ, at ties)", asym, with);
}

int main(void)
{
  test_plate_quadrature();
  test_box_footprint();
  test_points_footprint();
  test_round_footprints();
  test_poly_clip();
  test_poly_band();
  test_lowest_z();
  test_candidates();
  test_ball_on_slope();
  test_restitution_rest();
  test_penetration_push();
  test_mesa_box();
  test_quat_normalize();
  test_width();
  test_aabb();
  test_low_bounds();
  test_sort_runs();
  test_shape_sdf();
  test_pair_points();
  test_pair_edges();
  test_pair_random();
  return done_testing();
}
