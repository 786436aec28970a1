/* test_urdf.c -- URDF reading (DESIGN 4.2) and triangle meshes: the
 * structure of a four-bar with closures, springs and a mimic; rpy frames
 * against hand-computed quaternions; the "world" link; mesh path rules;
 * OBJ, STL and glTF meshes (bounds, scale, ray casts at exact heights, mass
 * properties against closed forms); meshes from arrays against analytic
 * planes; watertight ray casts through edges and vertices; and the
 * catalogue of bad URDFs under tests/data/urdf/bad/, each of which names
 * its expected error line and message in its first line:
 *   <!-- expect: LINE: SUBSTRING --> */
#include "soilsim.h"
#include "urdf.h"
#include "articulated.h"
#include "mesh.h"
#include "ss_math.h"
#include "tap.h"
#include "catalogue.h"

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <string.h>

static const char *srcdir(void)
{
  const char *s = getenv("top_srcdir");
  return s && *s ? s : ".";
}

static void data_path(char *out, size_t cap, const char *rel)
{
  snprintf(out, cap, "%s/tests/data/urdf/%s", srcdir(), rel);
}

static ssStatus load_str(const char *xml, const char *path, ssUrdf **u,
                         ssError *e)
{
  return ss_urdf_load_buffer(xml, strlen(xml), path, NULL, u, e);
}

static int quat_close(const double *q, const double *want, double tol)
{
  /* q and -q are the same rotation */
  double d1 = 0, d2 = 0;
  for (int i = 0; i < 4; i++) {
    d1 = fmax(d1, fabs(q[i] - want[i]));
    d2 = fmax(d2, fabs(q[i] + want[i]));
  }
  return fmin(d1, d2) <= tol;
}

static int vec_close(const double *a, const double *b, int n, double tol)
{
  for (int i = 0; i < n; i++)
    if (!(fabs(a[i] - b[i]) <= tol)) return 0;
  return 1;
}

/* R = Rz(yaw) Ry(pitch) Rx(roll), from the three elementary matrices */
static void rpy_matrix(double r, double p, double y, double R[9])
{
  double Rx[9] = {1, 0, 0, 0, cos(r), -sin(r), 0, sin(r), cos(r)};
  double Ry[9] = {cos(p), 0, sin(p), 0, 1, 0, -sin(p), 0, cos(p)};
  double Rz[9] = {cos(y), -sin(y), 0, sin(y), cos(y), 0, 0, 0, 1};
  double T[9];
  ss_m3_mul(T, Ry, Rx);
  ss_m3_mul(R, Rz, T);
}

/* ---------------------------------------------------------------------- */
/* the four-bar                                                            */

