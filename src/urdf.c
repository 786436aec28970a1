/* urdf.c -- URDF (DESIGN 4.2) into an ssUrdf: links, joints, geometry, loop
 * closures and force elements.
 *
 * The accepted format, the tree rules, the mesh path rules and the error
 * conventions are described in urdf.h.  The reader parses the whole document
 * with libxml2 (safely: xml_safe.h), then walks it in passes:
 * named materials, links, joints, the tree (roots, cycles, order, the
 * "world" link), mass checks, then constraints and springs, which name links
 * and joints by their final indices.  Every element is checked against a
 * list of allowed attributes and children so that typos are reported
 * instead of ignored. */
#include "urdf.h"
#include "scene.h"
#include "ss_math.h"
#include "xml_safe.h"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* attributes per element kept (none of ours allows nearly as many) */
#define MAX_ATTR 24
#define NAME_LEN 128

/* ---------------------------------------------------------------------- */
/* reader context and messages                                             */

typedef struct uMaterial {
  char name[NAME_LEN];
  double rgba[4];
  int has_color;
  int line;
} uMaterial;

/* A closure or spring read before the tree is known: names, resolved
 * later. */
typedef struct uPending {
  int kind;              /* 0 closure, 1 spring */
  int mimic;             /* a closure from a joint's <mimic> */
  ssUrdfClosure cl;
  ssUrdfSpring sp;
  char name1[NAME_LEN], name2[NAME_LEN];
  char label[80];        /* "<pin>", "joint 'j' <mimic>" */
  const char *attr1, *attr2; /* attribute names for messages */
} uPending;

/* Names to document indices (open addressing; slot = index + 1, 0 empty),
 * so that finding a link or joint by name does not walk all of them (a
 * URDF of many links took time quadratic in their number). */
typedef struct nameTab {
  int *slot;
  int cap;  /* a power of two, or 0 */
  int n;
} nameTab;

typedef struct uCtx {
  const char *path;      /* for messages */
  const char *buf;       /* the source, [0, len): lines of values */
  size_t len;
  char dir[1024];        /* the URDF's folder */
  const char *res_dir;
  xmlDocPtr doc;
  ssError e;

  int nmat, capmat;
  uMaterial *mat;

  /* links and joints in document order */
  int nlink, caplink, capextra;
  ssUrdfLink *link;
  int *link_extra;       /* line of the first inertial/visual/collision */
  int njoint, capjoint;
  ssUrdfJoint *joint;
  nameTab link_tab, joint_tab, mat_tab;
  const ssUrdf *out;     /* the result, while build_tree fills it */

  int npend, cappend;
  uPending *pend;
  int robot_line;
} uCtx;

static ssStatus fail(uCtx *c, ssStatus code, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static ssStatus fail(uCtx *c, ssStatus code, int line, const char *fmt, ...)
{
  c->e.code = code;
  snprintf(c->e.file, sizeof c->e.file, "%s", c->path);
  c->e.line = line;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(c->e.message, sizeof c->e.message, fmt, ap);
  va_end(ap);
  return code;
}

static ssStatus nomem(uCtx *c, int line)
{
  return fail(c, SS_ERR_NOMEM, line, "out of memory");
}

/* Grow *arr (elements of size sz) so that index n fits. */
static int grow(void **arr, int *cap, int n, size_t sz)
{
  if (n < *cap) return 0;
  int nc = *cap ? 2 * *cap : 8;
  while (nc <= n) nc *= 2;
  void *p = realloc(*arr, (size_t)nc * sz);
  if (!p) return -1;
  memset((char *)p + (size_t)*cap * sz, 0, (size_t)(nc - *cap) * sz);
  *arr = p;
  *cap = nc;
  return 0;
}

/* ---------------------------------------------------------------------- */
/* elements and attributes                                                 */

typedef struct xAttr {
  const char *name;
  const char *val;
} xAttr;

typedef struct xEl {
  xmlNodePtr node;
  const char *name;
  int line;
  char label[240];       /* "link 'arm' <inertial> <mass>" */
  int nattr;
  xAttr attr[MAX_ATTR];
  xmlChar *owned[MAX_ATTR];
} xEl;

static void el_free(xEl *e)
{
  for (int i = 0; i < e->nattr; i++)
    if (e->owned[i]) xmlFree(e->owned[i]);
  e->nattr = 0;
}

static ssStatus el_open(uCtx *c, xmlNodePtr node, const char *parent_label,
                        xEl *e)
{
  memset(e, 0, sizeof *e);
  e->node = node;
  e->name = (const char *)node->name;
  e->line = ss_xml_line(node);
  if (parent_label)
    snprintf(e->label, sizeof e->label, "%s <%s>", parent_label, e->name);
  else
    snprintf(e->label, sizeof e->label, "<%s>", e->name);
  for (xmlAttrPtr a = node->properties; a; a = a->next) {
    /* URDF has no namespaced attributes: read by its local part, a
     * prefixed one (xacro:mass) would stand for another */
    if (a->ns && a->ns->prefix)
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: namespaced attribute '%s:%s' (expand xacro files "
                  "first)", e->label, (const char *)a->ns->prefix,
                  (const char *)a->name);
    if (e->nattr == MAX_ATTR)
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: too many attributes (at most %d)", e->label, MAX_ATTR);
    xAttr *x = &e->attr[e->nattr];
    x->name = (const char *)a->name;
    x->val = ss_xml_attr_text(c->doc, a, &e->owned[e->nattr]);
    e->nattr++;
  }
  return SS_OK;
}

static ssStatus el_allow(uCtx *c, xEl *e, const char *const *allowed)
{
  for (int i = 0; i < e->nattr; i++)
    if (!ss_xml_in_list(e->attr[i].name, allowed)) {
      char list[400];
      ss_xml_join_names(list, sizeof list, allowed);
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: unknown attribute '%s' (allowed: %s)", e->label,
                  e->attr[i].name, allowed[0] ? list : "none");
    }
  return SS_OK;
}

static const char *el_find(const xEl *e, const char *name)
{
  for (int i = 0; i < e->nattr; i++)
    if (!strcmp(e->attr[i].name, name)) return e->attr[i].val;
  return NULL;
}

static ssStatus missing(uCtx *c, const xEl *e, const char *name)
{
  return fail(c, SS_ERR_PARSE, e->line, "%s: missing required attribute '%s'",
              e->label, name);
}

/* Parse n values (or, when n1 > 0, either n1 or n values; *got tells which)
 * of attribute `name`. */
static ssStatus parse_values(uCtx *c, const xEl *e, const char *name,
                             const char *v, int n, int n1, int *got,
                             double *out)
{
  long cnt = ss_xml_vec_count(v);
  if (cnt < 0)
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: attribute '%s' = '%.40s' has an empty value (values are "
                "separated by white space or by one comma)", e->label, name, v);
  if (cnt != n && !(n1 > 0 && cnt == n1)) {
    if (n1 > 0)
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: attribute '%s' = '%.40s' has %ld values, expected %d "
                  "or %d", e->label, name, v, cnt, n1, n);
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: attribute '%s' = '%.40s' has %ld value%s, expected %d",
                e->label, name, v, cnt, cnt == 1 ? "" : "s", n);
  }
  const char *p = v, *tb = NULL, *te = NULL;
  for (long k = 0; k < cnt; k++) {
    ss_xml_vec_next(&p, k == 0, &tb, &te);
    int r = ss_scene_parse_double(tb, te, &out[k]);
    if (r) {
      int len = (int)(te - tb) > 40 ? 40 : (int)(te - tb);
      char where[64] = "";
      if (cnt > 1)
        snprintf(where, sizeof where, " (value %ld of %ld)", k + 1, cnt);
      return fail(c, SS_ERR_PARSE,
                  ss_xml_value_line(c->buf, c->len, e->node, name, k),
                  "%s: bad number '%.*s'%s in attribute '%s' (%s)", e->label,
                  len, tb, where, name,
                  r == 2 ? "out of range"
                         : "expected a finite decimal number");
    }
  }
  if (got) *got = (int)cnt;
  return SS_OK;
}

static ssStatus get_vec(uCtx *c, const xEl *e, const char *name, int n,
                        int required, double *out)
{
  const char *v = el_find(e, name);
  if (!v) return required ? missing(c, e, name) : SS_OK;
  return parse_values(c, e, name, v, n, 0, NULL, out);
}

static ssStatus get_num(uCtx *c, const xEl *e, const char *name, int required,
                        double *out)
{
  return get_vec(c, e, name, 1, required, out);
}

/* A number that must be >= lo (strict: > lo). */
static ssStatus get_num_min(uCtx *c, const xEl *e, const char *name,
                            int required, double lo, int strict, double *out)
{
  double v = *out;
  ssStatus st = get_num(c, e, name, required, &v);
  if (st) return st;
  if (!el_find(e, name)) return SS_OK;
  if (strict ? !(v > lo) : !(v >= lo))
    return fail(c, SS_ERR_VALUE, e->line,
                "%s: %s = %.17g is invalid: must be %s %g", e->label, name, v,
                strict ? ">" : ">=", lo);
  *out = v;
  return SS_OK;
}

static ssStatus get_name(uCtx *c, const xEl *e, const char *attr,
                         char out[NAME_LEN])
{
  const char *v = el_find(e, attr);
  if (!v) return missing(c, e, attr);
  if (!*v)
    return fail(c, SS_ERR_PARSE, e->line, "%s: attribute '%s' is empty",
                e->label, attr);
  if (strlen(v) >= NAME_LEN)
    return fail(c, SS_ERR_VALUE, e->line,
                "%s: %s = '%.40s...' is too long (at most %d characters)",
                e->label, attr, v, NAME_LEN - 1);
  snprintf(out, NAME_LEN, "%s", v);
  return SS_OK;
}

/* Non-element children: blank text, comments and processing instructions
 * are fine; anything else is an error. */
static ssStatus check_other_node(uCtx *c, xmlNodePtr n, const xEl *parent)
{
  char msg[sizeof c->e.message];
  if (!ss_xml_stray(n, parent->name, msg, sizeof msg)) return SS_OK;
  return fail(c, SS_ERR_PARSE, ss_xml_line(n) ? ss_xml_line(n) : parent->line,
              "%s", msg);
}

