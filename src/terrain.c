/* terrain.c -- contacts between colliders and the static supports (soil
 * beds, rigid height maps, ground planes), and the soil state update.
 *
 * Soil quadrature (DESIGN 2.6): every bed vertex owns the cell dx x dy
 * around it (halved on the bed's edges).  A vertex is a quadrature point of
 * a collider when part of its cell lies inside the collider's footprint;
 * its weight is exactly that part's area, so a plate's loaded area is its
 * true area for any placement and heading.  The depth is measured on the
 * vertical (bed z) line through the vertex when its cell is fully covered;
 * for a partially covered cell it is measured through the centroid of the
 * covered part, which lies inside the footprint (the vertex itself may lie
 * on or beyond the footprint's edge, where the line meets a side face or
 * misses the collider).  The soil state stays at the vertex.
 * Only vertices inside the collider's bounding box are visited, so the cost
 * follows the contacts, not the bed size.
 *
 * A mesh's footprint is the convex hull of its vertices projected on the
 * bed (mesh_footprint), so a convex mesh's cells get their exact covered
 * areas as a box's do; its depths come from BVH ray casts, and a cell
 * whose line misses the mesh gives no point.  For a non-convex mesh the
 * hull is an outer bound: a cell partly under a concave notch gets the
 * hull's area there, a cell whose line passes through the notch none.
 * A mesh of more than SS_MESH_HULL_MAX distinct vertices (mesh.h) keeps
 * its bounding box as its footprint, and a hull of more than SS_POLY_MAX
 * vertices is cut down to that many (ss_points_footprint): both then
 * converge with the spacing instead of being exact. */
#include "terrain.h"
#include "articulated.h"
#include "collide.h"
#include "dynamics.h"
#include "mesh.h"
#include "solver.h"
#include "sort_runs.h"
#include "ss_math.h"

#include <stdlib.h>
#include <string.h>

void ss_hfield_frame(const ssData *d, int h, double R[9], double p[3])
{
  ss_quat_to_mat(R, d->hfield_quat + 4 * h);
  ss_v3_copy(p, d->hfield_pos + 3 * h);
}

/* Jacobian storage of a contact of system sys (see ss_contact_new) */
static long contact_jlen(const ssModel *m, int sys)
{
  if (sys < 0 || m->sys_nv[sys] == 0) return 0;
  return m->sys_type[sys] == SS_SYS_ARTICULATED ? 36 : 6L * m->sys_nv[sys];
}

/* The system-dependent part of geom g's contacts: their system and link;
 * a link contact's rows X, a rigid body's J and every response, which
 * only the sweeps use, come when they run (ss_solver_solve).  Formed once
 * per geom (attach_of), filled into each contact's head (attach_head) and
 * response (attach_response). */
typedef struct Attach {
  int sys, vadr, nv, link; /* sys -1 and nv 0: a static body */
} Attach;

static Attach attach_of(const ssModel *m, int g, int sys)
{
  if (sys >= 0 && m->sys_nv[sys] > 0)
    return (Attach){sys, m->sys_vadr[sys], m->sys_nv[sys],
                    m->sys_type[sys] == SS_SYS_ARTICULATED ? m->geom_body[g] : -1};
  return (Attach){-1, 0, 0, -1};
}

/* the system part of a contact's head: its system, velocity block and
 * link (a static body's: sys -1, nv 0, the head's vadr 0 and link -1) */
static inline void attach_head(const Attach *a, ssContact *c)
{
  c->sys = a->sys;
  c->nv = a->nv;
  if (a->nv > 0) {
    c->vadr = a->vadr;
    c->link = a->link;
  }
}

/* a static body's contact: its response G is zero (the rest's comes
 * with the sweeps) */
static inline void attach_response(const Attach *a, ssContact *c)
{
  if (!(a->nv > 0)) memset(c->G, 0, sizeof c->G);
}

/* the collider of geom g expressed in a frame (R, p); a mesh stands in as
 * its bounding box for the cells visited and the width (DESIGN 2.4), its
 * rigid contacts' candidates are its lowest vertices (mesh_candidates), its
 * footprint is its vertices' hull (mesh_footprint) and
 * its depth comes from ray casts (mesh_depth) */
static void shape_in_frame(const ssModel *m, const ssData *d, int g,
                           const double R[9], const double p[3], ssShape *s)
{
  double rel[3], c[3] = {0, 0, 0};
  s->type = m->geom_type[g];
  memcpy(s->size, m->geom_size + 3 * g, 3 * sizeof(double));
  if (s->type == SS_GEOM_MESH) {
    const ssMesh *me = m->mesh[m->geom_mesh[g]];
    s->type = SS_GEOM_BOX;
    for (int k = 0; k < 3; k++) {
      s->size[k] = me->hi[k] - me->lo[k];
      c[k] = 0.5 * (me->hi[k] + me->lo[k]);
    }
  }
  double cw[3];
  ss_m3_mulv(cw, d->geom_xmat + 9 * g, c);
  ss_v3_add(cw, cw, d->geom_xpos + 3 * g);
  ss_v3_sub(rel, cw, p);
  ss_m3_mulvT(s->pos, R, rel);
  double Rt[9];
  ss_m3_transpose(Rt, R);
  ss_m3_mul(s->R, Rt, d->geom_xmat + 9 * g);
}

_Static_assert(SS_MESH_HULL_MAX <= SS_HULL_POINTS_MAX,
               "a mesh's footprint points must fit ss_points_footprint");

/* the footprint of mesh geom g, s in the bed's frame (shape_in_frame: its
 * bounding box, centred where the footprint points are): the hull of its
 * footprint points projected, exact for a convex mesh; the box's where the
 * mesh keeps none.  Not inlined: the hull's buffers (ss_points_footprint)
 * are on the stack only while it runs */
static __attribute__((noinline)) void mesh_footprint(const ssModel *m, int g,
                                                     const ssShape *s, ssPoly2 *fp)
{
  const ssMesh *me = m->mesh[m->geom_mesh[g]];
  if (me->nhull > 0)
    ss_points_footprint(me->hull, me->nhull, s->R, s->pos, fp);
  else
    ss_shape_footprint(s, fp);
}

/* lowest point of a mesh geom on the bed-frame vertical line through
 * (x, y): a ray cast upwards in the mesh frame through the BVH */
