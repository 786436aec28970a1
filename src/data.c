/* data.c -- the mutable state of a world and its accessors. */
#include "soilsim.h"
#include "articulated.h"
#include "dynamics.h"
#include "solver.h"
#include "ss_math.h"

#include <stdlib.h>
#include <string.h>

ssData *ss_data_new(const ssModel *m)
{
  ssData *d = calloc(1, sizeof *d);
  if (!d) return NULL;
  d->model = m;
  size_t nq = m->nq ? m->nq : 1, nv = m->nv ? m->nv : 1;
  size_t nb = m->nbody ? m->nbody : 1, ng = m->ngeom ? m->ngeom : 1;
  size_t nh = m->nhfield ? m->nhfield : 1;
  size_t ns = m->nsys ? m->nsys : 1;
  size_t nhd = m->nhfielddata ? m->nhfielddata : 1;
  d->qpos = calloc(nq, sizeof(double));
  d->qvel = calloc(nv, sizeof(double));
  d->qvel_free = calloc(nv, sizeof(double));
  d->qvel_start = calloc(nv, sizeof(double));
  d->qvel_push = calloc(nv, sizeof(double));
  d->sys_active = calloc(ns, 1);
  d->body_xpos = calloc(nb * 3, sizeof(double));
  d->body_xquat = calloc(nb * 4, sizeof(double));
  d->body_xmat = calloc(nb * 9, sizeof(double));
  d->geom_xpos = calloc(ng * 3, sizeof(double));
  d->geom_xmat = calloc(ng * 9, sizeof(double));
  d->geom_patch = calloc(ng * 3, sizeof(double));
  d->hfield_pow = calloc(nh, sizeof(ssPowTable));
  d->body_iinv = calloc(nb * 9, sizeof(double));
  d->body_xipos = calloc(nb * 3, sizeof(double));
  d->pd_target = calloc((size_t)(m->npd ? m->npd : 1) * 2, sizeof(double));
  d->art = calloc(ns, sizeof(*d->art));
  d->hfield_pos = calloc(nh * 3, sizeof(double));
  d->hfield_quat = calloc(nh * 4, sizeof(double));
  d->soil_sinkage = calloc(nhd, sizeof(double));
  d->soil_plastic = calloc(nhd, sizeof(double));
  d->soil_shear = calloc(nhd, sizeof(double));
  if (!d->qpos || !d->qvel || !d->qvel_free || !d->qvel_start || !d->qvel_push ||
      !d->sys_active ||
      !d->body_xpos || !d->body_xquat || !d->body_xmat || !d->geom_xpos ||
      !d->geom_xmat || !d->geom_patch || !d->hfield_pow || !d->body_iinv ||
      !d->body_xipos || !d->pd_target ||
      !d->art || !d->hfield_pos || !d->hfield_quat || !d->soil_sinkage ||
      !d->soil_plastic || !d->soil_shear) {
    ss_data_free(d);
    return NULL;
  }
  for (int s = 0; s < m->nsys; s++)
    if (m->sys_type[s] == SS_SYS_ARTICULATED && !(d->art[s] = ss_art_work_new(m, s))) {
      ss_data_free(d);
      return NULL;
    }
  ss_data_reset(m, d);
  return d;
}

void ss_data_free(ssData *d)
{
  if (!d) return;
  free(d->qpos); free(d->qvel); free(d->qvel_free); free(d->qvel_start);
  free(d->qvel_push);
  free(d->sys_active);
  free(d->body_xpos); free(d->body_xquat); free(d->body_xmat);
  free(d->geom_xpos); free(d->geom_xmat); free(d->geom_patch); free(d->body_iinv);
  free(d->hfield_pow);
  free(d->body_xipos); free(d->pd_target);
  if (d->art)
    for (int s = 0; s < d->model->nsys; s++) ss_art_work_free(d->art[s]);
  free(d->art);
  free(d->hfield_pos); free(d->hfield_quat);
  free(d->soil_sinkage); free(d->soil_plastic); free(d->soil_shear);
  free(d->contact); free(d->jac); free(d->warm); free(d->warm_next);
  free(d->soil_loaded);
  for (int k = 0; k < 3; k++) free(d->newton_rec[k].c);
  ss_newton_work_free(d->newton);
  free(d);
}