/* A namespaced element (xacro:macro) or one of URDF's we do not read. */
static ssStatus unknown_child(uCtx *c, xmlNodePtr n, const xEl *parent,
                              const char *const *allowed)
{
  if (n->ns && n->ns->prefix)
    return fail(c, SS_ERR_PARSE, ss_xml_line(n),
                "unknown element <%s:%s> inside <%s> (namespaced elements "
                "are not URDF; expand xacro files first)",
                (const char *)n->ns->prefix, (const char *)n->name,
                parent->name);
  if (!allowed[0])
    return fail(c, SS_ERR_PARSE, ss_xml_line(n),
                "unknown element <%s> inside <%s> (<%s> has no child "
                "elements)", (const char *)n->name, parent->name,
                parent->name);
  char list[400];
  ss_xml_join_names(list, sizeof list, allowed);
  return fail(c, SS_ERR_PARSE, ss_xml_line(n),
              "unknown element <%s> inside <%s> (allowed: %s)",
              (const char *)n->name, parent->name, list);
}

/* Is n the element `name` (not namespaced)? */
static int is_el(xmlNodePtr n, const char *name)
{
  return n->type == XML_ELEMENT_NODE && !(n->ns && n->ns->prefix) &&
         !strcmp((const char *)n->name, name);
}

static ssStatus check_leaf(uCtx *c, const xEl *e)
{
  static const char *const none[] = {NULL};
  for (xmlNodePtr n = e->node->children; n; n = n->next) {
    ssStatus st = n->type == XML_ELEMENT_NODE ? unknown_child(c, n, e, none)
                                              : check_other_node(c, n, e);
    if (st) return st;
  }
  return SS_OK;
}

static ssStatus open_leaf(uCtx *c, xmlNodePtr n, const char *parent_label,
                          const char *const *allowed, xEl *e)
{
  ssStatus st = el_open(c, n, parent_label, e);
  if (!st) st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  return st;
}

static ssStatus once(uCtx *c, int *seen, const xEl *e)
{
  if (*seen)
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: element <%s> given twice (first at line %d)", e->label,
                e->name, *seen);
  *seen = e->line ? e->line : -1;
  return SS_OK;
}

/* ---------------------------------------------------------------------- */
/* small algebra                                                           */

/* URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll), q = qz qy qx. */
static void rpy_to_quat(const double rpy[3], double q[4])
{
  double cr = cos(0.5 * rpy[0]), sr = sin(0.5 * rpy[0]);
  double cp = cos(0.5 * rpy[1]), sp = sin(0.5 * rpy[1]);
  double cy = cos(0.5 * rpy[2]), sy = sin(0.5 * rpy[2]);
  q[0] = cr * cp * cy + sr * sp * sy;
  q[1] = sr * cp * cy - cr * sp * sy;
  q[2] = cr * sp * cy + sr * cp * sy;
  q[3] = cr * cp * sy - sr * sp * cy;
}

/* Eigenvalues of a symmetric 3x3 (row-major) by cyclic Jacobi rotations,
 * ascending. */
static void sym_eig3(const double A[9], double ev[3])
{
  double a[9];
  memcpy(a, A, sizeof a);
  for (int sweep = 0; sweep < 50; sweep++) {
    double off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
    double dia = a[0] * a[0] + a[4] * a[4] + a[8] * a[8];
    if (off == 0 || off <= 1e-36 * dia) break;
    for (int p = 0; p < 2; p++)
      for (int q = p + 1; q < 3; q++) {
        double apq = a[3 * p + q];
        if (apq == 0) continue;
        double app = a[3 * p + p], aqq = a[3 * q + q];
        double theta = (aqq - app) / (2 * apq);
        double t = (theta >= 0 ? 1.0 : -1.0) /
                   (fabs(theta) + sqrt(theta * theta + 1));
        double cs = 1 / sqrt(t * t + 1), sn = t * cs;
        /* a <- J^T a J with J the rotation in the (p, q) plane */
        for (int k = 0; k < 3; k++) {
          double akp = a[3 * k + p], akq = a[3 * k + q];
          a[3 * k + p] = cs * akp - sn * akq;
          a[3 * k + q] = sn * akp + cs * akq;
        }
        for (int k = 0; k < 3; k++) {
          double apk = a[3 * p + k], aqk = a[3 * q + k];
          a[3 * p + k] = cs * apk - sn * aqk;
          a[3 * q + k] = sn * apk + cs * aqk;
        }
        a[3 * p + q] = a[3 * q + p] = 0;
      }
  }
  ev[0] = a[0];
  ev[1] = a[4];
  ev[2] = a[8];
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2 - i; j++)
      if (ev[j] > ev[j + 1]) {
        double t = ev[j];
        ev[j] = ev[j + 1];
        ev[j + 1] = t;
      }
}

static void inertia_mat(const double in[6], double I[9])
{
  I[0] = in[0]; I[1] = in[1]; I[2] = in[2];
  I[3] = in[1]; I[4] = in[3]; I[5] = in[4];
  I[6] = in[2]; I[7] = in[4]; I[8] = in[5];
}

/* Positive definite: smallest principal moment above 1e-12 times the
 * largest. */
static int is_pd(const double ev[3])
{
  return ev[2] > 0 && ev[0] > 1e-12 * ev[2];
}

/* ---------------------------------------------------------------------- */
/* materials                                                               */

/* name tables (below): kinds of entry */
enum { TAB_LINK, TAB_JOINT, TAB_MAT, TAB_CLOSURE, TAB_SPRING };
static int tab_find(const uCtx *c, const nameTab *t, int kind, const char *name);
static int tab_add(const uCtx *c, nameTab *t, int kind, int i);

/* hashed: a URDF may define a material per link, and every visual that
 * names one looks it up */
static int find_material(const uCtx *c, const char *name)
{
  return tab_find(c, &c->mat_tab, TAB_MAT, name);
}

static ssStatus read_color(uCtx *c, xmlNodePtr n, const char *label,
                           double rgba[4])
{
  static const char *const a_color[] = {"rgba", NULL};
  xEl e;
  ssStatus st = open_leaf(c, n, label, a_color, &e);
  if (!st) st = get_vec(c, &e, "rgba", 4, 1, rgba);
  for (int k = 0; !st && k < 4; k++)
    if (rgba[k] < 0 || rgba[k] > 1)
      st = fail(c, SS_ERR_VALUE, e.line,
                "%s: rgba value %d is %.17g; each must be in [0, 1]", e.label,
                k + 1, rgba[k]);
  el_free(&e);
  return st;
}

/* <material name> <color rgba/> <texture filename/> </material>.  has_color
 * tells whether a colour was given. */
static ssStatus read_material_el(uCtx *c, xmlNodePtr n, const char *plabel,
                                 int name_required, uMaterial *m)
{
  static const char *const a_mat[] = {"name", NULL};
  static const char *const a_tex[] = {"filename", NULL};
  static const char *const kids[] = {"color", "texture", NULL};
  memset(m, 0, sizeof *m);
  xEl e;
  ssStatus st = el_open(c, n, plabel, &e);
  if (!st) st = el_allow(c, &e, a_mat);
  if (!st && (name_required || el_find(&e, "name")))
    st = get_name(c, &e, "name", m->name);
  if (!st && m->name[0])
    snprintf(e.label, sizeof e.label, "%s%s<material '%s'>",
             plabel ? plabel : "", plabel ? " " : "", m->name);
  m->line = e.line;
  int seen_c = 0, seen_t = 0;
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
    } else if (is_el(k, "color")) {
      xEl x;
      if (!(st = el_open(c, k, e.label, &x))) st = once(c, &seen_c, &x);
      el_free(&x);
      if (!st) st = read_color(c, k, e.label, m->rgba);
      m->has_color = 1;
    } else if (is_el(k, "texture")) {
      xEl x;
      if (!(st = open_leaf(c, k, e.label, a_tex, &x))) st = once(c, &seen_t, &x);
      el_free(&x);
    } else {
      st = unknown_child(c, k, &e, kids);
    }
  }
  el_free(&e);
  return st;
}

static ssStatus add_material(uCtx *c, const uMaterial *m)
{
  if (grow((void **)&c->mat, &c->capmat, c->nmat, sizeof *c->mat))
    return nomem(c, m->line);
  c->mat[c->nmat++] = *m;
  /* callers add only names not defined yet */
  if (tab_add(c, &c->mat_tab, TAB_MAT, c->nmat - 1)) return nomem(c, m->line);
  return SS_OK;
}

static ssStatus read_top_material(uCtx *c, xmlNodePtr n)
{
  uMaterial m;
  ssStatus st = read_material_el(c, n, NULL, 1, &m);
  if (st) return st;
  int i = find_material(c, m.name);
  if (i >= 0)
    return fail(c, SS_ERR_PARSE, m.line,
                "duplicate material name '%s' (first at line %d)", m.name,
                c->mat[i].line);
  return add_material(c, &m);
}

/* ---------------------------------------------------------------------- */
/* links                                                                   */

static ssStatus read_origin(uCtx *c, xmlNodePtr n, const char *label,
                            int *seen, double pos[3], double quat[4])
{
  static const char *const a_origin[] = {"xyz", "rpy", NULL};
  xEl e;
  double rpy[3] = {0, 0, 0};
  ssStatus st = open_leaf(c, n, label, a_origin, &e);
  if (!st) st = once(c, seen, &e);
  if (!st) st = get_vec(c, &e, "xyz", 3, 0, pos);
  if (!st) st = get_vec(c, &e, "rpy", 3, 0, rpy);
  if (!st) rpy_to_quat(rpy, quat);
  el_free(&e);
  return st;
}

static ssStatus check_readable(const char *p, int *why)
{
  struct stat st;
  if (stat(p, &st) != 0) {
    *why = 0;
    return SS_ERR_IO;
  }
  if (!S_ISREG(st.st_mode)) {
    *why = 1;
    return SS_ERR_IO;
  }
  if (access(p, R_OK) != 0) {
    *why = 2;
    return SS_ERR_IO;
  }
  return SS_OK;
}

static int join_path(char *out, size_t cap, const char *dir, const char *rest)
{
  int n = snprintf(out, cap, "%s%s%s", dir,
                   *dir && dir[strlen(dir) - 1] == '/' ? "" : "/", rest);
  return n >= 0 && (size_t)n < cap ? 0 : -1;
}