static int mesh_depth(const ssModel *m, const ssData *d, int g,
                      const double R[9], const double p[3], double x,
                      double y, double lo_z, double *z)
{
  const ssMesh *me = m->mesh[m->geom_mesh[g]];
  const double *Rg = d->geom_xmat + 9 * g, *pg = d->geom_xpos + 3 * g;
  double ol[3] = {x, y, lo_z - 1}, ow[3], up[3] = {R[2], R[5], R[8]};
  ss_m3_mulv(ow, R, ol);
  ss_v3_add(ow, ow, p);
  double rel[3], o[3], dir[3], t;
  ss_v3_sub(rel, ow, pg);
  ss_m3_mulvT(o, Rg, rel);
  ss_m3_mulvT(dir, Rg, up);
  if (!ss_mesh_raycast(me, o, dir, &t)) return 0;
  *z = lo_z - 1 + t;
  return 1;
}

/* How far a collider can travel towards a support in one step plus the
 * configured margin: points closer than this become contacts, so no
 * contact is missed by the implicit end-of-step solve.  The speed is the
 * free velocity's (contacts are made after it: gravity and every force
 * but the contacts' are in it), so the margin is left only the change
 * the contacts' own impulses make within the step (contact_margin,
 * soilsim.h).  n: the direction the gaps are measured along (a soil bed's
 * z), where the reach is the speed of the collider's points along it;
 * NULL (a rigid height map, whose normal varies): their speed in any
 * direction. */
static double geom_margin(const ssModel *m, const ssData *d, int g, int sys,
                          const double *n)
{
  double reach = m->opt.contact_margin;
  if (sys >= 0 && m->sys_nv[sys] > 0) {
    double rad = ss_dyn_geom_radius(m, g);
    reach += m->opt.timestep * (n ? ss_dyn_geom_approach(m, d, g, rad, n)
                                  : ss_dyn_geom_speed(m, d, g, rad));
  }
  return reach;
}

static void frame_from_bed(const double R[9], double frame[9])
{
  /* rows n = bed z, t1 = bed x, t2 = bed y (columns of R) */
  for (int k = 0; k < 3; k++) {
    frame[k] = R[3 * k + 2];
    frame[3 + k] = R[3 * k];
    frame[6 + k] = R[3 * k + 1];
  }
}

static void frame_from_normal(const double n[3], double frame[9])
{
  double t1[3], t2[3], a[3] = {1, 0, 0};
  if (fabs(n[0]) > 0.8) ss_v3_set(a, 0, 1, 0);
  ss_v3_cross(t1, a, n);
  ss_v3_normalize(t1);
  ss_v3_cross(t2, n, t1);
  memcpy(frame, n, 3 * sizeof(double));
  memcpy(frame + 3, t1, 3 * sizeof(double));
  memcpy(frame + 6, t2, 3 * sizeof(double));
}

/* quadrature points of geom g on soil bed h, whose type is type
 * (m->geom_type[g]) and which is s in the bed's frame; oblique: no slab
 * of its cast is parallel to the lines (ssShapeCast.par all 0: a box's
 * three, a cylinder's caps).  soil_contacts passes the common types, and
 * oblique where it holds, as constants. */
