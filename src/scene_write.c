/* scene_write.c -- the whole world (model + current state) as world XML.
 *
 * The output is the snake_case form of the format in scene.h, with every
 * height map in the explicit form and soil beds carrying their material and
 * state arrays, so that loading an export restores the world exactly and
 * exporting it again gives the same bytes.  Each double is written so that
 * it reads back to the same double (see fmt_double: as exact as "%.17g",
 * but 9.81 stays "9.81").  The text goes
 * through one buffer straight to the file (no per-number library calls
 * besides the formatting), and the file is replaced atomically.
 *
 * Files.  Height maps are written explicit, so the only files an export
 * names are an articulated system's URDF (urdf_path) and resource folder
 * (res_dir) and a mesh body's file (file_name).  The reader keeps them as
 * absolute, normalised paths (links resolved); they are written relative to
 * the export's own folder ("../assets/arm.urdf"), which is how the reader
 * resolves them, so an export written anywhere loads again and a folder
 * that holds both the export and its assets can be moved or copied as a
 * whole.  When the two share nothing but the root ("/tmp/out.xml" and
 * "/home/me/assets/arm.urdf") the path is written absolute instead: such an
 * export is more likely to be moved alone.  Either way the text depends
 * only on where the files are, not on the working folder, so export ->
 * load -> export gives the same bytes from any folder. */
#include "scene.h"
#include "dynamics.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct wBuf {
  ssAtomicFile *f;     /* keeps the first write error; later writes do nothing */
  char dir[4096];      /* the output file's folder, absolute and normalised
                          ("" if unknown: paths are then written absolute) */
  size_t n;
  char b[1 << 16];
} wBuf;

static void w_flush(wBuf *w)
{
  if (w->n) ss_atomic_write(w->f, w->b, w->n);
  w->n = 0;
}

static void w_put(wBuf *w, const char *s, size_t n)
{
  if (n > sizeof w->b - w->n) {
    w_flush(w);
    if (n > sizeof w->b) {
      ss_atomic_write(w->f, s, n);
      return;
    }
  }
  memcpy(w->b + w->n, s, n);
  w->n += n;
}

static void w_s(wBuf *w, const char *s) { w_put(w, s, strlen(s)); }

/* Exact and short: "%.17g" always reads back to the same double; when that
 * has 17 significant digits and the last two are within 12 of a multiple
 * of 100 (every double that is the nearest one to a 15-digit decimal
 * prints that way: half an ulp is at most 11.1 units of the 17th digit),
 * "%.15g" and then "%.16g" are tried and kept if they read back exactly.
 * So 9.81 is written "9.81", not "9.8100000000000005", while a typical
 * simulated value costs one format.  The result depends on the value
 * alone, so a loaded export writes the same bytes again.  Needs the C
 * locale.  Returns the length. */
static int fmt_double(char out[40], double v)
{
  if (v == 0) {
    strcpy(out, signbit(v) ? "-0" : "0");
    return signbit(v) ? 2 : 1;
  }
  int n = snprintf(out, 40, "%.17g", v);
  /* significant digits 16 and 17 */
  int nd = 0, tail = 0;
  for (const char *p = out; *p && *p != 'e'; p++) {
    if (*p < '0' || *p > '9') continue;
    if (nd == 0 && *p == '0') continue;
    nd++;
    if (nd >= 16) tail = tail * 10 + (*p - '0');
  }
  if (nd < 17 || (tail > 12 && tail < 88)) return n;
  char t[40];
  for (int prec = 15; prec <= 16; prec++) {
    int m = snprintf(t, sizeof t, "%.*g", prec, v);
    if (strtod(t, NULL) == v) {
      memcpy(out, t, (size_t)m + 1);
      return m;
    }
  }
  return n;
}

static void w_num(wBuf *w, double v)
{
  char t[40];
  int n = fmt_double(t, v);
  w_put(w, t, (size_t)n);
}

static void w_long(wBuf *w, long v)
{
  char t[32];
  int n = snprintf(t, sizeof t, "%ld", v);
  w_put(w, t, (size_t)n);
}

/* Attribute text: markup characters and the white space that attribute
 * normalisation would change are escaped. */