/* Resolve a mesh filename by the rules in urdf.h and check the file. */
static ssStatus resolve_mesh(uCtx *c, const xEl *e, const char *fn,
                             char *out, size_t cap)
{
  char cand[2][1024];
  int ncand = 0;
  if (!*fn)
    return fail(c, SS_ERR_PARSE, e->line, "%s: attribute 'filename' is empty",
                e->label);
  if (!strncmp(fn, "package://", 10)) {
    const char *pkg = fn + 10, *slash = strchr(pkg, '/');
    if (!slash || slash == pkg || !slash[1])
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: filename = '%.300s' is not package://NAME/PATH",
                  e->label, fn);
    const char *base = c->res_dir && *c->res_dir ? c->res_dir : c->dir;
    if (join_path(cand[0], sizeof cand[0], base, slash + 1) ||
        join_path(cand[1], sizeof cand[1], base, pkg))
      return fail(c, SS_ERR_VALUE, e->line, "%s: mesh path '%.300s' is too long",
                  e->label, fn);
    ncand = 2;
  } else if (strstr(fn, "://") && strncmp(fn, "file://", 7)) {
    return fail(c, SS_ERR_UNSUPPORTED, e->line,
                "%s: filename = '%.300s' uses an unsupported URI scheme "
                "(allowed: package://, file://, plain paths)", e->label, fn);
  } else {
    /* file://PATH or a plain PATH: absolute, or relative to the URDF */
    const char *p = strncmp(fn, "file://", 7) ? fn : fn + 7;
    if (!*p)
      return fail(c, SS_ERR_PARSE, e->line, "%s: filename = '%s' names no file",
                  e->label, fn);
    int bad = p[0] == '/' ? snprintf(cand[0], sizeof cand[0], "%s", p) >=
                                (int)sizeof cand[0]
                          : join_path(cand[0], sizeof cand[0], c->dir, p);
    if (bad)
      return fail(c, SS_ERR_VALUE, e->line, "%s: mesh path '%.300s' is too long",
                  e->label, fn);
    ncand = 1;
  }
  int why = 0, access_errno = 0;
  for (int k = 0; k < ncand; k++) {
    int w = 0;
    ssStatus r = check_readable(cand[k], &w);
    if (r != SS_OK && w == 2) access_errno = errno;
    if (r == SS_OK) {
      if (strlen(cand[k]) >= cap)
        return fail(c, SS_ERR_VALUE, e->line,
                    "%s: mesh path '%.300s' is too long", e->label, cand[k]);
      snprintf(out, cap, "%s", cand[k]);
      return SS_OK;
    }
    if (k == 0 || w > why) why = w;
  }
  char unreadable[160];
  snprintf(unreadable, sizeof unreadable, "not readable (%s)",
           strerror(access_errno ? access_errno : EACCES));
  const char *reason = why == 0   ? "not found"
                       : why == 1 ? "not a regular file"
                                  : unreadable;
  if (ncand == 2)
    return fail(c, SS_ERR_IO, e->line,
                "%s: mesh file '%.300s' %s (looked for '%.300s' and '%.300s')",
                e->label, fn, reason, cand[0], cand[1]);
  return fail(c, SS_ERR_IO, e->line, "%s: mesh file '%.300s' %s (looked for "
              "'%.300s')", e->label, fn, reason, cand[0]);
}

static ssStatus read_shape(uCtx *c, xmlNodePtr n, const char *label,
                           ssUrdfGeom *g)
{
  static const char *const a_box[] = {"size", NULL};
  static const char *const a_sphere[] = {"radius", NULL};
  static const char *const a_cyl[] = {"radius", "length", NULL};
  static const char *const a_mesh[] = {"filename", "scale", NULL};
  xEl e;
  ssStatus st = SS_OK;
  memset(g->size, 0, sizeof g->size);
  if (is_el(n, "box")) {
    g->type = SS_GEOM_BOX;
    if (!(st = open_leaf(c, n, label, a_box, &e)))
      st = get_vec(c, &e, "size", 3, 1, g->size);
    for (int k = 0; !st && k < 3; k++)
      if (!(g->size[k] > 0))
        st = fail(c, SS_ERR_VALUE, e.line,
                  "%s: size value %d is %.17g; box edges must be > 0", e.label,
                  k + 1, g->size[k]);
  } else if (is_el(n, "sphere")) {
    g->type = SS_GEOM_SPHERE;
    if (!(st = open_leaf(c, n, label, a_sphere, &e)))
      st = get_num_min(c, &e, "radius", 1, 0, 1, &g->size[0]);
  } else if (is_el(n, "cylinder") || is_el(n, "capsule")) {
    int cap = is_el(n, "capsule");
    g->type = cap ? SS_GEOM_CAPSULE : SS_GEOM_CYLINDER;
    if (!(st = open_leaf(c, n, label, a_cyl, &e)))
      st = get_num_min(c, &e, "radius", 1, 0, 1, &g->size[0]);
    if (!st) st = get_num_min(c, &e, "length", 1, 0, !cap, &g->size[1]);
  } else if (is_el(n, "mesh")) {
    g->type = SS_GEOM_MESH;
    if (!(st = open_leaf(c, n, label, a_mesh, &e))) {
      const char *v = el_find(&e, "scale");
      if (v) {
        double s[3];
        int got = 0;
        st = parse_values(c, &e, "scale", v, 3, 1, &got, s);
        if (!st && got == 1) s[1] = s[2] = s[0];
        for (int k = 0; !st && k < 3; k++)
          if (s[k] == 0)
            st = fail(c, SS_ERR_VALUE, e.line,
                      "%s: scale value %d is 0; mesh scales must be non-zero",
                      e.label, k + 1);
        if (!st) memcpy(g->mesh_scale, s, sizeof s);
      }
    }
    const char *fn = NULL;
    if (!st && !(fn = el_find(&e, "filename"))) st = missing(c, &e, "filename");
    if (!st) st = resolve_mesh(c, &e, fn, g->mesh_path, sizeof g->mesh_path);
  } else {
    return SS_ERR_NOTFOUND; /* caller reports */
  }
  el_free(&e);
  return st;
}

static ssStatus read_geometry(uCtx *c, xmlNodePtr n, const char *label,
                              ssUrdfGeom *g)
{
  static const char *const kids[] = {"box",     "sphere", "cylinder",
                                     "capsule", "mesh",   NULL};
  static const char *const none[] = {NULL};
  xEl e;
  ssStatus st = el_open(c, n, label, &e);
  if (!st) st = el_allow(c, &e, none);
  int nshape = 0;
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
      continue;
    }
    int known = 0;
    for (int i = 0; kids[i]; i++) known |= is_el(k, kids[i]);
    if (!known) {
      st = unknown_child(c, k, &e, kids);
    } else if (nshape++) {
      st = fail(c, SS_ERR_PARSE, ss_xml_line(k),
                "%s: more than one shape (<%s>); a <geometry> holds exactly "
                "one of box, sphere, cylinder, capsule, mesh", e.label,
                (const char *)k->name);
    } else {
      st = read_shape(c, k, e.label, g);
    }
  }
  if (!st && !nshape)
    st = fail(c, SS_ERR_PARSE, e.line,
              "%s: no shape given (expected one of box, sphere, cylinder, "
              "capsule, mesh)", e.label);
  el_free(&e);
  return st;
}

static ssStatus read_visual(uCtx *c, xmlNodePtr n, const char *label,
                            int collision, ssUrdfGeom *g)
{
  static const char *const a_vis[] = {"name", NULL};
  static const char *const k_vis[] = {"origin", "geometry", "material", NULL};
  static const char *const k_col[] = {"origin", "geometry", NULL};
  memset(g, 0, sizeof *g);
  g->quat[0] = 1;
  g->mesh_scale[0] = g->mesh_scale[1] = g->mesh_scale[2] = 1;
  g->collision = collision;
  xEl e;
  ssStatus st = el_open(c, n, label, &e);
  if (!st) st = el_allow(c, &e, a_vis);
  g->line = e.line;
  int seen_o = 0, seen_g = 0, seen_m = 0;
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
    } else if (is_el(k, "origin")) {
      st = read_origin(c, k, e.label, &seen_o, g->pos, g->quat);
    } else if (is_el(k, "geometry")) {
      xEl x;
      if (!(st = el_open(c, k, e.label, &x))) st = once(c, &seen_g, &x);
      el_free(&x);
      if (!st) st = read_geometry(c, k, e.label, g);
    } else if (!collision && is_el(k, "material")) {
      xEl x;
      if (!(st = el_open(c, k, e.label, &x))) st = once(c, &seen_m, &x);
      el_free(&x);
      uMaterial m;
      if (!st) st = read_material_el(c, k, e.label, 0, &m);
      if (st) break;
      if (m.has_color) {
        memcpy(g->rgba, m.rgba, sizeof g->rgba);
        /* a named colour given inline serves later references too, as in
         * urdfdom */
        if (m.name[0] && find_material(c, m.name) < 0)
          st = add_material(c, &m);
      } else if (m.name[0]) {
        int i = find_material(c, m.name);
        if (i < 0)
          st = fail(c, SS_ERR_NOTFOUND, m.line,
                    "%s <material>: material '%s' is not defined (define it "
                    "at the top level or give a <color>)", e.label, m.name);
        else
          memcpy(g->rgba, c->mat[i].rgba, sizeof g->rgba);
      } else {
        st = fail(c, SS_ERR_PARSE, m.line,
                  "%s <material>: give a name or a <color>", e.label);
      }
    } else {
      st = unknown_child(c, k, &e, collision ? k_col : k_vis);
    }
  }
  if (!st && !seen_g)
    st = fail(c, SS_ERR_PARSE, e.line, "%s: missing <geometry>", e.label);
  el_free(&e);
  return st;
}

