/* soilsim.h -- the public interface of the soilsim library.
 *
 * soilsim simulates rigid bodies and articulated systems on deformable soil
 * beds (Bekker pressure-sinkage, elastic unloading, permanent ruts, loading
 * viscosity, Mohr-Coulomb / Janosi-Hanamoto shear).  The library follows a
 * model/data split: an ssModel is the immutable description of a world (what
 * it is), an ssData holds everything that changes as it is stepped (where it
 * is now).  ss_step(m, d) advances d by one time step.
 *
 * Conventions: SI units everywhere (m, s, kg, N, Pa).  World frame Z up.
 * Quaternions are stored w, x, y, z.  Arrays are documented with their shape
 * as (rows x cols).  Library functions never print and never exit: fallible
 * functions return an ssStatus and fill a caller-owned ssError.
 */
#ifndef SOILSIM_H
#define SOILSIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SS_VERSION "0.1.0"

/* The largest speed a state may hold: every velocity coordinate (m/s, or
 * rad/s for angles) must be finite and at most this in magnitude, a
 * hundred times a rifle bullet and far beyond any vehicle, foot or plate
 * on soil.  Bodies and articulated systems given a faster state are
 * refused when they are added (ss_model_add_body,
 * ss_model_add_articulated); a step that starts or ends beyond it fails
 * (ss_step), and such a state is neither exported nor checkpointed. */
#define SS_SPEED_MAX 1e5

/* ---------------------------------------------------------------------- */
/* errors                                                                  */

typedef enum ssStatus {
  SS_OK = 0,
  SS_ERR_NOMEM,       /* allocation failed */
  SS_ERR_IO,          /* a file could not be read or written */
  SS_ERR_PARSE,       /* malformed input (XML syntax, numbers, ...) */
  SS_ERR_VALUE,       /* a value out of its allowed range */
  SS_ERR_UNSUPPORTED, /* a valid request this build does not support */
  SS_ERR_STATE,       /* the call is not allowed in the current state */
  SS_ERR_NUMERIC,     /* the simulation produced a non-finite state */
  SS_ERR_NOTFOUND     /* a named object does not exist */
} ssStatus;

/* A structured error, filled by the library and reported by the caller.
 * file and line name the input location when the error comes from a file
 * (line 0 when unknown).  message is one sentence without a trailing period
 * that says what is wrong and, where it helps, what is allowed. */
typedef struct ssError {
  ssStatus code;
  char file[512];
  int line;
  char message[1024];
} ssError;