static void w_esc(wBuf *w, const char *s)
{
  for (; *s; s++) {
    switch (*s) {
    case '&': w_s(w, "&amp;"); break;
    case '<': w_s(w, "&lt;"); break;
    case '>': w_s(w, "&gt;"); break;
    case '"': w_s(w, "&quot;"); break;
    case '\t': w_s(w, "&#9;"); break;
    case '\n': w_s(w, "&#10;"); break;
    case '\r': w_s(w, "&#13;"); break;
    default: w_put(w, s, 1);
    }
  }
}

/* XML 1.0 cannot carry other control characters, even escaped. */
static int name_ok(const char *s)
{
  for (; *s; s++) {
    unsigned char ch = (unsigned char)*s;
    if (ch < 0x20 && ch != '\t' && ch != '\n' && ch != '\r') return 0;
  }
  return 1;
}

static void a_str(wBuf *w, const char *name, const char *v)
{
  w_s(w, " ");
  w_s(w, name);
  w_s(w, "=\"");
  w_esc(w, v);
  w_s(w, "\"");
}

/* A file or folder the model was loaded from, as the reader will find it
 * from the output's folder (see the rule at the top).  A path the model
 * holds relative (a model built in code) is taken from the working folder,
 * as it was opened. */
static void a_path(wBuf *w, const char *name, const char *v)
{
  char abs[4096], rel[8192];
  if (ss_scene_path_absolute(v, abs, sizeof abs)) {
    a_str(w, name, v);
    return;
  }
  if (w->dir[0] && !ss_scene_path_relative(abs, w->dir, rel, sizeof rel))
    a_str(w, name, rel);
  else
    a_str(w, name, abs);
}

static void a_vec(wBuf *w, const char *name, const double *v, int n)
{
  w_s(w, " ");
  w_s(w, name);
  w_s(w, "=\"");
  for (int k = 0; k < n; k++) {
    if (k) w_s(w, " ");
    w_num(w, v[k]);
  }
  w_s(w, "\"");
}

static void a_num(wBuf *w, const char *name, double v) { a_vec(w, name, &v, 1); }

static void a_long(wBuf *w, const char *name, long v)
{
  w_s(w, " ");
  w_s(w, name);
  w_s(w, "=\"");
  w_long(w, v);
  w_s(w, "\"");
}

/* A grid array: one row of nx values per line. */
static void a_grid(wBuf *w, const char *indent, const char *name,
                   const double *v, int nx, int ny)
{
  w_s(w, "\n");
  w_s(w, indent);
  w_s(w, name);
  w_s(w, "=\"");
  for (int j = 0; j < ny; j++) {
    if (j) {
      w_s(w, "\n");
      w_s(w, indent);
      w_s(w, "  ");
    }
    const double *row = v + (size_t)j * nx;
    for (int i = 0; i < nx; i++) {
      if (i) w_s(w, " ");
      w_num(w, row[i]);
    }
  }
  w_s(w, "\"");
}

static const char *mat_name(const ssModel *m, int k)
{
  return k >= 0 && k < m->nmaterial ? m->material_name[k] : "default";
}

