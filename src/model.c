/* model.c -- the immutable world description and its builder. */
#include "soilsim.h"
#include "collide.h"
#include "mesh.h"
#include "model_build.h"
#include "ss_math.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

/* Largest height map we accept (vertices); keeps nx*ny and byte sizes far
 * from overflow and memory in reach. */
#define SS_MAX_HFIELD_VERTICES 100000000L
/* Ground planes in one model.  With the height maps (at most
 * SS_MAX_HFIELD_VERTICES / 4 of them) they number the rigid supports of
 * the warm start's keys (solver.h, ss_rigid_feature), which must stay
 * below 2^26 - 1. */
#define SS_MAX_PLANES 1000000
_Static_assert(SS_MAX_HFIELD_VERTICES / 4 + SS_MAX_PLANES < (1L << 26) - 1,
               "rigid supports fit ss_rigid_feature's keys");

ssOption ss_option_default(void)
{
  ssOption o;
  memset(&o, 0, sizeof o);
  o.timestep = 0.001;
  o.gravity[2] = -9.81;
  o.solver_max_sweeps = 200;
  o.solver_tolerance = 1e-9;
  o.scalar_tolerance = 1e-12;
  o.terrain_warm_start = 1;
  o.contact_margin = 0.002;
  o.rigid_erp = 0.2;
  return o;
}

ssBodyDef ss_body_def_default(void)
{
  ssBodyDef d;
  memset(&d, 0, sizeof d);
  d.shape = SS_GEOM_BOX;
  d.size[0] = d.size[1] = d.size[2] = 0.1;
  d.mass = 1;
  d.quat[0] = 1;
  d.mesh_scale[0] = d.mesh_scale[1] = d.mesh_scale[2] = 1;
  return d;
}

ssHfieldDef ss_hfield_def_default(void)
{
  ssHfieldDef d;
  memset(&d, 0, sizeof d);
  d.nx = d.ny = 2;
  d.x_size = d.y_size = 1;
  d.quat[0] = 1;
  d.source = SS_HFIELD_EXPLICIT;
  d.soilmat = ss_soil_material_default();
  return d;
}

/* ---------------------------------------------------------------------- */
/* the builder's look-up tables                                            */

/* Open-addressing hash tables (linear probing, at most half full) of
 * indices into the model's own arrays, so that building n objects is
 * linear: the duplicate-name check, ss_model_material and the pair table
 * scanned every earlier object, and 20 000 bodies or <pair_prop>s took
 * seconds.  A slot holds 1 + an entry's code (0: empty); the keys stay in
 * the model (names, pairs), so the tables hold no copies.
 *
 * The tables are a cache of the arrays.  Objects are only ever appended,
 * so each table remembers the counts it has seen and enters the tail
 * before it is used; a rollback (ss_model_rollback) or counts that went
 * down behind the builder's back rebuild it from the arrays.  Look-ups on
 * a const model (ss_model_find_sys, ss_model_pair) only read a table that
 * is up to date, and otherwise scan as before: a model shared read-only
 * between threads is never written. */
typedef struct idxTab {
  int *slot;
  int cap;  /* a power of two, or 0 */
  int n;
} idxTab;

typedef struct modelIndex {
  /* names of systems, grounds and height maps (unique together): codes
   * 3 i + kind, kind 0 system, 1 ground, 2 height map */
  idxTab name;
  int nsys, nplane, nhfield;  /* entered so far */
  idxTab mat;                 /* material names: code = material index */
  int nmat;
  idxTab pair;                /* pairs by (mat1, mat2): code = pair index */
  int npair;
} modelIndex;

/* The model and its tables in one allocation (ss_model_new is the only
 * place a model is made), so that the public struct stays as it is. */
typedef struct modelBox {
  ssModel m;  /* first: a model's address is its box's */
  modelIndex ix;
} modelBox;

static modelIndex *index_of(const ssModel *m)
{
  return &((modelBox *)(uintptr_t)m)->ix;
}

static uint64_t hash_str(const char *s)
{
  uint64_t h = 1469598103934665603ULL; /* FNV-1a */
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ULL;
  return h;
}

static uint64_t hash_pair(int a, int b)
{
  uint64_t h = ((uint64_t)(unsigned)a << 32 | (unsigned)b) * 0x9E3779B97F4A7C15ULL;
  return h ^ (h >> 29);
}

/* the key of an entry, for probing and for regrowing */
static const char *name_of_code(const ssModel *m, int code)
{
  int i = code / 3;
  switch (code % 3) {
  case 0: return m->sys_name[i];
  case 1: return m->plane_name[i];
  default: return m->hfield_name[i];
  }
}

static uint64_t code_hash(const ssModel *m, const idxTab *t, const modelIndex *ix,
                          int code)
{
  if (t == &ix->name) return hash_str(name_of_code(m, code));
  if (t == &ix->mat) return hash_str(m->material_name[code]);
  return hash_pair(m->pair[code].mat1, m->pair[code].mat2);
}

/* The slot of the entry whose key is `name` (or the pair a, b when name
 * is NULL) in t, or the empty slot it would take. */
static int tab_slot(const ssModel *m, const idxTab *t, const modelIndex *ix,
                    uint64_t h, const char *name, int a, int b)
{
  unsigned mask = (unsigned)t->cap - 1, k = (unsigned)h & mask;
  for (; t->slot[k]; k = (k + 1) & mask) {
    int code = t->slot[k] - 1;
    if (t == &ix->pair) {
      if (m->pair[code].mat1 == a && m->pair[code].mat2 == b) break;
    } else if (!strcmp(t == &ix->name ? name_of_code(m, code)
                                      : m->material_name[code], name)) {
      break;
    }
  }
  return (int)k;
}

/* The code of the entry with this key, or -1. */
static int tab_find(const ssModel *m, const idxTab *t, const modelIndex *ix,
                    uint64_t h, const char *name, int a, int b)
{
  return t->cap ? t->slot[tab_slot(m, t, ix, h, name, a, b)] - 1 : -1;
}

/* Enter an entry (its key already in the model) unless its key is there
 * already: the first of equal keys is the one found, as a scan finds it.
 * 0, or -1 out of memory. */
static int tab_add(const ssModel *m, idxTab *t, const modelIndex *ix, int code,
                   const char *name, int a, int b)
{
  if (2 * (t->n + 1) > t->cap) {
    if (t->cap > INT_MAX / 4) return -1;
    idxTab g = {NULL, t->cap ? 2 * t->cap : 64, 0};
    g.slot = calloc((size_t)g.cap, sizeof *g.slot);
    if (!g.slot) return -1;
    for (int k = 0; k < t->cap; k++)
      if (t->slot[k]) {
        int c = t->slot[k] - 1;
        unsigned mask = (unsigned)g.cap - 1;
        unsigned s = (unsigned)code_hash(m, t, ix, c) & mask;
        while (g.slot[s]) s = (s + 1) & mask;
        g.slot[s] = t->slot[k];
      }
    g.n = t->n;
    free(t->slot);
    *t = g;
  }
  uint64_t h = name ? hash_str(name) : hash_pair(a, b);
  int k = tab_slot(m, t, ix, h, name, a, b);
  if (!t->slot[k]) {
    t->slot[k] = code + 1;
    t->n++;
  }
  return 0;
}