static ssStatus read_inertial(uCtx *c, xmlNodePtr n, const char *label,
                              ssUrdfLink *l)
{
  static const char *const none[] = {NULL};
  static const char *const kids[] = {"origin", "mass", "inertia", NULL};
  static const char *const a_mass[] = {"value", NULL};
  static const char *const a_in[] = {"ixx", "ixy", "ixz", "iyy",
                                     "iyz", "izz", NULL};
  xEl e;
  ssStatus st = el_open(c, n, label, &e);
  if (!st) st = el_allow(c, &e, none);
  int seen_o = 0, seen_m = 0, seen_i = 0, line_i = 0;
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    xEl x;
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
    } else if (is_el(k, "origin")) {
      st = read_origin(c, k, e.label, &seen_o, l->com, l->com_quat);
    } else if (is_el(k, "mass")) {
      if (!(st = open_leaf(c, k, e.label, a_mass, &x))) st = once(c, &seen_m, &x);
      if (!st) st = get_num(c, &x, "value", 1, &l->mass);
      if (!st && l->mass < 0)
        st = fail(c, SS_ERR_VALUE, x.line,
                  "%s: value = %.17g is negative (a mass must be >= 0 kg)",
                  x.label, l->mass);
      el_free(&x);
    } else if (is_el(k, "inertia")) {
      if (!(st = open_leaf(c, k, e.label, a_in, &x))) st = once(c, &seen_i, &x);
      for (int i = 0; !st && i < 6; i++)
        st = get_num(c, &x, a_in[i], 1, &l->inertia[i]);
      line_i = x.line;
      el_free(&x);
    } else {
      st = unknown_child(c, k, &e, kids);
    }
  }
  if (!st && !seen_m)
    st = fail(c, SS_ERR_PARSE, e.line, "%s: missing <mass value=...>", e.label);
  if (!st && !seen_i)
    st = fail(c, SS_ERR_PARSE, e.line,
              "%s: missing <inertia ixx ixy ixz iyy iyz izz>", e.label);
  if (!st) {
    double I[9], ev[3];
    inertia_mat(l->inertia, I);
    sym_eig3(I, ev);
    if (l->mass > 0 && !is_pd(ev))
      st = fail(c, SS_ERR_VALUE, line_i,
                "%s <inertia>: not positive definite (principal moments %.6g, "
                "%.6g, %.6g kg m^2); a link with mass > 0 needs all principal "
                "moments > 0", e.label, ev[0], ev[1], ev[2]);
    else if (l->mass == 0 && ev[0] < -1e-12 * fabs(ev[2]))
      st = fail(c, SS_ERR_VALUE, line_i,
                "%s <inertia>: has a negative principal moment (%.6g, %.6g, "
                "%.6g kg m^2); moments must be >= 0", e.label, ev[0], ev[1],
                ev[2]);
  }
  el_free(&e);
  return st;
}

static uint64_t name_hash(const char *s)
{
  uint64_t h = 1469598103934665603ULL; /* FNV-1a */
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ULL;
  return h;
}

/* The name of entry i of a kind (TAB_*). */
static const char *entry_name(const uCtx *c, int kind, int i)
{
  switch (kind) {
  case TAB_LINK: return c->link[i].name;
  case TAB_JOINT: return c->joint[i].name;
  case TAB_MAT: return c->mat[i].name;
  case TAB_CLOSURE: return c->out->closure[i].name;
  default: return c->out->spring[i].name;
  }
}

/* The slot of `name` in t: its entry's, or the empty one it would take. */
static int tab_slot(const uCtx *c, const nameTab *t, int kind,
                    const char *name)
{
  unsigned mask = (unsigned)t->cap - 1;
  unsigned k = (unsigned)name_hash(name) & mask;
  while (t->slot[k] && strcmp(entry_name(c, kind, t->slot[k] - 1), name))
    k = (k + 1) & mask;
  return (int)k;
}

static int tab_find(const uCtx *c, const nameTab *t, int kind,
                    const char *name)
{
  return t->cap ? t->slot[tab_slot(c, t, kind, name)] - 1 : -1;
}

/* Enter entry i under its name (not yet entered); 0, or -1 out of memory. */
static int tab_add(const uCtx *c, nameTab *t, int kind, int i)
{
  if (2 * (t->n + 1) > t->cap) {
    nameTab g = {NULL, t->cap ? 2 * t->cap : 64, 0};
    g.slot = calloc((size_t)g.cap, sizeof *g.slot);
    if (!g.slot) return -1;
    for (int k = 0; k < t->cap; k++)
      if (t->slot[k])
        g.slot[tab_slot(c, &g, kind, entry_name(c, kind, t->slot[k] - 1))] =
            t->slot[k];
    g.n = t->n;
    free(t->slot);
    *t = g;
  }
  t->slot[tab_slot(c, t, kind, entry_name(c, kind, i))] = i + 1;
  t->n++;
  return 0;
}

static int find_link_doc(const uCtx *c, const char *name)
{
  return tab_find(c, &c->link_tab, TAB_LINK, name);
}

static int find_joint_doc(const uCtx *c, const char *name)
{
  return tab_find(c, &c->joint_tab, TAB_JOINT, name);
}

static ssStatus add_geom(uCtx *c, ssUrdfLink *l, int *cap, const ssUrdfGeom *g)
{
  if (grow((void **)&l->geom, cap, l->ngeom, sizeof *l->geom))
    return nomem(c, g->line);
  l->geom[l->ngeom++] = *g;
  return SS_OK;
}

static ssStatus read_link(uCtx *c, xmlNodePtr n)
{
  static const char *const a_link[] = {"name", NULL};
  static const char *const kids[] = {"inertial", "visual", "collision", NULL};
  if (grow((void **)&c->link, &c->caplink, c->nlink, sizeof *c->link) ||
      grow((void **)&c->link_extra, &c->capextra, c->nlink,
           sizeof *c->link_extra))
    return nomem(c, ss_xml_line(n));
  ssUrdfLink *l = &c->link[c->nlink];
  memset(l, 0, sizeof *l);
  l->com_quat[0] = 1;
  c->link_extra[c->nlink] = 0;
  c->nlink++; /* owned by the context from here on (freed on error) */
  xEl e;
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, a_link);
  if (!st) st = get_name(c, &e, "name", l->name);
  l->line = e.line;
  if (!st) {
    int i = find_link_doc(c, l->name);
    if (i >= 0)
      st = fail(c, SS_ERR_PARSE, e.line,
                "duplicate link name '%s' (first at line %d)", l->name,
                c->link[i].line);
    else if (tab_add(c, &c->link_tab, TAB_LINK, c->nlink - 1))
      st = nomem(c, e.line);
  }
  char label[NAME_LEN + 16];
  snprintf(label, sizeof label, "link '%s'", l->name);
  int seen_i = 0, capg = 0;
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
      continue;
    }
    if (is_el(k, "inertial") || is_el(k, "visual") || is_el(k, "collision"))
      if (!c->link_extra[c->nlink - 1])
        c->link_extra[c->nlink - 1] = ss_xml_line(k);
    if (is_el(k, "inertial")) {
      xEl x;
      if (!(st = el_open(c, k, label, &x))) st = once(c, &seen_i, &x);
      el_free(&x);
      if (!st) st = read_inertial(c, k, label, l);
    } else if (is_el(k, "visual") || is_el(k, "collision")) {
      ssUrdfGeom g;
      st = read_visual(c, k, label, is_el(k, "collision"), &g);
      if (!st) st = add_geom(c, l, &capg, &g);
    } else {
      st = unknown_child(c, k, &e, kids);
    }
  }
  el_free(&e);
  return st;
}

/* ---------------------------------------------------------------------- */
/* joints                                                                  */

static const char *const joint_types =
    "revolute, continuous, prismatic, fixed, floating, spherical";

static const char *type_name(int t)
{
  switch (t) {
  case SS_JOINT_FIXED: return "fixed";
  case SS_JOINT_REVOLUTE: return "revolute";
  case SS_JOINT_PRISMATIC: return "prismatic";
  case SS_JOINT_SPHERICAL: return "spherical";
  case SS_JOINT_FLOATING: return "floating";
  }
  return "?";
}

static int is_1dof(int t)
{
  return t == SS_JOINT_REVOLUTE || t == SS_JOINT_PRISMATIC;
}

static ssStatus add_pending(uCtx *c, const uPending *p, int line)
{
  if (grow((void **)&c->pend, &c->cappend, c->npend, sizeof *c->pend))
    return nomem(c, line);
  c->pend[c->npend++] = *p;
  return SS_OK;
}

static ssStatus read_link_ref(uCtx *c, xmlNodePtr k, const char *label,
                              int *seen, const char *role, int *out)
{
  static const char *const a_ref[] = {"link", NULL};
  xEl x;
  char name[NAME_LEN];
  ssStatus st = open_leaf(c, k, label, a_ref, &x);
  if (!st) st = once(c, seen, &x);
  if (!st) st = get_name(c, &x, "link", name);
  if (!st) {
    *out = find_link_doc(c, name);
    if (*out < 0)
      st = fail(c, SS_ERR_NOTFOUND, x.line,
                "%s: %s link '%s' is not defined (no <link name=\"%s\">)",
                label, role, name, name);
  }
  el_free(&x);
  return st;
}

