/* worlds.c -- worlds built in code, shared by the tests and the benchmark
 * program: a tiny in-memory URDF builder, the plate soil of DESIGN 2.7, and
 * the articulated benchmark bodies of DESIGN 8. */
#include "worlds.h"
#include "tap.h"
#include "solver.h"
#include "ss_math.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const double W_X[3] = {1, 0, 0}, W_Y[3] = {0, 1, 0}, W_Z[3] = {0, 0, 1};
const double FOURPAD_CX[4] = {-0.25, 0.25, -0.25, 0.25};
const double FOURPAD_CY[4] = {-0.3, -0.3, 0.3, 0.3};

ssUrdf *urdf_new(void)
{
  ssUrdf *u = calloc(1, sizeof *u);
  u->link = calloc(64, sizeof *u->link);
  u->joint = calloc(64, sizeof *u->joint);
  u->closure = calloc(16, sizeof *u->closure);
  u->spring = calloc(16, sizeof *u->spring);
  snprintf(u->path, sizeof u->path, "in-memory.urdf");
  return u;
}

/* a link of mass m with its COM at com and principal inertia (ix, iy, iz) */
int add_link(ssUrdf *u, const char *name, double m, const double com[3],
                    double ix, double iy, double iz)
{
  ssUrdfLink *l = &u->link[u->nlink];
  snprintf(l->name, sizeof l->name, "%s", name);
  l->mass = m;
  if (com) memcpy(l->com, com, sizeof l->com);
  l->com_quat[0] = 1;
  l->inertia[0] = ix;
  l->inertia[3] = iy;
  l->inertia[5] = iz;
  return u->nlink++;
}

void add_box(ssUrdf *u, int link, double x, double y, double z,
                    const double pos[3])
{
  ssUrdfLink *l = &u->link[link];
  l->geom = realloc(l->geom, (size_t)(l->ngeom + 1) * sizeof *l->geom);
  ssUrdfGeom *g = &l->geom[l->ngeom++];
  memset(g, 0, sizeof *g);
  g->type = SS_GEOM_BOX;
  g->size[0] = x;
  g->size[1] = y;
  g->size[2] = z;
  if (pos) memcpy(g->pos, pos, sizeof g->pos);
  g->quat[0] = 1;
  g->collision = 1;
}

int add_joint(ssUrdf *u, const char *name, int type, int parent,
                     int child, const double pos[3], const double axis[3])
{
  ssUrdfJoint *j = &u->joint[u->njoint];
  snprintf(j->name, sizeof j->name, "%s", name);
  j->type = type;
  j->parent = parent;
  j->child = child;
  if (pos) memcpy(j->pos, pos, sizeof j->pos);
  j->quat[0] = 1;
  if (axis) memcpy(j->axis, axis, sizeof j->axis);
  else j->axis[0] = 1;
  return u->njoint++;
}

ssSoilMaterial plate_soil(void)
{
  ssSoilMaterial s = ss_soil_material_default();
  s.bekker_kc = 0;
  s.bekker_kphi = 1e5;
  s.sinkage_exponent = 1;
  s.elastic_stiffness = 2e6;
  /* overdamped settling (critical ~ 5800 Pa s/m for the plate): the
   * quasi-static reference of DESIGN 2.7 without overshoot */
  s.damping = 1e4;
  return s;
}

/* an n x n soil bed "bed" of side size rising by slope (m) along x; its
 * index, or -1 (why in *e) */
static int add_sloped_bed(ssModel *m, int n, double size, double slope, ssSoilMaterial soil,
                          ssError *e)
{
  double *z = calloc((size_t)n * n, sizeof(double));
  if (!z) {
    snprintf(e->message, sizeof e->message, "out of memory");
    return -1;
  }
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) z[j * n + i] = n > 1 ? slope * i / (n - 1) : 0;
  ssHfieldDef hd = ss_hfield_def_default();
  hd.name = "bed";
  hd.nx = hd.ny = n;
  hd.x_size = hd.y_size = size;
  hd.height = z;
  hd.soil = 1;
  hd.soilmat = soil;
  int k = ss_model_add_hfield(m, &hd, e);
  free(z);
  return k;
}

int add_bed(ssModel *m, double size, double h, ssSoilMaterial soil)
{
  ssError e;
  return add_sloped_bed(m, (int)lround(size / h) + 1, size, 0, soil, &e);
}

int add_soil_bed(ssModel *m, double size, double h)
{
  return add_bed(m, size, h, plate_soil());
}

