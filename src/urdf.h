/* urdf.h -- URDF files (DESIGN 4.2) parsed into a plain description of
 * links, joints, geometry, loop closures and force elements.  The dynamics
 * build the articulated system from it; this module knows nothing of the
 * model or the solver.
 *
 * Frames follow URDF: a joint's origin places the child link frame in the
 * parent link frame at zero joint position; a link's inertial origin places
 * its centre of mass (and the inertia's axes) in the link frame; visual and
 * collision origins place geometry in the link frame.  rpy is URDF's
 * fixed-axis roll (x), then pitch (y), then yaw (z): R = Rz(yaw) Ry(pitch)
 * Rx(roll), stored as the quaternion w x y z.
 *
 * ---------------------------------------------------------------------------
 * Accepted elements (R = required attribute; others optional, [default]):
 *
 *   <robot name=R version>
 *     <material name=R> <color rgba=R/> <texture filename/> </material>
 *     <link name=R>
 *       <inertial>                                   (at most one)
 *         <origin xyz [0 0 0] rpy [0 0 0]/>
 *         <mass value=R/>                            kg, >= 0 (no
 *                                           <inertial>: mass 0, inertia 0)
 *         <inertia ixx=R ixy=R ixz=R iyy=R iyz=R izz=R/>   kg m^2
 *       </inertial>
 *       <visual name> | <collision name>             (any number)
 *         <origin xyz rpy/>
 *         <geometry>R  exactly one of
 *           <box size="x y z"/>   <sphere radius/>   <cylinder radius length/>
 *           <capsule radius length/>  (length: between the end-sphere centres)
 *           <mesh filename=R scale [1 1 1] (1 or 3 values, each non-zero)/>
 *         </geometry>
 *         <material name> <color rgba/> </material>  (visual only; a name
 *                    alone refers to a named material defined elsewhere)
 *       </visual>
 *     </link>
 *     <joint name=R type=R>   revolute | continuous | prismatic | fixed |
 *                             floating | spherical (planar: not supported)
 *       <parent link=R/>R  <child link=R/>R
 *       <origin xyz rpy/>
 *       <axis xyz [1 0 0]/>     normalised; zero is an error for revolute,
 *                               continuous and prismatic (ignored otherwise)
 *       <limit lower upper effort [0] velocity [0]/>   limited when lower or
 *                               upper is given (the other is then 0, as in
 *                               URDF; lower <= upper) on a revolute or
 *                               prismatic joint; a continuous joint is never
 *                               limited; effort, velocity >= 0 are read
 *                               but not simulated (a scene's <pd
 *                               effort_limit> bounds a drive)
 *       <dynamics damping [0] friction [0] stiffness [0] spring_mount [0]/>
 *                               all >= 0 but spring_mount; stiffness and
 *                               spring_mount are ours: a joint spring
 *                               tau = -stiffness (q - spring_mount) on a
 *                               revolute, continuous or prismatic joint;
 *                               damping there and on a spherical joint;
 *                               a non-zero value a joint cannot take is
 *                               an error (friction: read, not simulated)
 *       <mimic joint=R multiplier [1] offset [0]/>  becomes an equality
 *                               closure q(this) = multiplier q(joint) + offset
 *       <calibration rising falling reference_position/>,
 *       <safety_controller soft_lower_limit soft_upper_limit k_position
 *                          k_velocity/>   checked (names, numbers), not used
 *     </joint>
 *     <constraints>                         (any number; RaiSim's extension)
 *       <pin name body1=R body2=R anchor=R anchor2/>   anchor in body1's
 *                 frame; anchor2 in body2's, default: the point of body2 at
 *                 the anchor in the initial configuration
 *       <distance name body1=R body2=R anchor1 [0] anchor2 [0] length/>
 *                 (ours) |p1 - p2| = length > 0; default: the initial
 *                 distance (stored as -1)
 *       <equality name joint1=R joint2=R ratio [1] offset [0]/>   (ours)
 *                 q1 = ratio q2 + offset; two different 1-DOF joints
 *     </constraints>
 *     <spring name [springN] body1=R body2=R anchor1 [0] anchor2 [0]
 *             stiffness=R damping [0] rest_length/>   (ours) N/m >= 0,
 *                 N s/m >= 0, m >= 0; default rest length: the initial
 *                 distance (stored as -1)
 *     <gazebo>, <transmission>, <ros2_control>, <sensor>, <mujoco>: ignored
 *   </robot>
 *
 * Links and joints are named uniquely; body1/body2 name links (they must
 * differ), joint1/joint2 joints.  closure[] holds the <constraints> entries
 * in document order, then the <mimic> couplings in joint order.
 *
 * Unknown elements and attributes inside the ones read are errors (so are
 * namespaced elements such as xacro:*: expand xacro files first), and so is
 * non-blank text.  Numbers are strict decimal in the C locale (NaN, Inf,
 * overflow, hexadecimal and trailing junk refused); vectors are separated by
 * white space or one comma.
 *
 * Tree.  Every link but one (the root) is the child of exactly one joint;
 * cycles, links with two parents and several roots are errors (use
 * <constraints> for loops).  Links are stored in depth-first order from the
 * root: link 0 is the root and joint k's child is link k + 1, so parents
 * come before children; children follow the document order of their
 * joints.  The link named "world" stands for the world frame: it may carry
 * no inertial, visual or collision and be no joint's child.  When it is the
 * root and its only joint is floating or fixed, both are dropped: the root
 * is that joint's child, world_base is SS_URDF_BASE_FLOATING or
 * SS_URDF_BASE_FIXED and base_pos, base_quat hold the joint's origin (the
 * root's pose in the world).  When it is the root with other joints (a
 * pendulum hinged to the world), it stays as link 0 (massless; it must not
 * move) and world_base is SS_URDF_BASE_FIXED with an identity base pose.  A
 * floating joint anywhere else is an error.  Without a "world" link
 * world_base is SS_URDF_BASE_NONE: the scene decides (floating by
 * default).
 *
 * Mass.  After merging every fixed-joint subtree into its parent, each link
 * whose parent joint has degrees of freedom (and the root freed by a
 * dropped floating joint) must have composite mass > 0 and a positive-
 * definite composite rotational inertia (smallest principal moment above
 * 1e-12 times the largest).  A link with mass > 0 needs a positive-definite
 * inertia of its own; a massless link's inertia must be positive semi-
 * definite.  The root of a tree whose base the scene decides is not checked
 * here: a floating base needs mass, which ss_urdf_check_floating_root
 * checks for the scene.
 *
 * Mesh paths.  package://NAME/REST is looked up as BASE/REST, then as
 * BASE/NAME/REST, where BASE is res_dir when given, else the URDF's folder;
 * file:///ABS is ABS; an absolute path is used as is; a relative path is
 * relative to the URDF's folder (for a buffer: the folder of `path`).  Other
 * URI schemes are errors.  The file must exist and be readable when the
 * URDF is read (so the error can name its line); mesh_path holds the path
 * found.
 *
 * Safety and errors are as for world XML (scene.h): at most
 * SS_URDF_MAX_BYTES, any DOCTYPE refused, no entity expansion, no network,
 * a deny-all external entity loader, libxml2's messages captured, never
 * printed.  Every error has file = the URDF path, line = the line of the
 * element at fault (of the bad number itself in a value over many lines,
 * of the text for stray text), and a message naming the element, attribute, bad value
 * and what is allowed.  Nothing is returned on error.  Not safe to run
 * concurrently with other libxml2 users (libxml2's handlers are global).
 *
 * Example (tests/data/urdf/example.urdf): a crank and a strut on a base,
 * closed by a pin, with a joint spring and a coil-over.
 *
 *   <robot name="linkage">
 *     <link name="base">
 *       <inertial><mass value="5"/>
 *         <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.15" iyz="0" izz="0.18"/>
 *       </inertial>
 *       <collision><geometry><box size="0.6 0.3 0.1"/></geometry></collision>
 *     </link>
 *     <link name="arm">
 *       <inertial><origin xyz="0.2 0 0"/><mass value="1"/>
 *         <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.014" iyz="0" izz="0.014"/>
 *       </inertial>
 *       <visual><geometry><mesh filename="package://linkage/meshes/cube.obj"
 *                                scale="0.4 0.05 0.05"/></geometry></visual>
 *     </link>
 *     <link name="strut">
 *       <inertial><origin xyz="0 0 0.2"/><mass value="0.5"/>
 *         <inertia ixx="0.007" ixy="0" ixz="0" iyy="0.007" iyz="0" izz="0.0003"/>
 *       </inertial>
 *       <collision><origin xyz="0 0 0.2"/>
 *         <geometry><capsule radius="0.02" length="0.4"/></geometry></collision>
 *     </link>
 *     <joint name="shoulder" type="revolute">
 *       <parent link="base"/><child link="arm"/>
 *       <origin xyz="-0.2 0 0.05"/><axis xyz="0 1 0"/>
 *       <limit lower="-1" upper="1" effort="50" velocity="3"/>
 *       <dynamics damping="0.5" stiffness="20" spring_mount="0.1"/>
 *     </joint>
 *     <joint name="strut_hinge" type="continuous">
 *       <parent link="base"/><child link="strut"/>
 *       <origin xyz="0.2 0 0.05" rpy="0 -0.5 0"/><axis xyz="0 1 0"/>
 *     </joint>
 *     <constraints>
 *       <pin body1="arm" body2="strut" anchor="0.4 0 0"/>
 *     </constraints>
 *     <spring name="coilover" body1="base" anchor1="0 0 0.05" body2="arm"
 *             anchor2="0.2 0 0" stiffness="2000" damping="150"/>
 *   </robot>
 * ---------------------------------------------------------------------------
 */