static void write_body(wBuf *w, const ssModel *m, const ssData *d, int s,
                       int g)
{
  static const char *const tag[] = {"box", "sphere", "cylinder", "capsule",
                                    "mesh"};
  int b = m->sys_bodyadr[s];
  int is_static = m->sys_type[s] == SS_SYS_STATIC;
  const char *t = tag[m->geom_type[g]];
  const double *sz = m->geom_size + 3 * g;
  const double *q = d->qpos + m->sys_qadr[s];

  w_s(w, "    <");
  w_s(w, t);
  a_str(w, "name", m->sys_name[s]);
  if (is_static)
    a_str(w, "body_type", "static");
  else
    a_num(w, "mass", m->body_mass[b]);
  a_str(w, "material", mat_name(m, m->geom_material[g]));
  a_vec(w, "rgba", m->geom_rgba + 4 * g, 4);
  const int is_mesh = m->geom_type[g] == SS_GEOM_MESH;
  if (is_mesh) {
    /* the file and the scale the model baked into its vertices: the
     * reader loads the same vertices and finds the same centroid */
    int k = m->geom_mesh[g];
    const double *sc = m->mesh_scale + 3 * k;
    a_path(w, "file_name", m->mesh_path[k]);
    a_vec(w, "scale", sc, sc[0] == sc[1] && sc[1] == sc[2] ? 1 : 3);
    w_s(w, ">\n      <state");
  } else {
    w_s(w, ">\n      <dim");
  }
  switch (is_mesh ? -1 : m->geom_type[g]) {
  case -1:
    break;
  case SS_GEOM_BOX:
    a_num(w, "x", sz[0]);
    a_num(w, "y", sz[1]);
    a_num(w, "z", sz[2]);
    break;
  case SS_GEOM_SPHERE:
    a_num(w, "radius", sz[0]);
    break;
  default:
    a_num(w, "radius", sz[0]);
    a_num(w, "height", sz[1]);
    break;
  }
  if (!is_mesh) w_s(w, "/>\n      <state");
  a_vec(w, "pos", q, 3);
  a_vec(w, "quat", q + 3, 4);
  if (!is_static) {
    const double *v = d->qvel + m->sys_vadr[s];
    a_vec(w, "lin_vel", v, 3);
    a_vec(w, "ang_vel", v + 3, 3);
  }
  w_s(w, "/>\n");
  /* a dynamic mesh's inertia is always written: the reader would
   * integrate it again from the file (its mass over its volume), and the
   * one held is what replays bit for bit */
  if (m->body_inertia_given[b] || (is_mesh && !is_static)) {
    const double *I = m->body_inertia + 9 * b;
    w_s(w, "      <inertia");
    a_num(w, "xx", I[0]);
    a_num(w, "xy", I[1]);
    a_num(w, "xz", I[2]);
    a_num(w, "yy", I[4]);
    a_num(w, "yz", I[5]);
    a_num(w, "zz", I[8]);
    w_s(w, "/>\n");
  }
  for (int k = 0; k < m->nxforce; k++) {
    if (m->xforce_body[k] != b) continue;
    w_s(w, "      <external_force");
    a_vec(w, "force", m->xforce_force + 3 * k, 3);
    a_vec(w, "torque", m->xforce_torque + 3 * k, 3);
    a_num(w, "start", m->xforce_time[2 * k]);
    if (isfinite(m->xforce_time[2 * k + 1]))
      a_num(w, "end", m->xforce_time[2 * k + 1]);
    w_s(w, "/>\n");
  }
  w_s(w, "    </");
  w_s(w, t);
  w_s(w, ">\n");
}

static void write_hfield(wBuf *w, const ssModel *m, const ssData *d, int h)
{
  static const char ind[] = "               ";
  int nx = m->hfield_nx[h], ny = m->hfield_ny[h], a = m->hfield_adr[h];
  w_s(w, "    <heightmap");
  a_str(w, "name", m->hfield_name[h]);
  a_num(w, "x_size", m->hfield_size[2 * h]);
  a_num(w, "y_size", m->hfield_size[2 * h + 1]);
  a_long(w, "x_sample", nx);
  a_long(w, "y_sample", ny);
  a_num(w, "center_x", m->hfield_center[2 * h]);
  a_num(w, "center_y", m->hfield_center[2 * h + 1]);
  a_vec(w, "pos", d->hfield_pos + 3 * h, 3);
  a_vec(w, "quat", d->hfield_quat + 4 * h, 4);
  a_str(w, "material", mat_name(m, m->hfield_material[h]));
  a_grid(w, ind, "height", m->hfield_data + a, nx, ny);
  if (!m->hfield_soil[h]) {
    w_s(w, "/>\n");
    return;
  }
  const ssSoilMaterial *s = &m->hfield_soilmat[h];
  static const char sind[] = "            ";
  w_s(w, ">\n      <soil");
  a_num(w, "bekker_kc", s->bekker_kc);
  a_num(w, "bekker_kphi", s->bekker_kphi);
  a_num(w, "sinkage_exponent", s->sinkage_exponent);
  a_num(w, "elastic_stiffness", s->elastic_stiffness);
  w_s(w, "\n");
  w_s(w, sind);
  a_num(w, "damping", s->damping);
  a_num(w, "cohesion", s->cohesion);
  a_num(w, "friction_coefficient", s->friction_coefficient);
  a_num(w, "shear_displacement", s->shear_displacement);
  a_grid(w, sind, "sinkage", d->soil_sinkage + a, nx, ny);
  a_grid(w, sind, "plastic_sinkage", d->soil_plastic + a, nx, ny);
  a_grid(w, sind, "shear", d->soil_shear + a, nx, ny);
  w_s(w, "/>\n    </heightmap>\n");
}

