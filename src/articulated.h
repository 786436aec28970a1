/* articulated.h -- articulated systems in reduced coordinates: a floating or
 * fixed base and a tree of revolute, prismatic, spherical and fixed joints,
 * with loop closures, joint springs and dampers, point-to-point
 * spring-dampers and PD controllers (DESIGN 3).
 *
 * Spatial vectors are 6-vectors in world axes about the system's origin
 * O_s (ss_art_origin): motion (omega; v_O), force (torque about O_s;
 * force).  O_s is the root's position rounded to a multiple of 64 m: 0
 * for a system within 32 m of the world origin, and never far from the
 * system, so that no product of its distance from the world origin
 * enters the spatial quantities to cancel where they are used (about the
 * world origin, the buggy 1 km out took 10 times the Newton iterations
 * of the buggy at the origin; README, "Far from the origin").  A body's
 * spatial Jacobian J_b (6 x nv) has the world motion-subspace column of
 * every degree of freedom on its path to the root.  The step solves
 *   M' (u_new - u) = dt (tau - c) + J^T lambda + K^T mu,   K u_new = 0
 * where M' is the CRBA mass matrix plus the implicit terms of joint
 * dampers/springs and coil-overs, factored with Featherstone's LTDL (which
 * keeps the tree's sparsity), and the loop closures K are eliminated by
 * projection in the M' metric.  Contacts see the projected response
 * W = P M'^-1 J^T through a per-body six-component reduction
 * Y_b = P M'^-1 J_b^T (the six spatial directions projected once per link
 * and step), so a contact stores only its 3 x 6 spatial rows and the
 * solver sweeps the contacts of one link against the link's 6 x 6 block
 * J_b Y_b (solver.h). */
#ifndef SS_ARTICULATED_H
#define SS_ARTICULATED_H

#include "soilsim.h"
#include "urdf.h"

typedef struct ssArtWork ssArtWork;

/* How a scene instantiates a URDF. */
typedef struct ssArtDef {
  const char *name;
  int fixed_base;        /* 1: the root is welded to the world at pos/quat;
                            0: floating; -1 (default): as the URDF's "world"
                            link says, else floating */
  double pos[3];         /* root pose (floating: initial; fixed: weld) */
  double quat[4];
  int pose_given;        /* pos or quat given (a scene's <state pos quat>):
                            with qpos on a floating base, which sets the
                            same pose, an error instead of one of them
                            dropped */
  const double *qpos;    /* optional full initial qpos (nq), NULL = URDF zero
                            pose placed at pos/quat */
  int nqpos;
  const char *qpos_name; /* what errors call qpos (e.g. "reference_qpos");
                            NULL = "qpos" */
  const double *qvel;    /* optional (nv) */
  int nqvel;
  const char *material;  /* rigid material of all colliders */
  const char *urdf_path; /* recorded for export */
  const char *res_dir;
  int line;
} ssArtDef;

ssArtDef ss_art_def_default(void);

/* Add an articulated system built from a parsed URDF.  Loads meshes,
 * resolves closures at the initial configuration and checks that they are
 * independent.  Returns the system index or -1 with err set. */
int ss_model_add_articulated(ssModel *m, const ssUrdf *u, const ssArtDef *def,
                             ssError *err);
/* A joint PD controller on the joint named joint of system sys. */
int ss_model_add_pd(ssModel *m, int sys, const char *joint, double p_gain,
                    double d_gain, double position_target,
                    double velocity_target, double effort_limit, int line,
                    ssError *err);
/* Body index of a link of system sys by name, or -1. */
int ss_model_find_body(const ssModel *m, int sys, const char *name);

ssArtWork *ss_art_work_new(const ssModel *m, int sys);
void ss_art_work_free(ssArtWork *w);

/* Body poses, centres of mass and motion subspaces from qpos. */
void ss_art_forward(const ssModel *m, ssData *d, int sys);
/* 1 if the system's poses and motion subspaces are ss_art_forward's at
 * the current qpos: the last ss_art_forward ran at these very bytes of
 * its qpos (the model is immutable, and nothing else writes them), so
 * running it again would give the same bits. */
int ss_art_forward_current(const ssModel *m, const ssData *d, int sys);
/* qvel <- constrained free velocity; prepares the responses for contacts.
 * Returns SS_ERR_NUMERIC when the mass matrix is not positive definite. */
ssStatus ss_art_free_velocity(const ssModel *m, ssData *d, int sys,
                              ssError *err);
/* The response block of link b for this step, computed once per step and
 * shared by all contacts on the link: Y (nv x 6, row k: the velocity of
 * dof k per unit spatial impulse, loop closures eliminated) and the 6 x 6
 * block Lam = J_b Y, the link's spatial velocity per unit spatial impulse. */
