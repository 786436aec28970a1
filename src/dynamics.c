/* dynamics.c -- single rigid bodies in generalized coordinates.
 *
 * A free body has qpos = (COM position, orientation quaternion) and
 * qvel = (COM linear velocity, angular velocity), both in the world frame.
 * Time stepping is semi-implicit Euler: velocities first (forces at the
 * step start, contact impulses solved implicitly at the end-of-step
 * velocity), then positions from the new velocities; orientations advance
 * by the exact exponential map of omega dt. */
#include "dynamics.h"
#include "articulated.h"
#include "mesh.h"
#include "ss_math.h"

#include <float.h>
#include <stdio.h>
#include <string.h>

void ss_dyn_gyro(const double I[9], const double w[3], double dt, double g[3])
{
  double Iw[3], f[3];
  ss_m3_mulv(Iw, I, w);
  ss_v3_cross(f, w, Iw);
  /* the implicit midpoint rule I (w' - w) = -dt h((w + w') / 2), h(y) =
   * y x I y, by one Newton step from w: J (w - w') = dt h(w) with J = I +
   * dt/2 (skew(w) I - skew(I w)), the derivative of h at w (column k of
   * skew(a) B is a x B_k) */
  double J[9], Ji[9];
  for (int k = 0; k < 3; k++) {
    double col[3] = {I[k], I[3 + k], I[6 + k]}, wc[3], e[3] = {0, 0, 0}, iwe[3];
    e[k] = 1;
    ss_v3_cross(wc, w, col);
    ss_v3_cross(iwe, Iw, e);
    for (int i = 0; i < 3; i++) J[3 * i + k] = I[3 * i + k] + 0.5 * dt * (wc[i] - iwe[i]);
  }
  /* dw = (w - w') / dt = J^-1 f; where J is not positive definite (dt |w|
   * far beyond a small inertia), the explicit step's I^-1 f; where I is
   * singular too (a massless link), the explicit torque as it stands */
  double dw[3];
  double det = ss_m3_inv(Ji, J);
  if (!(det > 0) || !isfinite(det)) {
    det = ss_m3_inv(Ji, I);
    if (!(det > 0) || !isfinite(det)) {
      ss_v3_copy(g, f);
      return;
    }
  }
  ss_m3_mulv(dw, Ji, f);
  /* a gyroscopic torque does no work: w' is scaled to w's kinetic
   * energy, which the midpoint rule keeps and one Newton step of it
   * keeps to O(dt^3) (near a singular J it may not: an inertia of 1e-4
   * of the others' at 100 rad/s) */
  double w1[3], Iw1[3];
  for (int i = 0; i < 3; i++) w1[i] = w[i] - dt * dw[i];
  ss_m3_mulv(Iw1, I, w1);
  double e0 = ss_v3_dot(w, Iw), e1 = ss_v3_dot(w1, Iw1);
  if (e1 != e0) {
    double k = e1 > 0 && e0 >= 0 ? sqrt(e0 / e1) : 0;
    for (int i = 0; i < 3; i++) dw[i] = (w[i] - k * w1[i]) / dt;
  }
  /* g = I (w - w') / dt */
  ss_m3_mulv(g, I, dw);
}

static int sys_dynamic(const ssModel *m, const ssData *d, int s)
{
  return m->sys_type[s] == SS_SYS_FREE && d->sys_active[s];
}