static void tab_clear(idxTab *t)
{
  if (t->slot) memset(t->slot, 0, (size_t)t->cap * sizeof *t->slot);
  t->n = 0;
}

static void index_free(modelIndex *ix)
{
  free(ix->name.slot);
  free(ix->mat.slot);
  free(ix->pair.slot);
}

/* 1 if the name table holds exactly the model's names */
static int names_current(const ssModel *m)
{
  const modelIndex *ix = index_of(m);
  return ix->nsys == m->nsys && ix->nplane == m->nplane && ix->nhfield == m->nhfield;
}

/* Bring the name table up to the model's arrays; 0, or -1 out of memory
 * (the table is then left for a rebuild, and callers scan). */
static int names_sync(ssModel *m)
{
  modelIndex *ix = index_of(m);
  if (ix->nsys > m->nsys || ix->nplane > m->nplane || ix->nhfield > m->nhfield) {
    tab_clear(&ix->name);
    ix->nsys = ix->nplane = ix->nhfield = 0;
  }
  int *have[3] = {&ix->nsys, &ix->nplane, &ix->nhfield};
  const int want[3] = {m->nsys, m->nplane, m->nhfield};
  for (int kind = 0; kind < 3; kind++)
    for (; *have[kind] < want[kind]; ++*have[kind]) {
      int code = 3 * *have[kind] + kind;
      if (tab_add(m, &ix->name, ix, code, name_of_code(m, code), 0, 0)) {
        tab_clear(&ix->name);
        ix->nsys = ix->nplane = ix->nhfield = 0;
        return -1;
      }
    }
  return 0;
}

static int mats_sync(ssModel *m)
{
  modelIndex *ix = index_of(m);
  if (ix->nmat > m->nmaterial) {
    tab_clear(&ix->mat);
    ix->nmat = 0;
  }
  for (; ix->nmat < m->nmaterial; ix->nmat++)
    if (tab_add(m, &ix->mat, ix, ix->nmat, m->material_name[ix->nmat], 0, 0)) {
      tab_clear(&ix->mat);
      ix->nmat = 0;
      return -1;
    }
  return 0;
}

static int pairs_sync(ssModel *m)
{
  modelIndex *ix = index_of(m);
  if (ix->npair > m->npair) {
    tab_clear(&ix->pair);
    ix->npair = 0;
  }
  for (; ix->npair < m->npair; ix->npair++) {
    const ssMaterialPair *p = &m->pair[ix->npair];
    if (tab_add(m, &ix->pair, ix, ix->npair, NULL, p->mat1, p->mat2)) {
      tab_clear(&ix->pair);
      ix->npair = 0;
      return -1;
    }
  }
  return 0;
}

ssModel *ss_model_new(void)
{
  modelBox *box = calloc(1, sizeof *box);
  if (!box) return NULL;
  ssModel *m = &box->m;
  m->opt = ss_option_default();
  m->material_default.friction = 0.8;
  m->camera_fov_deg = 45;
  if (ss_model_material(m, "default") != 0) {
    ss_model_free(m);
    return NULL;
  }
  return m;
}

static void free_names(char **names, int n)
{
  if (!names) return;
  for (int i = 0; i < n; i++) free(names[i]);
  free(names);
}

void ss_model_free(ssModel *m)
{
  if (!m) return;
  free_names(m->sys_name, m->nsys);
  free(m->sys_type); free(m->sys_qadr); free(m->sys_nq); free(m->sys_vadr);
  free(m->sys_nv); free(m->sys_bodyadr); free(m->sys_nbody); free(m->sys_line);
  free(m->sys_fixed); free_names(m->sys_source, m->nsys);
  free_names(m->sys_resdir, m->nsys);
  free(m->qpos0); free(m->qvel0);
  free_names(m->body_name, m->nbody);
  free(m->body_sys); free(m->body_mass); free(m->body_inertia);
  free(m->body_inertia_given); free(m->body_ipos); free(m->body_parent);
  free(m->body_jnttype); free_names(m->body_jntname, m->nbody);
  free(m->body_jntpos); free(m->body_jntquat); free(m->body_jntaxis);
  free(m->body_qadr); free(m->body_dofadr); free(m->body_ndof);
  free(m->body_jntdamping); free(m->body_jntstiffness); free(m->body_jntref);
  free(m->body_jntlimited); free(m->body_jntrange);
  free_names(m->eq_name, m->neq);
  free(m->eq_type); free(m->eq_sys); free(m->eq_body); free(m->eq_anchor);
  free(m->eq_data); free(m->eq_line);
  free_names(m->spring_name, m->nspring);
  free(m->spring_body); free(m->spring_anchor); free(m->spring_param);
  free(m->pd_body); free(m->pd_gain); free(m->pd_target0);
  for (int i = 0; i < m->nmesh; i++) ss_mesh_free(m->mesh[i]);
  free(m->mesh); free_names(m->mesh_path, m->nmesh); free(m->mesh_scale);
  free(m->geom_type); free(m->geom_body); free(m->geom_size); free(m->geom_pos);
  free(m->geom_quat); free(m->geom_material); free(m->geom_rgba);
  free(m->geom_group); free(m->geom_mesh);
  free_names(m->plane_name, m->nplane);
  free(m->plane_height); free(m->plane_material);
  free_names(m->hfield_name, m->nhfield);
  free(m->hfield_nx); free(m->hfield_ny); free(m->hfield_size);
  free(m->hfield_center); free(m->hfield_pos0); free(m->hfield_quat0);
  free(m->hfield_adr); free(m->hfield_material); free(m->hfield_source);
  free(m->hfield_soil); free(m->hfield_soilmat); free(m->hfield_data);
  free(m->hfield_zrange);
  free_names(m->material_name, m->nmaterial);
  free(m->pair);
  free(m->xforce_body); free(m->xforce_force); free(m->xforce_torque);
  free(m->xforce_time);
  index_free(index_of(m));
  free((modelBox *)m);
}

/* grow an array of n items of size sz to hold `need` items (doubling) */
static int grow(void **p, int *cap, int need, size_t sz)
{
  if (need <= *cap) return 0;
  int c = *cap ? *cap : 4;
  while (c < need) {
    if (c > INT_MAX / 2) return -1;
    c *= 2;
  }
  void *q = realloc(*p, (size_t)c * sz);
  if (!q) return -1;
  *p = q;
  *cap = c;
  return 0;
}

/* Grow several parallel arrays that share one capacity counter. */
#define GROW(arr, cap, need, nfield)                                          \
  grow_field((void **)&(arr), (cap), (need), sizeof(*(arr)) * (nfield))

