/* dynamics.h -- rigid-body dynamics in generalized coordinates: free
 * velocities, contact Jacobians and responses, semi-implicit integration. */
#ifndef SS_DYNAMICS_H
#define SS_DYNAMICS_H

#include "soilsim.h"

/* ss_forward as a step runs it: an articulated system whose poses are
 * ss_art_forward's at the current qpos already (ss_art_forward_current:
 * the end of the last step, or the loop-closure projection's last pass)
 * is not formed again; the same bits as ss_forward. */
void ss_forward_step(const ssModel *m, ssData *d);
/* 1 when external load k acts over the step that starts now: the step
 * [t, t + dt] counts when its midpoint t + dt/2 lies in [start, end).
 * The clock is a running sum of dt, off a multiple of dt by round-off
 * (after 1000 steps of 1 ms, 0.99999999999990 s), so testing t itself
 * against a start or end on the step grid took a step too many or too
 * few by chance: the midpoint lies dt/2 from either side of it. */
static inline int ss_dyn_xforce_active(const ssModel *m, const ssData *d, int k)
{
  double mid = d->time + 0.5 * m->opt.timestep;
  return mid >= m->xforce_time[2 * k] && mid < m->xforce_time[2 * k + 1];
}
/* The gyroscopic torque w x (I w) of a rigid body (world inertia about
 * its centre of mass I, angular velocity w) as one step of dt takes it:
 * g = I (w - w') / dt, w' one Newton step of the implicit midpoint rule
 * on I dw/dt = -w x I w from w, scaled to w's kinetic energy (a
 * gyroscopic torque does no work).  The explicit term made a spin about
 * a body's major axis, stable in nature, grow without bound (a 0.1 x
 * 0.4 x 0.8 m box at 10 rad/s blew up after 68 s at dt = 2 ms); this
 * one keeps a torque-free body's energy to round-off and its angular
 * momentum to the step's order, and equals the explicit term to first
 * order in dt (both are 0 where w is along a principal axis).
 * Where the Newton matrix is not positive definite, the explicit step
 * scaled alike; where I is singular (a massless link), the explicit
 * term. */
void ss_dyn_gyro(const double I[9], const double w[3], double dt, double g[3]);
/* qvel <- qvel + dt M^-1 (gravity + external forces - gyroscopic terms),
 * for articulated systems with their force elements and loop closures. */
ssStatus ss_dyn_free_velocity(const ssModel *m, ssData *d, ssError *err);
/* Contact Jacobian rows (frame rows n, t1, t2) of a point on single rigid
 * body b: J (3 x 6), row k = [f_k, r x f_k] with r from the centre of
 * mass.  Articulated links use ss_art_contact_rows and
 * ss_art_contact_response. */
void ss_dyn_contact_jacobian(const ssData *d, int body, const double point[3],
                             const double frame[9], double *J);
/* The response of such a contact, from its J: W = M^-1 J^T (6 x 3) and
 * G = J W (3 x 3).  Only the Gauss-Seidel sweeps need them: the solver
 * forms them when sweeps follow the Newton phase. */
void ss_dyn_contact_response(const ssModel *m, ssData *d, int body,
                             const double *J, double *W, double G[9]);
/* qvel of body b += M^-1 F for an impulse F = (force; torque about the
 * centre of mass), the layout of J^T lambda. */
void ss_dyn_body_impulse(const ssModel *m, ssData *d, int body,
                         const double F[6]);
/* Velocity of a world point on body b. */
void ss_dyn_point_velocity(const ssModel *m, const ssData *d, int body,
                           const double point[3], double v[3]);
/* The same with the system velocities qvel (nv, laid out as d->qvel) in
 * place of d->qvel, at the poses of d */
void ss_dyn_point_velocity_of(const ssModel *m, const ssData *d, const double *qvel,
                              int body, const double point[3], double v[3]);
/* Radius of a sphere about geom g's origin that holds the whole geom (a
 * mesh: its farthest bounding-box corner). */
double ss_dyn_geom_radius(const ssModel *m, int g);
/* A bound on the speed of any point of geom g (radius: its bounding
 * radius about the geom centre). */
double ss_dyn_geom_speed(const ssModel *m, const ssData *d, int g,
                         double radius);
/* A bound on the speed along the unit direction n of any point of geom g
 * (radius as above): |v_c . n| + radius |n x omega|, v_c the velocity of
 * the geom centre.  At most ss_dyn_geom_speed's bound. */
double ss_dyn_geom_approach(const ssModel *m, const ssData *d, int g,
                            double radius, const double n[3]);
/* Positions from velocities (semi-implicit Euler); quaternions exact. */
void ss_dyn_integrate(const ssModel *m, ssData *d);
/* First active system whose coordinates are non-finite (*velocity = 0) or
 * whose velocities are non-finite or above SS_SPEED_MAX in magnitude (m/s
 * or rad/s; *velocity = 1), or -1. */
int ss_dyn_check_finite(const ssModel *m, const ssData *d, int *velocity);
/* The state a step starts from and an export or checkpoint writes: the
 * clock as <clock> allows it (time finite and >= 0, step >= 0), that
 * of ss_dyn_check_finite, every PD target finite, and every bed's
 * pose finite with a unit
 * quaternion (to 1e-6, as a checkpoint must hold it).  1 when it holds;
 * else 0 with what is wrong in msg ("the velocity of 'ball' is non-finite
 * or above 1e5 (m/s or rad/s)"). */
int ss_dyn_check_state(const ssModel *m, const ssData *d, char *msg, size_t cap);
/* Every quaternion in qpos (free bodies; articulated floating and
 * spherical joints) made unit where its squared length is off 1 by more
 * than 1e-12, as MuJoCo's step does: a caller may write one between steps
 * that is not (a zero one becomes the identity).  Those a step leaves are
 * unit to round-off and are left alone, bit for bit. */
void ss_dyn_unit_quats(const ssModel *m, ssData *d);

#endif
