/* collide.h -- geometry of colliders: footprints on a bed plane, exact
 * vertical ray casts (depth under a shape), rigid contact candidates, the
 * effective width b of DESIGN 2.4, signed distances and the contact points
 * of two shapes.
 *
 * Everything here works in one Cartesian frame chosen by the caller,
 * normally a height map's local frame (bed normal = +z).  Pure functions:
 * no allocation, no model or data access. */
#ifndef SS_COLLIDE_H
#define SS_COLLIDE_H

#include "soilsim.h"

#include <math.h>

/* A collider placed in the caller's frame. */
typedef struct ssShape {
  int type;        /* ssGeomType (box, sphere, cylinder, capsule) */
  double size[3];  /* as ssModel.geom_size */
  double pos[3];   /* centre */
  double R[9];     /* rotation shape-local -> frame, row-major (columns are
                      the shape's local axes expressed in the frame) */
} ssShape;

/* A convex polygon in the frame's xy plane, counter-clockwise. */
#define SS_POLY_MAX 192
typedef struct ssPoly2 {
  int n;
  double x[SS_POLY_MAX], y[SS_POLY_MAX];
} ssPoly2;

/* Number of segments used for a full circle in footprints; arcs are
 * scaled so that each circle's polygon has the circle's exact area. */
#define SS_FOOTPRINT_SEGMENTS 64

/* The shape's footprint: its projection along z onto the xy plane, as a
 * convex polygon.  Exact for boxes (hull of the 8 projected corners); for
 * spheres, cylinders and capsules the projected circles/ellipses are
 * area-matched polygons of SS_FOOTPRINT_SEGMENTS segments. */
void ss_shape_footprint(const ssShape *s, ssPoly2 *out);
/* Most points ss_points_footprint takes: its buffers are on the stack
 * (about 36 KiB with those of its cut, no more than the solver's blocks
 * take), and a mesh keeps at most SS_MESH_HULL_MAX (mesh.h).  Its cost: a
 * sort that is nearly linear for points in rings (a 64-gon prism's 130
 * points: 1.5 us), more for points in no order, and O(k log k) more for a
 * hull of k > SS_POLY_MAX vertices (SS_HULL_POINTS_MAX points all on the
 * hull, in no order: the worst, see README). */
#define SS_HULL_POINTS_MAX 512
/* The footprint of a point set (a mesh's footprint points, ssMesh.hull):
 * the convex hull of the points o + R q_k (q: n x 3) projected along z,
 * counter-clockwise from its least point, with ss_shape_footprint's
 * tolerance for collinear points.  A hull of more than SS_POLY_MAX
 * vertices is cut down to SS_POLY_MAX, the vertex whose triangle with its
 * neighbours is least removed first, one at a time: the polygon shrinks
 * into itself by the sum of those triangles (for a regular 256-gon, by
 * 1.5e-4 of its area).  Returns the hull's vertex count before the cut
 * (the cut's happened when it is more than out->n); n outside [0,
 * SS_HULL_POINTS_MAX]: 0 and an empty polygon. */
int ss_points_footprint(const double *q, int n, const double R[9], const double o[3],
                        ssPoly2 *out);
/* Axis-aligned bounds of the shape in the frame. */
void ss_shape_aabb(const ssShape *s, double lo[3], double hi[3]);
/* Bounds in x and y of the part of the shape at or below height zc: no
 * point of the shape outside [lo, hi] lies at or below zc.  Conservative
 * (may be wider, and zc is widened by a relative 1e-9 for round-off).
 * Returns 0 when no part of the shape lies at or below zc. */
int ss_shape_low_bounds(const ssShape *s, double zc, double lo[2], double hi[2]);
/* Signed area of a polygon (positive when counter-clockwise). */
double ss_poly_area(const ssPoly2 *p);
/* Area of (convex polygon) ∩ [x0,x1]×[y0,y1], exact (clipping).  When the
 * area is > 0 and cx, cy are not NULL they receive its centroid. */