/* The material a system's element names: its (first) collider's. */
static int sys_material(const ssModel *m, int s)
{
  int b0 = m->sys_bodyadr[s];
  for (int g = 0; g < m->ngeom; g++)
    if (m->geom_body[g] >= b0 && m->geom_body[g] < b0 + m->sys_nbody[s])
      return m->geom_material[g];
  return 0;
}

/* <articulated_system> with its URDF, base, full state and PD targets */
static void write_articulated(wBuf *w, const ssModel *m, const ssData *d, int s)
{
  w_s(w, "    <articulated_system");
  a_str(w, "name", m->sys_name[s]);
  a_path(w, "urdf_path", m->sys_source[s]);
  if (m->sys_resdir[s][0]) a_path(w, "res_dir", m->sys_resdir[s]);
  a_str(w, "base", m->sys_fixed[s] ? "fixed" : "floating");
  int b0 = m->sys_bodyadr[s];
  a_str(w, "material", mat_name(m, sys_material(m, s)));
  w_s(w, ">\n      <state");
  if (m->sys_fixed[s]) {
    a_vec(w, "pos", m->body_jntpos + 3 * b0, 3);
    a_vec(w, "quat", m->body_jntquat + 4 * b0, 4);
  }
  if (m->sys_nq[s]) {
    a_vec(w, "qpos", d->qpos + m->sys_qadr[s], m->sys_nq[s]);
    /* the configuration closures and springs took their implicit anchors
     * and lengths from, so a reload derives exactly the same ones */
    a_vec(w, "reference_qpos", m->qpos0 + m->sys_qadr[s], m->sys_nq[s]);
  }
  if (m->sys_nv[s]) a_vec(w, "qvel", d->qvel + m->sys_vadr[s], m->sys_nv[s]);
  w_s(w, "/>\n");
  for (int k = 0; k < m->npd; k++) {
    int b = m->pd_body[k];
    if (m->body_sys[b] != s) continue;
    const double *g = m->pd_gain + 3 * k, *t = d->pd_target + 2 * k;
    w_s(w, "      <pd");
    a_str(w, "joint", m->body_jntname[b]);
    a_num(w, "p_gain", g[0]);
    a_num(w, "d_gain", g[1]);
    a_num(w, "position_target", t[0]);
    a_num(w, "velocity_target", t[1]);
    a_num(w, "effort_limit", g[2]);
    w_s(w, "/>\n");
  }
  w_s(w, "    </articulated_system>\n");
}

/* The objects in the order they are written. */
enum { OBJ_PLANE, OBJ_SYS, OBJ_HFIELD };
typedef struct wObject {
  int kind;  /* OBJ_* */
  int index; /* plane, system or height map */
} wObject;

static int object_material(const ssModel *m, const wObject *o)
{
  return o->kind == OBJ_PLANE   ? m->plane_material[o->index]
         : o->kind == OBJ_HFIELD ? m->hfield_material[o->index]
                                 : sys_material(m, o->index);
}

/* The numbers the reader gives the materials of the pairs it has not met
 * yet: a pair's two names in the order they are written (see
 * write_materials). */
static void number_pairs(const ssModel *m, int *renum, int *nnum)
{
  for (int k = 0; k < m->npair; k++) {
    int a = m->pair[k].mat1, b = m->pair[k].mat2;
    if (a >= 0 && a < m->nmaterial && renum[a] < 0) renum[a] = (*nnum)++;
    if (b >= 0 && b < m->nmaterial && renum[b] < 0) renum[b] = (*nnum)++;
  }
}

/* The reader numbers the materials in the order it meets their names, so
 * the objects are written in an order that names them in the order of the
 * model's numbers: the reloaded world then has the same numbers (a
 * checkpoint's fingerprint compares them) and its pairs keep their names'
 * order, so export -> load -> export gives the same bytes.  Grounds,
 * systems and height maps each keep their own order (as the reader met
 * them, so such an order exists for a model read from a file); among the
 * next objects of the three, the first whose material is already named or
 * is the next number is taken, grounds before systems before height maps,
 * which leaves the usual order wherever it already works.  pairs_first:
 * the <material> element is to be written before <objects> (a scene that
 * has it there names its pairs' materials first).  renum[k] gets the
 * number the reader will give material k (-1: named by nothing written);
 * returns the number of objects. */