static void test_fourbar(void)
{
  char path[1024], resdir[1024];
  data_path(path, sizeof path, "fourbar.urdf");
  data_path(resdir, sizeof resdir, "");
  ssUrdf *u = NULL;
  ssError e;
  memset(&e, 0, sizeof e);
  ssStatus st = ss_urdf_load(path, NULL, &u, &e);
  if (!ok(st == SS_OK && u, "fourbar.urdf loads")) {
    diag("%s:%d: %s", e.file, e.line, e.message);
    return;
  }
  ok(!strcmp(u->name, "fourbar") && !strcmp(u->path, path), "robot name and path");
  ok(u->nlink == 7 && u->njoint == 6 && u->root == 0,
     "7 links, 6 joints, root is link 0 (got %d, %d, %d)", u->nlink, u->njoint,
     u->root);
  ok(u->world_base == SS_URDF_BASE_NONE && u->base_quat[0] == 1,
     "no world link: the scene decides the base");
  /* depth-first order from the root, children in joint document order */
  const char *order[] = {"ground", "crank", "coupler", "sensor",
                         "rocker", "tip", "slide"};
  int good = 1;
  for (int i = 0; i < 7 && i < u->nlink; i++)
    good &= !strcmp(u->link[i].name, order[i]);
  ok(good, "links in depth-first order: ground crank coupler sensor rocker tip slide");
  const char *jorder[] = {"crank_joint", "coupler_joint", "sensor_joint",
                          "rocker_joint", "tip_joint", "slide_joint"};
  good = 1;
  for (int k = 0; k < u->njoint; k++) {
    const ssUrdfJoint *j = &u->joint[k];
    good &= j->child == k + 1 && j->parent >= 0 && j->parent < j->child &&
            !strcmp(j->name, jorder[k]);
  }
  ok(good, "joint k has child k+1 and a parent before it");
  int jc = ss_urdf_find_joint(u, "crank_joint");
  int jco = ss_urdf_find_joint(u, "coupler_joint");
  int js = ss_urdf_find_joint(u, "sensor_joint");
  int jr = ss_urdf_find_joint(u, "rocker_joint");
  int jsl = ss_urdf_find_joint(u, "slide_joint");
  int jt = ss_urdf_find_joint(u, "tip_joint");
  ok(jc == 0 && jco == 1 && js == 2 && jr == 3 && jt == 4 && jsl == 5,
     "find_joint gives the final indices");
  ok(ss_urdf_find_link(u, "rocker") == 4 && ss_urdf_find_link(u, "nope") == -1 &&
     ss_urdf_find_joint(u, "nope") == -1 && ss_urdf_find_link(NULL, "a") == -1,
     "find_link / find_joint, -1 when absent");
  if (jc != 0 || jco != 1 || js != 2 || jr != 3 || jt != 4 || jsl != 5) {
    ss_urdf_free(u);
    return;
  }
  const ssUrdfJoint *J = u->joint;
  ok(J[jc].type == SS_JOINT_REVOLUTE && J[jc].limited && J[jc].lower == -3 &&
     J[jc].upper == 3 && J[jc].effort == 10 && J[jc].velocity == 5,
     "revolute with limits");
  ok(J[jc].damping == 0.5 && J[jc].friction == 0.1 && J[jc].stiffness == 3 &&
     J[jc].spring_mount == 0.25, "dynamics: damping friction stiffness spring_mount");
  double y[3] = {0, 1, 0};
  ok(vec_close(J[jc].axis, y, 3, 0), "axis 0 2 0 normalised to 0 1 0");
  double xyz[3] = {0.1, 0, 0.05};
  ok(vec_close(J[jc].pos, xyz, 3, 0), "joint origin xyz");
  {
    /* rpy 0.3 -0.2 0.5 against the product of the elementary rotations */
    double R[9], Rq[9];
    rpy_matrix(0.3, -0.2, 0.5, R);
    ss_quat_to_mat(Rq, J[jc].quat);
    ok(vec_close(R, Rq, 9, 1e-15), "rpy 0.3 -0.2 0.5 = Rz(0.5) Ry(-0.2) Rx(0.3)");
    double n = sqrt(J[jc].quat[0] * J[jc].quat[0] + J[jc].quat[1] * J[jc].quat[1] +
                    J[jc].quat[2] * J[jc].quat[2] + J[jc].quat[3] * J[jc].quat[3]);
    close_enough(n, 1, 1e-15, "joint quaternion has unit length");
  }
  ok(J[jco].type == SS_JOINT_REVOLUTE && !J[jco].limited && J[jco].lower == 0 &&
     J[jco].upper == 0 && J[jco].effort == 3 && J[jco].velocity == 4,
     "continuous -> revolute, unlimited (lower/upper ignored, effort kept)");
  double d11[3] = {sqrt(0.5), sqrt(0.5), 0};
  ok(vec_close(J[jco].axis, d11, 3, 2.3e-16), "axis 1 1 0 normalised");
  ok(J[jr].type == SS_JOINT_REVOLUTE && !J[jr].limited,
     "revolute without <limit>: unlimited");
  double qz90[4] = {cos(M_PI / 4), 0, 0, sin(M_PI / 4)};
  ok(quat_close(J[jr].quat, qz90, 1e-16), "rpy 0 0 pi/2 = (cos pi/4, 0, 0, sin pi/4)");
  ok(J[js].type == SS_JOINT_FIXED && J[js].axis[0] == 1 && J[js].axis[1] == 0,
     "fixed joint: a zero axis is ignored (default 1 0 0)");
  ok(J[jsl].type == SS_JOINT_PRISMATIC && J[jsl].limited && J[jsl].upper == 0.2 &&
     J[jsl].axis[2] == -1, "prismatic, axis 0 0 -1");
  double sl[3] = {-0.3, 0, 0};
  ok(vec_close(J[jsl].pos, sl, 3, 0), "comma-separated origin -0.3, 0, 0");
  ok(J[jt].type == SS_JOINT_SPHERICAL && !J[jt].limited, "spherical joint");

  /* links */
  const ssUrdfLink *L = u->link;
  int lc = ss_urdf_find_link(u, "coupler");
  ok(L[lc].mass == 1.5 && L[lc].inertia[0] == 0.02 && L[lc].inertia[5] == 0.001,
     "coupler mass and inertia");
  double q2[4] = {0.5, 0.5, 0.5, 0.5};
  ok(quat_close(L[lc].com_quat, q2, 2.3e-16),
     "inertial rpy pi/2 0 pi/2 = (1/2, 1/2, 1/2, 1/2)");
  double c15[3] = {0, 0, 0.15};
  ok(vec_close(L[lc].com, c15, 3, 0), "inertial origin");
  ok(L[lc].ngeom == 2 && L[lc].geom[0].type == SS_GEOM_CAPSULE &&
     L[lc].geom[0].size[0] == 0.02 && L[lc].geom[0].size[1] == 0.3 &&
     !L[lc].geom[0].collision && L[lc].geom[1].type == SS_GEOM_CYLINDER &&
     L[lc].geom[1].collision, "capsule visual and cylinder collision");
  ok(L[lc].geom[0].rgba[0] == 1 && L[lc].geom[0].rgba[3] == 1 &&
     L[lc].geom[1].rgba[3] == 0, "named top-level material; collision has none");
  int ls = ss_urdf_find_link(u, "sensor");
  ok(L[ls].mass == 0 && L[ls].ngeom == 0 && L[ls].com_quat[0] == 1,
     "a massless link on a fixed joint is fine");
  const ssUrdfLink *G = &L[0];
  ok(G->ngeom == 3 && G->geom[0].type == SS_GEOM_BOX && G->geom[0].size[0] == 1 &&
     G->geom[0].size[1] == 0.2 && G->geom[0].size[2] == 0.1,
     "ground: box visual");
  ok(G->geom[0].rgba[2] == 1 && G->geom[0].rgba[3] == 0.5 &&
     G->geom[2].rgba[2] == 1 && G->geom[2].rgba[3] == 0.5,
     "inline named colour, reused by name later");
  {
    char want[1024];
    snprintf(want, sizeof want, "%s/tests/data/urdf/meshes/cube.obj", srcdir());
    ok(G->geom[1].type == SS_GEOM_MESH && G->geom[1].collision &&
       !strcmp(G->geom[1].mesh_path, want) && G->geom[1].mesh_scale[0] == 0.5 &&
       G->geom[1].mesh_scale[2] == 0.5,
       "package://fourbar/meshes/cube.obj -> URDF folder/meshes/cube.obj, scale 0.5 for all axes (%s)",
       G->geom[1].mesh_path);
    snprintf(want, sizeof want, "%s/tests/data/urdf/meshes/tetra.stl", srcdir());
    ok(!strcmp(G->geom[2].mesh_path, want) && G->geom[2].mesh_scale[1] == 2 &&
       G->geom[2].mesh_scale[2] == 3, "relative mesh path, per-axis scale");
    double c90[4] = {cos(M_PI / 4), 0, 0, sin(M_PI / 4)};
    double p1[3] = {0, 0, -0.1};
    ok(quat_close(G->geom[1].quat, c90, 1e-16) && vec_close(G->geom[1].pos, p1, 3, 0),
       "collision origin");
    ok(G->geom[0].line == 26 && G->geom[1].line == 30 && L[lc].line == 7,
       "geometry and link lines (%d %d %d)", G->geom[0].line, G->geom[1].line,
       L[lc].line);
  }

  /* closures: the constraints in document order, then the mimic */
  ok(u->nclosure == 6, "6 closures (got %d)", u->nclosure);
  if (u->nclosure == 6) {
    const ssUrdfClosure *C = u->closure;
    int lrk = ss_urdf_find_link(u, "rocker"), lcr = ss_urdf_find_link(u, "crank");
    int lsl = ss_urdf_find_link(u, "slide"), ltp = ss_urdf_find_link(u, "tip");
    double a1[3] = {0, 0, 0.3}, a2[3] = {0.01, 0.02, 0.03};
    ok(C[0].type == SS_CLOSURE_PIN && C[0].body1 == lc && C[0].body2 == lrk &&
       vec_close(C[0].anchor1, a1, 3, 0) && !C[0].has_anchor2 && C[0].line == 109,
       "pin coupler-rocker, anchor in body1, second anchor from the initial pose");
    ok(C[1].type == SS_CLOSURE_PIN && C[1].body1 == lcr && C[1].has_anchor2 &&
       vec_close(C[1].anchor2, a2, 3, 0), "pin with anchor2");
    ok(C[2].type == SS_CLOSURE_DISTANCE && C[2].body1 == lcr && C[2].body2 == lsl &&
       C[2].length < 0 && C[2].anchor1[2] == 0.1,
       "distance without length: from the initial configuration (-1)");
    ok(C[3].type == SS_CLOSURE_DISTANCE && C[3].body1 == 0 && C[3].body2 == ltp &&
       C[3].length == 0.5 && C[3].anchor1[0] == 0 && C[3].anchor2[0] == 0,
       "distance with length, anchors default to the origins");
    ok(C[4].type == SS_CLOSURE_EQUALITY && C[4].joint1 == jr && C[4].joint2 == jc &&
       C[4].ratio == -1 && C[4].offset == 0.2, "equality rocker = -crank + 0.2");
    ok(C[5].type == SS_CLOSURE_EQUALITY && C[5].joint1 == jsl && C[5].joint2 == jc &&
       C[5].ratio == 0.05 && C[5].offset == 0.1 && C[5].line == 100,
       "mimic -> equality slide = 0.05 crank + 0.1");
  }
  ok(u->nspring == 2, "2 springs");
  if (u->nspring == 2) {
    const ssUrdfSpring *S = u->spring;
    double a1[3] = {0.2, 0, 0.1}, a2[3] = {0, 0, 0.2};
    ok(!strcmp(S[0].name, "coil") && S[0].body1 == 0 &&
       S[0].body2 == ss_urdf_find_link(u, "rocker") && vec_close(S[0].anchor1, a1, 3, 0) &&
       vec_close(S[0].anchor2, a2, 3, 0) && S[0].stiffness == 100 && S[0].damping == 5 &&
       S[0].rest_length == 0.3 && S[0].line == 115, "spring 'coil'");
    ok(!strcmp(S[1].name, "spring1") && S[1].rest_length < 0 && S[1].damping == 0 &&
       S[1].stiffness == 50, "unnamed spring: default name, rest length from the initial pose");
  }
  ss_urdf_free(u);

  /* res_dir: package://fourbar/meshes/cube.obj -> res_dir/meshes/cube.obj */
  char other[1024];
  data_path(other, sizeof other, "fourbar.urdf");
  char *txt = slurp(other, NULL);
  st = ss_urdf_load_buffer(txt, strlen(txt), "/nonexistent/dir/x.urdf", resdir, &u, &e);
  ok(st == SS_ERR_IO && e.line == 35 && strstr(e.message, "meshes/tetra.stl") &&
     !strcmp(e.file, "/nonexistent/dir/x.urdf"),
     "buffer: relative paths come from the folder of the given path, not res_dir");
  if (st != SS_ERR_IO) diag("%d %s:%d: %s", st, e.file, e.line, e.message);
  ss_urdf_free(u);
  free(txt);
}

/* The documented example of the extensions parses as described. */
static void test_example(void)
{
  char path[1024];
  data_path(path, sizeof path, "example.urdf");
  ssUrdf *u = NULL;
  ssError e;
  ssStatus st = ss_urdf_load(path, NULL, &u, &e);
  ok(st == SS_OK && u->nlink == 3 && u->njoint == 2 && u->nclosure == 1 &&
     u->nspring == 1 && u->closure[0].type == SS_CLOSURE_PIN &&
     u->joint[0].stiffness == 20 && u->joint[0].spring_mount == 0.1 &&
     u->joint[1].type == SS_JOINT_REVOLUTE && !u->joint[1].limited &&
     !strcmp(u->spring[0].name, "coilover") && u->spring[0].rest_length < 0 &&
     u->link[1].geom[0].type == SS_GEOM_MESH && u->link[1].geom[0].mesh_scale[0] == 0.4,
     "the documented example (example.urdf) parses as described");
  if (st) diag("%s:%d: %s", e.file, e.line, e.message);
  ss_urdf_free(u);
}

/* ---------------------------------------------------------------------- */
/* small inline robots                                                     */

#define INERTIAL \
  "<inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" " \
  "iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>"