double ss_poly_rect_area(const ssPoly2 *p, double x0, double x1, double y0,
                         double y1, double *cx, double *cy);
/* A polygon's split into two chains monotone in y: a vertex of least y
 * (l) and one of greatest y (r), and where the last searches along the
 * chains ended (hint: ss_poly_band starts its next searches there, so that
 * rows visited in order cost a step or two each). */
typedef struct ssPolyChains {
  int l, r;
  int hint[4];
} ssPolyChains;
/* The chains of p (hints cleared); 0 (c untouched) when it has none (fewer
 * than 3 vertices, zero height, not convex). */
int ss_poly_ychains(const ssPoly2 *p, ssPolyChains *c);

/* A row band of a convex polygon: its part in y0 <= y <= y1, as its two
 * chains monotone in x, whose cells [x0, x1] x [y0, y1] then cost a few
 * edge integrals each (ss_poly_band_area) instead of ss_poly_rect_area's
 * two clips.  Kept about (ox, oy), oy the band's middle and ox the
 * caller's, near the cells (digits: the coordinates stay small). */
#define SS_POLY_CLIP_MAX (SS_POLY_MAX + 8)
typedef struct ssPolyBand {
  int n, l;        /* vertices; the first chain's count (x[0..l-1]) */
  int k[2];        /* each chain's edge the last cell began at */
  double ox, oy;
  double x[2 * SS_POLY_CLIP_MAX], y[2 * SS_POLY_CLIP_MAX];
} ssPolyBand;
/* The band of p between y0 and y1 about (ox, (y0 + y1) / 2), visiting
 * only the edges near it along p's y chains yc (ss_poly_ychains; their
 * hints are updated).  Returns 0 when the band's chains are not monotone
 * in x (round-off on a polygon too thin to tell): then use
 * ss_poly_rect_area.  An empty band (n = 0) gives 0 for every cell. */
int ss_poly_band(const ssPoly2 *p, ssPolyChains *yc, double y0, double y1, double ox,
                 ssPolyBand *b);
/* ss_poly_rect_area of the band's polygon for the cell [x0, x1] x [y0, y1]
 * of its rows: the same area and centroid to round-off (integrated along
 * the chains, not clipped).  Cheapest with the cells visited in order of
 * x (the chains' places are kept in b). */
double ss_poly_band_area(ssPolyBand *b, double x0, double x1, double *cx, double *cy);

/* The chord [*x0, *x1] of a convex polygon on the line at height y;
 * 0 when the line misses it. */
int ss_poly_chord(const ssPoly2 *p, double y, double *x0, double *x1);
/* ss_poly_chord, bit for bit, visiting only the edges near y along p's y
 * chains yc (ss_poly_ychains; their hints are updated); yc NULL: all. */
int ss_poly_chord_y(const ssPoly2 *p, ssPolyChains *yc, double y, double *x0, double *x1);
/* 1 if (x, y) lies inside or on the polygon. */
int ss_poly_contains(const ssPoly2 *p, double x, double y);
/* Lowest point of the shape's surface on the vertical line through (x, y):
 * the z where the upward ray first enters the solid.  Exact ray/shape
 * intersection.  Returns 1 and sets *z on a hit, 0 if the line misses. */
int ss_shape_lowest_z(const ssShape *s, double x, double y, double *z);
/* ss_shape_lowest_z for many lines through one shape: what does not depend
 * on (x, y) formed once (ss_shape_cast_init), the direction's reciprocals
 * among it, so that a line costs no division for a box and one for a
 * cylinder (the results differ from a division's by rounding), and what
 * depends on y alone once per row of lines (ss_shape_cast_row).
 * ss_shape_lowest_z is the three in one. */