static ssStatus read_joint(uCtx *c, xmlNodePtr n)
{
  static const char *const a_joint[] = {"name", "type", NULL};
  static const char *const kids[] = {
      "origin", "parent", "child", "axis", "limit", "dynamics", "mimic",
      "calibration", "safety_controller", NULL};
  static const char *const a_axis[] = {"xyz", NULL};
  static const char *const a_limit[] = {"lower", "upper", "effort",
                                        "velocity", NULL};
  static const char *const a_dyn[] = {"damping", "friction", "stiffness",
                                      "spring_mount", NULL};
  static const char *const a_mimic[] = {"joint", "multiplier", "offset", NULL};
  if (grow((void **)&c->joint, &c->capjoint, c->njoint, sizeof *c->joint))
    return nomem(c, ss_xml_line(n));
  ssUrdfJoint *j = &c->joint[c->njoint++];
  memset(j, 0, sizeof *j);
  j->quat[0] = 1;
  j->axis[0] = 1;
  j->parent = j->child = -1;
  xEl e;
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, a_joint);
  if (!st) st = get_name(c, &e, "name", j->name);
  j->line = e.line;
  if (!st) {
    int i = find_joint_doc(c, j->name);
    if (i >= 0)
      st = fail(c, SS_ERR_PARSE, e.line,
                "duplicate joint name '%s' (first at line %d)", j->name,
                c->joint[i].line);
    else if (tab_add(c, &c->joint_tab, TAB_JOINT, c->njoint - 1))
      st = nomem(c, e.line);
  }
  char label[NAME_LEN + 16];
  snprintf(label, sizeof label, "joint '%s'", j->name);
  const char *ty = NULL;
  int continuous = 0;
  if (!st && !(ty = el_find(&e, "type"))) st = missing(c, &e, "type");
  if (!st) {
    if (!strcmp(ty, "revolute")) j->type = SS_JOINT_REVOLUTE;
    else if (!strcmp(ty, "continuous")) j->type = SS_JOINT_REVOLUTE, continuous = 1;
    else if (!strcmp(ty, "prismatic")) j->type = SS_JOINT_PRISMATIC;
    else if (!strcmp(ty, "fixed")) j->type = SS_JOINT_FIXED;
    else if (!strcmp(ty, "floating")) j->type = SS_JOINT_FLOATING;
    else if (!strcmp(ty, "spherical")) j->type = SS_JOINT_SPHERICAL;
    else if (!strcmp(ty, "planar"))
      st = fail(c, SS_ERR_UNSUPPORTED, e.line,
                "%s: type 'planar' is not supported (allowed: %s)", label,
                joint_types);
    else
      st = fail(c, SS_ERR_PARSE, e.line,
                "%s: unknown joint type '%.60s' (allowed: %s)", label, ty,
                joint_types);
  }
  int seen_o = 0, seen_p = 0, seen_c = 0, seen_a = 0, seen_l = 0, seen_d = 0,
      seen_m = 0, axis_line = 0, has_lo = 0, has_hi = 0, dyn_line = 0,
      seen_cal = 0, seen_saf = 0;
  double axis[3] = {1, 0, 0};
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    xEl x;
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
    } else if (is_el(k, "origin")) {
      st = read_origin(c, k, label, &seen_o, j->pos, j->quat);
    } else if (is_el(k, "parent")) {
      st = read_link_ref(c, k, label, &seen_p, "parent", &j->parent);
    } else if (is_el(k, "child")) {
      st = read_link_ref(c, k, label, &seen_c, "child", &j->child);
    } else if (is_el(k, "axis")) {
      if (!(st = open_leaf(c, k, label, a_axis, &x))) st = once(c, &seen_a, &x);
      if (!st) st = get_vec(c, &x, "xyz", 3, 1, axis);
      axis_line = x.line;
      el_free(&x);
    } else if (is_el(k, "limit")) {
      if (!(st = open_leaf(c, k, label, a_limit, &x))) st = once(c, &seen_l, &x);
      has_lo = el_find(&x, "lower") != NULL;
      has_hi = el_find(&x, "upper") != NULL;
      if (!st) st = get_num(c, &x, "lower", 0, &j->lower);
      if (!st) st = get_num(c, &x, "upper", 0, &j->upper);
      if (!st) st = get_num_min(c, &x, "effort", 0, 0, 0, &j->effort);
      if (!st) st = get_num_min(c, &x, "velocity", 0, 0, 0, &j->velocity);
      if (!st && !continuous && is_1dof(j->type) && (has_lo || has_hi) &&
          j->lower > j->upper)
        st = fail(c, SS_ERR_VALUE, x.line,
                  "%s: lower = %.17g is above upper = %.17g", x.label,
                  j->lower, j->upper);
      el_free(&x);
    } else if (is_el(k, "dynamics")) {
      if (!(st = open_leaf(c, k, label, a_dyn, &x))) st = once(c, &seen_d, &x);
      if (!st) st = get_num_min(c, &x, "damping", 0, 0, 0, &j->damping);
      if (!st) st = get_num_min(c, &x, "friction", 0, 0, 0, &j->friction);
      if (!st) st = get_num_min(c, &x, "stiffness", 0, 0, 0, &j->stiffness);
      if (!st) st = get_num(c, &x, "spring_mount", 0, &j->spring_mount);
      dyn_line = x.line;
      el_free(&x);
    } else if (is_el(k, "mimic")) {
      uPending p;
      memset(&p, 0, sizeof p);
      p.kind = 0;
      p.mimic = 1;
      p.cl.type = SS_CLOSURE_EQUALITY;
      p.cl.ratio = 1;
      if (!(st = open_leaf(c, k, label, a_mimic, &x))) st = once(c, &seen_m, &x);
      snprintf(p.name1, sizeof p.name1, "%s", j->name);
      if (!st) st = get_name(c, &x, "joint", p.name2);
      if (!st) st = get_num(c, &x, "multiplier", 0, &p.cl.ratio);
      if (!st) st = get_num(c, &x, "offset", 0, &p.cl.offset);
      p.cl.line = x.line;
      snprintf(p.label, sizeof p.label, "%.60s", x.label);
      p.attr1 = "(its joint)";
      p.attr2 = "joint";
      if (!st) st = add_pending(c, &p, x.line);
      el_free(&x);
    } else if (is_el(k, "calibration") || is_el(k, "safety_controller")) {
      /* ROS-specific, nothing to simulate: checked as URDF has them (a
       * typo is reported, not dropped), then not used */
      static const char *const a_cal[] = {"rising", "falling",
                                          "reference_position", NULL};
      static const char *const a_saf[] = {"soft_lower_limit", "soft_upper_limit",
                                          "k_position", "k_velocity", NULL};
      int cal = is_el(k, "calibration");
      const char *const *allowed = cal ? a_cal : a_saf;
      if (!(st = open_leaf(c, k, label, allowed, &x)))
        st = once(c, cal ? &seen_cal : &seen_saf, &x);
      for (int i = 0; !st && allowed[i]; i++) {
        double v = 0;
        st = get_num(c, &x, allowed[i], 0, &v);
      }
      el_free(&x);
    } else {
      st = unknown_child(c, k, &e, kids);
    }
  }
  /* what the joint's degrees of freedom cannot take would be dropped
   * without a word: a joint spring acts on one coordinate, and a fixed or
   * floating joint (the latter is the world's, dropped) has no damper */
  if (!st && seen_d && !is_1dof(j->type)) {
    const char *bad = NULL;
    double v = 0;
    if (j->stiffness != 0) bad = "stiffness", v = j->stiffness;
    else if (j->spring_mount != 0) bad = "spring_mount", v = j->spring_mount;
    else if (j->damping != 0 && j->type != SS_JOINT_SPHERICAL)
      bad = "damping", v = j->damping;
    if (bad)
      st = fail(c, SS_ERR_VALUE, dyn_line,
                "%s <dynamics>: %s = %.17g on a %s joint, %s (damping acts on "
                "revolute, continuous, prismatic and spherical joints; a joint "
                "spring, stiffness and spring_mount, on the first three only)",
                label, bad, v, type_name(j->type),
                j->type == SS_JOINT_SPHERICAL ? "which has no joint spring"
                : j->type == SS_JOINT_FIXED   ? "which does not move"
                                              : "the free base, which has "
                                                "neither damper nor spring");
  }
  if (!st && !seen_p)
    st = fail(c, SS_ERR_PARSE, e.line, "%s: missing <parent link=...>", label);
  if (!st && !seen_c)
    st = fail(c, SS_ERR_PARSE, e.line, "%s: missing <child link=...>", label);
  if (!st) {
    double len = ss_v3_norm(axis);
    /* huge (1e200) or tiny (1e-320) components over- or underflow the
     * norm: divide by the largest component first (ordinary axes are left
     * as they are, bit for bit) */
    double big = fmax(fabs(axis[0]), fmax(fabs(axis[1]), fabs(axis[2])));
    if (!(len > 1e-150 && len < 1e150) && big > 0 && isfinite(big)) {
      for (int a = 0; a < 3; a++) axis[a] /= big;
      len = ss_v3_norm(axis);
    }
    if (j->type == SS_JOINT_REVOLUTE || j->type == SS_JOINT_PRISMATIC) {
      if (!(len > 0))
        st = fail(c, SS_ERR_VALUE, axis_line,
                  "%s <axis>: xyz = 0 0 0 is a zero axis (a %s joint needs a "
                  "non-zero axis)", label, ty);
      else
        ss_v3_scale(j->axis, axis, 1 / len);
    } else if (len > 0) {
      ss_v3_scale(j->axis, axis, 1 / len);
    }
    /* an overflowing norm (1e200 components) is caught by its result */
    if (!st && !(isfinite(j->axis[0]) && isfinite(j->axis[1]) &&
                 isfinite(j->axis[2])))
      st = fail(c, SS_ERR_VALUE, axis_line, "%s <axis>: cannot be normalised",
                label);
  }
  if (!st) {
    j->limited = !continuous && is_1dof(j->type) && (has_lo || has_hi);
    if (continuous || !is_1dof(j->type)) j->lower = j->upper = 0;
  }
  el_free(&e);
  return st;
}

/* ---------------------------------------------------------------------- */
/* constraints and springs                                                 */

static ssStatus read_constraints(uCtx *c, xmlNodePtr n)
{
  static const char *const none[] = {NULL};
  static const char *const kids[] = {"pin", "distance", "equality", NULL};
  static const char *const a_pin[] = {"name", "body1", "body2", "anchor",
                                      "anchor2", NULL};
  static const char *const a_dist[] = {"name",    "body1",   "body2",
                                       "anchor1", "anchor2", "length", NULL};
  static const char *const a_eq[] = {"name",  "joint1", "joint2",
                                     "ratio", "offset", NULL};
  xEl e;
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, none);
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
      continue;
    }
    uPending p;
    memset(&p, 0, sizeof p);
    p.kind = 0;
    xEl x;
    if (is_el(k, "pin")) {
      p.cl.type = SS_CLOSURE_PIN;
      if (!(st = open_leaf(c, k, NULL, a_pin, &x)))
        st = get_vec(c, &x, "anchor", 3, 1, p.cl.anchor1);
      if (!st && el_find(&x, "anchor2")) {
        p.cl.has_anchor2 = 1;
        st = get_vec(c, &x, "anchor2", 3, 1, p.cl.anchor2);
      }
    } else if (is_el(k, "distance")) {
      p.cl.type = SS_CLOSURE_DISTANCE;
      p.cl.has_anchor2 = 1;
      p.cl.length = -1;
      if (!(st = open_leaf(c, k, NULL, a_dist, &x)))
        st = get_vec(c, &x, "anchor1", 3, 0, p.cl.anchor1);
      if (!st) st = get_vec(c, &x, "anchor2", 3, 0, p.cl.anchor2);
      if (!st) st = get_num_min(c, &x, "length", 0, 0, 1, &p.cl.length);
    } else if (is_el(k, "equality")) {
      p.cl.type = SS_CLOSURE_EQUALITY;
      p.cl.ratio = 1;
      if (!(st = open_leaf(c, k, NULL, a_eq, &x)))
        st = get_num(c, &x, "ratio", 0, &p.cl.ratio);
      if (!st) st = get_num(c, &x, "offset", 0, &p.cl.offset);
    } else {
      st = unknown_child(c, k, &e, kids);
      continue;
    }
    if (!st && el_find(&x, "name")) st = get_name(c, &x, "name", p.cl.name);
    int eq = p.cl.type == SS_CLOSURE_EQUALITY;
    p.attr1 = eq ? "joint1" : "body1";
    p.attr2 = eq ? "joint2" : "body2";
    if (!st) st = get_name(c, &x, p.attr1, p.name1);
    if (!st) st = get_name(c, &x, p.attr2, p.name2);
    p.cl.line = x.line;
    snprintf(p.label, sizeof p.label, "<%s>", x.name);
    if (!st) st = add_pending(c, &p, x.line);
    el_free(&x);
  }
  el_free(&e);
  return st;
}