static void test_world(void)
{
  ssUrdf *u = NULL;
  ssError e;
  static const char *floating =
      "<robot name=\"f\">\n"
      "<link name=\"world\"/>\n"
      "<link name=\"base\">" INERTIAL "</link>\n"
      "<link name=\"arm\">" INERTIAL "</link>\n"
      "<joint name=\"free\" type=\"floating\"><parent link=\"world\"/>"
      "<child link=\"base\"/><origin xyz=\"1 2 3\" rpy=\"0 0 1.5707963267948966\"/></joint>\n"
      "<joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"arm\"/></joint>\n"
      "</robot>\n";
  ssStatus st = load_str(floating, "f.urdf", &u, &e);
  double qz90[4] = {cos(M_PI / 4), 0, 0, sin(M_PI / 4)};
  double p[3] = {1, 2, 3};
  ok(st == SS_OK && u->nlink == 2 && u->njoint == 1 && !strcmp(u->link[0].name, "base") &&
     u->world_base == SS_URDF_BASE_FLOATING && vec_close(u->base_pos, p, 3, 0) &&
     quat_close(u->base_quat, qz90, 1e-16) && ss_urdf_find_joint(u, "free") < 0,
     "world --floating--> base: world and joint dropped, base pose kept");
  ss_urdf_free(u);
  u = NULL;

  static const char *fixed =
      "<robot name=\"f\">\n"
      "<link name=\"base\">" INERTIAL "</link>\n"
      "<link name=\"world\"/>\n"
      "<joint name=\"weld\" type=\"fixed\"><parent link=\"world\"/>"
      "<child link=\"base\"/><origin xyz=\"0 0 0.5\"/></joint>\n"
      "</robot>\n";
  st = load_str(fixed, "f.urdf", &u, &e);
  ok(st == SS_OK && u->nlink == 1 && u->njoint == 0 && u->world_base == SS_URDF_BASE_FIXED &&
     u->base_pos[2] == 0.5, "world --fixed--> base: a fixed base at the joint's origin");
  ss_urdf_free(u);
  u = NULL;

  static const char *hinge =
      "<robot name=\"p\">\n"
      "<link name=\"world\"/>\n"
      "<link name=\"arm\"><inertial><origin xyz=\"0 0 -0.5\"/><mass value=\"2\"/>"
      "<inertia ixx=\"0.17\" ixy=\"0\" ixz=\"0\" iyy=\"0.17\" iyz=\"0\" izz=\"0.01\"/></inertial>"
      "<visual><geometry><capsule radius=\"0.03\" length=\"1\"/></geometry>"
      "<material name=\"steel\"><color rgba=\"0.6 0.6 0.65 1\"/></material></visual></link>\n"
      "<joint name=\"hinge\" type=\"continuous\"><parent link=\"world\"/><child link=\"arm\"/>"
      "<origin xyz=\"0 0 2\" rpy=\"0 0 1.5707963267948966\"/><axis xyz=\"0 1 0\"/>"
      "<dynamics damping=\"0.1\" stiffness=\"5\" spring_mount=\"0\"/></joint>\n"
      "<spring name=\"coil\" body1=\"world\" anchor1=\"0.5 0 2\" body2=\"arm\" "
      "anchor2=\"0 0 -0.5\" stiffness=\"100\" damping=\"5\"/>\n"
      "</robot>\n";
  st = load_str(hinge, "p.urdf", &u, &e);
  ok(st == SS_OK && u->nlink == 2 && !strcmp(u->link[0].name, "world") &&
     u->world_base == SS_URDF_BASE_FIXED && u->njoint == 1 && !u->joint[0].limited &&
     u->nspring == 1 && u->spring[0].body1 == 0,
     "world hinged to an arm (the README example): world stays as the fixed root");
  if (st) diag("%s:%d: %s", e.file, e.line, e.message);
  ss_urdf_free(u);
  u = NULL;

  /* a massless link on a moving joint is fine when a massive one is fixed to it */
  static const char *merged =
      "<robot name=\"m\">\n"
      "<link name=\"base\">" INERTIAL "</link>\n"
      "<link name=\"carrier\"/>\n"
      "<link name=\"weight\">" INERTIAL "</link>\n"
      "<joint name=\"j\" type=\"prismatic\"><parent link=\"base\"/><child link=\"carrier\"/>"
      "<axis xyz=\"0 0 1\"/></joint>\n"
      "<joint name=\"w\" type=\"fixed\"><parent link=\"carrier\"/><child link=\"weight\"/>"
      "<origin xyz=\"0 0 1\"/></joint>\n"
      "</robot>\n";
  st = load_str(merged, "m.urdf", &u, &e);
  ok(st == SS_OK, "massless moving link carrying a massive fixed child is accepted");
  ss_urdf_free(u);
  u = NULL;

  /* a massless root of a floating base freed from the world */
  static const char *massless_root =
      "<robot name=\"m\">\n"
      "<link name=\"world\"/>\n"
      "<link name=\"base\"/>\n"
      "<joint name=\"free\" type=\"floating\"><parent link=\"world\"/><child link=\"base\"/></joint>\n"
      "</robot>\n";
  st = load_str(massless_root, "m.urdf", &u, &e);
  ok(st == SS_ERR_VALUE && u == NULL && e.line == 3 &&
     strstr(e.message, "link 'base' moves on floating joint 'free' but is massless"),
     "a floating root freed from the world needs mass");
  /* a root the scene decides is not checked */
  static const char *free_root =
      "<robot name=\"m\"><link name=\"base\"/></robot>\n";
  st = load_str(free_root, "m.urdf", &u, &e);
  ok(st == SS_OK && u->nlink == 1 && u->njoint == 0 && u->world_base == SS_URDF_BASE_NONE,
     "a single massless link parses (the scene checks a floating base)");
  ss_urdf_free(u);
  u = NULL;

  /* composite inertia: a point-like massive link is caught by its own check */
  static const char *flat =
      "<robot name=\"m\">\n"
      "<link name=\"base\">" INERTIAL "</link>\n"
      "<link name=\"disc\"><inertial><mass value=\"1\"/>\n"
      "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"0\"/></inertial></link>\n"
      "<joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"disc\"/></joint>\n"
      "</robot>\n";
  st = load_str(flat, "m.urdf", &u, &e);
  ok(st == SS_ERR_VALUE && e.line == 4 && strstr(e.message, "not positive definite"),
     "a singular inertia of a massive link is refused at its line");

  /* mimic of a spherical joint */
  static const char *mim =
      "<robot name=\"m\">\n"
      "<link name=\"a\">" INERTIAL "</link><link name=\"b\">" INERTIAL "</link>\n"
      "<link name=\"c\">" INERTIAL "</link>\n"
      "<joint name=\"ball\" type=\"spherical\"><parent link=\"a\"/><child link=\"b\"/></joint>\n"
      "<joint name=\"j\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/>\n"
      "<mimic joint=\"ball\"/></joint>\n"
      "</robot>\n";
  st = load_str(mim, "m.urdf", &u, &e);
  ok(st == SS_ERR_VALUE && e.line == 6 && strstr(e.message, "joint 'ball' is a spherical joint"),
     "a mimic of a spherical joint is refused");

  /* NULL arguments and empty input */
  ok(ss_urdf_load_buffer("", 0, "e.urdf", NULL, &u, &e) == SS_ERR_PARSE && e.line == 1 &&
     u == NULL, "an empty buffer is a parse error");
  ok(ss_urdf_load_buffer("x", 1, "e.urdf", NULL, NULL, &e) == SS_ERR_VALUE,
     "NULL output argument");
  ok(ss_urdf_load("/nonexistent/robot.urdf", NULL, &u, &e) == SS_ERR_IO && u == NULL &&
     !strcmp(e.file, "/nonexistent/robot.urdf") && strstr(e.message, "cannot open"),
     "a missing URDF is SS_ERR_IO naming the file");
  ss_urdf_free(NULL);
  ok(1, "ss_urdf_free(NULL) is fine");
}