static int grow_field(void **p, int cap, int need, size_t sz)
{
  if (need <= cap && *p) return 0;
  int c = cap < need ? need : cap;
  void *q = realloc(*p, (size_t)c * sz);
  if (!q) return -1;
  *p = q;
  return 0;
}

static char *dupstr(const char *s)
{
  size_t n = strlen(s) + 1;
  char *r = malloc(n);
  if (r) memcpy(r, s, n);
  return r;
}

static int name_taken(ssModel *m, const char *name)
{
  if (names_sync(m) == 0)
    return tab_find(m, &index_of(m)->name, index_of(m), hash_str(name), name, 0, 0) >= 0;
  /* out of memory for the table: the scan still answers */
  for (int i = 0; i < m->nsys; i++)
    if (!strcmp(m->sys_name[i], name)) return 1;
  for (int i = 0; i < m->nplane; i++)
    if (!strcmp(m->plane_name[i], name)) return 1;
  for (int i = 0; i < m->nhfield; i++)
    if (!strcmp(m->hfield_name[i], name)) return 1;
  return 0;
}

static ssStatus check_name(ssModel *m, const char *name, int line,
                           ssError *err)
{
  if (!name || !*name)
    return ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                        "an object needs a non-empty name");
  if (strlen(name) >= 120)
    return ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                        "name '%.40s...' is too long (at most 119 characters)",
                        name);
  if (name_taken(m, name))
    return ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                        "duplicate name '%s': names of bodies, systems, "
                        "grounds and height maps must be unique", name);
  return SS_OK;
}

int ss_model_material(ssModel *m, const char *name)
{
  if (!name || !*name) name = "default";
  if (mats_sync(m) == 0) {
    int i = tab_find(m, &index_of(m)->mat, index_of(m), hash_str(name), name, 0, 0);
    if (i >= 0) return i;
  } else {
    for (int i = 0; i < m->nmaterial; i++)
      if (!strcmp(m->material_name[i], name)) return i;
  }
  if (grow_field((void **)&m->material_name, m->cap_material,
                 m->nmaterial + 1, sizeof(char *)) != 0)
    return -1;
  if (m->nmaterial + 1 > m->cap_material) m->cap_material = m->nmaterial + 1;
  char *s = dupstr(name);
  if (!s) return -1;
  m->material_name[m->nmaterial] = s;
  return m->nmaterial++;
}

ssStatus ss_model_set_pair(ssModel *m, const char *name1, const char *name2,
                           double friction, double restitution,
                           double restitution_threshold, ssError *err)
{
  if (!isfinite(friction) || friction < 0)
    return ss_error_set(err, SS_ERR_VALUE, m->source_path, 0,
                        "friction %g: must be finite and >= 0", friction);
  if (!isfinite(restitution) || restitution < 0 || restitution > 1)
    return ss_error_set(err, SS_ERR_VALUE, m->source_path, 0,
                        "restitution %g: must be in [0, 1]", restitution);
  if (!isfinite(restitution_threshold) || restitution_threshold < 0)
    return ss_error_set(err, SS_ERR_VALUE, m->source_path, 0,
                        "restitution_threshold %g: must be finite and >= 0",
                        restitution_threshold);
  ssMaterialPair p = {0, 0, friction, restitution, restitution_threshold};
  if (!name1 && !name2) {
    m->material_default = p;
    return SS_OK;
  }
  int a = ss_model_material(m, name1), b = ss_model_material(m, name2);
  if (a < 0 || b < 0)
    return ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
  p.mat1 = a < b ? a : b;
  p.mat2 = a < b ? b : a;
  int i = -1;
  if (pairs_sync(m) == 0) {
    i = tab_find(m, &index_of(m)->pair, index_of(m), hash_pair(p.mat1, p.mat2),
                 NULL, p.mat1, p.mat2);
  } else {
    for (int k = 0; k < m->npair && i < 0; k++)
      if (m->pair[k].mat1 == p.mat1 && m->pair[k].mat2 == p.mat2) i = k;
  }
  if (i >= 0) {
    m->pair[i] = p;
    return SS_OK;
  }
  if (grow((void **)&m->pair, &m->cap_pair, m->npair + 1, sizeof p) != 0)
    return ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
  m->pair[m->npair++] = p;
  return SS_OK;
}

const ssMaterialPair *ss_model_pair(const ssModel *m, int mat1, int mat2)
{
  int a = mat1 < mat2 ? mat1 : mat2, b = mat1 < mat2 ? mat2 : mat1;
  /* the table when it is current and worth a hash (a step asks this for
   * every body contact); a few pairs are scanned */
  const modelIndex *ix = index_of(m);
  if (m->npair > 8 && ix->npair == m->npair) {
    int i = tab_find(m, &ix->pair, ix, hash_pair(a, b), NULL, a, b);
    return i >= 0 ? &m->pair[i] : &m->material_default;
  }
  for (int i = 0; i < m->npair; i++)
    if (m->pair[i].mat1 == a && m->pair[i].mat2 == b) return &m->pair[i];
  return &m->material_default;
}

/* Inertia about the centre of mass of a uniform solid (body frame). */
static void shape_inertia(ssGeomType t, const double s[3], double mass,
                          double I[9])
{
  memset(I, 0, 9 * sizeof(double));
  double ix = 0, iy = 0, iz = 0;
  switch (t) {
  case SS_GEOM_BOX:
    ix = mass * (s[1] * s[1] + s[2] * s[2]) / 12;
    iy = mass * (s[0] * s[0] + s[2] * s[2]) / 12;
    iz = mass * (s[0] * s[0] + s[1] * s[1]) / 12;
    break;
  case SS_GEOM_SPHERE:
    ix = iy = iz = 0.4 * mass * s[0] * s[0];
    break;
  case SS_GEOM_CYLINDER:
    iz = 0.5 * mass * s[0] * s[0];
    ix = iy = mass * (3 * s[0] * s[0] + s[1] * s[1]) / 12;
    break;
  case SS_GEOM_CAPSULE: {
    /* cylinder plus two hemispheres of the same density */
    double r = s[0], h = s[1];
    double vc = M_PI * r * r * h, vs = 4.0 / 3.0 * M_PI * r * r * r;
    double mc = mass * vc / (vc + vs), ms = mass - mc;
    iz = 0.5 * mc * r * r + 0.4 * ms * r * r;
    ix = iy = mc * (h * h / 12 + r * r / 4) +
              ms * (0.4 * r * r + h * h / 4 + 3 * h * r / 8);
    break;
  }
  case SS_GEOM_MESH:
    ix = iy = iz = 0.4 * mass * s[0] * s[0];
    break;
  }
  I[0] = ix;
  I[4] = iy;
  I[8] = iz;
}