static inline __attribute__((always_inline)) ssStatus
soil_contacts_as(const ssModel *m, ssData *d, int h, int g, int sys, const double R[9],
                 const double p[3], ssError *err, const ssShape *s, const int type,
                 const int oblique)
{
  double lo[3], hi[3];
  ss_shape_aabb(s, lo, hi);
  double nz[3] = {R[2], R[5], R[8]};
  double margin = geom_margin(m, d, g, sys, nz);
  double ztop = m->hfield_zrange[2 * h + 1];
  if (lo[2] > ztop + margin) return SS_OK;
  /* no bed vertex lies above the bed's top (plastic sinkage only lowers
   * it), so a cell can give a point only where the collider reaches below
   * the top plus the margin: a wheel's contact patch, not its whole
   * footprint (the cells beyond would be visited only to be dropped) */
  double blo[2], bhi[2];
  if (!ss_shape_low_bounds(s, ztop + margin, blo, bhi)) return SS_OK;
  for (int k = 0; k < 2; k++) {
    lo[k] = fmax(lo[k], blo[k]);
    hi[k] = fmin(hi[k], bhi[k]);
  }

  int nx = m->hfield_nx[h], ny = m->hfield_ny[h], adr = m->hfield_adr[h];
  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  double dx = xs / (nx - 1), dy = ys / (ny - 1);
  double x0 = m->hfield_center[2 * h] - 0.5 * xs;
  double y0 = m->hfield_center[2 * h + 1] - 0.5 * ys;
  /* vertices whose cells overlap the bounding box, clamped in double
   * before the conversion (a body far from the bed would overflow int) */
  double fi0 = ceil((lo[0] - x0) / dx - 0.5), fi1 = floor((hi[0] - x0) / dx + 0.5);
  double fj0 = ceil((lo[1] - y0) / dy - 0.5), fj1 = floor((hi[1] - y0) / dy + 0.5);
  if (!(fi1 >= 0 && fj1 >= 0 && fi0 <= nx - 1 && fj0 <= ny - 1)) return SS_OK;
  int i0 = fi0 > 0 ? (int)fi0 : 0, i1 = fi1 < nx - 1 ? (int)fi1 : nx - 1;
  int j0 = fj0 > 0 ? (int)fj0 : 0, j1 = fj1 < ny - 1 ? (int)fj1 : ny - 1;

  const int mesh = type == SS_GEOM_MESH;
  ssPoly2 fp;
  if (mesh)
    mesh_footprint(m, g, s, &fp);
  else
    ss_shape_footprint(s, &fp);
  /* formed in a copy: cast's address then reaches no call, so the calls
   * in the loop below (the band's, the reserve) cannot change it, and
   * the casts keep its fields without reloading them.  Its type is set
   * at each cast (below): a mesh's depth comes from mesh_depth, the cast
   * of its stand-in box is made to miss (the type it does not cast), so
   * that a cell tests for the mesh only where the cast missed */
  ssShapeCast cast;
  {
    ssShapeCast c0;
    ss_shape_cast_init(&c0, s);
    cast = c0;
  }
  /* a row's cells on the footprint's edge: area and centroid integrated
   * along the row's band of the footprint (ss_poly_band, formed at the
   * row's first such cell), the full clip where the band cannot be split
   * into chains monotone in x (round-off on a sliver) */
  ssPolyChains ych;
  ssPolyBand band;
  int banded = ss_poly_ychains(&fp, &ych);
  double up[3] = {0, 0, 1};
  double width = ss_shape_width(s, up);
  double frame[9];
  frame_from_bed(R, frame);
  /* a bed not turned (most: R from the unit quaternion is exactly I): a
   * point's world position is its bed position moved, without the
   * product by R's ones and zeros (which gives the same sums, up to the
   * sign of a zero).  Every point is stored moved by (p0, p1, p2): p on
   * such a bed (read once: through p, every point would reload it, as
   * the compiler sees the points' stores), -0 on a turned one, which
   * leaves the bed position as it is (x + -0 is x, -0 included) for
   * the pass that turns and moves its points once they are made (no
   * test at every point) */
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  int turned = memcmp(R, I3, sizeof I3) != 0;
  const double p0 = turned ? -0.0 : p[0], p1 = turned ? -0.0 : p[1], p2 = turned ? -0.0 : p[2];
  long njac = contact_jlen(m, sys);
  const Attach at = attach_of(m, g, sys);
  /* the head its points share (ss_contact_add_head), and where their
   * Jacobian storage starts */
  ssContact head;
  memcpy(&head, &ss_contact_blank, offsetof(ssContact, pos));
  head.type = SS_CONTACT_SOIL;
  head.geom = g;
  head.hfield = h;
  head.jlen = njac;
  head.bed_axes = !turned;
  attach_head(&at, &head);
  long jadr = ss_contact_jac_end(d);
  const int first = d->ncontact;
  const double *z0 = m->hfield_data + adr;
  const double *sp = d->soil_plastic + adr, *jj = d->soil_shear + adr;
  double tiny = 1e-12 * dx * dy, hdx = 0.5 * dx;

  ssStatus status = SS_OK;
  /* the chord at the last row's upper boundary, which is (to round-off)
   * this row's lower one */
  double b0 = 0, b1 = 0;
  int b_ok = 0;
  for (int j = j0; j <= j1; j++) {
    double y = y0 + j * dy;
    /* the casts through the row's vertices share y: their products by it
     * formed once (a centroid's line forms its own) */
    ssCastRow crow, cq;
    ss_shape_cast_row(&cast, y, &crow);
    double cy0 = j == 0 ? y : y - 0.5 * dy, cy1 = j == ny - 1 ? y : y + 0.5 * dy;
    /* cells whose x range lies inside both chords of the row's band lie
     * inside the (convex) footprint: fully covered, no clipping; a margin
     * of 1e-9 dx leaves the cells on the footprint's edge to the band
     * (and covers the round-off between the two rows' shared boundary) */
    double in0 = INFINITY, in1 = -INFINITY, a0 = b0, a1 = b1;
    ssPolyChains *yc = banded ? &ych : NULL;
    int a_ok = j > j0 ? b_ok : ss_poly_chord_y(&fp, yc, cy0, &a0, &a1);
    b_ok = ss_poly_chord_y(&fp, yc, cy1, &b0, &b1);
    if (a_ok && b_ok) {
      /* (found chords' ends are numbers: comparisons instead of fmax and
       * fmin's calls, and the sign of a zero is lost in the margin) */
      in0 = (a0 > b0 ? a0 : b0) + 1e-9 * dx;
      in1 = (a1 < b1 ? a1 : b1) - 1e-9 * dx;
    }
    int band_ready = 0;
    /* the row's vertices (vr: the first one's absolute index) */
    const int kr = j * nx, vr = adr + kr;
    const double *zr = z0 + kr, *spr = sp + kr, *jr = jj + kr;
    /* room for the row's points at once (ss_contact_add below); without
     * it the points made so far are finished (below) and the error kept */
    if (!ss_contact_reserve(d, i1 - i0 + 1, njac)) {
      status = ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
      break;
    }
    /* the cell's half width to the left: 0 for the bed's first vertex,
     * which only the row's first cell can be (x - 0 is x) */
    double hl = i0 == 0 ? 0 : hdx;
    for (int i = i0; i <= i1; i++) {
      double x = x0 + i * dx;
      double cx0 = x - hl, cx1 = i == nx - 1 ? x : x + hdx;
      hl = hdx;
      double qx = x, qy = y, full = (cx1 - cx0) * (cy1 - cy0), area = full;
      const ssCastRow *qrow = &crow;
      if (!(cx0 > in0 && cx1 < in1)) {
        if (!band_ready) {
          band_ready = banded && ss_poly_band(&fp, &ych, cy0, cy1, x, &band) ? 1 : -1;
        }
        /* (the centroid in its own pair: qx and qy, whose addresses the
         * calls would take, would live in memory for every cell) */
        double gx = x, gy = y;
        area = band_ready > 0 ? ss_poly_band_area(&band, cx0, cx1, &gx, &gy)
                              : ss_poly_rect_area(&fp, cx0, cx1, cy0, cy1, &gx, &gy);
        if (!(area > tiny)) continue;
        /* the point represents the covered part of the cell: the vertex
         * when the cell is fully covered, else the covered part's centroid
         * (a vertex on or outside the footprint's edge would see a side
         * face) */
        if (!(area >= full * (1 - 1e-9))) {
          qx = gx;
          qy = gy;
          ss_shape_cast_row(&cast, qy, &cq);
          qrow = &cq;
        }
      }
      /* the type (the geom's: the mesh's, not its box's) and, where
       * oblique, the slabs' par stored just before the cast reads them:
       * the compiler sees the values it reads, and where soil_contacts
       * passes constants the cast's tests of them fold away */
      double zl;
      cast.type = type;
      if (oblique) cast.par[0] = cast.par[1] = cast.par[2] = 0;
      /* an oblique cylinder's lines are not along its axis either
       * (soil_contacts: a != 0), so the cast's test of a folds away */
      if (type == SS_GEOM_CYLINDER && oblique && cast.a == 0) __builtin_unreachable();
      if (!ss_shape_cast_lowest_z(&cast, qrow, qx, &zl) &&
          !(mesh && mesh_depth(m, d, g, R, p, qx, qy, lo[2], &zl)))
        continue;
      double spi = spr[i], floor_z = zr[i] - spi;
      double g0 = zl - floor_z;
      if (g0 > margin) continue;
      ssContact *c = ss_contact_add_head(d, &head, jadr);
      jadr += njac;
      c->vertex = vr + i;
      c->pos[0] = qx + p0;
      c->pos[1] = qy + p1;
      c->pos[2] = zl + p2;
      memcpy(c->frame, frame, sizeof frame);
      c->area = area;
      c->width = width;
      c->g0 = g0;
      c->sp = spi;
      c->j = jr[i];
    }
  }
  /* once the points are made, the rarer cases' passes (not a test at
   * every point): a turned bed's points turned and moved into the world,
   * a static body's responses */
  if (turned)
    for (int k = first; k < d->ncontact; k++) {
      ssContact *c = d->contact + k;
      double pl[3];
      ss_v3_copy(pl, c->pos);
      ss_m3_mulv(c->pos, R, pl);
      ss_v3_add(c->pos, c->pos, p);
    }
  if (!(at.nv > 0))
    for (int k = first; k < d->ncontact; k++) attach_response(&at, d->contact + k);
  return status;
}