static void test_paths(void)
{
  char res[1024], xml[4096], want[1100];
  ssUrdf *u = NULL;
  ssError e;
  /* res_dir/REST first, then res_dir/NAME/REST */
  snprintf(res, sizeof res, "%s/tests/data", srcdir());
  snprintf(xml, sizeof xml,
           "<robot name=\"p\"><link name=\"a\"><visual><geometry>"
           "<mesh filename=\"package://urdf/meshes/cube.obj\"/></geometry></visual>"
           "</link></robot>");
  ssStatus st = ss_urdf_load_buffer(xml, strlen(xml), "/x/y.urdf", res, &u, &e);
  snprintf(want, sizeof want, "%s/urdf/meshes/cube.obj", res);
  ok(st == SS_OK && !strcmp(u->link[0].geom[0].mesh_path, want),
     "package://NAME/REST found as res_dir/NAME/REST when res_dir/REST is absent");
  if (st) diag("%s", e.message);
  ss_urdf_free(u);
  u = NULL;
  snprintf(res, sizeof res, "%s/tests/data/urdf", srcdir());
  st = ss_urdf_load_buffer(xml, strlen(xml), "/x/y.urdf", res, &u, &e);
  snprintf(want, sizeof want, "%s/meshes/cube.obj", res);
  ok(st == SS_OK && !strcmp(u->link[0].geom[0].mesh_path, want),
     "package://NAME/REST found as res_dir/REST");
  ss_urdf_free(u);
  u = NULL;
  /* file:// and absolute paths */
  char abs_[1024];
  snprintf(abs_, sizeof abs_, "%s/tests/data/urdf/meshes/tetra.stl", srcdir());
  if (abs_[0] == '/') {
    snprintf(xml, sizeof xml,
             "<robot name=\"p\"><link name=\"a\"><visual><geometry>"
             "<mesh filename=\"file://%s\"/></geometry></visual><collision><geometry>"
             "<mesh filename=\"%s\"/></geometry></collision></link></robot>", abs_, abs_);
    st = ss_urdf_load_buffer(xml, strlen(xml), "/x/y.urdf", NULL, &u, &e);
    ok(st == SS_OK && !strcmp(u->link[0].geom[0].mesh_path, abs_) &&
       !strcmp(u->link[0].geom[1].mesh_path, abs_), "file:///ABS and /ABS");
    ss_urdf_free(u);
    u = NULL;
  } else {
    ok(1, "# SKIP top_srcdir is relative");
  }
  snprintf(xml, sizeof xml,
           "<robot name=\"p\"><link name=\"a\"><visual><geometry>"
           "<mesh filename=\"http://example.com/a.obj\"/></geometry></visual>"
           "</link></robot>");
  st = ss_urdf_load_buffer(xml, strlen(xml), "/x/y.urdf", NULL, &u, &e);
  ok(st == SS_ERR_UNSUPPORTED && strstr(e.message, "unsupported URI scheme"),
     "http:// mesh paths are refused");
  snprintf(xml, sizeof xml,
           "<robot name=\"p\"><link name=\"a\"><visual><geometry>"
           "<mesh filename=\"package://nopath\"/></geometry></visual>"
           "</link></robot>");
  st = ss_urdf_load_buffer(xml, strlen(xml), "/x/y.urdf", NULL, &u, &e);
  ok(st == SS_ERR_PARSE && strstr(e.message, "is not package://NAME/PATH"),
     "package:// without a path is refused");
  /* a folder is not a mesh */
  snprintf(xml, sizeof xml,
           "<robot name=\"p\"><link name=\"a\"><visual><geometry>"
           "<mesh filename=\"meshes\"/></geometry></visual></link></robot>");
  char upath[1024];
  data_path(upath, sizeof upath, "x.urdf");
  st = ss_urdf_load_buffer(xml, strlen(xml), upath, NULL, &u, &e);
  ok(st == SS_ERR_IO && strstr(e.message, "not a regular file"), "a folder is not a mesh");
}

/* Numbers are read in the C locale whatever the process locale. */
static void test_locale(void)
{
  const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "C.UTF-8", NULL};
  const char *got = NULL;
  for (int i = 0; names[i] && !got; i++) got = setlocale(LC_NUMERIC, names[i]);
  ssUrdf *u = NULL;
  ssError e;
  const char *xml = "<robot name=\"l\"><link name=\"a\"><inertial><mass value=\"1.5\"/>"
                    "<inertia ixx=\"0.25\" ixy=\"0\" ixz=\"0\" iyy=\"0.25\" iyz=\"0\" "
                    "izz=\"0.25\"/></inertial></link></robot>";
  ssStatus st = load_str(xml, "l.urdf", &u, &e);
  ok(st == SS_OK && u->link[0].mass == 1.5 && u->link[0].inertia[3] == 0.25,
     "decimal points read in the C locale (process locale %s)", got ? got : "C");
  ss_urdf_free(u);
  setlocale(LC_NUMERIC, "C");
}

static void test_size_cap(void)
{
  size_t n = (size_t)SS_URDF_MAX_BYTES + 1;
  char *big = malloc(n);
  if (!big) {
    ok(1, "# SKIP no memory for the size-cap test");
    return;
  }
  memset(big, ' ', n);
  ssUrdf *u = NULL;
  ssError e;
  ok(ss_urdf_load_buffer(big, n, "big.urdf", NULL, &u, &e) == SS_ERR_IO && u == NULL &&
     strstr(e.message, "larger than the limit"), "a URDF above the size cap is refused");
  free(big);
}

/* ---------------------------------------------------------------------- */
/* meshes                                                                  */

static void test_mesh_obj(void)
{
  char path[1024];
  data_path(path, sizeof path, "meshes/cube.obj");
  ssMesh *m = NULL;
  ssError e;
  ssStatus st = ss_mesh_load(path, NULL, &m, &e);
  if (!ok(st == SS_OK && m, "cube.obj loads")) {
    diag("%s: %s", e.file, e.message);
    return;
  }
  ok(m->ntri == 12 && m->nvert == 8, "12 triangles, 8 shared vertices (got %d, %d)",
     m->ntri, m->nvert);
  double lo[3] = {-0.5, -0.5, 0}, hi[3] = {0.5, 0.5, 1};
  ok(vec_close(m->lo, lo, 3, 0) && vec_close(m->hi, hi, 3, 0), "bounding box");
  ok(m->nnode >= 3 && m->bvh_child[0] >= 0, "a BVH with %d nodes", m->nnode);
  /* every triangle in exactly one leaf */
  int *seen = calloc((size_t)m->ntri, sizeof *seen), good = 1;
  for (int k = 0; k < m->nnode; k++)
    if (m->bvh_child[2 * k] < 0) {
      int first = -1 - m->bvh_child[2 * k], cnt = m->bvh_child[2 * k + 1];
      good &= cnt >= 1 && cnt <= 4;
      for (int i = first; i < first + cnt; i++) seen[m->bvh_tri[i]]++;
    }
  for (int t = 0; t < m->ntri; t++) good &= seen[t] == 1;
  free(seen);
  ok(good, "each triangle in exactly one leaf of at most 4");
  /* rays from below hit the bottom at z = 0, from above the top at z = 1 */
  double d_up[3] = {0, 0, 1}, d_dn[3] = {0, 0, -1}, t = -1;
  double o1[3] = {0.1, 0.2, -5};
  ok(ss_mesh_raycast(m, o1, d_up, &t) && t == 5, "ray from below hits z = 0 (t = %.17g)", t);
  double o2[3] = {0.1, 0.2, 5};
  ok(ss_mesh_raycast(m, o2, d_dn, &t) && t == 4, "ray from above hits z = 1 (t = %.17g)", t);
  double o3[3] = {0.6, 0, -5};
  ok(!ss_mesh_raycast(m, o3, d_up, &t), "ray outside misses");
  double o4[3] = {0, 0, 0.5};
  ok(ss_mesh_raycast(m, o4, d_up, &t) && t == 0.5, "ray from inside hits the top (two-sided)");
  double o5[3] = {0.1, 0.1, 2};
  ok(!ss_mesh_raycast(m, o5, d_up, &t), "ray pointing away misses");
  /* through the diagonal edge, a vertex, and along side faces */
  double oc[3] = {0, 0, -1}, ov[3] = {0.5, 0.5, -1}, oe[3] = {0.5, 0, -1};
  ok(ss_mesh_raycast(m, oc, d_up, &t) && t == 1, "ray through the bottom's diagonal edge hits");
  ok(ss_mesh_raycast(m, ov, d_up, &t) && t == 1,
     "ray through a corner (in two side planes) hits the bottom vertex");
  ok(ss_mesh_raycast(m, oe, d_up, &t) && t == 1, "ray along a side face hits the bottom edge");
  double od[3] = {-2, 0.25, 0.5}, dd[3] = {2, 0, 0};
  ok(ss_mesh_raycast(m, od, dd, &t) && t == 0.75, "horizontal ray, t in units of |d|");
  double dz[3] = {0, 0, 0};
  ok(!ss_mesh_raycast(m, o1, dz, &t), "a zero direction never hits");
  double vol, cen[3], I[9];
  ss_mesh_mass_properties(m, &vol, cen, I);
  close_enough(vol, 1, 1e-15, "cube volume");
  double c0[3] = {0, 0, 0.5};
  ok(vec_close(cen, c0, 3, 1e-15), "cube centroid (0, 0, 0.5)");
  /* a^2 m / 6 with m = volume (unit density) */
  close_enough(I[0], 1.0 / 6, 1e-15, "cube Ixx = a^2 m / 6");
  close_enough(I[4], 1.0 / 6, 1e-15, "cube Iyy");
  close_enough(I[8], 1.0 / 6, 1e-15, "cube Izz");
  ok(fabs(I[1]) < 1e-15 && fabs(I[2]) < 1e-15 && fabs(I[5]) < 1e-15 && I[1] == I[3],
     "cube products of inertia vanish");
  ss_mesh_free(m);

  /* scaled 2 x 3 x 0.5 */
  double s[3] = {2, 3, 0.5};
  st = ss_mesh_load(path, s, &m, &e);
  ok(st == SS_OK, "scaled cube loads");
  if (st) return;
  double slo[3] = {-1, -1.5, 0}, shi[3] = {1, 1.5, 0.5};
  ok(vec_close(m->lo, slo, 3, 0) && vec_close(m->hi, shi, 3, 0), "scaled bounding box");
  double o6[3] = {0.9, -1.4, -1}, o7[3] = {0.9, -1.4, 3};
  ok(ss_mesh_raycast(m, o6, d_up, &t) && t == 1, "scaled: bottom at z = 0");
  ok(ss_mesh_raycast(m, o7, d_dn, &t) && t == 2.5, "scaled: top at z = 0.5");
  double o8[3] = {1.01, 0, -1};
  ok(!ss_mesh_raycast(m, o8, d_up, &t), "scaled: outside x = 1 misses");
  ss_mesh_mass_properties(m, &vol, cen, I);
  close_enough(vol, 3, 1e-14, "scaled volume 2 * 3 * 0.5");
  close_enough(I[0], 3 * (9 + 0.25) / 12, 1e-13, "scaled Ixx = m (b^2 + c^2) / 12");
  close_enough(I[4], 3 * (4 + 0.25) / 12, 1e-13, "scaled Iyy = m (a^2 + c^2) / 12");
  close_enough(I[8], 3 * (4 + 9) / 12.0, 1e-13, "scaled Izz = m (a^2 + b^2) / 12");
  /* normals stay unit */
  int unit = 1;
  for (int v = 0; v < m->nvert; v++)
    unit &= fabs(ss_v3_norm(m->normal + 3 * v) - 1) < 1e-12;
  ok(unit, "vertex normals have unit length");
  ss_mesh_free(m);

  /* a mirroring scale keeps the solid positive and outward */
  double mir[3] = {-1, 1, 1};
  st = ss_mesh_load(path, mir, &m, &e);
  ss_mesh_mass_properties(m, &vol, cen, I);
  double e1[3], e2[3], n[3];
  const int *f = m->tri;
  ss_v3_sub(e1, m->vert + 3 * f[1], m->vert + 3 * f[0]);
  ss_v3_sub(e2, m->vert + 3 * f[2], m->vert + 3 * f[0]);
  ss_v3_cross(n, e1, e2);
  ok(st == SS_OK && fabs(vol - 1) < 1e-15 && n[2] < 0,
     "mirrored cube: winding kept outward (bottom normal -z)");
  ss_mesh_free(m);
}