static int object_order(const ssModel *m, const ssData *d, int pairs_first,
                        wObject *order, int *renum, unsigned char *used)
{
  int count[3] = {m->nplane, m->nsys, m->nhfield}, next[3] = {0, 0, 0};
  int nobj = 0, nused = 1;
  for (int k = 0; k < m->nmaterial; k++) {
    renum[k] = -1;
    used[k] = 0;
  }
  if (m->nmaterial > 0) renum[0] = 0; /* "default", numbered first */
  if (pairs_first) number_pairs(m, renum, &nused);
  /* the materials the written objects name */
  for (int kind = 0; kind < 3; kind++)
    for (int i = 0; i < count[kind]; i++) {
      if (kind == OBJ_SYS && !d->sys_active[i]) continue;
      wObject o = {kind, i};
      int mat = object_material(m, &o);
      if (mat >= 0 && mat < m->nmaterial) used[mat] = 1;
    }
  int expect = 1;
  for (;;) {
    while (expect < m->nmaterial && (!used[expect] || renum[expect] >= 0))
      expect++;
    int pick = -1, fallback = -1;
    for (int kind = 0; kind < 3 && pick < 0; kind++) {
      while (kind == OBJ_SYS && next[kind] < count[kind] &&
             !d->sys_active[next[kind]])
        next[kind]++;
      if (next[kind] >= count[kind]) continue;
      if (fallback < 0) fallback = kind;
      wObject o = {kind, next[kind]};
      int mat = object_material(m, &o);
      if (mat < 0 || mat >= m->nmaterial || renum[mat] >= 0 ||
          mat == expect)
        pick = kind;
    }
    /* no order names them in the model's order (a model built in code):
     * the usual one */
    if (pick < 0) pick = fallback;
    if (pick < 0) break;
    wObject o = {pick, next[pick]++};
    int mat = object_material(m, &o);
    if (mat >= 0 && mat < m->nmaterial && renum[mat] < 0) renum[mat] = nused++;
    order[nobj++] = o;
  }
  if (!pairs_first) number_pairs(m, renum, &nused);
  return nobj;
}

/* Whether the reloaded world numbers every material written as this one. */
static int same_numbers(const ssModel *m, const int *renum)
{
  for (int k = 0; k < m->nmaterial; k++)
    if (renum[k] >= 0 && renum[k] != k) return 0;
  return 1;
}

/* <material>: the default and the pairs, each pair's names in the order
 * the reader numbers them (it keeps a pair's lower number first). */
static void write_materials(wBuf *w, const ssModel *m, const int *renum)
{
  w_s(w, "  <material>\n    <default");
  a_num(w, "friction", m->material_default.friction);
  a_num(w, "restitution", m->material_default.restitution);
  a_num(w, "restitution_threshold", m->material_default.restitution_threshold);
  w_s(w, "/>\n");
  for (int k = 0; k < m->npair; k++) {
    const ssMaterialPair *p = &m->pair[k];
    int a = p->mat1, b = p->mat2;
    if (a >= 0 && a < m->nmaterial && b >= 0 && b < m->nmaterial &&
        renum[b] < renum[a]) {
      int t = a;
      a = b;
      b = t;
    }
    w_s(w, "    <pair_prop");
    a_str(w, "name1", mat_name(m, a));
    a_str(w, "name2", mat_name(m, b));
    a_num(w, "friction", p->friction);
    a_num(w, "restitution", p->restitution);
    a_num(w, "restitution_threshold", p->restitution_threshold);
    w_s(w, "/>\n");
  }
  w_s(w, "  </material>\n");
}