#ifndef SS_URDF_H
#define SS_URDF_H

#include "soilsim.h"

/* Largest URDF read, in bytes: 64 MiB. */
#define SS_URDF_MAX_BYTES (64L * 1024 * 1024)

/* joint types: ssJointType in soilsim.h */

/* How the URDF attaches its root to a link named "world" (see above). */
typedef enum ssUrdfBase {
  SS_URDF_BASE_NONE = 0, /* no "world" link: the scene decides */
  SS_URDF_BASE_FIXED,    /* welded to the world at base_pos, base_quat */
  SS_URDF_BASE_FLOATING  /* freed by a floating joint; initial pose
                            base_pos, base_quat */
} ssUrdfBase;

typedef struct ssUrdfGeom {
  int type;              /* ssGeomType; a mesh is SS_GEOM_MESH */
  double size[3];        /* box: edges; sphere: radius; cylinder, capsule:
                            radius, length; mesh: 0 */
  double pos[3];         /* origin in the link frame */
  double quat[4];        /* w x y z (from URDF rpy) */
  char mesh_path[1024];  /* the mesh file found (see "Mesh paths") */
  double mesh_scale[3];  /* per axis; 1 1 1 for primitives */
  double rgba[4];        /* material colour; alpha 0 = none given */
  int collision;         /* 1: <collision>, 0: <visual> */
  int line;
} ssUrdfGeom;