static void check_tetra(ssMesh *m, const char *fmt, double dz)
{
  char what[128];
  snprintf(what, sizeof what, "%s", fmt);
  ok(m->ntri == 4, "%s: 4 triangles", what);
  double lo[3] = {0, 0, dz}, hi[3] = {1, 1, 1 + dz};
  ok(vec_close(m->lo, lo, 3, 0) && vec_close(m->hi, hi, 3, 0), "%s: bounding box", what);
  double o[3] = {0.25, 0.25, dz - 1}, d[3] = {0, 0, 1}, t;
  ok(ss_mesh_raycast(m, o, d, &t) && t == 1, "%s: from below hits the base", what);
  double o2[3] = {0.25, 0.25, dz + 2}, d2[3] = {0, 0, -1};
  ok(ss_mesh_raycast(m, o2, d2, &t) && fabs(t - 1.5) < 1e-15,
     "%s: from above hits x + y + z = 1 (t = %.17g)", what, t);
  double vol, cen[3], I[9];
  ss_mesh_mass_properties(m, &vol, cen, I);
  double c[3] = {0.25, 0.25, 0.25 + dz};
  ok(fabs(vol - 1.0 / 6) < 1e-15 && vec_close(cen, c, 3, 1e-15), "%s: volume 1/6, centroid",
     what);
  /* unit-density inertia of the corner tetrahedron about its centroid:
   * Ixx = 1/80, Ixy = 1/480 */
  ok(fabs(I[0] - 1.0 / 80) < 1e-15 && fabs(I[4] - 1.0 / 80) < 1e-15 &&
     fabs(I[1] - 1.0 / 480) < 1e-15 && fabs(I[5] - 1.0 / 480) < 1e-15,
     "%s: inertia Ixx = 1/80, Ixy = 1/480 (got %.17g, %.17g)", what, I[0], I[1]);
}

static void test_mesh_formats(void)
{
  char path[1024];
  ssMesh *m = NULL;
  ssError e;
  data_path(path, sizeof path, "meshes/tetra.stl");
  ssStatus st = ss_mesh_load(path, NULL, &m, &e);
  ok(st == SS_OK, "ASCII STL loads");
  if (st == SS_OK) check_tetra(m, "STL", 0);
  else diag("%s", e.message);
  ss_mesh_free(m);
  m = NULL;
  data_path(path, sizeof path, "meshes/tetra.gltf");
  st = ss_mesh_load(path, NULL, &m, &e);
  ok(st == SS_OK, "glTF 2.0 (embedded buffer, node translation 0 0 2) loads");
  if (st == SS_OK) check_tetra(m, "glTF", 2);
  else diag("%s", e.message);
  ss_mesh_free(m);
  m = NULL;

  /* errors: missing file, unreadable format, bad scale */
  data_path(path, sizeof path, "meshes/none.obj");
  st = ss_mesh_load(path, NULL, &m, &e);
  ok(st == SS_ERR_IO && m == NULL && !strcmp(e.file, path) && strstr(e.message, "cannot open"),
     "a missing mesh is SS_ERR_IO naming the path");
  data_path(path, sizeof path, "fourbar.urdf");
  st = ss_mesh_load(path, NULL, &m, &e);
  ok(st == SS_ERR_PARSE && m == NULL && strstr(e.message, "cannot load mesh"),
     "a file assimp cannot read: its message (%s)", e.message);
  data_path(path, sizeof path, "meshes/cube.obj");
  double s0[3] = {1, 0, 1};
  st = ss_mesh_load(path, s0, &m, &e);
  ok(st == SS_ERR_VALUE && m == NULL, "a zero scale is refused");
  ss_mesh_free(NULL);
  ok(1, "ss_mesh_free(NULL) is fine");
}

/* ss_mesh_load in a child process: its status as the exit code (0 loaded,
 * 1 refused), 2 when it had not returned after `seconds` (it is killed). */
static int load_in_child(const char *path, int seconds)
{
  fflush(stdout);
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    ssMesh *m = NULL;
    ssError e;
    ssStatus st = ss_mesh_load(path, NULL, &m, &e);
    ss_mesh_free(m);
    _exit(st == SS_OK ? 0 : 1);
  }
  for (int k = 0; k < 100 * seconds; k++) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    struct timespec ts = {0, 10000000};
    nanosleep(&ts, NULL);
  }
  kill(pid, SIGKILL);
  waitpid(pid, NULL, 0);
  return 2;
}

/* Files a mesh file names (an OBJ's mtllib, a glTF's buffer) are read
 * through the same checks as the mesh: a FIFO there is refused at once,
 * never waited on (the import once blocked for good opening it), and a
 * regular one is read as before. */