static ssStatus read_spring(uCtx *c, xmlNodePtr n)
{
  static const char *const a_spring[] = {
      "name",    "body1",     "body2",   "anchor1",
      "anchor2", "stiffness", "damping", "rest_length", NULL};
  uPending p;
  memset(&p, 0, sizeof p);
  p.kind = 1;
  p.sp.rest_length = -1;
  xEl x;
  ssStatus st = open_leaf(c, n, NULL, a_spring, &x);
  if (!st && el_find(&x, "name")) st = get_name(c, &x, "name", p.sp.name);
  if (!st && p.sp.name[0])
    snprintf(x.label, sizeof x.label, "spring '%s'", p.sp.name);
  p.attr1 = "body1";
  p.attr2 = "body2";
  if (!st) st = get_name(c, &x, "body1", p.name1);
  if (!st) st = get_name(c, &x, "body2", p.name2);
  if (!st) st = get_vec(c, &x, "anchor1", 3, 0, p.sp.anchor1);
  if (!st) st = get_vec(c, &x, "anchor2", 3, 0, p.sp.anchor2);
  if (!st) st = get_num_min(c, &x, "stiffness", 1, 0, 0, &p.sp.stiffness);
  if (!st) st = get_num_min(c, &x, "damping", 0, 0, 0, &p.sp.damping);
  if (!st) st = get_num_min(c, &x, "rest_length", 0, 0, 0, &p.sp.rest_length);
  p.sp.line = x.line;
  snprintf(p.label, sizeof p.label, "%.79s", x.label);
  if (!st) st = add_pending(c, &p, x.line);
  el_free(&x);
  return st;
}

/* ---------------------------------------------------------------------- */
/* the tree                                                                */

/* Pose of a link frame in another: p, q. */
typedef struct pose {
  double p[3], q[4];
} pose;

/* Composite mass, centre of mass and rotational inertia about it of link l
 * and every link attached to it by fixed joints (child lists by document
 * index), all in l's frame. */
static void composite(const uCtx *c, int l, const int *kid_first,
                      const int *kid_next, pose *tmp, int *stack,
                      double *mass, double com[3], double I[9])
{
  /* pass 1: poses of the fixed subtree, mass and centre of mass */
  int top = 0, nvis = 0;
  double M = 0, S[3] = {0, 0, 0};
  memset(&tmp[l], 0, sizeof tmp[l]);
  tmp[l].q[0] = 1;
  stack[top++] = l;
  int *order = stack + c->nlink; /* visited links, second half of stack */
  while (top) {
    int a = stack[--top];
    order[nvis++] = a;
    const ssUrdfLink *L = &c->link[a];
    double R[9], cw[3];
    ss_quat_to_mat(R, tmp[a].q);
    ss_m3_mulv(cw, R, L->com);
    ss_v3_add(cw, cw, tmp[a].p);
    M += L->mass;
    ss_v3_addscl(S, cw, L->mass);
    for (int j = kid_first[a]; j >= 0; j = kid_next[j]) {
      const ssUrdfJoint *J = &c->joint[j];
      if (J->type != SS_JOINT_FIXED) continue;
      int b = J->child;
      double d[3];
      ss_m3_mulv(d, R, J->pos);
      ss_v3_add(tmp[b].p, tmp[a].p, d);
      ss_quat_mul(tmp[b].q, tmp[a].q, J->quat);
      stack[top++] = b;
    }
  }
  double C[3] = {0, 0, 0};
  if (M > 0) ss_v3_scale(C, S, 1 / M);
  /* pass 2: inertia about the composite centre of mass */
  memset(I, 0, 9 * sizeof *I);
  for (int v = 0; v < nvis; v++) {
    int a = order[v];
    const ssUrdfLink *L = &c->link[a];
    double R[9], Rc[9], q[4], Ii[9], T[9], Rt[9], cw[3], d[3];
    ss_quat_to_mat(R, tmp[a].q);
    ss_m3_mulv(cw, R, L->com);
    ss_v3_add(cw, cw, tmp[a].p);
    ss_quat_mul(q, tmp[a].q, L->com_quat);
    ss_quat_to_mat(Rc, q);
    inertia_mat(L->inertia, Ii);
    ss_m3_mul(T, Rc, Ii);
    ss_m3_transpose(Rt, Rc);
    ss_m3_mul(T, T, Rt);
    ss_v3_sub(d, cw, C);
    double dd = ss_v3_dot(d, d);
    for (int r = 0; r < 3; r++)
      for (int s = 0; s < 3; s++)
        I[3 * r + s] += T[3 * r + s] +
                        L->mass * ((r == s ? dd : 0) - d[r] * d[s]);
  }
  /* symmetrise against rounding */
  for (int r = 0; r < 3; r++)
    for (int s = r + 1; s < 3; s++)
      I[3 * r + s] = I[3 * s + r] = 0.5 * (I[3 * r + s] + I[3 * s + r]);
  *mass = M;
  ss_v3_copy(com, C);
}

static ssStatus check_moving_mass(uCtx *c, int l, const ssUrdfJoint *J,
                                  const int *kid_first, const int *kid_next,
                                  pose *tmp, int *stack)
{
  double M, com[3], I[9], ev[3];
  composite(c, l, kid_first, kid_next, tmp, stack, &M, com, I);
  const ssUrdfLink *L = &c->link[l];
  if (!(M > 0))
    return fail(c, SS_ERR_VALUE, L->line,
                "link '%s' moves on %s joint '%s' but is massless: with the "
                "links fixed to it its mass is 0 kg (a moving link needs mass "
                "> 0 and a positive-definite rotational inertia)",
                L->name, type_name(J->type), J->name);
  sym_eig3(I, ev);
  if (!is_pd(ev))
    return fail(c, SS_ERR_VALUE, L->line,
                "link '%s' moves on %s joint '%s' but its rotational inertia "
                "(with the links fixed to it) is not positive definite "
                "(principal moments %.6g, %.6g, %.6g kg m^2; a moving link "
                "needs mass > 0 and a positive-definite rotational inertia)",
                L->name, type_name(J->type), J->name, ev[0], ev[1], ev[2]);
  return SS_OK;
}