static const double palette[][4] = {
  {0.85, 0.33, 0.10, 1}, {0.00, 0.45, 0.74, 1}, {0.47, 0.67, 0.19, 1},
  {0.49, 0.18, 0.56, 1}, {0.93, 0.69, 0.13, 1}, {0.30, 0.75, 0.93, 1},
};

static int finite_n(const double *v, int n)
{
  for (int i = 0; i < n; i++)
    if (!isfinite(v[i])) return 0;
  return 1;
}

/* realloc *p to n items of size sz (n >= 1) */
static int re(void **p, size_t n, size_t sz)
{
  void *q = realloc(*p, n * sz);
  if (!q) return -1;
  *p = q;
  return 0;
}
#define RE(p, n, k) re((void **)&(p), (size_t)(n) * (k), sizeof *(p))

static int next_cap(int cap, int need)
{
  int c = cap ? cap : 8;
  while (c < need) c *= 2;
  return c;
}

static int reserve_sys(ssModel *m, int n)
{
  if (n <= m->cap_sys) return 0;
  int c = next_cap(m->cap_sys, n);
  if (RE(m->sys_name, c, 1) || RE(m->sys_type, c, 1) || RE(m->sys_qadr, c, 1) ||
      RE(m->sys_nq, c, 1) || RE(m->sys_vadr, c, 1) || RE(m->sys_nv, c, 1) ||
      RE(m->sys_bodyadr, c, 1) || RE(m->sys_nbody, c, 1) || RE(m->sys_line, c, 1) ||
      RE(m->sys_fixed, c, 1) || RE(m->sys_source, c, 1) || RE(m->sys_resdir, c, 1))
    return -1;
  m->cap_sys = c;
  return 0;
}

static int reserve_body(ssModel *m, int n)
{
  if (n <= m->cap_body) return 0;
  int c = next_cap(m->cap_body, n);
  if (RE(m->body_name, c, 1) || RE(m->body_sys, c, 1) || RE(m->body_mass, c, 1) ||
      RE(m->body_inertia, c, 9) || RE(m->body_inertia_given, c, 1) ||
      RE(m->body_ipos, c, 3) || RE(m->body_parent, c, 1) ||
      RE(m->body_jnttype, c, 1) || RE(m->body_jntname, c, 1) ||
      RE(m->body_jntpos, c, 3) || RE(m->body_jntquat, c, 4) ||
      RE(m->body_jntaxis, c, 3) || RE(m->body_qadr, c, 1) ||
      RE(m->body_dofadr, c, 1) || RE(m->body_ndof, c, 1) ||
      RE(m->body_jntdamping, c, 1) || RE(m->body_jntstiffness, c, 1) ||
      RE(m->body_jntref, c, 1) || RE(m->body_jntlimited, c, 1) ||
      RE(m->body_jntrange, c, 2))
    return -1;
  m->cap_body = c;
  return 0;
}

static int reserve_geom(ssModel *m, int n)
{
  if (n <= m->cap_geom) return 0;
  int c = next_cap(m->cap_geom, n);
  if (RE(m->geom_type, c, 1) || RE(m->geom_body, c, 1) || RE(m->geom_size, c, 3) ||
      RE(m->geom_pos, c, 3) || RE(m->geom_quat, c, 4) || RE(m->geom_material, c, 1) ||
      RE(m->geom_rgba, c, 4) || RE(m->geom_group, c, 1) || RE(m->geom_mesh, c, 1))
    return -1;
  m->cap_geom = c;
  return 0;
}

int ss_model_push_sys(ssModel *m, const char *name, int type, int nq, int nv,
                      int line, ssError *err)
{
  if (check_name(m, name, line, err) != SS_OK) return -1;
  int s = m->nsys;
  if (reserve_sys(m, s + 1)) goto nomem;
  if (m->nq + nq > m->cap_q) {
    int c = next_cap(m->cap_q, m->nq + nq);
    if (RE(m->qpos0, c, 1)) goto nomem;
    m->cap_q = c;
  }
  if (m->nv + nv > m->cap_v) {
    int c = next_cap(m->cap_v, m->nv + nv);
    if (RE(m->qvel0, c, 1)) goto nomem;
    m->cap_v = c;
  }
  char *n1 = dupstr(name), *n2 = dupstr(""), *n3 = dupstr("");
  if (!n1 || !n2 || !n3) {
    free(n1); free(n2); free(n3);
    goto nomem;
  }
  m->sys_name[s] = n1;
  m->sys_source[s] = n2;
  m->sys_resdir[s] = n3;
  m->sys_type[s] = type;
  m->sys_qadr[s] = m->nq;
  m->sys_nq[s] = nq;
  m->sys_vadr[s] = m->nv;
  m->sys_nv[s] = nv;
  m->sys_bodyadr[s] = m->nbody;
  m->sys_nbody[s] = 0;
  m->sys_line[s] = line;
  m->sys_fixed[s] = 0;
  /* a system without coordinates (all links fixed) may leave the arrays
   * unallocated: NULL + 0 is undefined, so touch them only when needed */
  if (nq) memset(m->qpos0 + m->nq, 0, (size_t)nq * sizeof(double));
  if (nv) memset(m->qvel0 + m->nv, 0, (size_t)nv * sizeof(double));
  m->nq += nq;
  m->nv += nv;
  return m->nsys++;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, m->source_path, line, "out of memory");
  return -1;
}

int ss_model_push_body(ssModel *m, int sys, const char *name,
                       const char *jntname, int parent, ssError *err)
{
  int b = m->nbody;
  if (reserve_body(m, b + 1)) goto nomem;
  char *n1 = dupstr(name), *n2 = dupstr(jntname ? jntname : "");
  if (!n1 || !n2) {
    free(n1); free(n2);
    goto nomem;
  }
  m->body_name[b] = n1;
  m->body_jntname[b] = n2;
  m->body_sys[b] = sys;
  m->body_mass[b] = 0;
  memset(m->body_inertia + 9 * b, 0, 9 * sizeof(double));
  m->body_inertia_given[b] = 0;
  memset(m->body_ipos + 3 * b, 0, 3 * sizeof(double));
  m->body_parent[b] = parent;
  m->body_jnttype[b] = SS_JOINT_FIXED;
  memset(m->body_jntpos + 3 * b, 0, 3 * sizeof(double));
  ss_quat_identity(m->body_jntquat + 4 * b);
  memset(m->body_jntaxis + 3 * b, 0, 3 * sizeof(double));
  m->body_qadr[b] = -1;
  m->body_dofadr[b] = -1;
  m->body_ndof[b] = 0;
  m->body_jntdamping[b] = m->body_jntstiffness[b] = m->body_jntref[b] = 0;
  m->body_jntlimited[b] = 0;
  m->body_jntrange[2 * b] = m->body_jntrange[2 * b + 1] = 0;
  m->sys_nbody[sys]++;
  return m->nbody++;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
  return -1;
}