ssStatus ss_dyn_free_velocity(const ssModel *m, ssData *d, ssError *err)
{
  const double dt = m->opt.timestep;
  for (int s = 0; s < m->nsys; s++) {
    if (m->sys_type[s] == SS_SYS_ARTICULATED && d->sys_active[s] && m->sys_nv[s]) {
      ssStatus st = ss_art_free_velocity(m, d, s, err);
      if (st) return st;
      continue;
    }
    if (!sys_dynamic(m, d, s)) continue;
    int b = m->sys_bodyadr[s];
    double *v = d->qvel + m->sys_vadr[s], *w = v + 3;
    const double *R = d->body_xmat + 9 * b;
    double mass = m->body_mass[b];

    /* world inverse inertia R I^-1 R^T, and world inertia for the
     * gyroscopic term */
    double Ib_inv[9], tmp[9], Rt[9], Iw[9];
    ss_m3_inv(Ib_inv, m->body_inertia + 9 * b);
    ss_m3_transpose(Rt, R);
    ss_m3_mul(tmp, R, Ib_inv);
    ss_m3_mul(d->body_iinv + 9 * b, tmp, Rt);
    ss_m3_mul(tmp, R, m->body_inertia + 9 * b);
    ss_m3_mul(Iw, tmp, Rt);

    double f[3], tau[3];
    ss_v3_scale(f, m->opt.gravity, mass);
    ss_v3_set(tau, 0, 0, 0);
    for (int k = 0; k < m->nxforce; k++) {
      if (m->xforce_body[k] != b) continue;
      if (!ss_dyn_xforce_active(m, d, k)) continue;
      ss_v3_add(f, f, m->xforce_force + 3 * k);
      ss_v3_add(tau, tau, m->xforce_torque + 3 * k);
    }
    /* gyroscopic torque -w x (I w), implicit (ss_dyn_gyro) */
    double gyro[3];
    ss_dyn_gyro(Iw, w, dt, gyro);
    ss_v3_sub(tau, tau, gyro);

    double dw[3];
    ss_m3_mulv(dw, d->body_iinv + 9 * b, tau);
    ss_v3_addscl(v, f, dt / mass);
    ss_v3_addscl(w, dw, dt);
  }
  return SS_OK;
}

void ss_dyn_contact_jacobian(const ssData *d, int b, const double p[3],
                             const double frame[9], double *J)
{
  double r[3];
  ss_v3_sub(r, p, d->body_xipos + 3 * b);
  /* J row k = [f, r x f] */
  for (int k = 0; k < 3; k++) {
    const double *f = frame + 3 * k;
    ss_v3_copy(J + 6 * k, f);
    ss_v3_cross(J + 6 * k + 3, r, f);
  }
}

void ss_dyn_contact_response(const ssModel *m, ssData *d, int b,
                             const double *J, double *W, double G[9])
{
  double inv_m = 1.0 / m->body_mass[b];
  const double *Iinv = d->body_iinv + 9 * b;
  double wang[3][3];
  for (int k = 0; k < 3; k++) {
    /* W column k = [f / m, I^-1 (r x f)] */
    const double *f = J + 6 * k;
    ss_m3_mulv(wang[k], Iinv, J + 6 * k + 3);
    for (int i = 0; i < 3; i++) {
      W[3 * i + k] = f[i] * inv_m;
      W[3 * (3 + i) + k] = wang[k][i];
    }
  }
  for (int a = 0; a < 3; a++)
    for (int c = 0; c < 3; c++)
      G[3 * a + c] = ss_v3_dot(J + 6 * a, J + 6 * c) * inv_m + ss_v3_dot(J + 6 * a + 3, wang[c]);
}

void ss_dyn_body_impulse(const ssModel *m, ssData *d, int b, const double F[6])
{
  double *u = d->qvel + m->sys_vadr[m->body_sys[b]], dw[3];
  double inv_m = 1.0 / m->body_mass[b];
  for (int i = 0; i < 3; i++) u[i] += F[i] * inv_m;
  ss_m3_mulv(dw, d->body_iinv + 9 * b, F + 3);
  ss_v3_add(u + 3, u + 3, dw);
}

void ss_dyn_point_velocity(const ssModel *m, const ssData *d, int b,
                           const double p[3], double v[3])
{
  ss_dyn_point_velocity_of(m, d, d->qvel, b, p, v);
}