/* Build the final ssUrdf from the document-order links and joints. */
static ssStatus build_tree(uCtx *c, ssUrdf *u)
{
  int nl = c->nlink, nj = c->njoint;
  ssStatus st = SS_OK;
  if (nl == 0)
    return fail(c, SS_ERR_PARSE, c->robot_line, "<robot '%s'> has no <link>",
                u->name);
  int *pj = malloc((size_t)nl * sizeof *pj);        /* parent joint */
  int *kid_first = malloc((size_t)nl * sizeof *kid_first);
  int *kid_last = malloc((size_t)nl * sizeof *kid_last);
  int *kid_next = malloc((size_t)(nj ? nj : 1) * sizeof *kid_next);
  int *mark = calloc((size_t)nl, sizeof *mark);
  int *stack = malloc((size_t)(2 * nl + 2) * sizeof *stack);
  int *newidx = malloc((size_t)nl * sizeof *newidx);
  int *jnew = malloc((size_t)(nj ? nj : 1) * sizeof *jnew);
  pose *tmp = malloc((size_t)nl * sizeof *tmp);
  if (!pj || !kid_first || !kid_last || !kid_next || !mark || !stack ||
      !newidx || !jnew || !tmp) {
    st = nomem(c, 0);
    goto done;
  }
  for (int i = 0; i < nl; i++) pj[i] = kid_first[i] = kid_last[i] = -1;
  int world = find_link_doc(c, "world");

  /* one parent per link; children listed in document order */
  for (int j = 0; j < nj && !st; j++) {
    const ssUrdfJoint *J = &c->joint[j];
    kid_next[j] = -1;
    if (J->parent == J->child)
      st = fail(c, SS_ERR_VALUE, J->line,
                "joint '%s' closes a cycle: its parent and child are both "
                "link '%s' (a URDF is a tree; use <constraints> for loops)",
                J->name, c->link[J->child].name);
    else if (J->child == world)
      st = fail(c, SS_ERR_VALUE, J->line,
                "joint '%s': the link 'world' stands for the world frame and "
                "cannot be a joint's child", J->name);
    else if (pj[J->child] >= 0)
      st = fail(c, SS_ERR_VALUE, J->line,
                "link '%s' has two parent joints: '%s' (line %d) and '%s' "
                "(each link but the root is the child of exactly one joint; "
                "use <constraints> for loops)",
                c->link[J->child].name, c->joint[pj[J->child]].name,
                c->joint[pj[J->child]].line, J->name);
    else if (J->type == SS_JOINT_FLOATING && J->parent != world)
      st = fail(c, SS_ERR_VALUE, J->line,
                "joint '%s': a floating joint must have the link 'world' as "
                "its parent (found '%s'); it frees the root from the world",
                J->name, c->link[J->parent].name);
    if (st) break;
    pj[J->child] = j;
    if (kid_last[J->parent] < 0)
      kid_first[J->parent] = j;
    else
      kid_next[kid_last[J->parent]] = j;
    kid_last[J->parent] = j;
  }
  if (st) goto done;

  /* cycles: follow parent joints; a walk that meets itself is a loop,
   * reported at the joint of the loop written last */
  for (int s = 0; s < nl && !st; s++) {
    if (mark[s]) continue;
    int a = s;
    while (a >= 0 && !mark[a]) {
      mark[a] = s + 1;
      a = pj[a] >= 0 ? c->joint[pj[a]].parent : -1;
    }
    if (a >= 0 && mark[a] == s + 1) {
      /* a is on a cycle: collect it */
      int last = pj[a], b = c->joint[pj[a]].parent;
      while (b != a) {
        if (pj[b] > last) last = pj[b];
        b = c->joint[pj[b]].parent;
      }
      char chain[600];
      size_t k = 0;
      int start = c->joint[last].child;
      b = start;
      chain[0] = 0;
      /* chain in parent-to-child order: walk parents from the closing
       * joint's child back to it, then print reversed */
      int cyc[64], ncyc = 0;
      do {
        if (ncyc < 64) cyc[ncyc++] = b;
        b = c->joint[pj[b]].parent;
      } while (b != start);
      int w0 = snprintf(chain, sizeof chain, "'%s' -> ", c->link[start].name);
      k = w0 > 0 && (size_t)w0 < sizeof chain ? (size_t)w0 : 0;
      for (int i = ncyc - 1; i >= 1; i--) {
        int w = snprintf(chain + k, sizeof chain - k, "'%s' -> ",
                         c->link[cyc[i]].name);
        if (w < 0 || (size_t)w >= sizeof chain - k) break;
        k += (size_t)w;
      }
      snprintf(chain + k, sizeof chain - k, "'%s'", c->link[start].name);
      st = fail(c, SS_ERR_VALUE, c->joint[last].line,
                "joint '%s' closes a cycle: %s (a URDF is a tree; use "
                "<constraints> for loops)", c->joint[last].name, chain);
    }
  }
  if (st) goto done;

  /* exactly one root */
  int root = -1;
  for (int i = 0; i < nl && !st; i++) {
    if (pj[i] >= 0) continue;
    if (root < 0) {
      root = i;
    } else {
      st = fail(c, SS_ERR_VALUE, c->link[i].line,
                "more than one root link: '%s' (line %d) and '%s' are no "
                "joint's child (every link but one must be the child of a "
                "joint)", c->link[root].name, c->link[root].line,
                c->link[i].name);
    }
  }
  if (st) goto done;

  /* the world link: no body of its own; dropped with its only joint when
   * that joint is floating or fixed */
  u->world_base = SS_URDF_BASE_NONE;
  u->base_quat[0] = 1;
  int dropped = -1;
  if (world >= 0) {
    if (c->link_extra[world]) {
      st = fail(c, SS_ERR_VALUE, c->link_extra[world],
                "link 'world' stands for the world frame and cannot have "
                "<inertial>, <visual> or <collision>");
      goto done;
    }
    int nkid = 0;
    for (int j = kid_first[world]; j >= 0; j = kid_next[j]) nkid++;
    int j0 = kid_first[world];
    for (int j = j0; j >= 0; j = kid_next[j])
      if (c->joint[j].type == SS_JOINT_FLOATING && nkid > 1) {
        st = fail(c, SS_ERR_VALUE, c->joint[j].line,
                  "joint '%s': a floating joint must be the only joint of the "
                  "link 'world'", c->joint[j].name);
        goto done;
      }
    u->world_base = SS_URDF_BASE_FIXED;
    if (nkid == 1 && (c->joint[j0].type == SS_JOINT_FIXED ||
                      c->joint[j0].type == SS_JOINT_FLOATING)) {
      dropped = j0;
      if (c->joint[j0].type == SS_JOINT_FLOATING)
        u->world_base = SS_URDF_BASE_FLOATING;
      ss_v3_copy(u->base_pos, c->joint[j0].pos);
      memcpy(u->base_quat, c->joint[j0].quat, sizeof u->base_quat);
      root = c->joint[j0].child;
    }
  }

  /* depth-first order from the root, children in document order */
  int nout = 0, top = 0;
  for (int i = 0; i < nl; i++) newidx[i] = -1;
  stack[top++] = root;
  while (top) {
    int a = stack[--top];
    newidx[a] = nout++;
    /* push the children, then reverse them so the first is visited first */
    int lo = top;
    for (int j = kid_first[a]; j >= 0; j = kid_next[j])
      stack[top++] = c->joint[j].child;
    for (int x = lo, y = top - 1; x < y; x++, y--) {
      int t = stack[x];
      stack[x] = stack[y];
      stack[y] = t;
    }
  }

  /* mass of every link that moves */
  for (int j = 0; j < nj && !st; j++) {
    const ssUrdfJoint *J = &c->joint[j];
    if (J->type == SS_JOINT_FIXED) continue;
    st = check_moving_mass(c, J->child, J, kid_first, kid_next, tmp, stack);
  }
  if (st) goto done;

  /* move links and joints into the result */
  u->nlink = nout;
  u->link = calloc((size_t)nout, sizeof *u->link);
  u->njoint = nout - 1;
  u->joint = calloc((size_t)(nout > 1 ? nout - 1 : 1), sizeof *u->joint);
  if (!u->link || !u->joint) {
    st = nomem(c, 0);
    goto done;
  }
  for (int i = 0; i < nl; i++) {
    if (newidx[i] < 0) continue;
    u->link[newidx[i]] = c->link[i];
    c->link[i].geom = NULL; /* now owned by u */
    c->link[i].ngeom = 0;
  }
  for (int j = 0; j < nj; j++) {
    jnew[j] = -1;
    if (j == dropped) continue;
    const ssUrdfJoint *J = &c->joint[j];
    int k = newidx[J->child] - 1;
    jnew[j] = k;
    u->joint[k] = *J;
    u->joint[k].parent = newidx[J->parent];
    u->joint[k].child = newidx[J->child];
  }
  u->root = 0;

  /* closures and springs, by final indices */
  for (int i = 0; i < c->npend && !st; i++) {
    uPending *p = &c->pend[i];
    int line = p->kind ? p->sp.line : p->cl.line;
    int a, b;
    if (p->kind == 0 && p->cl.type == SS_CLOSURE_EQUALITY) {
      int ja = find_joint_doc(c, p->name1), jb = find_joint_doc(c, p->name2);
      const char *bad = ja < 0 ? p->name1 : jb < 0 ? p->name2 : NULL;
      if (bad) {
        st = fail(c, SS_ERR_NOTFOUND, line,
                  "%s: %s = '%s' names no joint", p->label,
                  ja < 0 ? p->attr1 : p->attr2, bad);
        break;
      }
      for (int s = 0; s < 2 && !st; s++) {
        int jj = s ? jb : ja;
        if (!is_1dof(c->joint[jj].type) || jj == dropped)
          st = fail(c, SS_ERR_VALUE, line,
                    "%s: joint '%s' is a %s joint; an equality couples two "
                    "1-DOF joints (revolute, continuous or prismatic)",
                    p->label, c->joint[jj].name, type_name(c->joint[jj].type));
      }
      if (!st && ja == jb)
        st = fail(c, SS_ERR_VALUE, line,
                  "%s: joint '%s' is coupled to itself", p->label, p->name1);
      if (st) break;
      p->cl.joint1 = jnew[ja];
      p->cl.joint2 = jnew[jb];
      p->cl.body1 = p->cl.body2 = -1;
    } else {
      int la = find_link_doc(c, p->name1), lb = find_link_doc(c, p->name2);
      a = la >= 0 ? newidx[la] : -1;
      b = lb >= 0 ? newidx[lb] : -1;
      if (a < 0 || b < 0) {
        int which = a < 0 ? 0 : 1;
        int l = which ? lb : la;
        st = fail(c, SS_ERR_NOTFOUND, line,
                  "%s: %s = '%s' %s", p->label, which ? p->attr2 : p->attr1,
                  which ? p->name2 : p->name1,
                  l < 0 ? "names no link"
                        : "is the world link, dropped with its joint (attach "
                          "to the root instead)");
        break;
      }
      if (a == b) {
        st = fail(c, SS_ERR_VALUE, line,
                  "%s: body1 and body2 are both '%s' (they must differ)",
                  p->label, p->name1);
        break;
      }
      if (p->kind) {
        p->sp.body1 = a;
        p->sp.body2 = b;
      } else {
        p->cl.body1 = a;
        p->cl.body2 = b;
        p->cl.joint1 = p->cl.joint2 = -1;
      }
    }
  }
  if (st) goto done;
  for (int i = 0; i < c->npend; i++) {
    if (c->pend[i].kind) u->nspring++;
    else u->nclosure++;
  }
  u->closure = calloc((size_t)(u->nclosure ? u->nclosure : 1), sizeof *u->closure);
  u->spring = calloc((size_t)(u->nspring ? u->nspring : 1), sizeof *u->spring);
  if (!u->closure || !u->spring) {
    st = nomem(c, 0);
    goto done;
  }
  /* <constraints> first, then mimics, each in document order */
  int kc = 0, ks = 0;
  for (int pass = 0; pass < 2; pass++)
    for (int i = 0; i < c->npend; i++) {
      uPending *p = &c->pend[i];
      if (p->kind) {
        if (pass == 0) u->spring[ks++] = p->sp;
      } else if (p->mimic == pass) {
        u->closure[kc++] = p->cl;
      }
    }
  /* unique names, each against the earlier ones through a name table
   * (the first of a name stays in it, so a duplicate names that one) */
  nameTab names = {NULL, 0, 0};
  c->out = u;
  for (int i = 0; i < u->nclosure && !st; i++) {
    const ssUrdfClosure *q = &u->closure[i];
    if (!q->name[0]) continue;
    int k = tab_find(c, &names, TAB_CLOSURE, q->name);
    if (k >= 0)
      st = fail(c, SS_ERR_PARSE, q->line,
                "duplicate constraint name '%s' (first at line %d)", q->name,
                u->closure[k].line);
    else if (tab_add(c, &names, TAB_CLOSURE, i))
      st = nomem(c, q->line);
  }
  free(names.slot);
  names = (nameTab){NULL, 0, 0};
  for (int i = 0; i < u->nspring && !st; i++) {
    ssUrdfSpring *s = &u->spring[i];
    if (!s->name[0]) snprintf(s->name, sizeof s->name, "spring%d", i);
    int k = tab_find(c, &names, TAB_SPRING, s->name);
    if (k >= 0)
      st = fail(c, SS_ERR_PARSE, s->line,
                "duplicate spring name '%s' (first at line %d)", s->name,
                u->spring[k].line);
    else if (tab_add(c, &names, TAB_SPRING, i))
      st = nomem(c, s->line);
  }
  free(names.slot);
  c->out = NULL;

done:
  free(pj);
  free(kid_first);
  free(kid_last);
  free(kid_next);
  free(mark);
  free(stack);
  free(newidx);
  free(jnew);
  free(tmp);
  return st;
}

