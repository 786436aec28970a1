/* dynamics.h -- rigid-body dynamics in generalized coordinates: free
 * velocities, contact Jacobians and responses, semi-implicit integration. */
#ifndef SS_DYNAMICS_H
#define SS_DYNAMICS_H

#include "soilsim.h"

/* qvel <- qvel + dt M^-1 (gravity + external forces - gyroscopic terms). */
void ss_dyn_free_velocity(const ssModel *m, ssData *d);
/* Contact Jacobian rows (frame rows n, t1, t2) of a point on system sys:
 * J (3 x nv) and W = M^-1 J^T (nv x 3), G = J W (3 x 3). */
void ss_dyn_contact_jacobian(const ssModel *m, const ssData *d, int sys,
                             const double point[3], const double frame[9],
                             double *J, double *W, double G[9]);
/* Velocity of a point on a system, world frame. */
void ss_dyn_point_velocity(const ssModel *m, const ssData *d, int sys,
                           const double point[3], double v[3]);
/* Positions from velocities (semi-implicit Euler); quaternions exact. */
void ss_dyn_integrate(const ssModel *m, ssData *d);
/* First system whose state is non-finite, or -1. */
int ss_dyn_check_finite(const ssModel *m, const ssData *d);

#endif