/* a chain of revolute links with joint springs, standing on link `on` */
int add_mast(ssUrdf *u, int on, int nlinks, double mass, const double at[3])
{
  int prev = on;
  const double *axes[3] = {W_X, W_Y, W_Z};
  for (int k = 0; k < nlinks; k++) {
    char name[32];
    snprintf(name, sizeof name, "mast%d_%d", on, k);
    double com[3] = {0, 0, 0.01};
    int l = add_link(u, name, mass, com, 1e-5, 1e-5, 1e-5);
    double pos[3] = {0, 0, 0.02};
    if (k == 0) memcpy(pos, at, sizeof pos);
    int j = add_joint(u, name, SS_JOINT_REVOLUTE, prev, l, pos, axes[k % 3]);
    u->joint[j].stiffness = 60;
    u->joint[j].damping = 0.5;
    prev = l;
  }
  return prev;
}


/* DESIGN 8 --body=articulated: the 0.4 x 0.6 plate as a floating base
 * carrying a 54-joint sprung mast; 20 kg in all, 60 DOF */
ssUrdf *carrier60(void)
{
  ssUrdf *u = urdf_new();
  int plate = add_link(u, "plate", 20 - 54 * 0.02, NULL, 0.6, 0.3, 0.8);
  add_box(u, plate, 0.4, 0.6, 0.05, NULL);
  double top[3] = {0, 0, 0.025};
  add_mast(u, plate, 54, 0.02, top);
  return u;
}

/* --body=pinned: the carrier with eight independent equality relations
 * tying pairs of mast joints together */
ssUrdf *carrier60_pinned(void)
{
  ssUrdf *u = carrier60();
  for (int k = 0; k < 8; k++) {
    ssUrdfClosure *c = &u->closure[u->nclosure++];
    memset(c, 0, sizeof *c);
    c->type = SS_CLOSURE_EQUALITY;
    c->joint1 = 6 * k + 3;  /* same axis, three joints apart */
    c->joint2 = 6 * k;
    c->ratio = 1;
    c->offset = 0;
  }
  return u;
}

/* --body=multilink: a frame on four 0.2 x 0.3 pads, each on x/y/z
 * sliders and a ball joint, plus a 34-joint mast; 20 kg, 0.24 m^2, 64 DOF */
ssUrdf *fourpad64(void)
{
  ssUrdf *u = urdf_new();
  double pad_mass = 4, slide_mass = 0.05, mast_mass = 0.04;
  double frame_mass = 20 - 4 * (pad_mass + 3 * slide_mass) - 34 * mast_mass;
  int frame = add_link(u, "frame", frame_mass, NULL, 0.05, 0.05, 0.08);
  for (int k = 0; k < 4; k++) {
    char nm[32];
    int prev = frame;
    const double *ax[3] = {W_X, W_Y, W_Z};
    for (int a = 0; a < 3; a++) {
      snprintf(nm, sizeof nm, "slide%d%c", k, "xyz"[a]);
      int l = add_link(u, nm, slide_mass, NULL, 1e-4, 1e-4, 1e-4);
      double p0[3] = {0, 0, 0};
      if (a == 0) {
        p0[0] = FOURPAD_CX[k];
        p0[1] = FOURPAD_CY[k];
        p0[2] = -0.1;
      }
      int j = add_joint(u, nm, SS_JOINT_PRISMATIC, prev, l, p0, ax[a]);
      u->joint[j].stiffness = a == 2 ? 2e4 : 5e3;
      u->joint[j].damping = 200;
      prev = l;
    }
    snprintf(nm, sizeof nm, "pad%d", k);
    int pad = add_link(u, nm, pad_mass, NULL, 0.03, 0.015, 0.04);
    add_box(u, pad, 0.2, 0.3, 0.04, NULL);
    double p0[3] = {0, 0, 0};
    int j = add_joint(u, nm, SS_JOINT_SPHERICAL, prev, pad, p0, NULL);
    u->joint[j].damping = 2;
  }
  double mtop[3] = {0, 0, 0.02};
  add_mast(u, frame, 34, mast_mass, mtop);
  return u;
}


/* ---------------------------------------------------------------------- */
/* the solver's packed link groups against the full per-contact update     */

double solver_paths_difference(ssModel *m, ssData *d, int sweeps, int *ncontact)
{
  ssError e;
  unsigned char *buf = NULL;
  size_t len = 0;
  int keep_sweeps = m->opt.solver_max_sweeps;
  double keep_tol = m->opt.solver_tolerance, worst = -1;
  /* exactly `sweeps` sweeps on both paths: no early stop at round-off */
  m->opt.solver_max_sweeps = sweeps;
  m->opt.solver_tolerance = 1e-300;
  int nv = m->nv, full = d->solver_full, gs = d->solver_gs_only;
  /* the sweeps alone: the Newton phase would move their start */
  d->solver_gs_only = 1;
  double *u = malloc((size_t)(nv ? nv : 1) * sizeof(double));
  if (!u || ss_checkpoint_save_buffer(m, d, &buf, &len, &e) != SS_OK) goto out;
  d->solver_full = 0;
  if (ss_step(m, d, &e) != SS_OK) goto out;
  memcpy(u, d->qvel, (size_t)nv * sizeof(double));
  if (ncontact) *ncontact = d->ncontact;
  if (ss_checkpoint_load_buffer(m, d, buf, len, &e) != SS_OK) goto out;
  d->solver_full = 1;
  if (ss_step(m, d, &e) != SS_OK) goto out;
  double du = 0, un = 0;
  for (int i = 0; i < nv; i++) {
    du = fmax(du, fabs(d->qvel[i] - u[i]));
    un = fmax(un, fabs(u[i]));
  }
  worst = un > 0 ? du / un : du;
out:
  d->solver_full = full;
  d->solver_gs_only = gs;
  m->opt.solver_max_sweeps = keep_sweeps;
  m->opt.solver_tolerance = keep_tol;
  free(buf);
  free(u);
  return worst;
}