/* soil_contacts_as for each common type apart, the type a constant, and
 * a box or cylinder apart where oblique (most: exactly level is rare):
 * each cell's cast (ss_shape_cast_lowest_z, inline) then tests neither
 * the type nor the slabs' par; the others (capsule, mesh, a level
 * cylinder) share one copy that tests them */
static ssStatus soil_contacts(const ssModel *m, ssData *d, int h, int g, int sys,
                              const double R[9], const double p[3], ssError *err)
{
  ssShape s;
  shape_in_frame(m, d, g, R, p, &s);
  /* the lines' direction in the shape's frame (ss_shape_cast_init: d),
   * whose zeros are the slabs parallel to them */
  const double *dl = s.R + 6;
  switch (m->geom_type[g]) {
  case SS_GEOM_CYLINDER:
    /* (the second test is the cast's a, ss_shape_cast_init, formed alike) */
    if (dl[2] != 0 && dl[0] * dl[0] + dl[1] * dl[1] != 0)
      return soil_contacts_as(m, d, h, g, sys, R, p, err, &s, SS_GEOM_CYLINDER, 1);
    break;
  case SS_GEOM_BOX:
    if (dl[0] != 0 && dl[1] != 0 && dl[2] != 0)
      return soil_contacts_as(m, d, h, g, sys, R, p, err, &s, SS_GEOM_BOX, 1);
    return soil_contacts_as(m, d, h, g, sys, R, p, err, &s, SS_GEOM_BOX, 0);
  case SS_GEOM_SPHERE:
    return soil_contacts_as(m, d, h, g, sys, R, p, err, &s, SS_GEOM_SPHERE, 0);
  }
  return soil_contacts_as(m, d, h, g, sys, R, p, err, &s, m->geom_type[g], 0);
}

/* bilinear height and upward normal of rigid height map h at local (x, y);
 * 0 outside the map */
static int hfield_sample(const ssModel *m, int h, double x, double y,
                         double *z, double n[3])
{
  int nx = m->hfield_nx[h], ny = m->hfield_ny[h];
  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  double dx = xs / (nx - 1), dy = ys / (ny - 1);
  double u = (x - (m->hfield_center[2 * h] - 0.5 * xs)) / dx;
  double v = (y - (m->hfield_center[2 * h + 1] - 0.5 * ys)) / dy;
  if (!(u >= 0 && v >= 0 && u <= nx - 1 && v <= ny - 1)) return 0;
  int i = (int)u, j = (int)v;
  if (i > nx - 2) i = nx - 2;
  if (j > ny - 2) j = ny - 2;
  double fu = u - i, fv = v - j;
  const double *zz = m->hfield_data + m->hfield_adr[h];
  double z00 = zz[j * nx + i], z10 = zz[j * nx + i + 1];
  double z01 = zz[(j + 1) * nx + i], z11 = zz[(j + 1) * nx + i + 1];
  *z = (1 - fv) * ((1 - fu) * z00 + fu * z10) + fv * ((1 - fu) * z01 + fu * z11);
  double gx = ((1 - fv) * (z10 - z00) + fv * (z11 - z01)) / dx;
  double gy = ((1 - fu) * (z01 - z00) + fu * (z11 - z10)) / dy;
  ss_v3_set(n, -gx, -gy, 1);
  ss_v3_normalize(n);
  return 1;
}

/* A mesh's candidate points on a rigid support, s its bounding box in the
 * support's frame (shape_in_frame): its lowest footprint points (ssMesh.
 * hull, its distinct vertices) along the support's normal (the frame's
 * z), at most SS_RIGID_CANDIDATES, so that a rock rests on its vertices
 * and not on its box's corners.  Ties go to the earlier point, and the
 * points chosen keep the mesh's order, so that each candidate's index (the
 * warm start's key, ss_rigid_feature) is the same vertex while the same
 * ones are lowest: all of them for a mesh of at most SS_RIGID_CANDIDATES.
 * The box's corners where the mesh keeps no footprint points (more than
 * SS_MESH_HULL_MAX). */
static int mesh_candidates(const ssModel *m, int g, const ssShape *s,
                           double pts[][3])
{
  const ssMesh *me = m->mesh[m->geom_mesh[g]];
  if (me->nhull <= 0) {
    double up[3] = {0, 0, 1};
    return ss_shape_candidates(s, up, pts, SS_RIGID_CANDIDATES);
  }
  /* the lowest so far, by height then index (insertion: n is small) */
  int best[SS_RIGID_CANDIDATES], n = 0;
  double bz[SS_RIGID_CANDIDATES];
  const double *R = s->R;
  for (int i = 0; i < me->nhull; i++) {
    const double *h = me->hull + 3 * i;
    double z = R[6] * h[0] + R[7] * h[1] + R[8] * h[2] + s->pos[2];
    if (n == SS_RIGID_CANDIDATES && !(z < bz[n - 1])) continue;
    int j = n < SS_RIGID_CANDIDATES ? n++ : n - 1;
    for (; j > 0 && z < bz[j - 1]; j--) {
      bz[j] = bz[j - 1];
      best[j] = best[j - 1];
    }
    bz[j] = z;
    best[j] = i;
  }
  /* back in the mesh's order */
  for (int a = 1; a < n; a++)
    for (int j = a; j > 0 && best[j] < best[j - 1]; j--) {
      int t = best[j];
      best[j] = best[j - 1];
      best[j - 1] = t;
    }
  for (int k = 0; k < n; k++) {
    ss_m3_mulv(pts[k], R, me->hull + 3 * best[k]);
    ss_v3_add(pts[k], pts[k], s->pos);
  }
  return n;
}

/* A round collider's candidate points on rigid height map h (its frame):
 * the points lowest along the map's normal under them, not along the
 * map's up.  ss_shape_candidates takes them lowest along up; on a slope a
 * sphere's lowest point is then not where it touches (directly below its
 * centre instead of along the normal), so the sphere sank r (1/cos(a) - 1)
 * into a slope of angle a (3 mm for r = 0.1 m at 14 degrees) and, pushed
 * at that point, did not roll.  Each point is moved to the support point
 * along the normal sampled under it, twice (the second sees the normal
 * where the first put it: exact on a plane, second order on a curved
 * map): per end of a capsule, and for a cylinder's whole ring from the
 * normal under its lowest rim point.  Where the map is level under the
 * points the candidates stay as they are.  Boxes (corners) and meshes
 * (their lowest vertices) are points of the body whatever the normal. */