typedef struct ssShapeCast {
  int type;
  double pos[3];
  double ox[3], oy[3]; /* the line's origin in the shape frame: ox wx + oy wy */
  double d[3], id[3];  /* its direction there, and 1/d (0 where d = 0) */
  int par[3];          /* d = 0: parallel to that axis' slab */
  double h[3], e[3];   /* slab half-widths, and signed as d */
  double ne[3];        /* -e, formed once (a negation is exact) */
  double r, rr, a, ia; /* radius, r^2, d_x^2 + d_y^2 and its reciprocal */
  double end[2][3];    /* a capsule's sphere centres */
} ssShapeCast;
void ss_shape_cast_init(ssShapeCast *c, const ssShape *s);
/* The part of the lines at one y that does not depend on x: y itself and
 * the origin's products oy wy (wy = y - pos_y), formed once for a row of
 * lines (ss_shape_cast_row) instead of once per line. */
typedef struct ssCastRow {
  double y;
  double oyw[3];
} ssCastRow;
static inline void ss_shape_cast_row(const ssShapeCast *c, double y, ssCastRow *r)
{
  double wy = y - c->pos[1];
  r->y = y;
  for (int k = 0; k < 3; k++) r->oyw[k] = c->oy[k] * wy;
}

/* The slab |o + t d| <= h along axis k of cast c, with d's reciprocal id
 * formed once (0 where d = 0: the line is parallel to it, inside or not)
 * and e = h signed as d, so that the entry and exit need no comparison:
 * [(-e - o) id, (e - o) id]. */
static inline int ss_cast_slab(const ssShapeCast *c, int k, double o, double *tin,
                               double *tout)
{
  if (c->par[k]) return fabs(o) <= c->h[k];
  double t0 = (c->ne[k] - o) * c->id[k], t1 = (c->e[k] - o) * c->id[k];
  *tin = t0 > *tin ? t0 : *tin;
  *tout = t1 < *tout ? t1 : *tout;
  return 1;
}

/* lowest z of a sphere over (x, y), in the caller's frame */
static inline int ss_cast_sphere(const double c[3], double r, double x, double y,
                                 double *z)
{
  double dx = x - c[0], dy = y - c[1];
  double h = r * r - (dx * dx + dy * dy);
  /* isless: the quiet compare that sqrt's errno check (the call to libm on
   * a negative) makes too, so the compiler sees it already made and drops
   * it; the same outcome as h < 0, NaN included */
  if (isless(h, 0)) return 0;
  *z = c[2] - sqrt(h);
  return 1;
}

/* ss_shape_lowest_z of the prepared shape c on the line through x of the
 * row r (inline: soil_contacts calls it once per cell) */
static inline int ss_shape_cast_lowest_z(const ssShapeCast *c, const ssCastRow *r, double x,
                                         double *z)
{
  const double y = r->y;
  if (c->type == SS_GEOM_SPHERE) return ss_cast_sphere(c->pos, c->r, x, y, z);
  if (c->type != SS_GEOM_BOX && c->type != SS_GEOM_CYLINDER && c->type != SS_GEOM_CAPSULE)
    return 0;
  double wx = x - c->pos[0];
  double o0 = c->ox[0] * wx + r->oyw[0], o1 = c->ox[1] * wx + r->oyw[1];
  double o2 = c->ox[2] * wx + r->oyw[2];
  double tin = -INFINITY, tout = INFINITY;

  if (c->type == SS_GEOM_BOX) {
    /* slab method */
    if (!ss_cast_slab(c, 0, o0, &tin, &tout) || !ss_cast_slab(c, 1, o1, &tin, &tout) ||
        !ss_cast_slab(c, 2, o2, &tin, &tout) || !(tin <= tout))
      return 0;
    *z = c->pos[2] + tin;
    return 1;
  }

  /* the finite cylinder x^2 + y^2 <= r^2, |z| <= hl: the infinite one's
   * interval (stable roots q / a and cc / q), then the caps' slab */
  int hit = 1;
  double b = o0 * c->d[0] + o1 * c->d[1], cc = o0 * o0 + o1 * o1 - c->rr;
  if (c->a == 0) {
    hit = !(cc > 0);
  } else {
    double disc = b * b - c->a * cc;
    /* (isless: as in ss_cast_sphere, sqrt's errno check folds into it) */
    if (isless(disc, 0)) {
      hit = 0;
    } else {
      double q = -(b + copysign(sqrt(disc), b));
      if (q == 0) {
        tin = tout = 0;
      } else {
        double r1 = q * c->ia, r2 = cc / q;
        tin = r1 < r2 ? r1 : r2;
        tout = r1 > r2 ? r1 : r2;
      }
    }
  }
  hit = hit && ss_cast_slab(c, 2, o2, &tin, &tout) && tin <= tout;
  double best = hit ? c->pos[2] + tin : INFINITY;
  if (c->type == SS_GEOM_CAPSULE) {
    /* union with the end spheres: the first entry of any piece */
    for (int e = 0; e < 2; e++) {
      double ze;
      if (ss_cast_sphere(c->end[e], c->r, x, y, &ze)) {
        hit = 1;
        best = fmin(best, ze);
      }
    }
  }
  if (!hit) return 0;
  *z = best;
  return 1;
}