typedef struct ssUrdfLink {
  char name[128];
  double mass;           /* kg (0 allowed only for links that move with no DOF) */
  double com[3];         /* inertial origin xyz in the link frame */
  double com_quat[4];    /* inertial origin rpy as a quaternion */
  double inertia[6];     /* ixx ixy ixz iyy iyz izz in the inertial frame */
  int ngeom;
  ssUrdfGeom *geom;
  int line;
} ssUrdfLink;

typedef struct ssUrdfJoint {
  char name[128];
  int type;              /* ssJointType */
  int parent, child;     /* link indices */
  double pos[3];         /* origin xyz in the parent link frame */
  double quat[4];        /* origin rpy as a quaternion */
  double axis[3];        /* unit axis in the child (joint) frame */
  int limited;           /* 1 if lower/upper apply */
  double lower, upper;   /* rad or m */
  double effort;         /* N or N m (stored; not simulated) */
  double velocity;       /* rad/s or m/s (stored; not simulated) */
  double damping;        /* <dynamics damping> (N m s/rad or N s/m) */
  double friction;       /* <dynamics friction> (stored; not simulated) */
  double stiffness;      /* <dynamics stiffness> joint spring (extension) */
  double spring_mount;   /* <dynamics spring_mount> rest position (extension) */
  int line;
} ssUrdfJoint;

/* closure types: ssClosureType in soilsim.h */

typedef struct ssUrdfClosure {
  char name[128];        /* <constraints> child's name, "" when it has none
                            (and for a <mimic>'s); two named alike are an
                            error, as two springs are */
  int type;              /* ssClosureType */
  int body1, body2;      /* links (pin, distance) */
  double anchor1[3];     /* in body1's frame */
  double anchor2[3];     /* in body2's frame; has_anchor2 = 0: taken at the
                            initial configuration so the closure holds there */
  int has_anchor2;
  double length;         /* distance; < 0: from the initial configuration */
  int joint1, joint2;    /* equality */
  double ratio, offset;
  int line;
} ssUrdfClosure;

typedef struct ssUrdfSpring {
  char name[128];
  int body1, body2;
  double anchor1[3], anchor2[3]; /* in each body's frame */
  double stiffness;      /* N/m */
  double damping;        /* N s/m */
  double rest_length;    /* m; < 0: the initial distance */
  int line;
} ssUrdfSpring;

typedef struct ssUrdf {
  char name[128];        /* <robot name> */
  char path[1024];       /* the file read */
  int nlink;
  ssUrdfLink *link;
  int njoint;
  ssUrdfJoint *joint;    /* one per non-root link, parents before children */
  int root;              /* root link index */
  int nclosure;
  ssUrdfClosure *closure;
  int nspring;
  ssUrdfSpring *spring;
  int world_base;        /* ssUrdfBase */
  double base_pos[3];    /* with world_base set: the root's pose in the */
  double base_quat[4];   /* world frame (identity when world stays link 0) */
} ssUrdf;

/* Link and joint indices by name, -1 when absent. */
int ss_urdf_find_link(const ssUrdf *u, const char *name);
int ss_urdf_find_joint(const ssUrdf *u, const char *name);

/* Read a URDF; res_dir (may be NULL) resolves package:// mesh paths (see
 * "Mesh paths" above).  Errors name the file and line.  load_buffer reads
 * len bytes of buf, naming `path` in errors and taking relative mesh paths
 * from its folder. */
ssStatus ss_urdf_load(const char *path, const char *res_dir, ssUrdf **out,
                      ssError *err);
ssStatus ss_urdf_load_buffer(const char *buf, size_t len, const char *path,
                             const char *res_dir, ssUrdf **out, ssError *err);
void ss_urdf_free(ssUrdf *u);  /* NULL ok */

/* For a root the scene sets floating (see "Mass"): SS_OK when link 0 with
 * the links fixed to it has mass > 0 and a positive-definite rotational
 * inertia, the check every moving link gets; otherwise an error at the
 * URDF's root link (file = the URDF, line = the link's). */
ssStatus ss_urdf_check_floating_root(const ssUrdf *u, ssError *err);

#endif /* SS_URDF_H */