int ss_model_push_geom(ssModel *m, int body, int type, const double size[3],
                       const double pos[3], const double quat[4], int material,
                       const double rgba[4], int group, int mesh, ssError *err)
{
  int g = m->ngeom;
  if (reserve_geom(m, g + 1)) {
    ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
    return -1;
  }
  m->geom_type[g] = type;
  m->geom_body[g] = body;
  memcpy(m->geom_size + 3 * g, size, 3 * sizeof(double));
  memcpy(m->geom_pos + 3 * g, pos, 3 * sizeof(double));
  memcpy(m->geom_quat + 4 * g, quat, 4 * sizeof(double));
  ss_quat_normalize(m->geom_quat + 4 * g);
  m->geom_material[g] = material;
  if (rgba && rgba[3] > 0)
    memcpy(m->geom_rgba + 4 * g, rgba, 4 * sizeof(double));
  else
    memcpy(m->geom_rgba + 4 * g, palette[m->body_sys[body] % 6], 4 * sizeof(double));
  m->geom_group[g] = group;
  m->geom_mesh[g] = mesh;
  return m->ngeom++;
}

int ss_model_push_mesh(ssModel *m, struct ssMesh *mesh, const char *path,
                       ssError *err)
{
  int k = m->nmesh;
  if (k + 1 > m->cap_mesh) {
    int c = next_cap(m->cap_mesh, k + 1);
    if (RE(m->mesh, c, 1) || RE(m->mesh_path, c, 1) || RE(m->mesh_scale, c, 3))
      goto nomem;
    m->cap_mesh = c;
  }
  char *p = dupstr(path ? path : "");
  if (!p) goto nomem;
  m->mesh[k] = mesh;
  m->mesh_path[k] = p;
  /* the caller that loaded it scaled sets the scale it baked in */
  for (int a = 0; a < 3; a++) m->mesh_scale[3 * k + a] = 1;
  return m->nmesh++;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
  return -1;
}

int ss_model_push_eq(ssModel *m, const char *name, int type, int sys,
                     int body1, int body2, const double anchor[6],
                     const double data[2], int line, ssError *err)
{
  int k = m->neq;
  if (k + 1 > m->cap_eq) {
    int c = next_cap(m->cap_eq, k + 1);
    if (RE(m->eq_name, c, 1) || RE(m->eq_type, c, 1) || RE(m->eq_sys, c, 1) ||
        RE(m->eq_body, c, 2) || RE(m->eq_anchor, c, 6) || RE(m->eq_data, c, 2) ||
        RE(m->eq_line, c, 1))
      goto nomem;
    m->cap_eq = c;
  }
  if (!(m->eq_name[k] = dupstr(name ? name : ""))) goto nomem;
  m->eq_type[k] = type;
  m->eq_sys[k] = sys;
  m->eq_body[2 * k] = body1;
  m->eq_body[2 * k + 1] = body2;
  memcpy(m->eq_anchor + 6 * k, anchor, 6 * sizeof(double));
  memcpy(m->eq_data + 2 * k, data, 2 * sizeof(double));
  m->eq_line[k] = line;
  return m->neq++;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, m->source_path, line, "out of memory");
  return -1;
}

int ss_model_push_spring(ssModel *m, const char *name, int body1, int body2,
                         const double anchor[6], const double param[3],
                         ssError *err)
{
  int k = m->nspring;
  if (k + 1 > m->cap_spring) {
    int c = next_cap(m->cap_spring, k + 1);
    if (RE(m->spring_name, c, 1) || RE(m->spring_body, c, 2) ||
        RE(m->spring_anchor, c, 6) || RE(m->spring_param, c, 3))
      goto nomem;
    m->cap_spring = c;
  }
  if (!(m->spring_name[k] = dupstr(name ? name : ""))) goto nomem;
  m->spring_body[2 * k] = body1;
  m->spring_body[2 * k + 1] = body2;
  memcpy(m->spring_anchor + 6 * k, anchor, 6 * sizeof(double));
  memcpy(m->spring_param + 3 * k, param, 3 * sizeof(double));
  return m->nspring++;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
  return -1;
}

int ss_model_push_pd(ssModel *m, int body, const double gain[3],
                     const double target[2], ssError *err)
{
  int k = m->npd;
  if (k + 1 > m->cap_pd) {
    int c = next_cap(m->cap_pd, k + 1);
    if (RE(m->pd_body, c, 1) || RE(m->pd_gain, c, 3) || RE(m->pd_target0, c, 2)) {
      ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
      return -1;
    }
    m->cap_pd = c;
  }
  m->pd_body[k] = body;
  memcpy(m->pd_gain + 3 * k, gain, 3 * sizeof(double));
  memcpy(m->pd_target0 + 2 * k, target, 2 * sizeof(double));
  return m->npd++;
}

ssModelMark ss_model_mark(const ssModel *m)
{
  ssModelMark k = {m->nsys, m->nbody, m->ngeom, m->nq, m->nv, m->neq,
                   m->nspring, m->npd, m->nmesh};
  return k;
}

void ss_model_rollback(ssModel *m, const ssModelMark *k)
{
  for (int i = k->nsys; i < m->nsys; i++) {
    free(m->sys_name[i]);
    free(m->sys_source[i]);
    free(m->sys_resdir[i]);
  }
  for (int i = k->nbody; i < m->nbody; i++) {
    free(m->body_name[i]);
    free(m->body_jntname[i]);
  }
  for (int i = k->neq; i < m->neq; i++) free(m->eq_name[i]);
  for (int i = k->nspring; i < m->nspring; i++) free(m->spring_name[i]);
  for (int i = k->nmesh; i < m->nmesh; i++) {
    ss_mesh_free(m->mesh[i]);
    free(m->mesh_path[i]);
  }
  /* names may come back under other indices: the table is rebuilt */
  if (m->nsys != k->nsys) {
    modelIndex *ix = index_of(m);
    tab_clear(&ix->name);
    ix->nsys = ix->nplane = ix->nhfield = 0;
  }
  m->nsys = k->nsys;
  m->nbody = k->nbody;
  m->ngeom = k->ngeom;
  m->nq = k->nq;
  m->nv = k->nv;
  m->neq = k->neq;
  m->nspring = k->nspring;
  m->npd = k->npd;
  m->nmesh = k->nmesh;
}

/* (soilsim.h) here, not in render.c: the scene reader asks it too, and a
 * program that never renders must link without GL */
int ss_camera_valid(const double pos[3], const double look_at[3])
{
  double dd[3];
  ss_v3_sub(dd, look_at, pos);
  double n = ss_v3_norm(dd);
  return n > 1e-9 && isfinite(n);
}