/* Rigid contact candidates against a surface with unit normal n: points of
 * the shape that can be lowest along n -- box: its 8 corners; sphere: the
 * point c - r n; capsule: c_i - r n for both end spheres; cylinder: for each
 * cap the rim point lowest along n, then 7 more rim points of each cap at
 * 45-degree steps from it (so a cylinder standing on its end rests on its
 * rim; the ring is placed from the lowest direction, not fixed on the
 * body, so that a rolling wheel's rim points do not strike the support
 * in turn).  Returns the count (<= max). */
int ss_shape_candidates(const ssShape *s, const double n[3], double pts[][3],
                        int max);
/* Signed distance of point p from the surface of shape s, both in the
 * caller's frame: negative inside.  n: the unit outward normal of s at the
 * nearest surface point (inside: the direction of the nearest way out).
 * Box, sphere, capsule, cylinder (exact); any other type: NAN, n untouched.
 * Where the nearest way out is not unique the choice is fixed: box --
 * the face of the lowest axis index among the nearest, on an axis' mid
 * plane its positive face; sphere at its centre -- +z of the frame;
 * capsule on its axis segment, cylinder on its axis -- the shape's local
 * +x as the radial direction; a cylinder point as near its cap as its
 * side -- the cap (the upper one at mid length). */
double ss_shape_sdf(const ssShape *s, const double p[3], double n[3]);