void ss_dyn_point_velocity_of(const ssModel *m, const ssData *d, const double *qvel,
                              int b, const double p[3], double v[3])
{
  int s = m->body_sys[b];
  if (m->sys_nv[s] == 0 || !d->sys_active[s]) {
    ss_v3_set(v, 0, 0, 0);
    return;
  }
  if (m->sys_type[s] == SS_SYS_ARTICULATED) {
    ss_art_point_velocity_of(m, d, qvel, b, p, v);
    return;
  }
  const double *u = qvel + m->sys_vadr[s];
  double r[3], wr[3];
  ss_v3_sub(r, p, d->body_xipos + 3 * b);
  ss_v3_cross(wr, u + 3, r);
  ss_v3_add(v, u, wr);
}

double ss_dyn_geom_radius(const ssModel *m, int g)
{
  const double *s = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
  case SS_GEOM_BOX: return 0.5 * sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  case SS_GEOM_SPHERE: return s[0];
  case SS_GEOM_CYLINDER: return sqrt(s[0] * s[0] + 0.25 * s[1] * s[1]);
  case SS_GEOM_CAPSULE: return s[0] + 0.5 * s[1];
  case SS_GEOM_MESH: {
    int k = m->geom_mesh ? m->geom_mesh[g] : -1;
    if (k < 0 || k >= m->nmesh || !m->mesh[k]) return 0;
    const ssMesh *me = m->mesh[k];
    double r2 = 0;
    for (int i = 0; i < 3; i++) {
      double a = fmax(fabs(me->lo[i]), fabs(me->hi[i]));
      r2 += a * a;
    }
    return sqrt(r2);
  }
  default: return s[0];
  }
}

double ss_dyn_geom_speed(const ssModel *m, const ssData *d, int g,
                         double radius)
{
  int b = m->geom_body[g], s = m->body_sys[b];
  if (!m->sys_nv[s] || !d->sys_active[s]) return 0;
  const double *c = d->geom_xpos + 3 * g;
  double v[3], w[3];
  ss_dyn_point_velocity(m, d, b, c, v);
  if (m->sys_type[s] == SS_SYS_ARTICULATED) {
    /* angular velocity of the body: difference of two point velocities
     * is w x r; bound |w| through the velocity of a point one metre away
     * along each axis */
    double wmax = 0;
    for (int k = 0; k < 3; k++) {
      double p[3] = {c[0], c[1], c[2]}, vk[3], dv[3];
      p[k] += 1;
      ss_dyn_point_velocity(m, d, b, p, vk);
      ss_v3_sub(dv, vk, v);
      wmax = fmax(wmax, ss_v3_norm(dv));
    }
    return ss_v3_norm(v) + 2 * wmax * radius;
  }
  ss_v3_copy(w, d->qvel + m->sys_vadr[s] + 3);
  return ss_v3_norm(v) + ss_v3_norm(w) * radius;
}

double ss_dyn_geom_approach(const ssModel *m, const ssData *d, int g,
                            double radius, const double n[3])
{
  int b = m->geom_body[g], s = m->body_sys[b];
  if (!m->sys_nv[s] || !d->sys_active[s]) return 0;
  const double *c = d->geom_xpos + 3 * g;
  double v[3], w[3], wn[3];
  ss_dyn_point_velocity(m, d, b, c, v);
  if (m->sys_type[s] == SS_SYS_ARTICULATED) {
    double sv[6];
    ss_art_link_velocity(m, d, b, sv);
    ss_v3_copy(w, sv);
  } else {
    ss_v3_copy(w, d->qvel + m->sys_vadr[s] + 3);
  }
  /* a point c + r (|r| <= radius) moves along n at v.n + (w x r).n =
   * v.n + r.(n x w) */
  ss_v3_cross(wn, n, w);
  return fabs(ss_v3_dot(v, n)) + radius * ss_v3_norm(wn);
}

void ss_dyn_integrate(const ssModel *m, ssData *d)
{
  const double dt = m->opt.timestep;
  for (int s = 0; s < m->nsys; s++) {
    if (m->sys_type[s] == SS_SYS_ARTICULATED && d->sys_active[s] && m->sys_nv[s]) {
      ss_art_integrate(m, d, s);
      continue;
    }
    if (!sys_dynamic(m, d, s)) continue;
    double *q = d->qpos + m->sys_qadr[s];
    const double *u = d->qvel + m->sys_vadr[s];
    ss_v3_addscl(q, u, dt);
    double rv[3], dq[4];
    ss_v3_scale(rv, u + 3, dt);
    ss_quat_from_rotvec(dq, rv);
    ss_quat_mul(q + 3, dq, q + 3);
    ss_quat_normalize(q + 3);
  }
}