static void test_mesh_named_files(void)
{
  char dir[] = "/tmp/soilsim-urdf-XXXXXX", obj[128], mtl[128], gltf[128],
       bin[128], fifo[128], src[1024];
  if (!mkdtemp(dir)) {
    ok(0, "a temporary folder: %s", strerror(errno));
    return;
  }
  snprintf(obj, sizeof obj, "%s/tet.obj", dir);
  snprintf(mtl, sizeof mtl, "%s/tet.mtl", dir);
  snprintf(gltf, sizeof gltf, "%s/tet.gltf", dir);
  snprintf(bin, sizeof bin, "%s/tet.bin", dir);
  snprintf(fifo, sizeof fifo, "%s/fifo.bin", dir);
  FILE *f = fopen(obj, "w");
  if (f) {
    fputs("mtllib tet.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
          "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n", f);
    fclose(f);
  }
  /* the glTF fixture with its buffer moved out to a file */
  data_path(src, sizeof src, "meshes/tetra.gltf");
  char *g = slurp(src, NULL), *uri = g ? strstr(g, "\"data:") : NULL;
  char *end = uri ? strchr(uri + 1, '"') : NULL;
  int made = mkfifo(mtl, 0600) == 0 && mkfifo(fifo, 0600) == 0 && f && end;
  if (made) {
    /* the buffer's 72 bytes: the base64 after the comma */
    static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    unsigned char raw[128];
    size_t n = 0;
    unsigned acc = 0;
    int bits = 0;
    for (const char *p = strchr(uri, ',') + 1; p < end && *p != '='; p++) {
      const char *c = strchr(b64, *p);
      if (!c) break;
      acc = (acc << 6) | (unsigned)(c - b64);
      bits += 6;
      if (bits >= 8 && n < sizeof raw) {
        bits -= 8;
        raw[n++] = (unsigned char)(acc >> bits);
      }
    }
    FILE *b = fopen(bin, "wb");
    made = b && fwrite(raw, 1, n, b) == n && n == 72;
    if (b) made &= fclose(b) == 0;
    for (int k = 0; k < 2 && made; k++) {
      FILE *o = fopen(gltf, "w");
      made = o && fprintf(o, "%.*s\"%s\"%s", (int)(uri - g), g,
                          k ? "fifo.bin" : "tet.bin", end + 1) > 0;
      if (o) made &= fclose(o) == 0;
      if (!made) break;
      int r = load_in_child(gltf, 10);
      if (k)
        ok(r == 1, "a glTF whose buffer is a FIFO is refused at once (%s)",
           r == 2 ? "it hung" : r == 0 ? "loaded" : "refused");
      else
        ok(r == 0, "a glTF with its buffer in a file beside it loads");
    }
    int r = load_in_child(obj, 10);
    ok(r == 0, "an OBJ whose mtllib is a FIFO loads at once without it (%s)",
       r == 2 ? "it hung" : r == 1 ? "refused" : "loaded");
  }
  if (!made) ok(0, "the files for the named-file checks could be made");
  free(g);
  unlink(obj);
  unlink(mtl);
  unlink(gltf);
  unlink(bin);
  unlink(fifo);
  rmdir(dir);
}