/* One contact point between two shapes a and b (ss_shape_pair_points). */
typedef struct ssPairPoint {
  double pos[3];  /* the contact point: on the surface of the shape whose
                     candidate it is */
  double n[3];    /* unit normal from b towards a (a separates along +n) */
  double gap;     /* signed separation along n, < 0 penetrating */
  int id;         /* the feature: [0, 16) a's candidates, [16, 32) b's
                     (two boxes: 0..7 a's corners, 8..15 edge crossings,
                     16..23 b's corners; a box and a cylinder or capsule:
                     the box's corners, then its edges across the other's
                     side at 8..11 past them; two round shapes' sides,
                     or one across a cylinder's cap: 3 on a capsule a,
                     5 on a cylinder a, 19 on a capsule b, 21 on a
                     cylinder b), the same number from step to step
                     while the same feature touches */
} ssPairPoint;
#define SS_PAIR_POINTS_MAX 32
/* Contacts of a with b (one frame): a's candidate points within margin of
 * b's surface (or inside it), and b's within margin of a's.  Returns the
 * count (<= max), in order of id; where there are more than max, the first
 * max in that order (a's before b's).  Any type but box, sphere, cylinder
 * and capsule (a mesh): 0.
 *
 * The candidates of a shape s against the other o (sdf_o: ss_shape_sdf of
 * o; k below is the id, 16 + k for b's):
 * - sphere (k = 0): its centre c, d = sdf_o(c) with o's normal m there:
 *   the point c - r m at gap d - r, normal m.  Exact for a sphere against
 *   anything.
 * - capsule: its two end spheres as spheres (k = 0 at -size[1]/2 along
 *   local z, k = 1 at +), and the point of its segment nearest o's centre
 *   as a third sphere (k = 2) only where it lies strictly between the ends
 *   (not within 1e-9 of the segment's length of either): a capsule lying
 *   across something touches in the middle.
 * - box: its 8 corners q (k = 0..7, ss_shape_candidates' order): gap
 *   sdf_o(q), normal o's normal at q, the point q.
 * - cylinder: ss_shape_candidates(s, m) with m o's normal at the
 *   cylinder's centre (its rim points lowest towards o first, k = 0, 1),
 *   each as a box's corner.
 * a's candidates take b's outward normal; b's, tested against a, minus a's
 * (still from b towards a).  Two spheres: a's candidate alone (b's is the
 * same contact).  Otherwise both sides' are kept (a sphere against a
 * capsule's end: each side's candidate lies on its own surface, so the two
 * are one point only where the gap is 0), except that a candidate of b is
 * dropped where it lies within 1e-9 of the shapes' size of one of a's kept
 * ones with the same normal (to 1e-9): a point where the two touch that
 * both sides give (a sphere resting on a box's corner at gap 0: one
 * contact; the same sphere 2 mm into the corner: two, a's and the
 * corner's, with one normal and one gap).  Kept: gap <= margin.  The same
 * inputs give the same bits.
 *
 * Two boxes: also their edges' crossings (ids 8..15, between a's corners
 * and b's).  An edge ea of a and an edge eb of b (12 each) are a contact
 * where all of these hold (eps = 1e-9 of the sum of the two boxes'
 * half diagonals):
 * - not parallel (the sine of their angle over 1e-6): the closest points
 *   of their lines, pa on ea and pb on eb, both strictly inside their
 *   edges (over 1e-9 of the edge's length from either end; at an end the
 *   corner's own candidate holds it) -- there the clamped segments'
 *   closest points are these;
 * - n = the unit ea x eb, turned so that (a.pos - b.pos) . n >= 0; the
 *   gap (pa - pb) . n <= margin;
 * - each edge within margin + eps of its box's extreme along n (pa of a's
 *   least points along n, pb of b's greatest): a contact along n is
 *   between the two boxes' nearest parts along it;
 * - gap >= S - eps, S the best separation of the boxes along the 15 axes
 *   of the separating axis test (6 face normals, 9 edge cross products):
 *   the edges meet along the axis the boxes meet along, not along one
 *   they overlap deeper on (a bar 1 mm into another's top: its end's
 *   vertical edges through the other's top edges overlap it sideways by
 *   most of a width: no contact there, the deepest pair would be wrong);
 * - the point midway, pos = (pa + pb) / 2, within margin + eps of both
 *   boxes (ss_shape_sdf): the two points meet there, not merely in
 *   projection.
 * The contact: pos, n, gap as above.  Its id: 8 + c + 4 s, c a colour of
 * a's edge (0..3, chosen so that the 4 edges of every face differ) and s
 * the side of eb's box ea crosses eb from (1 where ea's direction leaves
 * it, o = eb x n turned away from b's centre, ea . o > 0): fixed while
 * the same pair touches.  Two faces flat on each other meet in a convex
 * polygon whose vertices are corners and crossings, at most 8 of them:
 * every such crossing passes (its gap is S along the common normal) and
 * each has its own id (the crossings on one edge of a are one entering b's
 * face and one leaving it), so a bar across a bar stands on the 4 corners
 * of their overlap, a slab turned 45 degrees on a slab on the 8 of their
 * octagon.  Edge pairs on the same id otherwise (deep overlaps): the
 * deepest (least gap) kept, the first in order (ea, eb) on ties.
 *
 * A box and a cylinder or a capsule (round, below): also the box's edges
 * across the round shape's side (ids 8..11 past the box's corners: 8..11
 * where the box is a, 24..27 where it is b).  An edge e (12) is a
 * contact where the closest points of its line and the round shape's
 * axis are, on the edge, strictly inside it (over 1e-9 of its length
 * from either end: at an end its corner holds it) and, on the axis,
 * between its ends or within the margin past one (a plank lying across
 * a post's top, its bottom edges over the cap, which the rim's 8 points
 * may all miss), the edge and the axis not parallel (sine over 1e-6: a
 * box's edge along a cylinder is held by corners and rims); at that
 * point p of the edge, its point nearest the axis and so deepest into
 * the side, the contact is p's as a corner's (gap sdf(p), the round
 * shape's normal there: the side's, or over a cap the cap's).
 * Its id: the base past the box's corners plus the edge's colour (0..3,
 * as above); two edges of one colour (never two of one face, nor two
 * that share a corner): the deepest kept, the first in order on ties.
 * The segment a cylinder's side shares with a box's face ends at the
 * cylinder's caps (its lowest rim points) or where it crosses the face's
 * edges (these contacts), so a log lying across a narrower table rests
 * on the table's two edges under it and a crate across a log on its two
 * bottom edges over the log's top line.
 *
 * Two round shapes (cylinders, capsules): also their sides where their
 * axes cross.  Where the closest points of the two axes' lines, pa on
 * a's and pb on b's, lie strictly between each one's ends (as above) and
 * the axes are not parallel (sine over 1e-6), n is the unit common
 * normal a's axis x b's, turned so that (pa - pb) . n > 0 (where the
 * axes meet, (a.pos - b.pos) . n >= 0), and the gap (pa - pb) . n - r_a
 * - r_b; kept within margin.  Its point and id: on a's side, pa - r_a n,
 * with id 3 for a capsule a (past its three candidates) and 5 for a
 * cylinder a (the slot of its rim point farthest from b on its first
 * cap, which gives way to it where it is within margin as well), but on
 * b's side, pb + r_b n with id 19, for a cylinder a and a capsule b.  A
 * contact of the same point and normal as one already there
 * (same_contact: a capsule's middle point where the axes cross square at
 * its centre) is not added again.  So a log dropped across another rests
 * on it, and two capsules crossed away from their centres meet where
 * they cross.  Where instead the closest point on a cylinder y's axis
 * lies past its end by at most the other's radius r_x plus the margin
 * (and x's strictly between its ends): x lies across y's cap (a log
 * across a post's top), and the contact is x's surface point from its
 * axis's closest point against the cap's normal (taken across x's axis),
 * tested against y as a corner is: on x's side, with x's slot as above
 * (3 or 5 as a, 19 or 21 as b; 21 is a cylinder b's farthest rim point's,
 * which gives way to it).  So a log across a post rests on its cap
 * where the rim's 8 points all miss it.
 *
 * Limits: a cylinder's cap rim against another round shape's side
 * between its 8 points; a shape lying across a cap away from the cap's
 * axis is met at its point over the axis, not its deepest; the
 * crossings of two boxes go by the separating axis test's best axis, so
 * where two boxes overlap deeply in every direction they are where the
 * least overlap's axis says, not every place edges cross, and their ids
 * may collide there (one kept); a cylinder's rim is sampled at 8 points
 * a cap (its side on a face it finds exactly, through the lowest rim
 * points); a capsule's middle point is taken towards o's centre, not o's
 * nearest point, exact on a large flat face under it (across a box's
 * edges or another round shape's side the contacts above hold it). */
int ss_shape_pair_points(const ssShape *a, const ssShape *b, double margin,
                         ssPairPoint *out, int max);
/* Effective width b (DESIGN 2.4), measured in the shape's own frame so that
 * heading does not change it: box -> the shorter of its two edge lengths
 * whose axes are most nearly in the plane normal to n; cylinder with its
 * axis within 45 degrees of the plane -> its length (tread width), else its
 * diameter; sphere, capsule -> diameter. */
double ss_shape_width(const ssShape *s, const double n[3]);

#endif /* SS_COLLIDE_H */