int ss_model_add_body(ssModel *m, const ssBodyDef *def, ssError *err)
{
  const char *f = m->source_path;
  if (check_name(m, def->name, def->line, err) != SS_OK) return -1;
  static const char *shape_names[] = {"box", "sphere", "cylinder", "capsule",
                                      "mesh"};
  if (def->shape < SS_GEOM_BOX || def->shape > SS_GEOM_MESH) {
    ss_error_set(err, SS_ERR_UNSUPPORTED, f, def->line,
                 "body '%s': shape %d is not supported for single bodies "
                 "(box, sphere, cylinder, capsule, mesh)", def->name,
                 (int)def->shape);
    return -1;
  }
  const int is_mesh = def->shape == SS_GEOM_MESH;
  /* a mesh's size is its file's: def->size is not used */
  int nsize = is_mesh ? 0
              : def->shape == SS_GEOM_BOX ? 3
              : def->shape == SS_GEOM_SPHERE ? 1 : 2;
  for (int k = 0; k < nsize; k++)
    if (!isfinite(def->size[k]) || def->size[k] <= 0) {
      ss_error_set(err, SS_ERR_VALUE, f, def->line,
                   "%s '%s': dimension %d is %g; dimensions must be finite "
                   "and > 0", shape_names[def->shape], def->name, k,
                   def->size[k]);
      return -1;
    }
  if (!def->is_static && (!isfinite(def->mass) || def->mass <= 0)) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "body '%s': mass %g; a dynamic body needs a finite mass > 0",
                 def->name, def->mass);
    return -1;
  }
  if (!finite_n(def->pos, 3) || !finite_n(def->quat, 4) ||
      !finite_n(def->lin_vel, 3) || !finite_n(def->ang_vel, 3)) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "body '%s': state values must be finite", def->name);
    return -1;
  }
  if (!ss_all_within(def->lin_vel, 3, SS_SPEED_MAX) ||
      !ss_all_within(def->ang_vel, 3, SS_SPEED_MAX)) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "body '%s': lin_vel %g %g %g, ang_vel %g %g %g; each "
                 "component must be at most 1e5 in magnitude (m/s, rad/s), the "
                 "largest speed a step accepts", def->name, def->lin_vel[0],
                 def->lin_vel[1], def->lin_vel[2], def->ang_vel[0],
                 def->ang_vel[1], def->ang_vel[2]);
    return -1;
  }
  double qn = sqrt(def->quat[0] * def->quat[0] + def->quat[1] * def->quat[1] +
                   def->quat[2] * def->quat[2] + def->quat[3] * def->quat[3]);
  if (qn < 1e-9) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "body '%s': quaternion has zero length", def->name);
    return -1;
  }
  if (is_mesh && (!def->mesh_path || !def->mesh_path[0])) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "mesh '%s': no mesh file given", def->name);
    return -1;
  }
  for (int k = 0; is_mesh && k < 3; k++)
    if (!isfinite(def->mesh_scale[k]) || def->mesh_scale[k] == 0) {
      ss_error_set(err, SS_ERR_VALUE, f, def->line,
                   "mesh '%s': scale value %d is %g; mesh scales must be finite "
                   "and non-zero", def->name, k + 1, def->mesh_scale[k]);
      return -1;
    }
  /* a mesh: loaded first (its failures are the likeliest), its solid's
   * mass properties at uniform density give the body frame's origin (the
   * centroid) and, unless given, the inertia */
  ssMesh *mesh = NULL;
  double centroid[3] = {0, 0, 0}, Imesh[9];
  int solid = 0;
  if (is_mesh) {
    ssError me;
    if (ss_mesh_load(def->mesh_path, def->mesh_scale, &mesh, &me) != SS_OK) {
      ss_error_set(err, me.code, f, def->line, "mesh '%s': %s: %s", def->name,
                   def->mesh_path, me.message);
      return -1;
    }
    int closed = ss_mesh_closed(mesh);
    if (closed < 0) {
      ss_mesh_free(mesh);
      ss_error_set(err, SS_ERR_NOMEM, f, def->line, "out of memory");
      return -1;
    }
    double V = 0, L = 0;
    ss_mesh_mass_properties(mesh, &V, centroid, Imesh);
    for (int k = 0; k < 3; k++)
      if (mesh->hi[k] - mesh->lo[k] > L) L = mesh->hi[k] - mesh->lo[k];
    /* flat: a volume that is rounding next to its extent's cube */
    solid = closed && V > 1e-9 * L * L * L;
    if (solid) {
      double scl = (def->is_static ? 1 : def->mass) / V;
      for (int k = 0; k < 9; k++) Imesh[k] *= scl;
    } else {
      if (!def->inertia_given && !def->is_static) {
        ss_error_set(err, SS_ERR_VALUE, f, def->line,
                     "mesh '%s': %s encloses no volume (it is %s), so its "
                     "inertia cannot be computed: give it an <inertia>",
                     def->name, def->mesh_path, closed ? "flat" : "open");
        ss_mesh_free(mesh);
        return -1;
      }
      /* a shell: its body frame at the surface's centroid (a static one's
       * inertia is never used: its bounding box's stands in) */
      ss_mesh_surface_centroid(mesh, centroid);
      double box[3];
      for (int k = 0; k < 3; k++) box[k] = mesh->hi[k] - mesh->lo[k];
      shape_inertia(SS_GEOM_BOX, box, 1, Imesh);
    }
  }
  double I[9];
  if (def->inertia_given) {
    const double *v = def->inertia;
    double t[9] = {v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5]};
    memcpy(I, t, sizeof I);
    /* positive definite: leading minors > 0 */
    double m1 = I[0], m2 = I[0] * I[4] - I[1] * I[3];
    double Iinv[9];
    double det = ss_m3_inv(Iinv, I);
    if (!finite_n(v, 6) || !(m1 > 0) || !(m2 > 0) || !(det > 0)) {
      ss_error_set(err, SS_ERR_VALUE, f, def->line,
                   "body '%s': inertia must be symmetric positive definite",
                   def->name);
      ss_mesh_free(mesh);
      return -1;
    }
  } else if (is_mesh) {
    memcpy(I, Imesh, sizeof I);
  } else {
    shape_inertia(def->shape, def->size, def->is_static ? 1 : def->mass, I);
  }
  int mat = ss_model_material(m, def->material);
  if (mat < 0) {
    ss_error_set(err, SS_ERR_NOMEM, f, def->line, "out of memory");
    ss_mesh_free(mesh);
    return -1;
  }
  int nv = def->is_static ? 0 : 6;
  ssModelMark mark = ss_model_mark(m);
  int s = ss_model_push_sys(m, def->name, def->is_static ? SS_SYS_STATIC : SS_SYS_FREE,
                            7, nv, def->line, err);
  if (s < 0) {
    ss_mesh_free(mesh);
    return -1;
  }
  int b = ss_model_push_body(m, s, def->name, "", -1, err);
  if (b < 0) {
    ss_mesh_free(mesh);
    ss_model_rollback(m, &mark);
    return -1;
  }
  m->body_mass[b] = def->is_static ? 0 : def->mass;
  memcpy(m->body_inertia + 9 * b, I, sizeof I);
  m->body_inertia_given[b] = def->inertia_given;
  m->body_jnttype[b] = def->is_static ? SS_JOINT_FIXED : SS_JOINT_FLOATING;
  m->body_qadr[b] = m->sys_qadr[s];
  m->body_dofadr[b] = nv ? m->sys_vadr[s] : -1;
  m->body_ndof[b] = nv;
  double size[3] = {def->size[0], def->shape == SS_GEOM_SPHERE ? 0 : def->size[1],
                    def->shape == SS_GEOM_BOX ? def->size[2] : 0};
  double gpos[3] = {0, 0, 0}, ident[4] = {1, 0, 0, 0};
  int k = -1;
  if (is_mesh) {
    /* the geom frame is the file's, at -centroid in the body frame, so
     * that the body's origin (its state's pos) is the centre of mass;
     * its size is the bounding box's, as a URDF link's mesh */
    k = ss_model_push_mesh(m, mesh, def->mesh_path, err);
    if (k < 0) {
      ss_mesh_free(mesh);
      ss_model_rollback(m, &mark);
      return -1;
    }
    memcpy(m->mesh_scale + 3 * k, def->mesh_scale, 3 * sizeof(double));
    for (int a = 0; a < 3; a++) {
      size[a] = mesh->hi[a] - mesh->lo[a];
      gpos[a] = -centroid[a];
    }
  }
  if (ss_model_push_geom(m, b, def->shape, size, gpos, ident, mat, def->rgba, 3,
                         k, err) < 0) {
    ss_model_rollback(m, &mark);
    return -1;
  }
  double *q = m->qpos0 + m->sys_qadr[s];
  memcpy(q, def->pos, 3 * sizeof(double));
  memcpy(q + 3, def->quat, 4 * sizeof(double));
  ss_quat_normalize(q + 3);
  if (nv) {
    memcpy(m->qvel0 + m->sys_vadr[s], def->lin_vel, 3 * sizeof(double));
    memcpy(m->qvel0 + m->sys_vadr[s] + 3, def->ang_vel, 3 * sizeof(double));
  }
  return s;
}