static void round_on_slope(const ssModel *m, int h, const ssShape *s,
                           double pts[][3], int npt)
{
  int type = s->type, ring = type == SS_GEOM_CYLINDER;
  if (type != SS_GEOM_SPHERE && type != SS_GEOM_CAPSULE && !ring) return;
  double low[SS_RIGID_CANDIDATES][3];
  for (int pass = 0; pass < 2; pass++)
    for (int k = 0; k < (ring ? 1 : npt); k++) {
      double zs, nl[3];
      if (!hfield_sample(m, h, pts[k][0], pts[k][1], &zs, nl) || (nl[0] == 0 && nl[1] == 0)) {
        if (ring) return;
        continue;
      }
      /* the candidates lowest along nl: the whole ring, or point k (the
       * sphere's, or the capsule's end k's) */
      ss_shape_candidates(s, nl, low, npt);
      if (ring) memcpy(pts, low, (size_t)npt * sizeof low[0]);
      else ss_v3_copy(pts[k], low[k]);
    }
}

/* A rigid contact of geom g (attached as at, njac Jacobian values) on
 * support h (-1: a plane or a collider) at point pl with the support's
 * unit normal nl (both in the support's frame R, p), gap along it, cache
 * key key; with gb >= 0 a pair contact whose second body is collider gb
 * (attached as bt, jb Jacobian values after the first body's).  0 out
 * of memory. */
static int rigid_add(const ssModel *m, ssData *d, int g, int h, int key, const double R[9],
                     const double p[3], const double pl[3], const double nl[3], double gap,
                     const ssMaterialPair *pair, long njac, const Attach *at, int gb,
                     const Attach *bt, long jb)
{
  ssContact *c = ss_contact_new(d, njac + jb);
  if (!c) return 0;
  c->type = gb >= 0 ? SS_CONTACT_PAIR : SS_CONTACT_RIGID;
  c->geom = g;
  c->hfield = h;
  c->vertex = key;
  ss_m3_mulv(c->pos, R, pl);
  ss_v3_add(c->pos, c->pos, p);
  double nw[3];
  ss_m3_mulv(nw, R, nl);
  frame_from_normal(nw, c->frame);
  c->g0 = gap;
  d->contact_deep += gap < 0;
  c->mu = pair->friction;
  /* lowest allowed end-of-step normal velocity: close a gap, stop in a
   * penetration (the push moves it out, ss_solver_push, and leaves the
   * velocity alone), or bounce */
  double dt = m->opt.timestep;
  c->vn_target = gap >= 0 ? -gap / dt : 0;
  if (njac > 0 && gap <= m->opt.contact_margin) {
    /* the approach before this step's loads (qvel_start): with
     * gravity's g dt in it, a body resting on the support met it at
     * g dt every step and bounced by restitution times that, hopping
     * for ever (a box with restitution 0.5 and threshold 0 between
     * 51.99 and 52.00 mm instead of resting at 50) */
    double v[3];
    ss_dyn_point_velocity_of(m, d, d->qvel_start, m->geom_body[g], c->pos, v);
    if (gb >= 0) {
      /* (a pair's approach: the first body's less the second's) */
      double vb[3];
      ss_dyn_point_velocity_of(m, d, d->qvel_start, m->geom_body[gb], c->pos, vb);
      ss_v3_sub(v, v, vb);
    }
    double vn = ss_v3_dot(v, nw);
    if (pair->restitution > 0 && vn < -pair->restitution_threshold &&
        -pair->restitution * vn > c->vn_target)
      c->vn_target = -pair->restitution * vn;
  }
  attach_head(at, c);
  attach_response(at, c);
  if (gb >= 0) {
    c->geom2 = gb;
    c->sys2 = bt->sys;
    c->vadr2 = bt->vadr;
    c->nv2 = bt->nv;
    c->link2 = bt->link;
    c->jadr2 = c->jadr + njac;
  }
  return 1;
}

/* A rigid height map's vertex that reaches into a collider: a peak or a
 * ridge the collider's own candidate points (its corners, rims) cannot
 * see, such as a rock under a slab's middle.  The vertex p (map frame),
 * the collider's outward normal n nearest it and its signed distance
 * gap (ss_shape_sdf). */
typedef struct MapPoint {
  double p[3], n[3], gap;
  long v;
} MapPoint;
/* Most such vertices a collider takes on one map (the deepest), and the
 * first candidate number their cache keys take (ss_rigid_feature: the
 * collider's own candidates take fewer than 16) */
enum { MAP_POINTS = 8, MAP_POINT_KEY = 16 };
_Static_assert(MAP_POINT_KEY + MAP_POINTS <= SS_RIGID_CANDIDATES,
               "the map's points' keys fit beside the collider's candidates");

/* The interior vertices of rigid map h inside the box [lo, hi] (map frame,
 * widened by margin) that stand above the mean of their four neighbours
 * (a peak or a ridge: on a flat or evenly sloped map none does, so a box
 * resting on one gets no contact at every vertex under it), lie within
 * margin of shape s (its signed distance) and farther than a grid spacing
 * from each of the nmade points where the collider's own candidates made
 * contacts (made: x, y), which hold it there already (a ball on a hilltop
 * touches it at its tangent point, a box's corner beside a peak): the
 * MAP_POINTS deepest, ties to the lower vertex index, in order of vertex
 * index (their cache keys, MAP_POINT_KEY on).  Returns their count. */
static int map_points(const ssModel *m, int h, const ssShape *s, const double lo[3],
                      const double hi[3], double margin, const double (*made)[2],
                      int nmade, MapPoint out[MAP_POINTS])
{
  int nx = m->hfield_nx[h], ny = m->hfield_ny[h];
  double xs = m->hfield_size[2 * h], ys = m->hfield_size[2 * h + 1];
  double dx = xs / (nx - 1), dy = ys / (ny - 1);
  double x0 = m->hfield_center[2 * h] - 0.5 * xs, y0 = m->hfield_center[2 * h + 1] - 0.5 * ys;
  /* (clamped in double before the conversion, as soil_contacts does) */
  double fi0 = ceil((lo[0] - margin - x0) / dx), fi1 = floor((hi[0] + margin - x0) / dx);
  double fj0 = ceil((lo[1] - margin - y0) / dy), fj1 = floor((hi[1] + margin - y0) / dy);
  if (!(fi1 >= 1 && fj1 >= 1 && fi0 <= nx - 2 && fj0 <= ny - 2)) return 0;
  int i0 = fi0 > 1 ? (int)fi0 : 1, i1 = fi1 < nx - 2 ? (int)fi1 : nx - 2;
  int j0 = fj0 > 1 ? (int)fj0 : 1, j1 = fj1 < ny - 2 ? (int)fj1 : ny - 2;
  const double *z = m->hfield_data + m->hfield_adr[h];
  /* above the neighbours' mean by more than round-off on an even slope */
  const double bump = 1e-9 * (dx < dy ? dx : dy);
  int n = 0;
  for (int j = j0; j <= j1; j++)
    for (int i = i0; i <= i1; i++) {
      long v = (long)j * nx + i;
      double zv = z[v];
      if (zv < lo[2] - margin) continue;
      double mean = 0.25 * ((z[v - 1] + z[v + 1]) + (z[v - nx] + z[v + nx]));
      if (!(zv - mean > bump)) continue;
      MapPoint q = {{x0 + i * dx, y0 + j * dy, zv}, {0, 0, 0}, 0, v};
      int near = 0;
      for (int k = 0; k < nmade && !near; k++)
        near = fabs(made[k][0] - q.p[0]) <= dx && fabs(made[k][1] - q.p[1]) <= dy;
      if (near) continue;
      q.gap = ss_shape_sdf(s, q.p, q.n);
      if (!(q.gap <= margin)) continue;
      /* into the deepest MAP_POINTS so far (ties: the earlier vertex) */
      int k = n < MAP_POINTS ? n++ : MAP_POINTS;
      if (k == MAP_POINTS && !(q.gap < out[MAP_POINTS - 1].gap)) continue;
      if (k == MAP_POINTS) k = MAP_POINTS - 1;
      for (; k > 0 && q.gap < out[k - 1].gap; k--) out[k] = out[k - 1];
      out[k] = q;
    }
  /* the kept ones in vertex order */
  for (int a = 1; a < n; a++) {
    MapPoint q = out[a];
    int k = a;
    for (; k > 0 && out[k - 1].v > q.v; k--) out[k] = out[k - 1];
    out[k] = q;
  }
  return n;
}