void ss_data_reset(const ssModel *m, ssData *d)
{
  d->time = 0;
  d->step = 0;
  d->in_step = 0;
  if (m->nq) memcpy(d->qpos, m->qpos0, (size_t)m->nq * sizeof(double));
  if (m->nv) memcpy(d->qvel, m->qvel0, (size_t)m->nv * sizeof(double));
  memset(d->sys_active, 1, (size_t)m->nsys);
  if (m->npd) memcpy(d->pd_target, m->pd_target0, (size_t)m->npd * 2 * sizeof(double));
  d->closure_error = 0;
  if (m->nhfield) {
    memcpy(d->hfield_pos, m->hfield_pos0, (size_t)m->nhfield * 3 * sizeof(double));
    memcpy(d->hfield_quat, m->hfield_quat0, (size_t)m->nhfield * 4 * sizeof(double));
  }
  if (m->nhfielddata) {
    size_t n = (size_t)m->nhfielddata * sizeof(double);
    memset(d->soil_sinkage, 0, n);
    memset(d->soil_plastic, 0, n);
    memset(d->soil_shear, 0, n);
  }
  d->ncontact = 0;
  d->nwarm = 0;
  for (int k = 0; k < 3; k++) d->newton_rec[k].step = -1;
  d->nsoil_loaded = 0;
  memset(&d->stats, 0, sizeof d->stats);
  ss_forward(m, d);
}

static void forward(const ssModel *m, ssData *d, int reuse)
{
  for (int s = 0; s < m->nsys; s++) {
    if (m->sys_type[s] == SS_SYS_ARTICULATED) {
      if (!(reuse && ss_art_forward_current(m, d, s))) ss_art_forward(m, d, s);
      continue;
    }
    /* single bodies: qpos holds the pose of the body frame (its COM) */
    int b = m->sys_bodyadr[s];
    const double *q = d->qpos + m->sys_qadr[s];
    memcpy(d->body_xpos + 3 * b, q, 3 * sizeof(double));
    memcpy(d->body_xipos + 3 * b, q, 3 * sizeof(double));
    memcpy(d->body_xquat + 4 * b, q + 3, 4 * sizeof(double));
    ss_quat_to_mat(d->body_xmat + 9 * b, q + 3);
  }
  for (int g = 0; g < m->ngeom; g++) {
    int b = m->geom_body[g];
    const double *R = d->body_xmat + 9 * b;
    double off[3], Rg[9];
    ss_m3_mulv(off, R, m->geom_pos + 3 * g);
    ss_v3_add(d->geom_xpos + 3 * g, d->body_xpos + 3 * b, off);
    ss_quat_to_mat(Rg, m->geom_quat + 4 * g);
    ss_m3_mul(d->geom_xmat + 9 * g, R, Rg);
  }
}

void ss_forward(const ssModel *m, ssData *d)
{
  forward(m, d, 0);
}

/* (dynamics.h) */
void ss_forward_step(const ssModel *m, ssData *d)
{
  forward(m, d, 1);
}

ssStatus ss_remove(const ssModel *m, ssData *d, const char *name, ssError *err)
{
  int s = ss_model_find_sys(m, name);
  if (s < 0)
    return ss_error_set(err, SS_ERR_NOTFOUND, NULL, 0,
                        "no body or articulated system named '%s'", name);
  if (d->in_step)
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "cannot remove '%s' in the middle of a step", name);
  d->sys_active[s] = 0;
  if (m->sys_nv[s])
    memset(d->qvel + m->sys_vadr[s], 0, (size_t)m->sys_nv[s] * sizeof(double));
  return SS_OK;
}

/* Rebuild the list of vertices that hold elastic sinkage or shear (after a
 * state change from outside the step).  Costs one pass over the beds. */
static ssStatus rebuild_loaded(const ssModel *m, ssData *d)
{
  int n = 0;
  for (int k = 0; k < m->nhfielddata; k++)
    if (d->soil_sinkage[k] > d->soil_plastic[k] || d->soil_shear[k] > 0) n++;
  if (n > d->cap_soil_loaded) {
    int *p = realloc(d->soil_loaded, (size_t)n * sizeof(int));
    if (!p) return SS_ERR_NOMEM;
    d->soil_loaded = p;
    d->cap_soil_loaded = n;
  }
  d->nsoil_loaded = 0;
  for (int k = 0; k < m->nhfielddata; k++)
    if (d->soil_sinkage[k] > d->soil_plastic[k] || d->soil_shear[k] > 0)
      d->soil_loaded[d->nsoil_loaded++] = k;
  return SS_OK;
}

static ssStatus check_bed(const ssModel *m, const ssData *d, int h,
                          ssError *err)
{
  if (h < 0 || h >= m->nhfield)
    return ss_error_set(err, SS_ERR_NOTFOUND, NULL, 0,
                        "no height map with index %d", h);
  if (!m->hfield_soil[h])
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "height map '%s' is rigid: it has no soil state",
                        m->hfield_name[h]);
  if (d && d->in_step)
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "soil state of '%s' is only accessible between steps",
                        m->hfield_name[h]);
  return SS_OK;
}

ssStatus ss_soil_get_state(const ssModel *m, const ssData *d, int h,
                           double *sinkage, double *plastic, double *shear,
                           ssError *err)
{
  ssStatus st = check_bed(m, d, h, err);
  if (st) return st;
  size_t n = (size_t)m->hfield_nx[h] * m->hfield_ny[h], a = m->hfield_adr[h];
  if (sinkage) memcpy(sinkage, d->soil_sinkage + a, n * sizeof(double));
  if (plastic) memcpy(plastic, d->soil_plastic + a, n * sizeof(double));
  if (shear) memcpy(shear, d->soil_shear + a, n * sizeof(double));
  return SS_OK;
}

