/* model.c -- the immutable world description and its builder. */
#include "soilsim.h"
#include "collide.h"
#include "ss_math.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

/* Largest height map we accept (vertices); keeps nx*ny and byte sizes far
 * from overflow and memory in reach. */
#define SS_MAX_HFIELD_VERTICES 100000000L

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
  o.contact_margin = 0.01;
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

ssModel *ss_model_new(void)
{
  ssModel *m = calloc(1, sizeof *m);
  if (!m) return NULL;
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
  free(m->qpos0); free(m->qvel0);
  free_names(m->body_name, m->nbody);
  free(m->body_sys); free(m->body_mass); free(m->body_inertia);
  free(m->body_inertia_given);
  free(m->geom_type); free(m->geom_body); free(m->geom_size); free(m->geom_pos);
  free(m->geom_quat); free(m->geom_material); free(m->geom_rgba);
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
  free(m);
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

static int name_taken(const ssModel *m, const char *name)
{
  for (int i = 0; i < m->nsys; i++)
    if (!strcmp(m->sys_name[i], name)) return 1;
  for (int i = 0; i < m->nplane; i++)
    if (!strcmp(m->plane_name[i], name)) return 1;
  for (int i = 0; i < m->nhfield; i++)
    if (!strcmp(m->hfield_name[i], name)) return 1;
  return 0;
}

static ssStatus check_name(const ssModel *m, const char *name, int line,
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
  for (int i = 0; i < m->nmaterial; i++)
    if (!strcmp(m->material_name[i], name)) return i;
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
  for (int i = 0; i < m->npair; i++)
    if (m->pair[i].mat1 == p.mat1 && m->pair[i].mat2 == p.mat2) {
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

int ss_model_add_body(ssModel *m, const ssBodyDef *def, ssError *err)
{
  const char *f = m->source_path;
  if (check_name(m, def->name, def->line, err) != SS_OK) return -1;
  static const char *shape_names[] = {"box", "sphere", "cylinder", "capsule",
                                      "mesh"};
  if (def->shape < SS_GEOM_BOX || def->shape > SS_GEOM_CAPSULE) {
    ss_error_set(err, SS_ERR_UNSUPPORTED, f, def->line,
                 "body '%s': shape %d is not supported for single bodies "
                 "(box, sphere, cylinder, capsule)", def->name, (int)def->shape);
    return -1;
  }
  int nsize = def->shape == SS_GEOM_BOX ? 3 : def->shape == SS_GEOM_SPHERE ? 1 : 2;
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
  double qn = sqrt(def->quat[0] * def->quat[0] + def->quat[1] * def->quat[1] +
                   def->quat[2] * def->quat[2] + def->quat[3] * def->quat[3]);
  if (qn < 1e-9) {
    ss_error_set(err, SS_ERR_VALUE, f, def->line,
                 "body '%s': quaternion has zero length", def->name);
    return -1;
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
      return -1;
    }
  } else {
    shape_inertia(def->shape, def->size, def->is_static ? 1 : def->mass, I);
  }
  int mat = ss_model_material(m, def->material);
  if (mat < 0) goto nomem;

  int s = m->nsys, b = m->nbody, g = m->ngeom;
  int nq = 7, nv = def->is_static ? 0 : 6;
  /* systems */
  if (GROW(m->sys_name, m->cap_sys, s + 1, 1) || GROW(m->sys_type, m->cap_sys, s + 1, 1) ||
      GROW(m->sys_qadr, m->cap_sys, s + 1, 1) || GROW(m->sys_nq, m->cap_sys, s + 1, 1) ||
      GROW(m->sys_vadr, m->cap_sys, s + 1, 1) || GROW(m->sys_nv, m->cap_sys, s + 1, 1) ||
      GROW(m->sys_bodyadr, m->cap_sys, s + 1, 1) || GROW(m->sys_nbody, m->cap_sys, s + 1, 1) ||
      GROW(m->sys_line, m->cap_sys, s + 1, 1))
    goto nomem;
  if (m->cap_sys < s + 1) m->cap_sys = s + 1;
  /* bodies */
  if (GROW(m->body_name, m->cap_body, b + 1, 1) || GROW(m->body_sys, m->cap_body, b + 1, 1) ||
      GROW(m->body_mass, m->cap_body, b + 1, 1) || GROW(m->body_inertia, m->cap_body, b + 1, 9) ||
      GROW(m->body_inertia_given, m->cap_body, b + 1, 1))
    goto nomem;
  if (m->cap_body < b + 1) m->cap_body = b + 1;
  /* geoms */
  if (GROW(m->geom_type, m->cap_geom, g + 1, 1) || GROW(m->geom_body, m->cap_geom, g + 1, 1) ||
      GROW(m->geom_size, m->cap_geom, g + 1, 3) || GROW(m->geom_pos, m->cap_geom, g + 1, 3) ||
      GROW(m->geom_quat, m->cap_geom, g + 1, 4) || GROW(m->geom_material, m->cap_geom, g + 1, 1) ||
      GROW(m->geom_rgba, m->cap_geom, g + 1, 4))
    goto nomem;
  if (m->cap_geom < g + 1) m->cap_geom = g + 1;
  /* coordinates */
  if (GROW(m->qpos0, m->cap_q, m->nq + nq, 1)) goto nomem;
  if (m->cap_q < m->nq + nq) m->cap_q = m->nq + nq;
  if (GROW(m->qvel0, m->cap_v, m->nv + nv + 1, 1)) goto nomem;
  if (m->cap_v < m->nv + nv + 1) m->cap_v = m->nv + nv + 1;

  char *n1 = dupstr(def->name), *n2 = dupstr(def->name);
  if (!n1 || !n2) {
    free(n1);
    free(n2);
    goto nomem;
  }
  m->sys_name[s] = n1;
  m->sys_type[s] = def->is_static ? SS_SYS_STATIC : SS_SYS_FREE;
  m->sys_qadr[s] = m->nq;
  m->sys_nq[s] = nq;
  m->sys_vadr[s] = m->nv;
  m->sys_nv[s] = nv;
  m->sys_bodyadr[s] = b;
  m->sys_nbody[s] = 1;
  m->sys_line[s] = def->line;

  m->body_name[b] = n2;
  m->body_sys[b] = s;
  m->body_mass[b] = def->is_static ? 0 : def->mass;
  memcpy(m->body_inertia + 9 * b, I, sizeof I);
  m->body_inertia_given[b] = def->inertia_given;

  m->geom_type[g] = def->shape;
  m->geom_body[g] = b;
  memcpy(m->geom_size + 3 * g, def->size, 3 * sizeof(double));
  if (def->shape == SS_GEOM_SPHERE) m->geom_size[3 * g + 1] = m->geom_size[3 * g + 2] = 0;
  if (def->shape == SS_GEOM_CYLINDER || def->shape == SS_GEOM_CAPSULE) m->geom_size[3 * g + 2] = 0;
  m->geom_pos[3 * g] = m->geom_pos[3 * g + 1] = m->geom_pos[3 * g + 2] = 0;
  ss_quat_identity(m->geom_quat + 4 * g);
  m->geom_material[g] = mat;
  if (def->rgba[3] > 0)
    memcpy(m->geom_rgba + 4 * g, def->rgba, 4 * sizeof(double));
  else
    memcpy(m->geom_rgba + 4 * g, palette[s % 6], 4 * sizeof(double));

  double *q = m->qpos0 + m->nq;
  memcpy(q, def->pos, 3 * sizeof(double));
  memcpy(q + 3, def->quat, 4 * sizeof(double));
  ss_quat_normalize(q + 3);
  if (nv) {
    memcpy(m->qvel0 + m->nv, def->lin_vel, 3 * sizeof(double));
    memcpy(m->qvel0 + m->nv + 3, def->ang_vel, 3 * sizeof(double));
  }
  m->nq += nq;
  m->nv += nv;
  m->nsys++;
  m->nbody++;
  m->ngeom++;
  return s;
nomem:
  ss_error_set(err, SS_ERR_NOMEM, f, def->line, "out of memory");
  return -1;
}

int ss_model_add_plane(ssModel *m, const char *name, double height,
                       const char *material, int line, ssError *err)
{
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
  for (int h = 0; h < m->nhfield; h++)
    if (m->hfield_soil[h]) {
      ssError e2;
      if (ss_soil_material_validate(&m->hfield_soilmat[h], &e2) != SS_OK)
        return ss_error_set(err, SS_ERR_VALUE, f, 0, "heightmap '%s': %s",
                            m->hfield_name[h], e2.message);
    }
  return SS_OK;
}

double ss_geom_width(const ssModel *m, int geom, const double xmat[9],
                     const double n_bed[3])
{
  ssShape s;
  memset(&s, 0, sizeof s);
  s.type = m->geom_type[geom];
  memcpy(s.size, m->geom_size + 3 * geom, 3 * sizeof(double));
  memcpy(s.R, xmat, 9 * sizeof(double));
  return ss_shape_width(&s, n_bed);
}