/* Coulomb contacts of geom g against a rigid surface: candidate points of
 * the collider (a mesh's: mesh_candidates) tested against the surface
 * (plane when h < 0), and on a rigid height map its peaks and ridges
 * inside the collider (map_points). */
static ssStatus rigid_contacts(const ssModel *m, ssData *d, int h, int plane,
                               int g, int sys, ssError *err)
{
  double R[9], p[3];
  if (h >= 0) {
    ss_hfield_frame(d, h, R, p);
  } else {
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(R, I, sizeof I);
    ss_v3_set(p, 0, 0, m->plane_height[plane]);
  }
  ssShape s;
  shape_in_frame(m, d, g, R, p, &s);
  double lo[3], hi[3];
  ss_shape_aabb(&s, lo, hi);
  double margin = geom_margin(m, d, g, sys, NULL);
  double top = h >= 0 ? m->hfield_zrange[2 * h + 1] : 0;
  if (lo[2] > top + margin) return SS_OK;

  double up[3] = {0, 0, 1}, pts[SS_RIGID_CANDIDATES][3];
  int npt = m->geom_type[g] == SS_GEOM_MESH
                ? mesh_candidates(m, g, &s, pts)
                : ss_shape_candidates(&s, up, pts, SS_RIGID_CANDIDATES);
  if (h >= 0) round_on_slope(m, h, &s, pts, npt);
  const int support = h >= 0 ? h : m->nhfield + plane;
  int mat = h >= 0 ? m->hfield_material[h] : m->plane_material[plane];
  const ssMaterialPair *pair = ss_model_pair(m, m->geom_material[g], mat);
  long njac = contact_jlen(m, sys);
  const Attach at = attach_of(m, g, sys);
  int nmade = 0;
  double made[SS_RIGID_CANDIDATES][2];
  for (int k = 0; k < npt; k++) {
    double zs = 0, nl[3] = {0, 0, 1};
    if (h >= 0 && !hfield_sample(m, h, pts[k][0], pts[k][1], &zs, nl)) continue;
    double gap = (pts[k][2] - zs) * nl[2];
    if (gap > margin) continue;
    made[nmade][0] = pts[k][0];
    made[nmade++][1] = pts[k][1];
    if (!rigid_add(m, d, g, h, ss_rigid_feature(support, k), R, p, pts[k], nl, gap, pair,
                   njac, &at, -1, NULL, 0))
      return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  }
  /* the map's own peaks and ridges inside the collider (a rigid height
   * map only; a mesh has no signed distance here) */
  if (h >= 0 && m->geom_type[g] != SS_GEOM_MESH) {
    MapPoint mp[MAP_POINTS];
    int nmp = map_points(m, h, &s, lo, hi, margin, made, nmade, mp);
    for (int k = 0; k < nmp; k++) {
      const double nl[3] = {-mp[k].n[0], -mp[k].n[1], -mp[k].n[2]};
      if (!rigid_add(m, d, g, h, ss_rigid_feature(support, MAP_POINT_KEY + k), R, p, mp[k].p,
                     nl, mp[k].gap, pair, njac, &at, -1, NULL, 0))
        return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
    }
  }
  return SS_OK;
}

/* ---------------------------------------------------------------------- */
/* contacts between bodies                                                 */

/* A collider in the broad phase: its box in the world, widened by how
 * far it can move in the step (geom_margin's reach) */
typedef struct PairBox {
  double lo[3], hi[3];
  int g;
  ssShape s; /* the collider in the world (shape_in_frame) */
} PairBox;

static int pair_box_cmp(const void *pa, const void *pb)
{
  const PairBox *a = pa, *b = pb;
  if (a->lo[0] != b->lo[0]) return a->lo[0] < b->lo[0] ? -1 : 1;
  return a->g < b->g ? -1 : a->g > b->g;
}

/* The contacts of colliders ga (moving) and gb (another system's, static
 * or moving), A and B in the world, from ss_shape_pair_points: against a static body a rigid
 * contact of ga's with gb as its support, between two moving bodies a
 * pair contact (ga takes lambda, gb -lambda).  Keys as a rigid contact's
 * (ss_rigid_feature), with gb's support number nhfield + nplane + gb and
 * the point's feature. */
static ssStatus pair_contacts(const ssModel *m, ssData *d, int ga, int gb, const ssShape *A,
                              const ssShape *B, ssError *err)
{
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, o[3] = {0, 0, 0};
  int sa = m->body_sys[m->geom_body[ga]], sb = m->body_sys[m->geom_body[gb]];
  int dynb = m->sys_nv[sb] > 0;
  long support = (long)m->nhfield + m->nplane + gb;
  /* (the keys' room: ss_rigid_feature) */
  if (support >= (1L << 26) - 1) return SS_OK;
  double margin = geom_margin(m, d, ga, sa, NULL);
  if (dynb) margin += geom_margin(m, d, gb, sb, NULL) - m->opt.contact_margin;
  ssPairPoint pts[SS_PAIR_POINTS_MAX];
  int npt = ss_shape_pair_points(A, B, margin, pts, SS_PAIR_POINTS_MAX);
  if (!npt) return SS_OK;
  const ssMaterialPair *pair =
      ss_model_pair(m, m->geom_material[ga], m->geom_material[gb]);
  long ja = contact_jlen(m, sa), jb = dynb ? contact_jlen(m, sb) : 0;
  const Attach at = attach_of(m, ga, sa), bt = attach_of(m, gb, dynb ? sb : -1);
  for (int k = 0; k < npt; k++) {
    const ssPairPoint *q = pts + k;
    if (q->gap > margin) continue;
    if (!rigid_add(m, d, ga, -1, ss_rigid_feature((int)support, q->id), I3, o, q->pos, q->n,
                   q->gap, pair, ja, &at, dynb ? gb : -1, &bt, jb))
      return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  }
  return SS_OK;
}