/* ---------------------------------------------------------------------- */
/* the Newton phase against the sweeps alone                               */

int newton_paths(ssModel *m, ssData *d, PathCompare *out)
{
  ssError e;
  unsigned char *buf = NULL;
  size_t len = 0;
  int gs = d->solver_gs_only, ok = 0, nc = 0;
  double *lam = NULL;
  memset(out, 0, sizeof *out);
  out->dlam = -1;
  if (ss_checkpoint_save_buffer(m, d, &buf, &len, &e) != SS_OK) goto done;
  /* the sweeps alone first, their impulses kept */
  d->solver_gs_only = 1;
  if (ss_step(m, d, &e) != SS_OK) goto done;
  nc = d->ncontact;
  if (!(lam = malloc((size_t)(nc ? nc : 1) * 3 * sizeof(double)))) goto done;
  for (int i = 0; i < nc; i++) memcpy(lam + 3 * i, d->contact[i].lambda, 3 * sizeof(double));
  out->sweeps[1] = d->stats.sweeps;
  out->newton[1] = d->stats.newton;
  out->converged[1] = d->stats.converged;
  /* then the same step with the Newton phase */
  if (ss_checkpoint_load_buffer(m, d, buf, len, &e) != SS_OK) goto done;
  d->solver_gs_only = 0;
  if (ss_step(m, d, &e) != SS_OK || d->ncontact != nc) goto done;
  out->sweeps[0] = d->stats.sweeps;
  out->newton[0] = d->stats.newton;
  out->converged[0] = d->stats.converged;
  double dmax = 0, lmax = 0;
  for (int i = 0; i < nc; i++) {
    const double *a = d->contact[i].lambda, *b = lam + 3 * i;
    dmax = fmax(dmax, fabs(a[0] - b[0]) + fabs(a[1] - b[1]) + fabs(a[2] - b[2]));
    lmax = fmax(lmax, fabs(b[0]) + fabs(b[1]) + fabs(b[2]));
  }
  out->dlam = lmax > 0 ? dmax / lmax : dmax;
  out->ncontact = nc;
  ok = 1;
done:
  d->solver_gs_only = gs;
  free(buf);
  free(lam);
  return ok;
}

int plate_world(int n, double size, double slope, double pull, const ssSoilMaterial *soil,
                ssModel **mout, ssData **dout, ssError *e)
{
  ssModel *m = ss_model_new();
  if (!m) {
    snprintf(e->message, sizeof e->message, "out of memory");
    return 0;
  }
  int bed = add_sloped_bed(m, n, size, slope, soil ? *soil : plate_soil(), e);
  ssBodyDef bd = ss_body_def_default();
  bd.name = "plate";
  bd.shape = SS_GEOM_BOX;
  ss_v3_set(bd.size, 0.4, 0.6, 0.05);
  bd.mass = 20;
  ss_v3_set(bd.pos, 0.013, -0.007, 0.0265);
  int body = bed >= 0 ? ss_model_add_body(m, &bd, e) : -1;
  int ok = bed >= 0 && body >= 0;
  if (ok && pull != 0) {
    double f[3] = {pull, 0, 0}, t[3] = {0, 0, 0};
    ok = ss_model_add_xforce(m, m->sys_bodyadr[body], f, t, 0.03, 1e9, e) >= 0;
  }
  if (ok) ok = ss_model_validate(m, e) == SS_OK;
  ssData *d = ok ? ss_data_new(m) : NULL;
  if (!d) {
    if (ok) snprintf(e->message, sizeof e->message, "out of memory");
    ss_model_free(m);
    return 0;
  }
  *mout = m;
  *dout = d;
  return 1;
}

int load_scene_file(const char *rel, ssModel **m, ssData **d)
{
  const char *top = getenv("top_srcdir");
  char path[1024];
  ssError e;
  snprintf(path, sizeof path, "%s/%s", top && *top ? top : ".", rel);
  if (ss_scene_load(path, m, d, &e) != SS_OK) {
    diag("%s:%d: %s", e.file, e.line, e.message);
    return 0;
  }
  return 1;
}
