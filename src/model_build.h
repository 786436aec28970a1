/* model_build.h -- internal builder steps shared by the single-body and the
 * articulated builders.  Each returns the new index or -1 with err set. */
#ifndef SS_MODEL_BUILD_H
#define SS_MODEL_BUILD_H

#include "soilsim.h"

struct ssMesh;

/* a system with nq/nv coordinates appended to qpos0/qvel0 (zeroed) */
int ss_model_push_sys(ssModel *m, const char *name, int type, int nq, int nv,
                      int line, ssError *err);
/* a body of system sys with defaults: no mass, fixed joint, identity frames */
int ss_model_push_body(ssModel *m, int sys, const char *name,
                       const char *jntname, int parent, ssError *err);
int ss_model_push_geom(ssModel *m, int body, int type, const double size[3],
                       const double pos[3], const double quat[4], int material,
                       const double rgba[4], int group, int mesh, ssError *err);
/* takes ownership of mesh on success */
int ss_model_push_mesh(ssModel *m, struct ssMesh *mesh, const char *path,
                       ssError *err);
int ss_model_push_eq(ssModel *m, const char *name, int type, int sys,
                     int body1, int body2, const double anchor[6],
                     const double data[2], int line, ssError *err);
int ss_model_push_spring(ssModel *m, const char *name, int body1, int body2,
                         const double anchor[6], const double param[3],
                         ssError *err);
int ss_model_push_pd(ssModel *m, int body, const double gain[3],
                     const double target[2], ssError *err);

/* The builder's counts at one moment; a failed add rolls back to it, so a
 * model never keeps half an object. */
typedef struct ssModelMark {
  int nsys, nbody, ngeom, nq, nv, neq, nspring, npd, nmesh;
} ssModelMark;

ssModelMark ss_model_mark(const ssModel *m);
/* Free everything added since the mark and restore its counts. */
void ss_model_rollback(ssModel *m, const ssModelMark *mark);

#endif