static void test_mesh_arrays(void)
{
  /* the corner tetrahedron: faces z = 0, y = 0, x = 0, x + y + z = 1 */
  const double v[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const int f[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  ssMesh *m = NULL;
  ssError e;
  ssStatus st = ss_mesh_from_arrays(v, 4, f, 4, &m, &e);
  ok(st == SS_OK, "tetrahedron from arrays");
  if (st) return;
  check_tetra(m, "arrays", 0);
  /* rays against the analytic planes over a grid of points */
  int good = 1, n = 0;
  for (int i = -3; i <= 23; i++)
    for (int j = -3; j <= 23; j++) {
      double x = i / 20.0 + 0.013, y = j / 20.0 + 0.007;
      int inside = x >= 0 && y >= 0 && x + y <= 1;
      double o[3] = {x, y, -2}, d[3] = {0, 0, 1}, t = -1;
      int h = ss_mesh_raycast(m, o, d, &t);
      good &= h == inside && (!h || fabs(t - 2) <= 1e-15);
      double o2[3] = {x, y, 3}, d2[3] = {0, 0, -1};
      h = ss_mesh_raycast(m, o2, d2, &t);
      good &= h == inside && (!h || fabs(t - (3 - (1 - x - y))) <= 1e-14);
      /* along +x from x = -1 at height z: hits x = 0 when y, z inside */
      double z = 0.3;
      double o3[3] = {-1, y, z}, d3[3] = {0.5, 0, 0};
      int in3 = y >= 0 && y + z <= 1;
      h = ss_mesh_raycast(m, o3, d3, &t);
      good &= h == in3 && (!h || fabs(t - 2) <= 1e-15);
      n += 3;
    }
  ok(good, "%d rays agree with the analytic planes", n);
  /* an oblique ray: from (0.1, 0.1, 2) along (0.1, 0.1, -4) meets
   * x + y + z = 1 at s with 0.2 + 0.2 s + 2 - 4 s = 1, s = 1.2 / 3.8 */
  double o[3] = {0.1, 0.1, 2}, d[3] = {0.1, 0.1, -4}, t;
  ok(ss_mesh_raycast(m, o, d, &t) && fabs(t - 1.2 / 3.8) < 1e-15,
     "oblique ray on the slanted face (t = %.17g)", t);
  ss_mesh_free(m);
  m = NULL;
  /* invalid input */
  const int bad[3] = {0, 1, 7};
  ok(ss_mesh_from_arrays(v, 4, bad, 1, &m, &e) == SS_ERR_VALUE && m == NULL &&
     strstr(e.message, "uses vertex 7"), "an index out of range is refused");
  double vn[12];
  memcpy(vn, v, sizeof vn);
  vn[4] = NAN;
  ok(ss_mesh_from_arrays(vn, 4, f, 4, &m, &e) == SS_ERR_VALUE && m == NULL,
     "a NaN vertex is refused");
}

/* Icosphere: subdivided icosahedron of radius 1. */
typedef struct growMesh {
  double *v;
  int nv, capv;
  int *f;
  int nf, capf;
} growMesh;

static int gm_vert(growMesh *g, double x, double y, double z)
{
  if (g->nv == g->capv) {
    g->capv = g->capv ? 2 * g->capv : 64;
    g->v = realloc(g->v, (size_t)g->capv * 3 * sizeof *g->v);
  }
  double n = sqrt(x * x + y * y + z * z);
  g->v[3 * g->nv] = x / n;
  g->v[3 * g->nv + 1] = y / n;
  g->v[3 * g->nv + 2] = z / n;
  return g->nv++;
}

static void gm_face(growMesh *g, int a, int b, int c)
{
  if (g->nf == g->capf) {
    g->capf = g->capf ? 2 * g->capf : 64;
    g->f = realloc(g->f, (size_t)g->capf * 3 * sizeof *g->f);
  }
  g->f[3 * g->nf] = a;
  g->f[3 * g->nf + 1] = b;
  g->f[3 * g->nf + 2] = c;
  g->nf++;
}

/* midpoint vertex of edge (a, b): an open-addressing table of edges */
static int gm_mid(const int *tab, int cap, int a, int b, int *slot)
{
  int lo = a < b ? a : b, hi = a < b ? b : a;
  unsigned h = ((unsigned)lo * 2654435761u ^ (unsigned)hi * 40503u) % (unsigned)cap;
  while (tab[3 * h] >= 0) {
    if (tab[3 * h] == lo && tab[3 * h + 1] == hi) return tab[3 * h + 2];
    h = (h + 1) % (unsigned)cap;
  }
  *slot = (int)h;
  return -1;
}

static void icosphere(growMesh *g, int levels)
{
  double p = (1 + sqrt(5.0)) / 2;
  double iv[12][3] = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0},
                      {0, -1, p}, {0, 1, p}, {0, -1, -p}, {0, 1, -p},
                      {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  int ifc[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                    {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                    {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                    {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  memset(g, 0, sizeof *g);
  for (int i = 0; i < 12; i++) gm_vert(g, iv[i][0], iv[i][1], iv[i][2]);
  for (int i = 0; i < 20; i++) gm_face(g, ifc[i][0], ifc[i][1], ifc[i][2]);
  for (int l = 0; l < levels; l++) {
    int nf = g->nf, *old = g->f;
    g->f = NULL;
    g->nf = g->capf = 0;
    int cap = 4 * nf + 7;
    int *tab = malloc((size_t)cap * 3 * sizeof *tab);
    for (int i = 0; i < 3 * cap; i++) tab[i] = -1;
    for (int k = 0; k < nf; k++) {
      int c[3] = {old[3 * k], old[3 * k + 1], old[3 * k + 2]}, mid[3];
      for (int e = 0; e < 3; e++) {
        int a = c[e], b = c[(e + 1) % 3];
        int slot = -1;
        int mv = gm_mid(tab, cap, a, b, &slot);
        if (mv < 0) {
          mv = gm_vert(g, g->v[3 * a] + g->v[3 * b], g->v[3 * a + 1] + g->v[3 * b + 1],
                       g->v[3 * a + 2] + g->v[3 * b + 2]);
          tab[3 * slot] = a < b ? a : b;
          tab[3 * slot + 1] = a < b ? b : a;
          tab[3 * slot + 2] = mv;
        }
        mid[e] = mv;
      }
      gm_face(g, c[0], mid[0], mid[2]);
      gm_face(g, c[1], mid[1], mid[0]);
      gm_face(g, c[2], mid[2], mid[1]);
      gm_face(g, mid[0], mid[1], mid[2]);
    }
    free(tab);
    free(old);
  }
}

/* Nearest hit by brute force over every face plane (reference). */
static int brute_ray(const growMesh *g, const double o[3], const double d[3], double *t)
{
  int hit = 0;
  double best = INFINITY;
  for (int k = 0; k < g->nf; k++) {
    const double *a = g->v + 3 * g->f[3 * k], *b = g->v + 3 * g->f[3 * k + 1],
                 *c = g->v + 3 * g->f[3 * k + 2];
    double e1[3], e2[3], n[3], ao[3];
    ss_v3_sub(e1, b, a);
    ss_v3_sub(e2, c, a);
    ss_v3_cross(n, e1, e2);
    double den = ss_v3_dot(n, d);
    if (den == 0) continue;
    ss_v3_sub(ao, a, o);
    double tt = ss_v3_dot(n, ao) / den;
    if (!(tt >= 0) || tt >= best) continue;
    double p[3], x[3];
    for (int i = 0; i < 3; i++) p[i] = o[i] + tt * d[i];
    /* inside test with a small tolerance */
    const double *vv[3] = {a, b, c};
    int in = 1;
    for (int e = 0; e < 3; e++) {
      double ed[3], pe[3];
      ss_v3_sub(ed, vv[(e + 1) % 3], vv[e]);
      ss_v3_sub(pe, p, vv[e]);
      ss_v3_cross(x, ed, pe);
      if (ss_v3_dot(x, n) < -1e-12 * ss_v3_dot(n, n)) in = 0;
    }
    if (in) {
      best = tt;
      hit = 1;
    }
  }
  *t = best;
  return hit;
}

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double urand(void)
{
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (double)(rng_state >> 11) / 9007199254740992.0;
}

static void test_watertight(void)
{
  growMesh g;
  icosphere(&g, 3);
  ssMesh *m = NULL;
  ssError e;
  ssStatus st = ss_mesh_from_arrays(g.v, g.nv, g.f, g.nf, &m, &e);
  ok(st == SS_OK && m->ntri == 1280, "icosphere of 1280 triangles from arrays");
  if (st) return;
  double vol, cen[3], I[9];
  ss_mesh_mass_properties(m, &vol, cen, I);
  ok(vol > 0.95 * 4 * M_PI / 3 && vol < 4 * M_PI / 3 && ss_v3_norm(cen) < 1e-15,
     "icosphere volume %.6f below the sphere's, centroid at 0", vol);
  /* vertical rays through every vertex and every edge midpoint, from
   * below: each must find an entry (no cracks on shared edges/vertices) */
  int miss = 0, nray = 0;
  double d[3] = {0, 0, 1}, t;
  for (int v = 0; v < g.nv; v++) {
    const double *p = g.v + 3 * v;
    if (fabs(p[2]) < 0.3) continue; /* silhouette: grazing is fine either way */
    double o[3] = {p[0], p[1], -3};
    nray++;
    if (!ss_mesh_raycast(m, o, d, &t)) miss++;
  }
  for (int k = 0; k < g.nf; k++)
    for (int q = 0; q < 3; q++) {
      const double *a = g.v + 3 * g.f[3 * k + q], *b = g.v + 3 * g.f[3 * k + (q + 1) % 3];
      double o[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), -3};
      if (o[0] * o[0] + o[1] * o[1] > 0.9) continue;
      nray++;
      if (!ss_mesh_raycast(m, o, d, &t)) miss++;
    }
  ok(miss == 0, "%d vertical rays through vertices and edges all hit (%d missed)", nray, miss);
  /* rays aimed at vertices from outside, in random directions */
  miss = 0;
  for (int v = 0; v < g.nv; v++) {
    const double *p = g.v + 3 * v;
    double o[3] = {p[0] * 3, p[1] * 3, p[2] * 3}, dd[3];
    ss_v3_sub(dd, p, o);
    if (!ss_mesh_raycast(m, o, dd, &t) || fabs(t - 1) > 1e-12) miss++;
  }
  ok(miss == 0, "radial rays through all %d vertices hit at the vertex (%d bad)", g.nv, miss);
  /* random rays against the brute-force reference */
  int bad = 0;
  for (int k = 0; k < 2000; k++) {
    double o[3], dd[3];
    for (int i = 0; i < 3; i++) {
      o[i] = 4 * urand() - 2;
      dd[i] = 2 * urand() - 1;
    }
    double tb, tr;
    int hb = brute_ray(&g, o, dd, &tb), hr = ss_mesh_raycast(m, o, dd, &tr);
    if (hb != hr || (hb && fabs(tb - tr) > 1e-12 * (1 + tb))) bad++;
  }
  ok(bad == 0, "2000 random rays agree with a brute-force search (%d differ)", bad);
  /* grid of vertical rays inside the inscribed radius: all hit */
  miss = 0;
  nray = 0;
  for (int i = -60; i <= 60; i++)
    for (int j = -60; j <= 60; j++) {
      double x = i / 64.0, y = j / 64.0;
      if (x * x + y * y > 0.8) continue;
      double o[3] = {x, y, -3};
      nray++;
      if (!ss_mesh_raycast(m, o, d, &t)) miss++;
    }
  ok(miss == 0, "%d grid rays through the sphere all find an entry", nray);
  ss_mesh_free(m);
  free(g.v);
  free(g.f);

  /* a bigger sphere: the BVH stays balanced and agrees with level 3 */
  icosphere(&g, 5);
  st = ss_mesh_from_arrays(g.v, g.nv, g.f, g.nf, &m, &e);
  ok(st == SS_OK && m->ntri == 20480 && m->nnode <= 2 * m->ntri,
     "icosphere of 20480 triangles, %d BVH nodes", st == SS_OK ? m->nnode : 0);
  if (st == SS_OK) {
    int depth_ok = 1;
    /* depth by walking: the median split keeps it near log2(n / 4) */
    int stack[128], dep[128], top = 0, maxd = 0;
    stack[top] = 0;
    dep[top++] = 1;
    while (top) {
      int k = stack[--top], dk = dep[top];
      if (dk > maxd) maxd = dk;
      if (m->bvh_child[2 * k] >= 0 && top + 2 < 128) {
        stack[top] = m->bvh_child[2 * k];
        dep[top++] = dk + 1;
        stack[top] = m->bvh_child[2 * k + 1];
        dep[top++] = dk + 1;
      }
    }
    depth_ok = maxd <= 16;
    ok(depth_ok, "BVH depth %d (log2(20480 / 4) = 12.3)", maxd);
    double o[3] = {0.1, 0.2, -5};
    ok(ss_mesh_raycast(m, o, d, &t) && fabs(t - (5 - sqrt(1 - 0.05))) < 2e-3,
       "ray hits near the sphere's surface");
    /* same mesh built twice gives the same tree (determinism) */
    ssMesh *m2 = NULL;
    ss_mesh_from_arrays(g.v, g.nv, g.f, g.nf, &m2, &e);
    ok(m2 && m2->nnode == m->nnode &&
       !memcmp(m2->bvh_tri, m->bvh_tri, (size_t)m->ntri * sizeof(int)) &&
       !memcmp(m2->bvh_child, m->bvh_child, (size_t)m->nnode * 2 * sizeof(int)),
       "BVH construction is deterministic");
    ss_mesh_free(m2);
  }
  ss_mesh_free(m);
  free(g.v);
  free(g.f);
}

/* ---------------------------------------------------------------------- */
/* catalogue of bad URDFs                                                  */

static ssStatus load_bad_urdf(const char *path, ssError *e, int *nothing)
{
  ssUrdf *u = NULL;
  ssStatus st = ss_urdf_load(path, NULL, &u, e);
  *nothing = u == NULL;
  ss_urdf_free(u);
  return st;
}

static void test_bad_catalogue(void)
{
  char dir[1024];
  data_path(dir, sizeof dir, "bad");
  catalogue_check(dir, ".urdf", "URDF", 30, load_bad_urdf);
}

/* ss_urdf_check_floating_root: a root without mass (massless_root.urdf:
 * no <inertial>, nothing fixed to it) cannot float; one with mass can. */
static void test_floating_root(void)
{
  char path[1024];
  ssUrdf *u = NULL;
  ssError e;
  data_path(path, sizeof path, "massless_root.urdf");
  ssStatus st = ss_urdf_load(path, NULL, &u, &e);
  if (!ok(st == SS_OK, "massless_root.urdf loads (a fixed base may be massless)")) {
    diag("%s:%d: %s", e.file, e.line, e.message);
    return;
  }
  st = ss_urdf_check_floating_root(u, &e);
  ok(st == SS_ERR_VALUE && !strcmp(e.file, path) && e.line == 5 &&
         strstr(e.message, "link 'mount' is the root of a floating base"),
     "its root cannot float: refused at the root link's line (%s:%d: %s)", e.file,
     e.line, st ? e.message : "accepted");
  ss_urdf_free(u);
  u = NULL;
  data_path(path, sizeof path, "example.urdf");
  st = ss_urdf_load(path, NULL, &u, &e);
  ok(st == SS_OK && ss_urdf_check_floating_root(u, &e) == SS_OK,
     "example.urdf's root can float");
  ss_urdf_free(u);
}

/* A chain of n links on fixed joints, read: 1 when it loads with n + 1
 * links, each joint k joining link k - 1 to link k in the file's order */
static int chain_reads(int n)
{
  size_t cap = (size_t)n * 120 + 64, k = 0;
  char *buf = malloc(cap);
  if (!buf) return 0;
  k += (size_t)snprintf(buf + k, cap - k, "<robot name=\"chain\">\n");
  for (int i = 0; i <= n; i++)
    k += (size_t)snprintf(buf + k, cap - k, "<link name=\"l%d\"/>\n", i);
  for (int i = 1; i <= n; i++)
    k += (size_t)snprintf(buf + k, cap - k,
                          "<joint name=\"j%d\" type=\"fixed\"><parent link=\"l%d\"/>"
                          "<child link=\"l%d\"/></joint>\n", i, i - 1, i);
  k += (size_t)snprintf(buf + k, cap - k, "</robot>\n");
  ssUrdf *u = NULL;
  ssError e;
  ssStatus st = ss_urdf_load_buffer(buf, k, "chain.urdf", NULL, &u, &e);
  int good = st == SS_OK && u->nlink == n + 1 && u->njoint == n;
  for (int j = 0; good && j < u->njoint; j++) {
    const ssUrdfJoint *jt = u->joint + j;
    good = jt->parent >= 0 && jt->child >= 0 && atoi(u->link[jt->parent].name + 1) == j &&
           atoi(u->link[jt->child].name + 1) == j + 1;
  }
  ss_urdf_free(u);
  free(buf);
  return good;
}

/* Links and joints are found by name in constant time (a 64 MiB URDF of
 * short links once took hours): a chain of 32 000 links reads, every
 * joint joining the links it names.  Correctness only: how the time
 * grows with the links is benchmarks --bench load's (a timed ratio here,
 * as before, would fail on a busy machine). */
static void test_many_links(void)
{
  ok(chain_reads(4000) && chain_reads(32000),
     "chains of 4000 and 32000 links read, every joint joining the links it names");
}

/* A URDF of many links, each with a material of its own that its visual
 * names, on revolute joints, with springs: it loads and builds with the
 * right counts; a material or spring name repeated at the end is refused
 * naming the first, as when every earlier one was scanned (the look-ups
 * are hashed).  Correctness only: the time is benchmarks --bench load's. */
static char *many_urdf(int n, int dup_mat, int dup_spring, size_t *len)
{
  size_t cap = (size_t)n * 600 + 400, k = 0;
  char *buf = malloc(cap);
  if (!buf) return NULL;
  /* line 1 <robot>, material i on line 2 + i, link i on 2 + n + i */
  k += (size_t)snprintf(buf + k, cap - k, "<robot name=\"many\">\n");
  for (int i = 0; i < n; i++)
    k += (size_t)snprintf(buf + k, cap - k,
                          "<material name=\"c%d\"><color rgba=\"0.%d 0 0 1\"/></material>\n",
                          i == n - 1 && dup_mat >= 0 ? dup_mat : i, i % 10);
  for (int i = 0; i < n; i++)
    k += (size_t)snprintf(buf + k, cap - k,
                          "<link name=\"l%d\"><inertial><mass value=\"1\"/><inertia "
                          "ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" "
                          "izz=\"0.01\"/></inertial><visual><geometry><sphere "
                          "radius=\"0.05\"/></geometry><material name=\"c%d\"/></visual>"
                          "</link>\n", i, n - 1 - i);
  for (int i = 1; i < n; i++)
    k += (size_t)snprintf(buf + k, cap - k,
                          "<joint name=\"j%d\" type=\"revolute\"><parent link=\"l%d\"/>"
                          "<child link=\"l%d\"/><origin xyz=\"0 0 0.1\"/></joint>\n",
                          i, (i - 1) / 4, i);
  /* springs on line 1 + 3 n + i */
  for (int i = 0; i + 1 < n; i++)
    k += (size_t)snprintf(buf + k, cap - k,
                          "<spring name=\"s%d\" body1=\"l%d\" body2=\"l%d\" stiffness=\"1\"/>\n",
                          i + 2 == n && dup_spring >= 0 ? dup_spring : i, i, i + 1);
  k += (size_t)snprintf(buf + k, cap - k, "</robot>\n");
  *len = k;
  return buf;
}

static void test_many_names(void)
{
  enum { N = 5000 };
  size_t len = 0;
  ssUrdf *u = NULL;
  ssError e;
  char *buf = many_urdf(N, -1, -1, &len);
  ssStatus st = buf ? ss_urdf_load_buffer(buf, len, "many.urdf", NULL, &u, &e) : SS_ERR_NOMEM;
  int good = st == SS_OK && u->nlink == N && u->njoint == N - 1 && u->nspring == N - 1;
  /* link 0 is l0; the material of l(i) is c(N - 1 - i), red 0.(that % 10) */
  for (int i = 0; good && i < u->nlink; i++) {
    int li = atoi(u->link[i].name + 1), c = N - 1 - li;
    good = u->link[i].ngeom == 1 && u->link[i].geom[0].rgba[0] == (double)(c % 10) / 10;
  }
  ssModel *m = good ? ss_model_new() : NULL;
  int s = -1;
  if (m) {
    ssArtDef d = ss_art_def_default();
    d.name = "many";
    d.fixed_base = 1;
    s = ss_model_add_articulated(m, u, &d, &e);
  }
  ok(good && s == 0 && m->nbody == N && m->ngeom == N && m->nv == N - 1 &&
         m->nspring == N - 1 && m->neq == 0 && ss_model_find_body(m, 0, "l4999") >= 0,
     "%d links, materials and springs load and build (%s)", N,
     st ? e.message : s < 0 && m ? e.message : "ok");
  ss_model_free(m);
  ss_urdf_free(u);
  free(buf);
  u = NULL;

  buf = many_urdf(N, 2345, -1, &len);
  st = buf ? ss_urdf_load_buffer(buf, len, "many.urdf", NULL, &u, &e) : SS_ERR_NOMEM;
  char want[200];
  snprintf(want, sizeof want, "duplicate material name 'c2345' (first at line %d)", 2 + 2345);
  ok(st == SS_ERR_PARSE && e.line == 2 + N - 1 && !strcmp(e.message, want) && !u,
     "the last of %d materials repeating an earlier name: refused at its line, naming "
     "the first (%s:%d: %s)", N, e.file, e.line, e.message);
  ss_urdf_free(u);
  free(buf);
  u = NULL;

  buf = many_urdf(N, -1, 17, &len);
  st = buf ? ss_urdf_load_buffer(buf, len, "many.urdf", NULL, &u, &e) : SS_ERR_NOMEM;
  snprintf(want, sizeof want, "duplicate spring name 's17' (first at line %d)",
           1 + 3 * N + 17);
  ok(st == SS_ERR_PARSE && e.line == 1 + 3 * N + N - 2 && !strcmp(e.message, want) && !u,
     "the last of %d springs repeating an earlier name: refused at its line, naming "
     "the first (%s:%d: %s)", N - 1, e.file, e.line, e.message);
  ss_urdf_free(u);
  free(buf);
}

int main(void)
{
  test_fourbar();
  test_example();
  test_world();
  test_floating_root();
  test_many_links();
  test_many_names();
  test_paths();
  test_locale();
  test_size_cap();
  test_mesh_obj();
  test_mesh_formats();
  test_mesh_named_files();
  test_mesh_arrays();
  test_watertight();
  test_bad_catalogue();
  return done_testing();
}