int ss_model_add_plane(ssModel *m, const char *name, double height,
                       const char *material, int line, ssError *err)
{
  if (m->nplane >= SS_MAX_PLANES) {
    ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                 "ground '%s': at most %d ground planes", name ? name : "", SS_MAX_PLANES);
    return -1;
  }
  if (check_name(m, name, line, err) != SS_OK) return -1;
  if (!isfinite(height)) {
    ss_error_set(err, SS_ERR_VALUE, m->source_path, line,
                 "ground '%s': height must be finite", name);
    return -1;
  }
  int mat = ss_model_material(m, material);
  int p = m->nplane;
  if (mat < 0 || GROW(m->plane_name, m->cap_plane, p + 1, 1) ||
      GROW(m->plane_height, m->cap_plane, p + 1, 1) ||
      GROW(m->plane_material, m->cap_plane, p + 1, 1)) {
    ss_error_set(err, SS_ERR_NOMEM, m->source_path, line, "out of memory");
    return -1;
  }
  if (m->cap_plane < p + 1) m->cap_plane = p + 1;
  if (!(m->plane_name[p] = dupstr(name))) {
    ss_error_set(err, SS_ERR_NOMEM, m->source_path, line, "out of memory");
    return -1;
  }
  m->plane_height[p] = height;
  m->plane_material[p] = mat;
  return m->nplane++;
}

int ss_model_add_hfield(ssModel *m, const ssHfieldDef *def, ssError *err)
{
  const char *f = m->source_path;
  if (check_name(m, def->name, def->line, err) != SS_OK) return -1;
  if (def->nx < 2 || def->ny < 2 ||
      (long)def->nx * (long)def->ny > SS_MAX_HFIELD_VERTICES ||
      (long)m->nhfielddata + (long)def->nx * def->ny > SS_MAX_HFIELD_VERTICES) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "heightmap '%s': %d x %d samples; each count must be >= 2 and "
                 "all height maps together at most %ld vertices",
                 def->name, def->nx, def->ny, SS_MAX_HFIELD_VERTICES);
    return -1;
  }
  if (!isfinite(def->x_size) || def->x_size <= 0 || !isfinite(def->y_size) ||
      def->y_size <= 0) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "heightmap '%s': x_size %g, y_size %g; sizes must be finite "
                 "and > 0", def->name, def->x_size, def->y_size);
    return -1;
  }
  if (!isfinite(def->center_x) || !isfinite(def->center_y) ||
      !finite_n(def->pos, 3) || !finite_n(def->quat, 4)) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "heightmap '%s': centre and pose must be finite", def->name);
    return -1;
  }
  int n = def->nx * def->ny;
  for (int k = 0; k < n; k++)
    if (!isfinite(def->height[k])) {
      ss_error_set(err, SS_ERR_VALUE, f, def->line,
                   "heightmap '%s': height[%d] is not finite", def->name, k);
      return -1;
    }
  if (def->soil) {
    ssError e2;
    if (ss_soil_material_validate(&def->soilmat, &e2) != SS_OK) {
      ss_error_set(err, SS_ERR_VALUE, f, def->line, "heightmap '%s': %s",
                   def->name, e2.message);
      return -1;
    }
  }
  int mat = ss_model_material(m, def->material);
  int h = m->nhfield;
  if (mat < 0 || GROW(m->hfield_name, m->cap_hfield, h + 1, 1) ||
      GROW(m->hfield_nx, m->cap_hfield, h + 1, 1) || GROW(m->hfield_ny, m->cap_hfield, h + 1, 1) ||
      GROW(m->hfield_size, m->cap_hfield, h + 1, 2) || GROW(m->hfield_center, m->cap_hfield, h + 1, 2) ||
      GROW(m->hfield_pos0, m->cap_hfield, h + 1, 3) || GROW(m->hfield_quat0, m->cap_hfield, h + 1, 4) ||
      GROW(m->hfield_adr, m->cap_hfield, h + 1, 1) || GROW(m->hfield_material, m->cap_hfield, h + 1, 1) ||
      GROW(m->hfield_source, m->cap_hfield, h + 1, 1) || GROW(m->hfield_soil, m->cap_hfield, h + 1, 1) ||
      GROW(m->hfield_soilmat, m->cap_hfield, h + 1, 1) ||
      GROW(m->hfield_zrange, m->cap_hfield, h + 1, 2) ||
      GROW(m->hfield_data, m->cap_hfielddata, m->nhfielddata + n, 1))
    goto nomem;
  if (m->cap_hfield < h + 1) m->cap_hfield = h + 1;
  if (m->cap_hfielddata < m->nhfielddata + n) m->cap_hfielddata = m->nhfielddata + n;
  if (!(m->hfield_name[h] = dupstr(def->name))) goto nomem;
  m->hfield_nx[h] = def->nx;
  m->hfield_ny[h] = def->ny;
  m->hfield_size[2 * h] = def->x_size;
  m->hfield_size[2 * h + 1] = def->y_size;
  m->hfield_center[2 * h] = def->center_x;
  m->hfield_center[2 * h + 1] = def->center_y;
  memcpy(m->hfield_pos0 + 3 * h, def->pos, 3 * sizeof(double));
  memcpy(m->hfield_quat0 + 4 * h, def->quat, 4 * sizeof(double));
  ss_quat_normalize(m->hfield_quat0 + 4 * h);
  m->hfield_adr[h] = m->nhfielddata;
  m->hfield_material[h] = mat;
  m->hfield_source[h] = def->source;
  m->hfield_soil[h] = def->soil ? 1 : 0;
  m->hfield_soilmat[h] = def->soil ? def->soilmat : ss_soil_material_default();
  memcpy(m->hfield_data + m->nhfielddata, def->height, (size_t)n * sizeof(double));
  ss_hfield_update_range(m, h);
  m->nhfielddata += n;
  return m->nhfield++;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, f, def->line, "out of memory");
  return -1;
}