static void write_world(wBuf *w, const ssModel *m, const ssData *d,
                        const wObject *order, int nobj, const int *renum,
                        int pairs_first)
{
  const ssOption *o = &m->opt;
  w_s(w, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         "<!-- soilsim " SS_VERSION " world export -->\n"
         "<raisim version=\"1.0\">\n");
  w_s(w, "  <time_step");
  a_num(w, "value", o->timestep);
  w_s(w, "/>\n  <gravity");
  a_vec(w, "value", o->gravity, 3);
  w_s(w, "/>\n  <contact_solver");
  a_long(w, "max_sweeps", o->solver_max_sweeps);
  a_num(w, "tolerance", o->solver_tolerance);
  a_num(w, "scalar_tolerance", o->scalar_tolerance);
  a_str(w, "terrain_warm_start", o->terrain_warm_start ? "true" : "false");
  a_num(w, "contact_margin", o->contact_margin);
  a_num(w, "rigid_erp", o->rigid_erp);
  w_s(w, "/>\n  <clock");
  a_num(w, "time", d->time);
  a_long(w, "step", d->step);
  w_s(w, "/>\n");
  if (m->camera_given) {
    w_s(w, "  <camera");
    a_vec(w, "pos", m->camera_pos, 3);
    a_vec(w, "look_at", m->camera_look_at, 3);
    a_num(w, "fov_deg", m->camera_fov_deg);
    /* a removed body is not written, so the camera cannot follow it */
    int f = m->camera_follow[0] ? ss_model_find_sys(m, m->camera_follow) : -1;
    if (f >= 0 && d->sys_active[f]) a_str(w, "follow", m->camera_follow);
    w_s(w, "/>\n");
  }

  if (pairs_first) write_materials(w, m, renum);
  w_s(w, "  <objects>\n");
  for (int k = 0; k < nobj; k++) {
    int i = order[k].index;
    if (order[k].kind == OBJ_PLANE) {
      w_s(w, "    <ground");
      a_str(w, "name", m->plane_name[i]);
      a_num(w, "height", m->plane_height[i]);
      a_str(w, "material", mat_name(m, m->plane_material[i]));
      w_s(w, "/>\n");
    } else if (order[k].kind == OBJ_HFIELD) {
      write_hfield(w, m, d, i);
    } else if (m->sys_type[i] == SS_SYS_ARTICULATED) {
      write_articulated(w, m, d, i);
    } else {
      int b = m->sys_bodyadr[i];
      for (int g = 0; g < m->ngeom; g++)
        if (m->geom_body[g] == b) {
          write_body(w, m, d, i, g);
          break;
        }
    }
  }
  w_s(w, "  </objects>\n");

  if (!pairs_first) write_materials(w, m, renum);
  w_s(w, "</raisim>\n");
}

/* What the format cannot (yet) express. */
static ssStatus check_exportable(const ssModel *m, const ssData *d,
                                 const char *path, ssError *err)
{
  if (d->in_step)
    return ss_error_set(err, SS_ERR_STATE, path, 0,
                        "cannot export in the middle of a step");
  /* what the reader would refuse is not written (the limits a step keeps:
   * see SS_SPEED_MAX) */
  char why[300];
  if (!ss_dyn_check_state(m, d, why, sizeof why))
    return ss_error_set(err, SS_ERR_VALUE, path, 0, "cannot export: %s", why);
  for (int s = 0; s < m->nsys; s++) {
    if (!d->sys_active[s]) continue;
    if (m->sys_type[s] == SS_SYS_ARTICULATED) continue;
    if (m->sys_nbody[s] != 1)
      return ss_error_set(err, SS_ERR_UNSUPPORTED, path, 0,
                          "cannot export '%s': a single body must have one "
                          "body", m->sys_name[s]);
    int b = m->sys_bodyadr[s], ng = 0;
    for (int g = 0; g < m->ngeom; g++)
      if (m->geom_body[g] == b) {
        ng++;
        if (m->geom_type[g] < SS_GEOM_BOX || m->geom_type[g] > SS_GEOM_MESH ||
            (m->geom_type[g] == SS_GEOM_MESH &&
             (m->geom_mesh[g] < 0 || m->geom_mesh[g] >= m->nmesh ||
              !m->mesh_path[m->geom_mesh[g]][0])))
          return ss_error_set(err, SS_ERR_UNSUPPORTED, path, 0,
                              "cannot export '%s': its collider is not a "
                              "primitive or a mesh loaded from a file",
                              m->sys_name[s]);
      }
    if (ng != 1)
      return ss_error_set(err, SS_ERR_UNSUPPORTED, path, 0,
                          "cannot export '%s': a single body needs exactly one "
                          "collider (it has %d)", m->sys_name[s], ng);
    if (!name_ok(m->sys_name[s]))
      return ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "cannot export body %d: its name has control "
                          "characters", s);
  }
  for (int p = 0; p < m->nplane; p++)
    if (!name_ok(m->plane_name[p]))
      return ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "cannot export ground %d: its name has control "
                          "characters", p);
  for (int h = 0; h < m->nhfield; h++)
    if (!name_ok(m->hfield_name[h]))
      return ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "cannot export height map %d: its name has control "
                          "characters", h);
  for (int k = 0; k < m->nmaterial; k++)
    if (!name_ok(m->material_name[k]))
      return ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "cannot export material %d: its name has control "
                          "characters", k);
  if (m->camera_given && !name_ok(m->camera_follow))
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "cannot export the camera: its follow name has "
                        "control characters");
  return SS_OK;
}