/* Contacts between the colliders of different systems, at least one of
 * them moving: a sweep over their boxes along x (sorted by their lower
 * ends, then index: the same order every run), each overlapping pair's
 * points from ss_shape_pair_points.  Meshes take no part (their shape
 * has no signed distance here); nor do two colliders of one system (an
 * articulated system's links do not collide with each other). */
static ssStatus body_contacts(const ssModel *m, ssData *d, ssError *err)
{
  /* nothing to do where the colliders are all one system's (the buggy's:
   * no boxes formed a step) */
  int n = 0, first = -1, several = 0;
  for (int g = 0; g < m->ngeom; g++) {
    int s = m->body_sys[m->geom_body[g]];
    if (d->sys_active[s] && (m->geom_group[g] & 1) && m->geom_type[g] != SS_GEOM_MESH) {
      n++;
      if (first < 0) first = s;
      several |= s != first;
    }
  }
  if (!several) return SS_OK;
  PairBox *box = malloc((size_t)n * sizeof *box);
  if (!box) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, o[3] = {0, 0, 0};
  int nmoving = 0;
  n = 0;
  for (int g = 0; g < m->ngeom; g++) {
    int s = m->body_sys[m->geom_body[g]];
    if (!(d->sys_active[s] && (m->geom_group[g] & 1) && m->geom_type[g] != SS_GEOM_MESH))
      continue;
    PairBox *b = box + n++;
    shape_in_frame(m, d, g, I3, o, &b->s);
    ss_shape_aabb(&b->s, b->lo, b->hi);
    double reach = geom_margin(m, d, g, m->sys_nv[s] > 0 ? s : -1, NULL);
    for (int k = 0; k < 3; k++) {
      b->lo[k] -= reach;
      b->hi[k] += reach;
    }
    b->g = g;
    nmoving += m->sys_nv[s] > 0;
  }
  ssStatus st = SS_OK;
  if (nmoving > 0) {
    qsort(box, (size_t)n, sizeof *box, pair_box_cmp);
    for (int i = 0; i < n && !st; i++)
      for (int j = i + 1; j < n && !st && box[j].lo[0] <= box[i].hi[0]; j++) {
        const PairBox *a = box + i, *b = box + j;
        if (a->lo[1] > b->hi[1] || b->lo[1] > a->hi[1] || a->lo[2] > b->hi[2] ||
            b->lo[2] > a->hi[2])
          continue;
        int ga = a->g, gb = b->g;
        int sa = m->body_sys[m->geom_body[ga]], sb = m->body_sys[m->geom_body[gb]];
        if (sa == sb) continue;
        int da = m->sys_nv[sa] > 0, db = m->sys_nv[sb] > 0;
        if (!da && !db) continue;
        /* the moving one first; of two moving ones the lower index */
        if (!da || (db && gb < ga)) {
          const PairBox *t = a;
          a = b;
          b = t;
        }
        st = pair_contacts(m, d, a->g, b->g, &a->s, &b->s, err);
      }
  }
  free(box);
  return st;
}

ssStatus ss_terrain_contacts(const ssModel *m, ssData *d, ssError *err)
{
  d->ncontact = 0;
  d->contact_deep = 0;
  for (int g = 0; g < m->ngeom; g++) {
    int sys = m->body_sys[m->geom_body[g]];
    if (!d->sys_active[sys] || !(m->geom_group[g] & 1)) continue;
    int dyn = m->sys_nv[sys] > 0;
    ssStatus st;
    for (int h = 0; h < m->nhfield; h++) {
      if (m->hfield_soil[h]) {
        double R[9], p[3];
        ss_hfield_frame(d, h, R, p);
        st = soil_contacts(m, d, h, g, dyn ? sys : -1, R, p, err);
      } else {
        /* a static body cannot push on a rigid support */
        if (!dyn) continue;
        st = rigid_contacts(m, d, h, -1, g, sys, err);
      }
      if (st) return st;
    }
    if (!dyn) continue;
    for (int pl = 0; pl < m->nplane; pl++)
      if ((st = rigid_contacts(m, d, -1, pl, g, sys, err))) return st;
  }
  return body_contacts(m, d, err);
}

ssStatus ss_terrain_reserve(ssData *d, ssError *err)
{
  if (2 * d->ncontact <= d->cap_soil_loaded) return SS_OK;
  int *p = realloc(d->soil_loaded, (size_t)d->ncontact * 2 * sizeof(int));
  if (!p) return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  d->soil_loaded = p;
  d->cap_soil_loaded = 2 * d->ncontact;
  return SS_OK;
}

/* vertex indices, merged from their runs (one per collider) */
static int int_less(const int *a, const int *b) { return *a < *b; }
SS_SORT_RUNS(merge_sort_runs, int, int_less)

/* The loaded vertices' runs whose starts the soil update keeps (one per
 * collider, each strictly ascending): merged pairwise where they are
 * known, so that no pass scans for them, and the last merge drops the
 * vertices two colliders share as it goes (no pass of its own); more
 * runs than this: the sort (merge_sort_runs) */
#define LOADED_RUNS_MAX 16

/* o = the ascending merge of ascending [a, ea) and [b, eb); its end */
static int *merge_two(int *o, const int *a, const int *ea, const int *b, const int *eb)
{
  while (a < ea && b < eb) *o++ = *b < *a ? *b++ : *a++;
  memcpy(o, a, (size_t)(ea - a) * sizeof *o);
  o += ea - a;
  memcpy(o, b, (size_t)(eb - b) * sizeof *o);
  return o + (eb - b);
}

/* merge_two, each vertex once (no vertex is -1) */
static int *merge_two_unique(int *o, const int *a, const int *ea, const int *b, const int *eb)
{
  int last = -1;
  while (a < ea && b < eb) {
    int x = *b < *a ? *b++ : *a++;
    if (x != last) *o++ = last = x;
  }
  for (; a < ea; a++)
    if (*a != last) *o++ = last = *a;
  for (; b < eb; b++)
    if (*b != last) *o++ = last = *b;
  return o;
}