void ss_hfield_update_range(ssModel *m, int h)
{
  const double *z = m->hfield_data + m->hfield_adr[h];
  int n = m->hfield_nx[h] * m->hfield_ny[h];
  double lo = z[0], hi = z[0];
  for (int k = 1; k < n; k++) {
    if (z[k] < lo) lo = z[k];
    if (z[k] > hi) hi = z[k];
  }
  m->hfield_zrange[2 * h] = lo;
  m->hfield_zrange[2 * h + 1] = hi;
}

int ss_model_add_xforce(ssModel *m, int body, const double force[3],
                        const double torque[3], double start, double end,
                        ssError *err)
{
  if (body < 0 || body >= m->nbody) {
    ss_error_set(err, SS_ERR_NOTFOUND, m->source_path, 0,
                 "external force on a missing body");
    return -1;
  }
  if (!finite_n(force, 3) || !finite_n(torque, 3) || isnan(start) ||
      isnan(end) || start > end) {
    ss_error_set(err, SS_ERR_VALUE, m->source_path, 0,
                 "external force on '%s': force and torque must be finite and "
                 "start <= end", m->body_name[body]);
    return -1;
  }
  int k = m->nxforce;
  if (GROW(m->xforce_body, m->cap_xforce, k + 1, 1) ||
      GROW(m->xforce_force, m->cap_xforce, k + 1, 3) ||
      GROW(m->xforce_torque, m->cap_xforce, k + 1, 3) ||
      GROW(m->xforce_time, m->cap_xforce, k + 1, 2)) {
    ss_error_set(err, SS_ERR_NOMEM, m->source_path, 0, "out of memory");
    return -1;
  }
  if (m->cap_xforce < k + 1) m->cap_xforce = k + 1;
  m->xforce_body[k] = body;
  memcpy(m->xforce_force + 3 * k, force, 3 * sizeof(double));
  memcpy(m->xforce_torque + 3 * k, torque, 3 * sizeof(double));
  m->xforce_time[2 * k] = start;
  m->xforce_time[2 * k + 1] = end;
  return m->nxforce++;
}

int ss_model_find_sys(const ssModel *m, const char *name)
{
  /* names are unique across systems, grounds and height maps: the one
   * entry of this name is the system or none is */
  if (names_current(m)) {
    const modelIndex *ix = index_of(m);
    int code = tab_find(m, &ix->name, ix, hash_str(name), name, 0, 0);
    return code >= 0 && code % 3 == 0 ? code / 3 : -1;
  }
  for (int i = 0; i < m->nsys; i++)
    if (!strcmp(m->sys_name[i], name)) return i;
  return -1;
}

int ss_model_find_hfield(const ssModel *m, const char *name)
{
  for (int i = 0; i < m->nhfield; i++)
    if (!strcmp(m->hfield_name[i], name)) return i;
  return -1;
}

ssStatus ss_model_validate(const ssModel *m, ssError *err)
{
  const ssOption *o = &m->opt;
  const char *f = m->source_path;
  if (!isfinite(o->timestep) || o->timestep <= 0 || o->timestep > 1)
    return ss_error_set(err, SS_ERR_VALUE, f, 0,
                        "time step %g: must be in (0, 1] s", o->timestep);
  if (!finite_n(o->gravity, 3))
    return ss_error_set(err, SS_ERR_VALUE, f, 0, "gravity must be finite");
  if (o->solver_max_sweeps < 1 || o->solver_max_sweeps > 1000000)
    return ss_error_set(err, SS_ERR_VALUE, f, 0,
                        "max_sweeps %d: must be in [1, 1000000]",
                        o->solver_max_sweeps);
  if (!isfinite(o->solver_tolerance) || o->solver_tolerance <= 0 ||
      o->solver_tolerance >= 1)
    return ss_error_set(err, SS_ERR_VALUE, f, 0,
                        "tolerance %g: must be in (0, 1)", o->solver_tolerance);
  if (!isfinite(o->scalar_tolerance) || o->scalar_tolerance <= 0 ||
      o->scalar_tolerance >= 1)
    return ss_error_set(err, SS_ERR_VALUE, f, 0,
                        "scalar_tolerance %g: must be in (0, 1)",
                        o->scalar_tolerance);
  if (!isfinite(o->contact_margin) || o->contact_margin < 0)
    return ss_error_set(err, SS_ERR_VALUE, f, 0,
                        "contact_margin %g: must be finite and >= 0",
                        o->contact_margin);
  if (!isfinite(o->rigid_erp) || o->rigid_erp < 0 || o->rigid_erp > 1)
    return ss_error_set(err, SS_ERR_VALUE, f, 0,
                        "rigid_erp %g: must be in [0, 1]", o->rigid_erp);
  return ss_model_validate_soil(m, err);
}

ssStatus ss_model_validate_soil(const ssModel *m, ssError *err)
{
  for (int h = 0; h < m->nhfield; h++)
    if (m->hfield_soil[h]) {
      ssError e2;
      if (ss_soil_material_validate(&m->hfield_soilmat[h], &e2) != SS_OK)
        return ss_error_set(err, SS_ERR_VALUE, m->source_path, 0,
                            "heightmap '%s': %s", m->hfield_name[h], e2.message);
    }
  return SS_OK;
}

double ss_geom_width(const ssModel *m, int geom, const double xmat[9],
                     const double n_bed[3])
{
  ssShape s;
  memset(&s, 0, sizeof s);
  /* a mesh: its bounding box's rule (DESIGN 2.4), as the soil contacts
   * take it; its size is that box's edge lengths (ss_shape_width knows
   * no mesh and gave 0) */
  s.type = m->geom_type[geom] == SS_GEOM_MESH ? SS_GEOM_BOX : m->geom_type[geom];
  memcpy(s.size, m->geom_size + 3 * geom, 3 * sizeof(double));
  memcpy(s.R, xmat, 9 * sizeof(double));
  return ss_shape_width(&s, n_bed);
}