/* ---------------------------------------------------------------------- */
/* the document                                                            */

static ssStatus read_robot(uCtx *c, xmlNodePtr root, ssUrdf *u)
{
  static const char *const a_robot[] = {"name", "version", NULL};
  static const char *const kids[] = {"link",   "joint",  "material",
                                     "constraints", "spring", NULL};
  static const char *const ignored[] = {"gazebo", "transmission",
                                        "ros2_control", "sensor", "mujoco",
                                        NULL};
  if (!is_el(root, "robot"))
    return fail(c, SS_ERR_PARSE, ss_xml_line(root),
                "root element is <%s>, expected <robot>",
                (const char *)root->name);
  xEl e;
  ssStatus st = el_open(c, root, NULL, &e);
  c->robot_line = e.line;
  if (!st) st = el_allow(c, &e, a_robot);
  if (!st) st = get_name(c, &e, "name", u->name);
  /* pass 1: named materials and the check of every child */
  for (xmlNodePtr k = root->children; !st && k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) {
      st = check_other_node(c, k, &e);
      continue;
    }
    int known = 0;
    for (int i = 0; kids[i]; i++) known |= is_el(k, kids[i]);
    for (int i = 0; ignored[i]; i++) known |= is_el(k, ignored[i]);
    if (!known) st = unknown_child(c, k, &e, kids);
    else if (is_el(k, "material")) st = read_top_material(c, k);
  }
  /* pass 2: links; pass 3: joints, constraints, springs */
  for (xmlNodePtr k = root->children; !st && k; k = k->next)
    if (is_el(k, "link")) st = read_link(c, k);
  for (xmlNodePtr k = root->children; !st && k; k = k->next) {
    if (is_el(k, "joint")) st = read_joint(c, k);
  }
  for (xmlNodePtr k = root->children; !st && k; k = k->next) {
    if (is_el(k, "constraints")) st = read_constraints(c, k);
    else if (is_el(k, "spring")) st = read_spring(c, k);
  }
  el_free(&e);
  if (!st) st = build_tree(c, u);
  return st;
}

/* ---------------------------------------------------------------------- */
/* parsing                                                                 */

static ssStatus parse_xml(uCtx *c, const char *buf, size_t len,
                          xmlDocPtr *out)
{
  *out = NULL;
  if (len == 0)
    return fail(c, SS_ERR_PARSE, 1, "empty URDF: expected a <robot> element");
  if (len > (size_t)SS_URDF_MAX_BYTES)
    return fail(c, SS_ERR_IO, 0, "URDF is %zu bytes, larger than the limit "
                "of %ld", len, (long)SS_URDF_MAX_BYTES);
  /* libxml2's default size limits stay on */
  ssXmlResult r;
  *out = ss_xml_parse(buf, len, 0, &r);
  switch (r.fail) {
  case SS_XML_OK:
    return SS_OK;
  case SS_XML_NOMEM:
    return fail(c, SS_ERR_NOMEM, 0, "out of memory starting the XML parser");
  case SS_XML_DOCTYPE:
    return fail(c, SS_ERR_PARSE, r.line,
                "DOCTYPE declarations are not allowed in URDF files (no DTDs, "
                "no entities)");
  case SS_XML_SYNTAX:
    return fail(c, SS_ERR_PARSE, r.line, "XML syntax error: %s", r.message);
  case SS_XML_NO_ROOT:
    break;
  }
  return fail(c, SS_ERR_PARSE, r.line, "no root element: expected <robot>");
}

/* ---------------------------------------------------------------------- */
/* entry points                                                            */

static void ctx_free(uCtx *c)
{
  for (int i = 0; i < c->nlink; i++) free(c->link[i].geom);
  free(c->link);
  free(c->link_extra);
  free(c->joint);
  free(c->mat);
  free(c->pend);
  free(c->link_tab.slot);
  free(c->joint_tab.slot);
  free(c->mat_tab.slot);
  if (c->doc) xmlFreeDoc(c->doc);
  memset(c, 0, sizeof *c);
}

void ss_urdf_free(ssUrdf *u)
{
  if (!u) return;
  for (int i = 0; i < u->nlink; i++) free(u->link[i].geom);
  free(u->link);
  free(u->joint);
  free(u->closure);
  free(u->spring);
  free(u);
}

static ssStatus load(const char *buf, size_t len, const char *path,
                     const char *res_dir, ssUrdf **out, ssError *err)
{
  uCtx c;
  memset(&c, 0, sizeof c);
  c.path = path;
  c.buf = buf;
  c.len = len;
  c.res_dir = res_dir;
  ss_scene_path_dir(path, c.dir, sizeof c.dir);

  ssCLocale loc;
  if (ss_scene_c_locale_begin(&loc, path, err) != SS_OK) return SS_ERR_STATE;
  ssUrdf *u = calloc(1, sizeof *u);
  ssStatus st = u ? SS_OK : fail(&c, SS_ERR_NOMEM, 0, "out of memory");
  if (!st) {
    snprintf(u->path, sizeof u->path, "%s", path);
    st = parse_xml(&c, buf, len, &c.doc);
  }
  if (!st) st = read_robot(&c, xmlDocGetRootElement(c.doc), u);
  ssError e = c.e;
  ctx_free(&c);
  ss_scene_c_locale_pop(&loc);
  if (st) {
    ss_urdf_free(u);
    if (err) *err = e;
    return st;
  }
  *out = u;
  return SS_OK;
}

ssStatus ss_urdf_load_buffer(const char *buf, size_t len, const char *path,
                             const char *res_dir, ssUrdf **out, ssError *err)
{
  const char *name = path && *path ? path : "(buffer)";
  if (!out)
    return ss_error_set(err, SS_ERR_VALUE, name, 0,
                        "ss_urdf_load_buffer: NULL output argument");
  *out = NULL;
  if (!buf && len)
    return ss_error_set(err, SS_ERR_VALUE, name, 0,
                        "ss_urdf_load_buffer: NULL buffer");
  return load(buf ? buf : "", len, name, res_dir, out, err);
}

ssStatus ss_urdf_load(const char *path, const char *res_dir, ssUrdf **out,
                      ssError *err)
{
  if (!out)
    return ss_error_set(err, SS_ERR_VALUE, path ? path : "", 0,
                        "ss_urdf_load: NULL output argument");
  *out = NULL;
  char *buf = NULL;
  size_t len = 0;
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "no URDF file name given");
  ssStatus st = ss_read_file(path, SS_URDF_MAX_BYTES, &buf, &len, err);
  if (st != SS_OK) return st;
  st = load(buf, len, path, res_dir, out, err);
  free(buf);
  return st;
}

ssStatus ss_urdf_check_floating_root(const ssUrdf *u, ssError *err)
{
  if (!u || u->nlink < 1)
    return ss_error_set(err, SS_ERR_VALUE, u ? u->path : "", 0,
                        "the URDF has no link");
  int nl = u->nlink, nj = u->njoint;
  int *kid_first = malloc((size_t)nl * sizeof *kid_first);
  int *kid_next = malloc((size_t)(nj ? nj : 1) * sizeof *kid_next);
  int *stack = malloc((size_t)(2 * nl + 2) * sizeof *stack);
  pose *tmp = malloc((size_t)nl * sizeof *tmp);
  ssStatus st = SS_OK;
  if (!kid_first || !kid_next || !stack || !tmp) {
    st = ss_error_set(err, SS_ERR_NOMEM, u->path, 0, "out of memory");
  } else {
    /* child lists by final index (joint k's child is link k + 1), in the
     * order composite() reads them */
    int *kid_last = stack;
    for (int i = 0; i < nl; i++) kid_first[i] = kid_last[i] = -1;
    for (int j = 0; j < nj; j++) {
      int a = u->joint[j].parent;
      kid_next[j] = -1;
      if (a < 0 || a >= nl) continue;
      if (kid_last[a] < 0) kid_first[a] = j;
      else kid_next[kid_last[a]] = j;
      kid_last[a] = j;
    }
    uCtx c;
    memset(&c, 0, sizeof c);
    c.link = u->link;
    c.joint = u->joint;
    c.nlink = nl;
    c.njoint = nj;
    double M, com[3], I[9], ev[3] = {0, 0, 0};
    composite(&c, 0, kid_first, kid_next, tmp, stack, &M, com, I);
    if (M > 0) sym_eig3(I, ev);
    const ssUrdfLink *L = &u->link[0];
    if (!(M > 0) || !is_pd(ev))
      st = ss_error_set(err, SS_ERR_VALUE, u->path, L->line,
                        "link '%s' is the root of a floating base but, with "
                        "the links fixed to it, has mass %.6g kg and "
                        "principal moments %.6g, %.6g, %.6g kg m^2 (a floating "
                        "base needs mass > 0 and a positive-definite "
                        "rotational inertia: give it an <inertial>, or "
                        "base=\"fixed\" in the scene)", L->name, M, ev[0],
                        ev[1], ev[2]);
  }
  free(kid_first);
  free(kid_next);
  free(stack);
  free(tmp);
  return st;
}

int ss_urdf_find_link(const ssUrdf *u, const char *name)
{
  if (!u || !name) return -1;
  for (int i = 0; i < u->nlink; i++)
    if (!strcmp(u->link[i].name, name)) return i;
  return -1;
}

int ss_urdf_find_joint(const ssUrdf *u, const char *name)
{
  if (!u || !name) return -1;
  for (int i = 0; i < u->njoint; i++)
    if (!strcmp(u->joint[i].name, name)) return i;
  return -1;
}