/* v[0, n): the k runs that begin at bd[0] = 0 < bd[1] < ... < bd[k - 1]
 * (2 <= k <= LOADED_RUNS_MAX; bd has room for k + 1), with the scratch
 * v + n: merged into v, each vertex once; its count */
static int merge_loaded(int *v, int n, int *bd, int k)
{
  int *src = v, *dst = v + n;
  bd[k] = n;
  for (; k > 2; k = (k + 1) / 2) {
    /* a pass: runs 2r and 2r + 1 into run r of dst (the last one
     * copied where k is odd) */
    for (int r = 0; r < k; r += 2) {
      int e = r + 2 <= k ? bd[r + 2] : n;
      if (r + 1 < k)
        merge_two(dst + bd[r], src + bd[r], src + bd[r + 1], src + bd[r + 1], src + e);
      else
        memcpy(dst + bd[r], src + bd[r], (size_t)(e - bd[r]) * sizeof *v);
      bd[r / 2] = bd[r];
    }
    bd[(k + 1) / 2] = n;
    int *t = src;
    src = dst;
    dst = t;
  }
  int u = (int)(merge_two_unique(dst, src, src + bd[1], src + bd[1], src + n) - dst);
  if (dst != v) memcpy(v, dst, (size_t)u * sizeof *v);
  return u;
}

/* the soil update's sums over the contacts (ss_terrain_update) */
typedef struct PointSums {
  int nrigid, nsoil, nload, nrun;
  double area, normal;
} PointSums;

/* The soil update's loop over the contacts: every loaded point's vertex
 * updated and the statistics summed; where collect, the loaded vertices
 * listed into loaded and the starts of their strictly ascending runs
 * (one collider's vertices come so) into run (run[0] = 0; those after
 * LOADED_RUNS_MAX counted, not kept).  collect a constant: the loop is
 * made twice, not tested at every point. */
static inline __attribute__((always_inline)) PointSums
update_points(const ssModel *m, ssData *d, int *loaded, int *run, const int collect)
{
  const double dt = m->opt.timestep;
  const int ncontact = d->ncontact;
  const ssContact *contact = d->contact;
  /* the material of bed `bed` and s^(n-1) for it: 1 where n = 1, else
   * by its table (solver.h), else libm, as the law forms it */
  int bed = -1;
  const ssSoilMaterial *mat = NULL;
  const ssPowTable *pt = NULL;
  double n1 = 0;
  ssModulusMemo mod = {NAN, 0};
  /* the statistics' sums in locals, in the same order (the soil arrays'
   * stores could alias them, as the compiler sees it) */
  int nrigid = 0, nsoil = 0, nload = 0, nrun = 1, last = -1;
  double area = 0, normal = 0;
  for (int i = 0; i < ncontact; i++) {
    const ssContact *c = contact + i;
    if (c->type != SS_CONTACT_SOIL) {
      if (c->type == SS_CONTACT_RIGID || c->type == SS_CONTACT_PAIR) nrigid++;
      continue;
    }
    nsoil++;
    if (!c->loaded) continue;
    if (c->hfield != bed) {
      bed = c->hfield;
      mat = &m->hfield_soilmat[bed];
      pt = ss_solver_pow_table(m, d, bed);
      n1 = mat->sinkage_exponent - 1;
      mod.b = NAN;
    }
    double delta = -(c->g0 + dt * c->v[0]);
    double s = c->sp + delta;
    double spn = ss_soil_plastic_update_pow(mat, ss_soil_modulus_at(mat, &mod, c->width), s, c->sp,
                                            n1 == 0 ? 1 : pt ? ss_pow_tab(pt, s) : pow(s, n1));
    double jn = c->j + dt * sqrt(c->v[1] * c->v[1] + c->v[2] * c->v[2]);
    int v = c->vertex;
    /* two colliders on one vertex: the deeper imprint wins */
    if (s > d->soil_sinkage[v]) d->soil_sinkage[v] = s;
    if (spn > d->soil_plastic[v]) d->soil_plastic[v] = spn;
    if (jn > d->soil_shear[v]) d->soil_shear[v] = jn;
    area += c->area;
    normal += c->lambda[0] / dt;
    if (collect) {
      loaded[nload] = v;
      if (v <= last) {
        if (nrun < LOADED_RUNS_MAX) run[nrun] = nload;
        nrun++;
      }
      last = v;
    }
    nload++;
  }
  return (PointSums){nrigid, nsoil, nload, nrun, area, normal};
}

void ss_terrain_update(const ssModel *m, ssData *d)
{
  ssStepStats *st = &d->stats;

  /* unloaded vertices recover elastically to the rut floor at once */
  for (int k = 0; k < d->nsoil_loaded; k++) {
    int v = d->soil_loaded[k];
    d->soil_sinkage[v] = d->soil_plastic[v];
    d->soil_shear[v] = 0;
  }
  /* room for the new list of loaded vertices (at most one per contact)
   * and the scratch of its sort after it, which ss_terrain_reserve made
   * before the solve (a step that cannot have it fails there); without
   * it the old list would stay, and a vertex loaded now but not in the
   * next step would never recover */
  const int ncontact = d->ncontact;
  if (2 * ncontact > d->cap_soil_loaded) {
    int *p = realloc(d->soil_loaded, (size_t)ncontact * 2 * sizeof(int));
    if (p) {
      d->soil_loaded = p;
      d->cap_soil_loaded = 2 * ncontact;
    }
  }
  const int collect = 2 * ncontact <= d->cap_soil_loaded;
  int *loaded = d->soil_loaded;
  int run[LOADED_RUNS_MAX + 1];
  run[0] = 0;
  const PointSums sum = collect ? update_points(m, d, loaded, run, 1)
                                : update_points(m, d, NULL, NULL, 0);
  const int nload = sum.nload, nrun = sum.nrun;
  st->rigid_contacts = sum.nrigid;
  st->soil_contacts = sum.nsoil;
  st->soil_loaded = nload;
  st->soil_contact_area = sum.area;
  st->soil_normal_force = sum.normal;
  if (!collect) return;
  /* the new list of loaded vertices (unique): as they came where they
   * ascend strictly (one collider's, or none loaded, when the list may
   * not exist yet: no arithmetic on its NULL), else merged from their
   * runs (one per collider), by their known starts where they were kept */
  if (nrun == 1) {
    d->nsoil_loaded = nload;
    return;
  }
  if (nrun <= LOADED_RUNS_MAX) {
    d->nsoil_loaded = merge_loaded(loaded, nload, run, nrun);
    return;
  }
  const int *v = merge_sort_runs_from(loaded, loaded + nload, nload, run[1]);
  int u = 0;
  for (int i = 0; i < nload; i++)
    if (u == 0 || loaded[u - 1] != v[i]) loaded[u++] = v[i];
  d->nsoil_loaded = u;
}