/* Fill err (may be NULL) and return code.  printf-style message. */
ssStatus ss_error_set(ssError *err, ssStatus code, const char *file, int line,
                      const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;
void ss_error_clear(ssError *err);
const char *ss_status_name(ssStatus code);

/* ---------------------------------------------------------------------- */
/* soil material and constitutive law (DESIGN 2.3-2.5); pure functions     */

typedef struct ssSoilMaterial {
  double bekker_kc;            /* cohesive modulus k_c (Pa m^(1-n)) */
  double bekker_kphi;          /* frictional modulus k_phi (Pa / m^n) */
  double sinkage_exponent;     /* n (-) */
  double elastic_stiffness;    /* K_e, un/reloading stiffness (Pa / m) */
  double damping;              /* D, loading-only viscosity (Pa s / m) */
  double cohesion;             /* c (Pa) */
  double friction_coefficient; /* mu = tan(phi) (-) */
  double shear_displacement;   /* K_j, Janosi-Hanamoto modulus (m); 0 = full
                                  (and any K_j whose 1/K_j overflows) */
} ssSoilMaterial;

/* The documented defaults (illustrative, not a calibrated soil). */
ssSoilMaterial ss_soil_material_default(void);
/* SS_OK, or SS_ERR_VALUE with a message naming the field and its value. */
ssStatus ss_soil_material_validate(const ssSoilMaterial *mat, ssError *err);

/* Bekker envelope p_y = (k_c/b + k_phi) s^n for sinkage s >= 0 (Pa). */
double ss_soil_envelope(const ssSoilMaterial *mat, double b, double s);
/* d p_y / d s (Pa/m); finite for s > 0. */
double ss_soil_envelope_slope(const ssSoilMaterial *mat, double b, double s);
/* Elastic branch p_e = K_e (s - s_p) (Pa); may be negative for s < s_p. */
double ss_soil_elastic(const ssSoilMaterial *mat, double s, double s_p);
/* Static pressure p = min(p_e, p_y) if s > s_p, else 0 (Pa). */
double ss_soil_pressure(const ssSoilMaterial *mat, double b, double s,
                        double s_p);
/* Permanent sinkage after reaching s: max(s_p, s - p/K_e) (m). */
double ss_soil_plastic_update(const ssSoilMaterial *mat, double b, double s,
                              double s_p);
/* Loading viscosity p_v = D max(sdot, 0) (Pa); sdot > 0 pushes down. */
double ss_soil_viscous(const ssSoilMaterial *mat, double sdot);
/* Mohr-Coulomb strength tau_f = c + mu p_n (Pa), p_n >= 0. */
double ss_soil_shear_strength(const ssSoilMaterial *mat, double p_n);
/* Janosi-Hanamoto limit tau_max = tau_f (1 - exp(-j/K_j)) (Pa). */
double ss_soil_shear_limit(const ssSoilMaterial *mat, double p_n, double j);
/* d tau_max / d j (1/m * Pa). */
double ss_soil_shear_limit_slope(const ssSoilMaterial *mat, double p_n,
                                 double j);

/* ---------------------------------------------------------------------- */
/* model: what the world is                                                */

typedef enum ssGeomType {
  SS_GEOM_BOX = 0,  /* size = full edge lengths x, y, z */
  SS_GEOM_SPHERE,   /* size[0] = radius */
  SS_GEOM_CYLINDER, /* size[0] = radius, size[1] = length along local z */
  SS_GEOM_CAPSULE,  /* size[0] = radius, size[1] = distance between centres */
  SS_GEOM_MESH      /* triangle mesh (ssModel.mesh); size = its bounding
                       box's edge lengths */
} ssGeomType;

typedef enum ssJointType {
  SS_JOINT_FIXED = 0,
  SS_JOINT_REVOLUTE,   /* 1 DOF about axis (continuous = revolute, no limits) */
  SS_JOINT_PRISMATIC,  /* 1 DOF along axis */
  SS_JOINT_SPHERICAL,  /* 3 DOF ball joint: quaternion q, local angular velocity */
  SS_JOINT_FLOATING    /* 6 DOF: position + quaternion, world lin/ang velocity */
} ssJointType;

typedef enum ssClosureType {
  SS_CLOSURE_PIN = 0,  /* point on body1 coincides with point on body2 */
  SS_CLOSURE_DISTANCE, /* |p1 - p2| = length */
  SS_CLOSURE_EQUALITY  /* q(joint1) = ratio q(joint2) + offset */
} ssClosureType;

typedef enum ssSysType {
  SS_SYS_FREE = 0,   /* single rigid body, 6 DOF: nq = 7, nv = 6 */
  SS_SYS_STATIC,     /* single fixed body: nq = 7 (pose), nv = 0 */
  SS_SYS_ARTICULATED /* tree of links with loop closures (later issue) */
} ssSysType;

/* Solver and integration options: part of the world, saved in exports. */
typedef struct ssOption {
  double timestep;           /* dt (s) */
  double gravity[3];         /* (m/s^2) */
  int solver_max_sweeps;     /* Gauss-Seidel sweep cap */
  double solver_tolerance;   /* relative impulse change that ends the sweeps */
  double scalar_tolerance;   /* residual tolerance of the per-point solves */
  int terrain_warm_start;    /* 1: start from the cached tractions */
  double contact_margin;     /* (m) points closer than this beyond the
                                collider's reach in the step (its speed
                                towards the support at the free velocity,
                                all forces but the contacts' applied,
                                times dt) become contacts; default 0.002:
                                what the reach cannot see, the contacts'
                                own change of that velocity within the
                                step (2 m/s at dt = 1 ms) */
  double rigid_erp;          /* fraction of rigid penetration (or of a joint
                                past its limit) removed per step, by a
                                push that moves positions only
                                (ss_solver_push) */
} ssOption;

ssOption ss_option_default(void);

/* Coulomb contact properties between two rigid materials. */
typedef struct ssMaterialPair {
  int mat1, mat2;               /* material indices (mat1 <= mat2) */
  double friction;              /* Coulomb coefficient (-) */
  double restitution;           /* (-) */
  double restitution_threshold; /* approach speed below which e = 0 (m/s) */
} ssMaterialPair;

/* How a height map's heights were given in the scene (export writes them
 * back explicitly whatever the source). */
typedef enum ssHfieldSource {
  SS_HFIELD_EXPLICIT = 0,
  SS_HFIELD_PNG,
  SS_HFIELD_TEXT,
  SS_HFIELD_GENERATED
} ssHfieldSource;

typedef struct ssModel {
  ssOption opt;

  /* systems: independent dynamic units (a single body or an articulated
   * system); what --remove and the CSV columns name */
  int nsys;
  char **sys_name;      /* (nsys) */
  int *sys_type;        /* (nsys) ssSysType */
  int *sys_qadr;        /* (nsys) first index into qpos */
  int *sys_nq;          /* (nsys) */
  int *sys_vadr;        /* (nsys) first index into qvel */
  int *sys_nv;          /* (nsys) */
  int *sys_bodyadr;     /* (nsys) first body */
  int *sys_nbody;       /* (nsys) */
  int *sys_line;        /* (nsys) line in the scene file (0 if built in code) */
  int *sys_fixed;       /* (nsys) articulated: 1 if the base is welded */
  char **sys_source;    /* (nsys) articulated: URDF path ("" otherwise);
                           absolute and normalised when read from a scene */
  char **sys_resdir;    /* (nsys) articulated: resource folder ("" if none),
                           likewise */

  int nq, nv;           /* generalized coordinate / velocity counts */
  double *qpos0;        /* (nq) initial positions (pos, quat for free bodies) */
  double *qvel0;        /* (nv) initial velocities (lin_vel, ang_vel world) */

  /* bodies: rigid links (a single rigid body is one body whose frame is
   * its centre of mass) */
  int nbody;
  char **body_name;     /* (nbody) */
  int *body_sys;        /* (nbody) owning system */
  double *body_mass;    /* (nbody) (kg) */
  double *body_inertia; /* (nbody x 9) about the centre of mass, body frame */
  int *body_inertia_given; /* (nbody) 1 if the scene overrode it */
  double *body_ipos;    /* (nbody x 3) centre of mass in the body frame */

  /* joints: every articulated link has one joint to its parent */
  int *body_parent;     /* (nbody) parent body, -1 for a system's root */
  int *body_jnttype;    /* (nbody) ssJointType of the joint to the parent */
  char **body_jntname;  /* (nbody) joint name ("" for single bodies) */
  double *body_jntpos;  /* (nbody x 3) joint frame in the parent frame; for
                           a fixed-base root: its pose in the world */
  double *body_jntquat; /* (nbody x 4) */
  double *body_jntaxis; /* (nbody x 3) unit axis in the joint (child) frame */
  int *body_qadr;       /* (nbody) first qpos of the joint (-1: none) */
  int *body_dofadr;     /* (nbody) first qvel of the joint (-1: none) */
  int *body_ndof;       /* (nbody) 0, 1, 3 or 6 */
  double *body_jntdamping;   /* (nbody) viscous joint damping */
  double *body_jntstiffness; /* (nbody) joint spring stiffness */
  double *body_jntref;       /* (nbody) joint spring rest position */
  int *body_jntlimited;      /* (nbody) 1: range applies */
  double *body_jntrange;     /* (nbody x 2) lower, upper (rad or m) */

  /* loop closures of articulated systems (DESIGN 3) */
  int neq;
  char **eq_name;       /* (neq) */
  int *eq_type;         /* (neq) ssClosureType */
  int *eq_sys;          /* (neq) */
  int *eq_body;         /* (neq x 2) bodies (pin, distance) or the bodies
                           whose joints are coupled (equality) */
  double *eq_anchor;    /* (neq x 6) anchor1 in body1, anchor2 in body2 */
  double *eq_data;      /* (neq x 2) distance: length; equality: ratio, offset */
  int *eq_line;         /* (neq) source line */

  /* point-to-point spring-dampers between two bodies (coil-overs) */
  int nspring;
  char **spring_name;   /* (nspring) */
  int *spring_body;     /* (nspring x 2) */
  double *spring_anchor;/* (nspring x 6) in each body's frame */
  double *spring_param; /* (nspring x 3) stiffness (N/m), damping (N s/m),
                           rest length (m) */

  /* joint PD controllers (the scene's <pd>) */
  int npd;
  int *pd_body;         /* (npd) the controlled joint is this body's joint */
  double *pd_gain;      /* (npd x 3) p_gain, d_gain, effort_limit (0 = none) */
  double *pd_target0;   /* (npd x 2) initial position and velocity targets */

  /* geoms: colliders and visuals attached to bodies */
  int ngeom;
  int *geom_type;       /* (ngeom) ssGeomType */
  int *geom_body;       /* (ngeom) */
  double *geom_size;    /* (ngeom x 3) see ssGeomType */
  double *geom_pos;     /* (ngeom x 3) in the body frame */
  double *geom_quat;    /* (ngeom x 4) in the body frame */
  int *geom_material;   /* (ngeom) rigid material index */
  double *geom_rgba;    /* (ngeom x 4) display colour */
  int *geom_group;      /* (ngeom) bit 1: collides, bit 2: drawn */
  int *geom_mesh;       /* (ngeom) mesh index, -1 for primitives */

  /* triangle meshes (struct ssMesh, see mesh.h) */
  int nmesh;
  struct ssMesh **mesh; /* (nmesh) */
  char **mesh_path;     /* (nmesh) file each mesh came from */
  double *mesh_scale;   /* (nmesh x 3) the scale baked into its vertices */

  /* rigid ground planes z = height */
  int nplane;
  char **plane_name;    /* (nplane) */
  double *plane_height; /* (nplane) (m) */
  int *plane_material;  /* (nplane) */

  /* height maps: rigid, or soil beds when hfield_soil is set (DESIGN 2.1) */
  int nhfield;
  char **hfield_name;     /* (nhfield) */
  int *hfield_nx;         /* (nhfield) vertices along local x, >= 2 */
  int *hfield_ny;         /* (nhfield) vertices along local y, >= 2 */
  double *hfield_size;    /* (nhfield x 2) x_size, y_size (m) */
  double *hfield_center;  /* (nhfield x 2) center_x, center_y, local frame (m) */
  double *hfield_pos0;    /* (nhfield x 3) initial pose: position */
  double *hfield_quat0;   /* (nhfield x 4) initial pose: orientation */
  int *hfield_adr;        /* (nhfield) first vertex in hfield_data / soil */
  int *hfield_material;   /* (nhfield) rigid material (rigid maps) */
  int *hfield_source;     /* (nhfield) ssHfieldSource */
  int *hfield_soil;       /* (nhfield) 1: soil bed, 0: rigid height map */
  ssSoilMaterial *hfield_soilmat; /* (nhfield) soil material (soil beds) */
  double *hfield_zrange;  /* (nhfield x 2) min, max undeformed height */
  int nhfielddata;        /* total vertices of all height maps */
  double *hfield_data;    /* (nhfielddata) undeformed heights, j*nx + i */

  /* materials: names; pair table with a default */
  int nmaterial;
  char **material_name;   /* (nmaterial); index 0 is "default" */
  ssMaterialPair material_default;
  int npair;
  ssMaterialPair *pair;   /* (npair) */

  /* external forces: constant loads on a body over [start, end) */
  int nxforce;
  int *xforce_body;       /* (nxforce) */
  double *xforce_force;   /* (nxforce x 3) world frame (N) at the COM */
  double *xforce_torque;  /* (nxforce x 3) world frame (N m) */
  double *xforce_time;    /* (nxforce x 2) start, end (s) */

  /* default camera for rendering (DESIGN 4.1) */
  int camera_given;
  double camera_pos[3];
  double camera_look_at[3];
  double camera_fov_deg;    /* vertical field of view, in (0, 180) degrees:
                               the camera above's, or the automatic one's */
  char camera_follow[128];

  /* where the model came from (for messages and [THIS_DIR]) */
  char source_path[512];

  /* builder capacities (internal) */
  int cap_sys, cap_body, cap_geom, cap_plane, cap_hfield, cap_hfielddata,
      cap_material, cap_pair, cap_xforce, cap_q, cap_v, cap_eq, cap_spring,
      cap_pd, cap_mesh;
} ssModel;

/* ---------------------------------------------------------------------- */
/* model builder                                                           */

/* Definition of a single rigid body (Box2D-style def with defaults). */
/* A single rigid body.  pos is its centre of mass for every shape: a
 * primitive's centre, or a mesh's centroid (shape SS_GEOM_MESH: the body
 * frame has the mesh file's axes, its origin at the centroid of the solid
 * the mesh encloses, so the mesh sits at -centroid in it). */
typedef struct ssBodyDef {
  const char *name;
  ssGeomType shape;
  double size[3];        /* see ssGeomType (not used by a mesh) */
  const char *mesh_path; /* SS_GEOM_MESH: the file (ss_mesh_load) */
  double mesh_scale[3];  /* SS_GEOM_MESH: per-axis scale, each non-zero
                            (default 1 1 1) */
  double mass;           /* (kg) > 0 for dynamic bodies */
  int inertia_given;     /* 1: use inertia[] instead of the uniform solid
                            (required for a mesh enclosing no volume) */
  double inertia[6];     /* xx xy xz yy yz zz about the COM, body frame */
  int is_static;         /* 1: fixed in place */
  const char *material;  /* rigid material name (NULL = "default") */
  double pos[3];         /* COM position, world (m) */
  double quat[4];        /* orientation w x y z (normalized on add) */
  double lin_vel[3];     /* world (m/s) */
  double ang_vel[3];     /* world (rad/s) */
  double rgba[4];        /* display colour; alpha 0 = pick a default */
  int line;              /* scene line for messages (0 if none) */
} ssBodyDef;

ssBodyDef ss_body_def_default(void);

typedef struct ssHfieldDef {
  const char *name;
  int nx, ny;            /* vertex counts >= 2 */
  double x_size, y_size; /* (m) > 0 */
  double center_x, center_y;
  const double *height;  /* (nx*ny) undeformed heights, j*nx + i */
  double pos[3];         /* bed pose in the world */
  double quat[4];
  const char *material;  /* rigid material name (NULL = "default") */
  int source;            /* ssHfieldSource */
  int soil;              /* 1: soil bed */
  ssSoilMaterial soilmat;
  int line;
} ssHfieldDef;

ssHfieldDef ss_hfield_def_default(void);

ssModel *ss_model_new(void);
void ss_model_free(ssModel *m); /* accepts NULL */

/* Each add returns the new object's index (>= 0) or -1 with err filled.
 * Names must be unique among systems, planes and height maps. */
int ss_model_add_body(ssModel *m, const ssBodyDef *def, ssError *err);
int ss_model_add_plane(ssModel *m, const char *name, double height,
                       const char *material, int line, ssError *err);
int ss_model_add_hfield(ssModel *m, const ssHfieldDef *def, ssError *err);
/* Find or add a rigid material by name. */
int ss_model_material(ssModel *m, const char *name);
/* Set the friction/restitution of a material pair (or of the default when
 * both names are NULL). */
ssStatus ss_model_set_pair(ssModel *m, const char *name1, const char *name2,
                           double friction, double restitution,
                           double restitution_threshold, ssError *err);
const ssMaterialPair *ss_model_pair(const ssModel *m, int mat1, int mat2);
int ss_model_add_xforce(ssModel *m, int body, const double force[3],
                        const double torque[3], double start, double end,
                        ssError *err);
/* Look-ups by name; -1 when absent. */
int ss_model_find_sys(const ssModel *m, const char *name);
int ss_model_find_hfield(const ssModel *m, const char *name);
/* Checks the whole model (options, materials, sizes); call once built.
 * ss_step calls it too, since a program may edit m->opt and
 * m->hfield_soilmat between steps. */
ssStatus ss_model_validate(const ssModel *m, ssError *err);
/* The part of it that checks every soil bed's material (DESIGN 2.5). */
ssStatus ss_model_validate_soil(const ssModel *m, ssError *err);
/* Effective width b of a geom on a bed whose normal is n_bed (DESIGN 2.4),
 * given the geom's world rotation (row-major 3x3). */
double ss_geom_width(const ssModel *m, int geom, const double xmat[9],
                     const double n_bed[3]);

/* ---------------------------------------------------------------------- */
/* data: where the world is now                                            */

/* Statistics of the last step (DESIGN 2.6). */
typedef struct ssStepStats {
  int soil_contacts;        /* quadrature points near bodies */
  int soil_loaded;          /* of those, loaded ones */
  double soil_contact_area; /* area of the loaded points (m^2) */
  double soil_normal_force; /* total normal force of the loaded points (N) */
  int rigid_contacts;       /* rigid (Coulomb) contacts */
  int sweeps;               /* Gauss-Seidel sweeps used */
  int newton;               /* iterations of the Newton phase that started
                               the sweeps (0: it declined or did not apply) */
  int newton_sticking;      /* soil points that phase solved in impulse form
                               (sticking or nearly; see README) */
  int newton_linear;        /* 1: that phase's answer is the end of its last
                               step by the laws' linear model, not evaluated
                               there (newton.c, apply_linear; checked as
                               every answer is) */
  int creep;                /* passes over the points of the creeping solve
                               among the sweeps (solver.h, ss_newton_creep;
                               0: it did not run); newton counts them too */
  double residual;          /* final relative impulse change */
  int converged;            /* 1 if the tolerance was met */
  /* wall time of each stage of the last step (s): forward kinematics, free
   * velocity, contact generation, solve, soil update, integration */
  double time_stage[6];
} ssStepStats;

/* One step's answer of the Newton phase (solver internals, newton.c): the
 * contacts' effect on its unknowns, from which later steps start */
typedef struct ssNewtonRecord {
  long step;              /* the step it solved (d->step before it); -1: none */
  int n, cap;             /* its unknowns (6 per contact link or body and bed,
                             1 per joint row); room in c */
  uint64_t key;           /* which unknowns (a hash of the links, beds and
                             rows) */
  double *c;              /* (n) y - y_free at the answer */
} ssNewtonRecord;

typedef struct ssContact ssContact; /* solver contact (internal layout) */
typedef struct ssWarmEntry ssWarmEntry;

typedef struct ssData {
  const ssModel *model;   /* the model this data was made for */
  double time;            /* simulated time (s) */
  long step;              /* completed steps */
  int in_step;            /* 1 while ss_step runs: state setters refuse */

  double *qpos;           /* (nq) free body: COM position (3), quat (4,
                             w x y z); finite, or a step refuses it; a
                             step makes a quaternion written here unit
                             first (a zero one the identity) */
  double *qvel;           /* (nv) free body: lin vel (3), ang vel (3), world;
                             each within SS_SPEED_MAX, or a step refuses it */
  unsigned char *sys_active; /* (nsys) 0 once removed from the world */
  double *pd_target;      /* (npd x 2) position and velocity targets */

  /* derived kinematics (ss_forward), outputs: a step forms them from
   * qpos, and keeps an articulated system's where its qpos is the one
   * they were formed at; write qpos, never these */
  double *body_xpos;      /* (nbody x 3) origin of the body's frame, world:
                             a free body's centre of mass, an articulated
                             link's URDF frame (body_xipos: its centre of
                             mass) */
  double *body_xquat;     /* (nbody x 4) */
  double *body_xmat;      /* (nbody x 9) rotation, row-major */
  double *geom_xpos;      /* (ngeom x 3) */
  double *geom_xmat;      /* (ngeom x 9) */
  double *body_iinv;      /* (nbody x 9) inverse inertia, world frame */
  double *body_xipos;     /* (nbody x 3) centre of mass, world */
  struct ssArtWork **art; /* (nsys) articulated workspaces (NULL otherwise) */
  double closure_error;   /* largest loop-closure violation after the last
                             step (m for points, rad or m for joints) */

  /* height map poses: move a bed between steps with ss_hfield_set_pose,
   * which checks the pose, makes the quaternion unit and drops the warm
   * start (a step refuses a pose written here directly that is not
   * finite or whose quaternion is not unit) */
  double *hfield_pos;     /* (nhfield x 3) */
  double *hfield_quat;    /* (nhfield x 4) */

  /* soil state, one value per vertex of every soil bed (zero elsewhere) */
  double *soil_sinkage;   /* (nhfielddata) total sinkage s >= 0 (m) */
  double *soil_plastic;   /* (nhfielddata) permanent sinkage s_p (m) */
  double *soil_shear;     /* (nhfielddata) accumulated shear j (m) */
  int nsoil_loaded, cap_soil_loaded;
  int *soil_loaded;       /* (nsoil_loaded) vertices with s > s_p or j > 0:
                             the ones that recover when their load goes */

  /* solver */
  int ncontact, cap_contact;
  ssContact *contact;     /* (ncontact) contacts of the last step */
  double *jac;            /* contact Jacobians and responses (internal) */
  size_t cap_jac;
  double *qvel_free;      /* (nv) velocity before contact impulses */
  double *qvel_push;      /* (nv) the step's push out of penetrations, which
                             moves the positions and not the velocities
                             (ss_solver_push; scratch within a step) */
  double *qvel_start;     /* (nv) velocity at the step's start, before its
                             loads: a rigid contact's approach speed for
                             restitution (ss_step sets it) */
  int nwarm, cap_warm;
  ssWarmEntry *warm;      /* (nwarm) warm-start cache */
  int cap_warm_next;
  ssWarmEntry *warm_next; /* the next cache while it is sorted (scratch) */
  ssNewtonRecord newton_rec[3]; /* the Newton phase's start (newton.c):
                             the answers of the last two steps it solved
                             ([0] the later), and this step's ([2]) until
                             ss_solver_store_warm keeps it; saved in
                             checkpoints */
  double *geom_patch;     /* (ngeom x 3) each collider's soil patch when the
                             cache is stored: fastest loaded slip, sums of
                             normal and of tangential impulses (scratch) */
  struct ssPowTable *hfield_pow; /* (nhfield) each soil bed's s^(n-1) by
                             table (ss_math.h), formed for the exponent its
                             material holds before each step's contacts
                             (internal) */
  int solver_full;        /* 1: every contact updates the full velocity
                             (no packed link groups); the reference path of
                             the tests, equal to the default at round-off */
  int solver_gs_only;     /* 1: no Newton phase before the sweeps and no
                             creeping solve among them (solver.h): the
                             sweeps alone, the reference path of the
                             tests */
  int solver_no_predict;  /* 1: the Newton phase starts from the warm start
                             alone, not from its last answers extrapolated
                             (newton.c); the reference path of the tests */
  int solver_no_linear_end; /* 1: the Newton phase evaluates the laws at
                             the end of its last step before its check, as
                             at every other step, instead of applying its
                             linear model there (newton.c); the reference
                             path of the tests */
  int solver_warm_eager;  /* 1: the warm start is applied at once, also
                             where the Newton phase may start from its
                             prediction (solver.c); the reference path of
                             the tests, the same bits */
  int solver_settled;     /* 1: the last solve's answer was its warm start
                             as it came (the Newton phase's settled body),
                             whose laws' impulses the cache keeps (internal,
                             solver.c) */
  int warm_pending;       /* 1: the warm start's cache entries are matched
                             (ssContact.warm_entry) but their impulses are
                             not yet in the contacts and qvel
                             (ss_solver_warm_apply; internal, solver.c) */
  int warm_creep_rates;   /* the pending warm start extrapolates creeping
                             colliders too (internal) */
  int contact_deep;       /* the step's rigid contacts, pair contacts and
                             joint limits that penetrate or pass their
                             limit (g0 < 0), counted as they are made:
                             none, and ss_solver_push has nothing to do
                             (internal) */
  struct ssNewtonWork *newton; /* the Newton phase's workspace (internal) */
  ssStepStats stats;
} ssData;

ssData *ss_data_new(const ssModel *m);
void ss_data_free(ssData *d); /* accepts NULL */
/* Back to the model's initial state, soil state zero, time 0. */
void ss_data_reset(const ssModel *m, ssData *d);
/* Recompute derived kinematics (body and geom poses) from qpos. */
void ss_forward(const ssModel *m, ssData *d);

/* One time step.  SS_ERR_NUMERIC (naming the step and body) if a velocity
 * became non-finite or absurd (above SS_SPEED_MAX m/s or rad/s) or a
 * position non-finite.  SS_ERR_VALUE, before anything is stepped, if the
 * state it starts from is already so, a bed's pose is non-finite or its
 * quaternion not unit, the clock is outside what <clock> allows (as
 * written into d between steps) or the time would not stay finite, or an
 * option or a soil bed's material is invalid (as edited into m between
 * steps; ss_model_validate).  SS_ERR_STATE, nothing stepped, when d->step
 * is LONG_MAX: the step counter's limit.  A step
 * that fails for any reason leaves d exactly as it was (positions,
 * velocities, soil, warm-start cache, statistics). */
ssStatus ss_step(const ssModel *m, ssData *d, ssError *err);

/* Remove a system from the world (from the next step on). */
ssStatus ss_remove(const ssModel *m, ssData *d, const char *name, ssError *err);

/* soil state API (valid only between steps; DESIGN 2.2) */
ssStatus ss_soil_get_state(const ssModel *m, const ssData *d, int hfield,
                           double *sinkage, double *plastic, double *shear,
                           ssError *err);
ssStatus ss_soil_set_state(const ssModel *m, ssData *d, int hfield,
                           const double *sinkage, const double *plastic,
                           const double *shear, ssError *err);
ssStatus ss_soil_reset(const ssModel *m, ssData *d, int hfield, ssError *err);
/* Undeformed heights (nx*ny), valid for rigid maps too. */
const double *ss_hfield_heights(const ssModel *m, int hfield);
/* Height edits: z holds nx*ny heights (as ss_hfield_heights returns
 * them); allowed on rigid maps, SS_ERR_STATE on soil beds, SS_ERR_VALUE
 * (nothing changed) where one is not finite. */
ssStatus ss_hfield_set_heights(ssModel *m, int hfield, const double *z,
                               ssError *err);
/* Recompute hfield_zrange after the heights changed (builders call it). */
void ss_hfield_update_range(ssModel *m, int hfield);
ssStatus ss_hfield_set_pose(const ssModel *m, ssData *d, int hfield,
                            const double pos[3], const double quat[4],
                            ssError *err);
/* Current surface height of vertex (i, j) in the bed frame (m). */
double ss_hfield_surface(const ssModel *m, const ssData *d, int hfield, int i,
                         int j);

/* ---------------------------------------------------------------------- */
/* scenes (world XML, DESIGN 4.1)                                          */

/* Read a world XML scene; on success *mout and *dout own the world.
 * Errors carry the file and line. */
ssStatus ss_scene_load(const char *path, ssModel **mout, ssData **dout,
                       ssError *err);
/* Same, from a memory buffer; base_path names the file for messages and
 * [THIS_DIR]. */
ssStatus ss_scene_load_buffer(const char *buf, size_t len,
                              const char *base_path, ssModel **mout,
                              ssData **dout, ssError *err);
struct ssAtomicFile; /* an output file, below */
/* Write the whole world (model + current state + soil arrays) as XML,
 * atomically (temporary file, then rename; a stream such as /dev/stdout
 * is written in place, see ss_atomic_open). */
ssStatus ss_scene_export(const ssModel *m, const ssData *d, const char *path,
                         ssError *err);
/* The same into an output opened with ss_atomic_open, left open: the
 * caller commits it, or aborts it on failure.  Paths in the file are
 * written relative to the folder of the path it was opened with. */
ssStatus ss_scene_export_to(const ssModel *m, const ssData *d,
                            struct ssAtomicFile *f, ssError *err);

/* ---------------------------------------------------------------------- */
/* off-screen rendering (DESIGN 6)                                         */

typedef enum ssColorMode {
  SS_COLOR_SINKAGE = 0, /* bed coloured by total sinkage, with a colour bar */
  SS_COLOR_PLASTIC,     /* bed coloured by permanent sinkage (ruts) */
  SS_COLOR_SOIL         /* plain soil colour */
} ssColorMode;

typedef struct ssRenderOptions {
  int width, height;        /* image size in pixels */
  int color_mode;           /* ssColorMode */
  double sinkage_max;       /* colour-bar full scale (m); <= 0: automatic */
  int camera_given;         /* 1: use the camera below, else the model's
                               <camera>, else an automatic overview */
  double camera_pos[3];
  double camera_look_at[3];
  double camera_fov_deg;    /* vertical field of view, in (0, 180) degrees:
                               the camera above's, or the automatic one's */
  char camera_follow[128];  /* system name the camera follows ("" = none) */
} ssRenderOptions;

ssRenderOptions ss_render_options_default(void);
/* 1 when a camera at pos looking at look_at has a direction: two finite
 * points more than 1e-9 m apart (what ss_render_new asks of a camera) */
int ss_camera_valid(const double pos[3], const double look_at[3]);

typedef struct ssRenderer ssRenderer;

/* Create the off-screen context (OSMesa, or EGL surfaceless) and load the
 * model's meshes.  Fails early (bad size, no GL) with a clear message. */
ssRenderer *ss_render_new(const ssModel *m, const ssRenderOptions *opt,
                          ssError *err);
void ss_render_free(ssRenderer *r); /* accepts NULL */
/* Draw the current state into rgba (width*height*4, row 0 at the top). */
ssStatus ss_render_pixels(ssRenderer *r, const ssModel *m, const ssData *d,
                          unsigned char *rgba, ssError *err);
/* Draw the current state and write it as a PNG, atomically. */
ssStatus ss_render_frame(ssRenderer *r, const ssModel *m, const ssData *d,
                         const char *png_path, ssError *err);
/* Top-down rut map of the first soil bed (or hfield >= 0): sinkage or
 * plastic sinkage as colour, colour bar labelled in millimetres, metre
 * scale.  Each side SS_RUT_MAP_MIN_SIDE to 16384 pixels, and the width at
 * least SS_RUT_MAP_MIN_WIDTH (the colour bar and its labels beside the
 * map take 74 pixels at the smallest font; 96 leaves the map 22).  Does
 * not need a GL context. */
#define SS_RUT_MAP_MIN_SIDE 64
#define SS_RUT_MAP_MIN_WIDTH 96
ssStatus ss_render_rut_map(const ssModel *m, const ssData *d, int hfield,
                           int plastic, int width, int height,
                           const char *png_path, ssError *err);
/* The same into an output opened with ss_atomic_open (see below), left
 * open: the caller commits it, or aborts it on failure, so that a program
 * writing several outputs can write them all before it commits any. */
ssStatus ss_render_rut_map_to(const ssModel *m, const ssData *d, int hfield,
                              int plastic, int width, int height,
                              struct ssAtomicFile *af, ssError *err);
/* Whether that rut map could be drawn, all but the soil's values: the
 * bed, the size and the label font, so that a program finds before a
 * long run what would otherwise fail only at its end.  SS_OK, or the
 * error the map would give. */
ssStatus ss_render_rut_map_check(const ssModel *m, int hfield, int width, int height,
                                 const char *png_path, ssError *err);

/* ---------------------------------------------------------------------- */
/* checkpoints (DESIGN 5)                                                  */

/* A checkpoint is a versioned, checksummed binary file holding everything
 * in an ssData that the next step reads: time and step count, qpos, qvel,
 * which systems are in the world, controller targets, bed poses, the soil
 * state of every bed, the solver's warm-start cache, the solver options and
 * the last step's statistics (without the stage wall times).  Restoring it
 * and stepping gives bit-identical results to stepping on from the moment it
 * was written.  The model is not in the file: a checkpoint is restored into
 * a data made for the same world (same counts, masses, joints, colliders,
 * heights, soil materials, time step, gravity, ...), which a fingerprint of
 * the model checks.  The layout is described in checkpoint.c. */

/* What a checkpoint says about itself. */
typedef struct ssCheckpointInfo {
  int version;        /* format version */
  double time;        /* simulated time when it was written (s) */
  long step;          /* completed steps when it was written */
  ssOption opt;       /* the options of the world that wrote it */
  char source[512];   /* that model's source_path ("" if built in code) */
  size_t bytes;       /* size of the checkpoint */
} ssCheckpointInfo;

/* Write the state of d, atomically (temporary file, then rename; see
 * ss_atomic_open).  Only between steps. */
ssStatus ss_checkpoint_save(const ssModel *m, const ssData *d,
                            const char *path, ssError *err);
/* Restore a checkpoint into d, which must have been made for m
 * (ss_data_new(m)), and recompute the derived kinematics.  Refused with a
 * clear message, leaving d unchanged, when the file is not a checkpoint, is
 * truncated or corrupted (checksum), has an unknown version, was written for
 * a different world, or when its solver options (max_sweeps, tolerance,
 * scalar_tolerance, terrain_warm_start, contact_margin, rigid_erp) differ
 * from m->opt: the options are part of the world and the model is const
 * here, so a caller that wants them applies them to its model first with
 * ss_checkpoint_info and ss_option_copy_solver.  Only between steps. */
ssStatus ss_checkpoint_load(const ssModel *m, ssData *d, const char *path,
                            ssError *err);
/* The same in memory: *buf is malloc'd (release it with free()). */
ssStatus ss_checkpoint_save_buffer(const ssModel *m, const ssData *d,
                                   unsigned char **buf, size_t *len,
                                   ssError *err);
ssStatus ss_checkpoint_load_buffer(const ssModel *m, ssData *d,
                                   const void *buf, size_t len, ssError *err);
/* Verify a checkpoint (signature, version, size, checksum) and describe it
 * without a model. */
ssStatus ss_checkpoint_info(const char *path, ssCheckpointInfo *info,
                            ssError *err);
ssStatus ss_checkpoint_info_buffer(const void *buf, size_t len,
                                   ssCheckpointInfo *info, ssError *err);
/* Copy the solver configuration (max_sweeps, tolerance, scalar_tolerance,
 * terrain_warm_start, contact_margin, rigid_erp) from src to dst; the time
 * step and gravity, which define the world, stay as they are. */
void ss_option_copy_solver(ssOption *dst, const ssOption *src);

/* ---------------------------------------------------------------------- */
/* output files: atomic (temporary file, then rename), or streams        */

typedef struct ssAtomicFile {
  void *fp;            /* FILE*, open for writing while active */
  int error;           /* errno of the first failed write, 0 if none */
  int direct;          /* 1: a character device or FIFO, written in place */
  char path[1024];     /* the path as given (messages) */
  char target[1024];   /* the file replaced: path, its symbolic links followed */
  char tmp_path[1056]; /* target.tmpPID while writing; empty for a stream */
} ssAtomicFile;

/* Opens PATH for writing.  What that means depends on what PATH is now
 * (stat, following symbolic links):
 *
 * - nothing: a new file, made by renaming a complete temporary file;
 * - a regular file: replaced by renaming a complete temporary file that
 *   has been given the old file's permission bits (rwx; a 0600 file stays
 *   0600) and, where the system allows it (root; a group the writer is
 *   in), its owner and group;
 * - a symbolic link, to a file or to nothing yet: followed, link after
 *   link, and the file it leads to is written as above, the temporary file
 *   in that file's folder (renaming in the link's folder would put a
 *   regular file in place of the link);
 * - a character device or a FIFO (/dev/null, /dev/stdout, a terminal, a
 *   pipe): written in place, with no temporary file and no rename, which
 *   would put a regular file in place of the device or FIFO (as root,
 *   /dev/null itself); a FIFO's open waits for its reader.  Atomicity does
 *   not apply to a stream: what was written before a failure stays
 *   written;
 * - a directory, a block device, a socket: an error naming the path
 *   ("cannot write: is a directory").
 *
 * The temporary file is TARGET.tmpPID (TARGET.tmpPID.K when that name is
 * taken), created exclusively and never through a symbolic link, so a
 * file or link planted under that name is neither followed nor
 * overwritten. */
ssStatus ss_atomic_open(ssAtomicFile *f, const char *path, ssError *err);
/* The absolute, normalised form of path (malloc'd, the caller frees it;
 * NULL for an empty path or when out of memory): realpath where it
 * exists (links resolved); else its folder's, found the same way (that
 * may not exist yet either), with the last component appended ("." adds
 * nothing, ".." takes one off); a link to nothing counts as the path it
 * names.  The CLI compares outputs by it, the scene reader keeps the
 * files it loaded by it (so that an export can name them). */
char *ss_path_absolute(const char *path);
/* Whether PATH can be written, as ss_atomic_open would write it, without
 * writing it: a temporary file is created and removed; a stream is not
 * opened (a FIFO would wait for its reader, and closing it would give the
 * reader an end of file), only checked for write permission. */
ssStatus ss_atomic_check(const char *path, ssError *err);
/* Writes n bytes; returns 0, or -1 after a failure, whose errno is kept
 * for the message of ss_atomic_commit (later writes do nothing). */
int ss_atomic_write(ssAtomicFile *f, const void *buf, size_t n);
/* Flush, sync, close and rename over the target (a stream: flush and
 * close); on failure (including an earlier failed write, whose reason it
 * reports: "write failed: No space left on device") the temporary file is
 * removed and the old file stays. */
ssStatus ss_atomic_commit(ssAtomicFile *f, ssError *err);
/* Close and delete the temporary file (safe to call after commit); a
 * stream is closed. */
void ss_atomic_abort(ssAtomicFile *f);

#ifdef __cplusplus
}
#endif
#endif /* SOILSIM_H */