ssStatus ss_soil_set_state(const ssModel *m, ssData *d, int h,
                           const double *sinkage, const double *plastic,
                           const double *shear, ssError *err)
{
  ssStatus st = check_bed(m, d, h, err);
  if (st) return st;
  size_t n = (size_t)m->hfield_nx[h] * m->hfield_ny[h], a = m->hfield_adr[h];
  /* validate everything before writing anything */
  for (size_t k = 0; k < n; k++) {
    double s = sinkage ? sinkage[k] : d->soil_sinkage[a + k];
    double p = plastic ? plastic[k] : d->soil_plastic[a + k];
    double j = shear ? shear[k] : d->soil_shear[a + k];
    if (!isfinite(s) || !isfinite(p) || !isfinite(j) || p < 0 || s < p || j < 0)
      return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                          "soil state of '%s' at vertex %zu (sinkage %g, "
                          "plastic_sinkage %g, shear %g): need 0 <= "
                          "plastic_sinkage <= sinkage and shear >= 0, all finite",
                          m->hfield_name[h], k, s, p, j);
  }
  if (sinkage) memcpy(d->soil_sinkage + a, sinkage, n * sizeof(double));
  if (plastic) memcpy(d->soil_plastic + a, plastic, n * sizeof(double));
  if (shear) memcpy(d->soil_shear + a, shear, n * sizeof(double));
  /* cached tractions belong to the old state */
  d->nwarm = 0;
  if (rebuild_loaded(m, d) != SS_OK)
    return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  return SS_OK;
}

ssStatus ss_soil_reset(const ssModel *m, ssData *d, int h, ssError *err)
{
  ssStatus st = check_bed(m, d, h, err);
  if (st) return st;
  size_t n = (size_t)m->hfield_nx[h] * m->hfield_ny[h], a = m->hfield_adr[h];
  memset(d->soil_sinkage + a, 0, n * sizeof(double));
  memset(d->soil_plastic + a, 0, n * sizeof(double));
  memset(d->soil_shear + a, 0, n * sizeof(double));
  d->nwarm = 0;
  if (rebuild_loaded(m, d) != SS_OK)
    return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "out of memory");
  return SS_OK;
}

const double *ss_hfield_heights(const ssModel *m, int h)
{
  if (h < 0 || h >= m->nhfield) return NULL;
  return m->hfield_data + m->hfield_adr[h];
}

ssStatus ss_hfield_set_heights(ssModel *m, int h, const double *z, ssError *err)
{
  if (h < 0 || h >= m->nhfield)
    return ss_error_set(err, SS_ERR_NOTFOUND, NULL, 0,
                        "no height map with index %d", h);
  if (m->hfield_soil[h])
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "height map '%s' is a soil bed: its heights cannot be "
                        "edited (that would bypass the soil history)",
                        m->hfield_name[h]);
  size_t n = (size_t)m->hfield_nx[h] * m->hfield_ny[h];
  for (size_t k = 0; k < n; k++)
    if (!isfinite(z[k]))
      return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                          "height[%zu] is not finite", k);
  memcpy(m->hfield_data + m->hfield_adr[h], z, n * sizeof(double));
  ss_hfield_update_range(m, h);
  return SS_OK;
}

ssStatus ss_hfield_set_pose(const ssModel *m, ssData *d, int h,
                            const double pos[3], const double quat[4],
                            ssError *err)
{
  if (h < 0 || h >= m->nhfield)
    return ss_error_set(err, SS_ERR_NOTFOUND, NULL, 0,
                        "no height map with index %d", h);
  if (d->in_step)
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "a bed can only be moved between steps");
  double q[4] = {quat[0], quat[1], quat[2], quat[3]};
  for (int k = 0; k < 3; k++)
    if (!isfinite(pos[k]))
      return ss_error_set(err, SS_ERR_VALUE, NULL, 0, "bed position must be finite");
  if (!isfinite(q[0] + q[1] + q[2] + q[3]) || ss_quat_normalize(q) < 1e-9)
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "bed orientation must be a finite non-zero quaternion");
  memcpy(d->hfield_pos + 3 * h, pos, 3 * sizeof(double));
  memcpy(d->hfield_quat + 4 * h, q, 4 * sizeof(double));
  d->nwarm = 0;
  return SS_OK;
}

double ss_hfield_surface(const ssModel *m, const ssData *d, int h, int i, int j)
{
  int k = m->hfield_adr[h] + j * m->hfield_nx[h] + i;
  return m->hfield_data[k] - (m->hfield_soil[h] ? d->soil_sinkage[k] : 0);
}