int ss_dyn_check_finite(const ssModel *m, const ssData *d, int *velocity)
{
  /* SS_SPEED_MAX: far beyond any vehicle, foot or plate on soil; after a
   * step, a sign that it blew up */
  for (int s = 0; s < m->nsys; s++) {
    if (!d->sys_active[s]) continue;
    *velocity = 0;
    for (int k = 0; k < m->sys_nq[s]; k++)
      if (!isfinite(d->qpos[m->sys_qadr[s] + k])) return s;
    *velocity = 1;
    if (!ss_all_within(d->qvel + m->sys_vadr[s], m->sys_nv[s], SS_SPEED_MAX)) return s;
  }
  return -1;
}

static void unit_quat(double q[4])
{
  double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (fabs(n2 - 1) > 1e-12) ss_quat_normalize(q);
}

void ss_dyn_unit_quats(const ssModel *m, ssData *d)
{
  for (int s = 0; s < m->nsys; s++) {
    if (m->sys_type[s] == SS_SYS_FREE) {
      unit_quat(d->qpos + m->sys_qadr[s] + 3);
      continue;
    }
    for (int b = m->sys_bodyadr[s]; b < m->sys_bodyadr[s] + m->sys_nbody[s]; b++) {
      if (m->body_qadr[b] < 0) continue;
      double *q = d->qpos + m->body_qadr[b];
      if (m->body_jnttype[b] == SS_JOINT_SPHERICAL) unit_quat(q);
      else if (m->body_jnttype[b] == SS_JOINT_FLOATING) unit_quat(q + 3);
    }
  }
}

int ss_dyn_check_state(const ssModel *m, const ssData *d, char *msg, size_t cap)
{
  /* the clock as the scene and checkpoint readers take it (<clock>) */
  if (!(isfinite(d->time) && d->time >= 0) || d->step < 0) {
    snprintf(msg, cap, "the clock (time %g s, step %ld) is invalid: the time "
             "must be finite and >= 0 s, the step count >= 0", d->time, d->step);
    return 0;
  }
  int vel, s = ss_dyn_check_finite(m, d, &vel);
  if (s >= 0) {
    snprintf(msg, cap, "the %s of '%s' is %s", vel ? "velocity" : "position",
             m->sys_name[s], vel ? "non-finite or above 1e5 (m/s or rad/s)" : "non-finite");
    return 0;
  }
  /* PD targets finite, as the scene and checkpoint readers take them: a
   * program writes d->pd_target between steps, and a NaN there made the
   * step fail as if it were too stiff, an export write position_target
   * "nan" and a checkpoint one its reader refuses as corrupted */
  for (int k = 0; k < m->npd; k++) {
    const double *t = d->pd_target + 2 * k;
    if (!isfinite(t[0]) || !isfinite(t[1])) {
      int b = m->pd_body[k];
      snprintf(msg, cap, "the PD target of joint '%s' of '%s' (position %g, velocity %g) "
               "is non-finite", m->body_jntname[b], m->sys_name[m->body_sys[b]], t[0], t[1]);
      return 0;
    }
  }
  /* a bed's quaternion unit as ss_hfield_set_pose leaves it and the
   * checkpoint reader asks */
  for (int h = 0; h < m->nhfield; h++) {
    if (!ss_all_within(d->hfield_pos + 3 * h, 3, DBL_MAX) ||
        !ss_quat_is_unit(d->hfield_quat + 4 * h)) {
      snprintf(msg, cap, "the pose of height map '%s' is non-finite or not a unit "
               "quaternion (move beds with ss_hfield_set_pose)", m->hfield_name[h]);
      return 0;
    }
  }
  return 1;
}