/* Writes the world into f (open), which the caller commits or aborts. */
static ssStatus export_to(const ssModel *m, const ssData *d, ssAtomicFile *f,
                          ssError *err)
{
  const char *path = f->path;
  wBuf *w = malloc(sizeof *w);
  size_t nall = (size_t)m->nplane + (size_t)m->nsys + (size_t)m->nhfield;
  wObject *order = malloc((nall + 1) * sizeof *order);
  int *renum = malloc(((size_t)m->nmaterial + 1) * sizeof *renum);
  unsigned char *used = malloc((size_t)m->nmaterial + 1);
  if (!w || !order || !renum || !used) {
    free(w);
    free(order);
    free(renum);
    free(used);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
  }
  /* <material> after <objects>, as usual, unless only before them does
   * the reloaded world number the materials as this one does */
  int pairs_first = 0;
  int nobj = object_order(m, d, 0, order, renum, used);
  if (!same_numbers(m, renum)) {
    nobj = object_order(m, d, 1, order, renum, used);
    pairs_first = same_numbers(m, renum);
    if (!pairs_first) nobj = object_order(m, d, 0, order, renum, used);
  }
  free(used);
  w->f = f;
  w->n = 0;
  /* the folder exists (the temporary file is in it), so this is its real
   * path; if even so it cannot be had, paths are written absolute */
  char dir[4096];
  ss_scene_path_dir(path, dir, sizeof dir);
  if (ss_scene_path_absolute(dir, w->dir, sizeof w->dir)) w->dir[0] = 0;

  ssCLocale loc;
  int have_loc = ss_scene_c_locale_push(&loc) == 0;
  struct lconv *lc = have_loc ? NULL : localeconv();
  if (!have_loc && (!lc || !lc->decimal_point || strcmp(lc->decimal_point, "."))) {
    free(w);
    free(order);
    free(renum);
    return ss_error_set(err, SS_ERR_STATE, path, 0,
                        "cannot switch to the C locale to write numbers");
  }
  write_world(w, m, d, order, nobj, renum, pairs_first);
  w_flush(w);
  if (have_loc) ss_scene_c_locale_pop(&loc);
  free(w);
  free(order);
  free(renum);
  return SS_OK;
}

ssStatus ss_scene_export(const ssModel *m, const ssData *d, const char *path,
                         ssError *err)
{
  if (!m || !d || !path)
    return ss_error_set(err, SS_ERR_VALUE, path ? path : "", 0,
                        "ss_scene_export: NULL argument");
  if (d->model && d->model != m)
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "ss_scene_export: the data belongs to another model");
  ssStatus st = check_exportable(m, d, path, err);
  if (st != SS_OK) return st;
  ssAtomicFile f;
  st = ss_atomic_open(&f, path, err);
  if (st != SS_OK) return st;
  st = export_to(m, d, &f, err);
  if (st != SS_OK) {
    ss_atomic_abort(&f);
    return st;
  }
  /* a failed write is reported by the commit, with its reason */
  return ss_atomic_commit(&f, err);
}

ssStatus ss_scene_export_to(const ssModel *m, const ssData *d, ssAtomicFile *f,
                            ssError *err)
{
  if (!f || !f->fp)
    return ss_error_set(err, SS_ERR_STATE, f ? f->path : "", 0,
                        "ss_scene_export_to: the output is not open");
  if (!m || !d)
    return ss_error_set(err, SS_ERR_VALUE, f->path, 0,
                        "ss_scene_export_to: NULL argument");
  if (d->model && d->model != m)
    return ss_error_set(err, SS_ERR_VALUE, f->path, 0,
                        "ss_scene_export_to: the data belongs to another model");
  ssStatus st = check_exportable(m, d, f->path, err);
  if (st != SS_OK) return st;
  return export_to(m, d, f, err);
}