void ss_art_link_block(const ssModel *m, ssData *d, int b, const double **Y,
                       const double **Lam);
/* The block J_a Y_b (6 x 6, row i at out + ldo i) between links a and b of
 * one system, from the factors without forming Y_b (the Newton phase's
 * route: each link's path reduced once per step); the same as J_a of
 * ss_art_link_block's Y_b to round-off. */
void ss_art_link_pair(const ssModel *m, ssData *d, int a, int b, double *out, int ldo);
/* Spatial impulses on links of one system, summed (J_b^T F_b, add), then
 * applied at once (apply: u += P M'^-1 sum, u the system's velocities),
 * which is sum Y_b F_b with one solve instead of Y_b's six. */
void ss_art_force_add(const ssModel *m, ssData *d, int b, const double F[6]);
void ss_art_force_apply(const ssModel *m, ssData *d, int sys, double *u);
/* The point system sys's spatial vectors are about (world, m), as the
 * last ss_art_forward set it. */
const double *ss_art_origin(const ssData *d, int sys);
/* Spatial velocity J_b u of link b (world axes, about the system's
 * origin: omega; v_O). */
void ss_art_link_velocity(const ssModel *m, const ssData *d, int b,
                          double V[6]);
/* The same for any velocities u of the link's system (its nv values): the
 * spatial motion J_b u. */
void ss_art_link_motion(const ssModel *m, const ssData *d, int b,
                        const double *u, double V[6]);
/* The same for the ncol columns of U (the system's velocities, row k = dof
 * k at U + ldu k), into out (6 x ncol, row i at out + ldo i): column by
 * column, ss_art_link_motion being this with one */
void ss_art_link_motion_cols(const ssModel *m, const ssData *d, int b, const double *U,
                             int ldu, int ncol, double *out, int ldo);
/* Contact rows of a point p (from the system's origin, ss_art_origin)
 * with contact frame `frame` (rows n, t1, t2) on a link: X (3 x 6) maps
 * the link's spatial velocity to the contact-frame velocity of the
 * point.  The contact's Jacobian is X J_b, its response Y X^T. */
void ss_art_contact_rows(const double p[3], const double frame[9], double X[18]);
/* The contact's response on link b, from its rows X: LX (3 x 6, row i =
 * Lam X_i^T) the link's velocity change per unit impulse along each
 * contact direction, and G = X Lam X^T.  Only the Gauss-Seidel sweeps need
 * them: the solver forms them when sweeps follow the Newton phase. */
void ss_art_contact_response(const ssModel *m, ssData *d, int b,
                             const double X[18], double LX[18], double G[9]);
/* Row of one degree of freedom (PD, limits): J = sign e_k (3 nv, the rows
 * after the first zero) and G = J P M'^-1 J^T (its first entry; from the
 * factors).  Its response W = P M'^-1 J^T (nv x 3, the columns after the
 * first zero) is formed apart, only where the sweeps or an applied warm
 * start need it (ss_art_dof_response). */
void ss_art_dof_row(ssData *d, int sys, int dof, double sign, double *J, double G[9]);
void ss_art_dof_response(ssData *d, int sys, int dof, double sign, double *W);
/* The factored route for joint rows (see ss_art_link_pair): J_b P M'^-1 e_dof
 * (6), e_dof1^T P M'^-1 e_dof2, and an impulse f along dof added to the
 * sum that ss_art_force_apply applies. */
void ss_art_link_dof_pair(const ssModel *m, ssData *d, int b, int dof, double out[6]);
double ss_art_dof_pair(ssData *d, int sys, int dof1, int dof2);
void ss_art_dof_force_add(ssData *d, int sys, int dof, double f);
/* Velocity of a world point on body b. */
void ss_art_point_velocity(const ssModel *m, const ssData *d, int b,
                           const double p[3], double v[3]);
/* the same with the velocities qvel (laid out as d->qvel) at d's poses */
void ss_art_point_velocity_of(const ssModel *m, const ssData *d, const double *qvel, int b,
                              const double pw[3], double v[3]);
/* Positions from velocities, then loop-closure drift removed by projection
 * (Newton in the M' metric); sets d->closure_error. */
void ss_art_integrate(const ssModel *m, ssData *d, int sys);
/* Append the solver rows of PD controllers and active joint limits. */
ssStatus ss_art_rows(const ssModel *m, ssData *d, ssError *err);
/* Largest closure violation of a system at the current qpos. */
double ss_art_closure_error(const ssModel *m, ssData *d, int sys);

#endif /* SS_ARTICULATED_H */
