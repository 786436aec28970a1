/* scene_read.c -- world XML (DESIGN 4.1) into a model and its data.
 *
 * The accepted format, the safety measures and the error conventions are
 * described in scene.h.  The reader parses the whole document with libxml2
 * (safely: xml_safe.h), then walks the tree once, building the model with
 * the model builder; every element is checked against a list of allowed
 * attributes and children so that typos are reported instead of ignored. */
#include "scene.h"
#include "articulated.h"
#include "urdf.h"
#include "ss_math.h"
#include "xml_safe.h"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* attributes per element kept (no element allows nearly as many) */
#define MAX_ATTR 40
#define NAME_CAP 64
/* largest height map (vertices), as in the model builder */
#define MAX_VERTICES 100000000L

/* ---------------------------------------------------------------------- */
/* files, locale, numbers                                                  */

ssStatus ss_read_file(const char *path, long max_bytes, char **buf,
                      size_t *len, ssError *err)
{
  *buf = NULL;
  *len = 0;
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "no file name given");
  /* O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused
   * below as not a regular file */
  int fd = open(path, O_RDONLY | O_NONBLOCK);
  if (fd < 0)
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot open: %s",
                        strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0) {
    int e = errno;
    close(fd);
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot read: %s",
                        strerror(e));
  }
  if (!S_ISREG(st.st_mode)) {
    close(fd);
    return ss_error_set(err, SS_ERR_IO, path, 0,
                        "cannot read: not a regular file");
  }
  if (st.st_size > max_bytes) {
    close(fd);
    return ss_error_set(err, SS_ERR_IO, path, 0,
                        "file is %lld bytes, larger than the limit of %ld",
                        (long long)st.st_size, max_bytes);
  }
  size_t n = (size_t)st.st_size;
  char *b = malloc(n + 1);
  if (!b) {
    close(fd);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory reading %zu bytes", n);
  }
  size_t got = 0;
  while (got < n) {
    ssize_t r = read(fd, b + got, n - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      int e = errno;
      free(b);
      close(fd);
      return ss_error_set(err, SS_ERR_IO, path, 0, "cannot read: %s",
                          strerror(e));
    }
    if (r == 0) break; /* the file shrank: take what is there */
    got += (size_t)r;
  }
  close(fd);
  b[got] = 0;
  *buf = b;
  *len = got;
  return SS_OK;
}

int ss_scene_c_locale_push(ssCLocale *l)
{
  l->loc = (locale_t)0;
  l->old = (locale_t)0;
  locale_t c = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
  if (c == (locale_t)0) return -1;
  l->old = uselocale(c);
  l->loc = c;
  return 0;
}

void ss_scene_c_locale_pop(ssCLocale *l)
{
  if (l->loc == (locale_t)0) return;
  uselocale(l->old);
  freelocale(l->loc);
  l->loc = (locale_t)0;
}

ssStatus ss_scene_c_locale_begin(ssCLocale *l, const char *path, ssError *err)
{
  if (ss_scene_c_locale_push(l) == 0) return SS_OK;
  struct lconv *lc = localeconv();
  if (!lc || !lc->decimal_point || strcmp(lc->decimal_point, "."))
    return ss_error_set(err, SS_ERR_STATE, path, 0,
                        "cannot switch to the C locale to read numbers");
  return SS_OK;
}

void ss_scene_path_dir(const char *path, char *dir, size_t cap)
{
  const char *slash = path ? strrchr(path, '/') : NULL;
  if (!slash)
    snprintf(dir, cap, ".");
  else if (slash == path)
    snprintf(dir, cap, "/");
  else
    snprintf(dir, cap, "%.*s", (int)(slash - path), path);
}

int ss_scene_path_absolute(const char *path, char *out, size_t cap)
{
  char *abs = ss_path_absolute(path);
  int n = abs ? snprintf(out, cap, "%s", abs) : -1;
  free(abs);
  return n >= 0 && (size_t)n < cap ? 0 : -1;
}

int ss_scene_path_relative(const char *target, const char *dir, char *out,
                           size_t cap)
{
  if (target[0] != '/' || dir[0] != '/') return -1;
  /* the longest common run of whole components */
  size_t common = 0;
  for (size_t i = 0;; i++) {
    int te = target[i] == 0 || target[i] == '/';
    int de = dir[i] == 0 || dir[i] == '/';
    if (te && de) {
      if (i) common = i;
      if (!target[i] || !dir[i]) break;
    } else if (target[i] != dir[i]) {
      break;
    }
  }
  /* sharing only the root: the two are unrelated, so the absolute path
   * survives moving the scene better than a climb to the root would */
  if (common == 0) return -1;
  size_t k = 0;
  for (const char *s = dir + common; *s; s++)
    if (*s == '/') {
      if (k + 3 >= cap) return -1;
      memcpy(out + k, "../", 3);
      k += 3;
    }
  const char *rest = target + common;
  if (*rest == '/') rest++;
  size_t n = strlen(rest);
  if (k + n + 2 > cap) return -1;
  if (n) {
    memcpy(out + k, rest, n + 1);
  } else if (k) {
    out[--k] = 0; /* "../../" -> "../.." */
  } else {
    memcpy(out, ".", 2);
  }
  return 0;
}

static int is_digit(char ch) { return ch >= '0' && ch <= '9'; }

int ss_scene_parse_double(const char *s, const char *end, double *out)
{
  /* grammar first: [+-] digits [. digits] [(e|E) [+-] digits], at least one
   * mantissa digit; this keeps out nan, inf, hexadecimal and junk */
  const char *p = s;
  if (p < end && (*p == '+' || *p == '-')) p++;
  int nd = 0;
  while (p < end && is_digit(*p)) p++, nd++;
  if (p < end && *p == '.') {
    p++;
    while (p < end && is_digit(*p)) p++, nd++;
  }
  if (nd == 0) return 1;
  if (p < end && (*p == 'e' || *p == 'E')) {
    p++;
    if (p < end && (*p == '+' || *p == '-')) p++;
    int ne = 0;
    while (p < end && is_digit(*p)) p++, ne++;
    if (ne == 0) return 1;
  }
  if (p != end) return 1;
  /* the token is followed by a separator or the end of the string, so
   * strtod stops exactly at `end` */
  char *e = NULL;
  errno = 0;
  double v = strtod(s, &e);
  if (e != end) return 1;
  /* underflow (ERANGE with a tiny result) is accepted: subnormals must read
   * back exactly; overflow is not */
  if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1)) return 2;
  *out = v;
  return 0;
}

int ss_scene_parse_long(const char *s, const char *end, long *out)
{
  const char *p = s;
  if (p < end && (*p == '+' || *p == '-')) p++;
  if (p == end) return 1;
  for (const char *q = p; q < end; q++)
    if (!is_digit(*q)) return 1;
  char *e = NULL;
  errno = 0;
  long v = strtol(s, &e, 10);
  if (e != end) return 1;
  if (errno == ERANGE) return 2;
  *out = v;
  return 0;
}

/* ---------------------------------------------------------------------- */
/* reader context and messages                                             */

typedef struct pendingSoil {
  int hfield, line;
  double *sinkage, *plastic, *shear; /* (nx*ny) or NULL */
} pendingSoil;

typedef struct readCtx {
  const char *path;  /* scene path for messages */
  const char *buf;   /* the source, [0, len): lines of values in messages */
  size_t len;
  char dir[1024];    /* [THIS_DIR] */
  xmlDocPtr doc;
  ssModel *m;
  ssError e;
  int npend, cappend;
  pendingSoil *pend;
  int nqpend, capqpend;
  int *qpend_sys;      /* (nqpend) systems whose qpos is applied after */
  double **qpend;      /* (nqpend) the data exists: that qpos, owned */
  int clock_given;
  double clock_time;
  long clock_step;
  int camera_line;
} readCtx;

static ssStatus fail(readCtx *c, ssStatus code, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static ssStatus fail(readCtx *c, ssStatus code, int line, const char *fmt, ...)
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

/* After a builder call failed: point the error at the scene and element. */
static ssStatus fix_error(readCtx *c, int line, const char *prefix)
{
  snprintf(c->e.file, sizeof c->e.file, "%s", c->path);
  if (c->e.line == 0) c->e.line = line;
  if (prefix) {
    char msg[sizeof c->e.message];
    snprintf(msg, sizeof msg, "%.100s: %.900s", prefix, c->e.message);
    memcpy(c->e.message, msg, sizeof msg);
  }
  if (c->e.code == SS_OK) c->e.code = SS_ERR_VALUE;
  return c->e.code;
}

/* ---------------------------------------------------------------------- */
/* elements and attributes                                                 */

typedef struct xAttr {
  const char *raw;      /* name as written */
  char name[NAME_CAP];  /* snake_case */
  const char *val;
} xAttr;

typedef struct xEl {
  xmlNodePtr node;
  const char *raw;
  char name[NAME_CAP];
  int line;
  char label[200];      /* "box 'plate'", "box 'plate' <dim>", "<gravity>" */
  int nattr;
  xAttr attr[MAX_ATTR];
  xmlChar *owned[MAX_ATTR];
} xEl;

static int is_upper(char ch) { return ch >= 'A' && ch <= 'Z'; }

/* camelCase -> snake_case; `timestep` -> time_step.  A name is one of the
 * two spellings: snake_case (no capital letter) or camelCase (a lower-case
 * first letter, no '_', no two capitals in a row); any other (`Box`,
 * `x_Size`, `XSIZE`) and names too long for the buffer become "?" (never
 * a valid name: reported as unknown under the name as written). */
static void norm_name(const char *in, char out[NAME_CAP])
{
  int camel = 0;
  for (const char *p = in; *p; p++) camel |= is_upper(*p);
  if (camel && (!(in[0] >= 'a' && in[0] <= 'z') || strchr(in, '_'))) {
    strcpy(out, "?");
    return;
  }
  size_t k = 0;
  for (const char *p = in; *p; p++) {
    char ch = *p;
    if (k + 3 >= NAME_CAP || (is_upper(ch) && is_upper(p[1]))) {
      strcpy(out, "?");
      return;
    }
    if (is_upper(ch)) {
      out[k++] = '_';
      out[k++] = (char)(ch - 'A' + 'a');
    } else {
      out[k++] = ch;
    }
  }
  out[k] = 0;
  if (!strcmp(out, "timestep")) strcpy(out, "time_step");
}

static void el_free(xEl *e)
{
  for (int i = 0; i < e->nattr; i++)
    if (e->owned[i]) xmlFree(e->owned[i]);
  e->nattr = 0;
}

/* Collect node's attributes with normalised names; spellings of one name
 * given twice are an error. */
static ssStatus el_open(readCtx *c, xmlNodePtr node, const char *parent_label,
                        xEl *e)
{
  memset(e, 0, sizeof *e);
  e->node = node;
  e->raw = (const char *)node->name;
  norm_name(e->raw, e->name);
  e->line = ss_xml_line(node);
  if (parent_label)
    snprintf(e->label, sizeof e->label, "%s <%s>", parent_label, e->name);
  else
    snprintf(e->label, sizeof e->label, "<%s>", e->name);
  /* the format has no namespaces: a prefixed name would otherwise be
   * read by its local part (q:mass as mass) */
  if (node->ns && node->ns->prefix)
    return fail(c, SS_ERR_PARSE, e->line,
                "namespaced element <%s:%s> (the scene format has no namespaces)",
                (const char *)node->ns->prefix, e->raw);
  for (xmlAttrPtr a = node->properties; a; a = a->next) {
    if (a->ns && a->ns->prefix)
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: namespaced attribute '%s:%s' (the scene format has no "
                  "namespaces)", e->label, (const char *)a->ns->prefix,
                  (const char *)a->name);
    if (e->nattr == MAX_ATTR)
      return fail(c, SS_ERR_PARSE, e->line, "%s: too many attributes (at most %d)",
                  e->label, MAX_ATTR);
    xAttr *x = &e->attr[e->nattr];
    x->raw = (const char *)a->name;
    norm_name(x->raw, x->name);
    x->val = ss_xml_attr_text(c->doc, a, &e->owned[e->nattr]);
    e->nattr++;
    /* "?" (not a name of either spelling) is reported as unknown below */
    for (int i = 0; i < e->nattr - 1 && strcmp(x->name, "?"); i++)
      if (!strcmp(e->attr[i].name, x->name))
        return fail(c, SS_ERR_PARSE, e->line,
                    "%s: attribute '%s' given twice (as '%s' and '%s')",
                    e->label, x->name, e->attr[i].raw, x->raw);
  }
  return SS_OK;
}

/* Every attribute must be in `allowed` (NULL-terminated). */
static ssStatus el_allow(readCtx *c, xEl *e, const char *const *allowed)
{
  for (int i = 0; i < e->nattr; i++)
    if (!ss_xml_in_list(e->attr[i].name, allowed)) {
      char list[600];
      ss_xml_join_names(list, sizeof list, allowed);
      return fail(c, SS_ERR_PARSE, e->line,
                  "unknown attribute '%s' on <%s> (allowed: %s)", e->attr[i].raw,
                  e->name, allowed[0] ? list : "none");
    }
  return SS_OK;
}

static const char *el_find(xEl *e, const char *name)
{
  for (int i = 0; i < e->nattr; i++)
    if (!strcmp(e->attr[i].name, name)) return e->attr[i].val;
  return NULL;
}

static ssStatus missing(readCtx *c, xEl *e, const char *name)
{
  return fail(c, SS_ERR_PARSE, e->line, "%s: missing required attribute '%s'",
              e->label, name);
}

static ssStatus get_str(readCtx *c, xEl *e, const char *name, int required,
                        const char **out)
{
  const char *v = el_find(e, name);
  if (!v) return required ? missing(c, e, name) : SS_OK;
  *out = v;
  return SS_OK;
}

/* A material name: optional, but never empty (an empty name would be a
 * material of its own that no <pair_prop> can name). */
static ssStatus get_material(readCtx *c, xEl *e, const char **out)
{
  const char *v = el_find(e, "material");
  if (v && !*v)
    return fail(c, SS_ERR_VALUE, e->line,
                "%s: material is empty (give a material name, or leave the "
                "attribute out for the default material)", e->label);
  if (v) *out = v;
  return SS_OK;
}

/* The line of value `index` of attribute `name` (normalised) of e: where
 * it stands in the source, which for an attribute over many lines (an
 * exported height map's arrays) is not the element's line. */
static int value_line(readCtx *c, xEl *e, const char *name, long index)
{
  for (int i = 0; i < e->nattr; i++)
    if (!strcmp(e->attr[i].name, name))
      return ss_xml_value_line(c->buf, c->len, e->node, e->attr[i].raw, index);
  return e->line;
}

static ssStatus bad_number(readCtx *c, xEl *e, const char *name, const char *tb,
                           const char *te, long index, long n, int why)
{
  int len = (int)(te - tb) > 40 ? 40 : (int)(te - tb);
  char where[64] = "";
  if (n > 1) snprintf(where, sizeof where, " (value %ld of %ld)", index + 1, n);
  return fail(c, SS_ERR_PARSE, value_line(c, e, name, index),
              "%s: bad number '%.*s'%s in attribute '%s' (%s)", e->label, len,
              tb, where, name,
              why == 2 ? "out of range" : "expected a finite decimal number");
}

/* Check that attribute `name` (value v) has exactly n values; `what`
 * describes the expected count for messages (NULL: just the number). */
static ssStatus check_count(readCtx *c, xEl *e, const char *name,
                            const char *v, long n, const char *what)
{
  long got = ss_xml_vec_count(v);
  if (got < 0)
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: attribute '%s' has an empty value (values are separated "
                "by white space or by one comma)", e->label, name);
  if (got != n) {
    if (what)
      return fail(c, SS_ERR_PARSE, e->line,
                  "%s: attribute '%s' has %ld values, expected %s = %ld",
                  e->label, name, got, what, n);
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: attribute '%s' has %ld value%s, expected %ld", e->label,
                name, got, got == 1 ? "" : "s", n);
  }
  return SS_OK;
}

/* Parse exactly n values of attribute `name` into out (check_count). */
static ssStatus parse_values(readCtx *c, xEl *e, const char *name,
                             const char *v, long n, const char *what,
                             double *out)
{
  ssStatus st = check_count(c, e, name, v, n, what);
  if (st) return st;
  const char *p = v, *tb = NULL, *te = NULL;
  for (long k = 0; k < n; k++) {
    ss_xml_vec_next(&p, k == 0, &tb, &te);
    int r = ss_scene_parse_double(tb, te, &out[k]);
    if (r) return bad_number(c, e, name, tb, te, k, n, r);
  }
  return SS_OK;
}

static ssStatus get_vec(readCtx *c, xEl *e, const char *name, int n,
                        int required, double *out)
{
  const char *v = el_find(e, name);
  if (!v) return required ? missing(c, e, name) : SS_OK;
  return parse_values(c, e, name, v, n, NULL, out);
}

static ssStatus get_num(readCtx *c, xEl *e, const char *name, int required,
                        double *out)
{
  return get_vec(c, e, name, 1, required, out);
}

/* Parse a whole array attribute (expected n values) into a malloc'd
 * buffer; *out stays NULL when the attribute is absent. */
static ssStatus get_array(readCtx *c, xEl *e, const char *name, long n,
                          const char *what, int required, double **out)
{
  *out = NULL;
  const char *v = el_find(e, name);
  if (!v) return required ? missing(c, e, name) : SS_OK;
  /* the count first: a short attribute never costs n doubles */
  ssStatus cs = check_count(c, e, name, v, n, what);
  if (cs) return cs;
  double *a = malloc((size_t)(n > 0 ? n : 1) * sizeof *a);
  if (!a) return fail(c, SS_ERR_NOMEM, e->line, "out of memory");
  ssStatus st = parse_values(c, e, name, v, n, what, a);
  if (st != SS_OK) {
    free(a);
    return st;
  }
  *out = a;
  return SS_OK;
}

/* An optional array attribute of any length: its *n values into *out. */
static ssStatus get_list(readCtx *c, xEl *e, const char *name, int *n,
                         double **out)
{
  const char *v = el_find(e, name);
  if (!v) return SS_OK;
  *n = (int)ss_xml_vec_count(v);
  return get_array(c, e, name, *n, "as many", 0, out);
}

static ssStatus get_long(readCtx *c, xEl *e, const char *name, int required,
                         long lo, long hi, long *out)
{
  const char *v = el_find(e, name);
  if (!v) return required ? missing(c, e, name) : SS_OK;
  const char *p = v, *tb = NULL, *te = NULL;
  long n = ss_xml_vec_count(v);
  int r = 1;
  long x = 0;
  if (n == 1) {
    ss_xml_vec_next(&p, 1, &tb, &te);
    r = ss_scene_parse_long(tb, te, &x);
  }
  if (r != 0) {
    int len = (int)strlen(v) > 40 ? 40 : (int)strlen(v);
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: attribute '%s' is '%.*s', %s", e->label, name, len, v,
                r == 2 ? "an integer too large to represent"
                       : "expected an integer");
  }
  if (x < lo || x > hi)
    return fail(c, SS_ERR_VALUE, e->line,
                "%s: %s = %ld is invalid: must be in [%ld, %ld]", e->label,
                name, x, lo, hi);
  *out = x;
  return SS_OK;
}

static ssStatus get_int(readCtx *c, xEl *e, const char *name, int required,
                        int lo, int hi, int *out)
{
  long x = *out;
  ssStatus st = get_long(c, e, name, required, lo, hi, &x);
  if (st == SS_OK) *out = (int)x;
  return st;
}

static ssStatus get_bool(readCtx *c, xEl *e, const char *name, int *out)
{
  const char *v = el_find(e, name);
  if (!v) return SS_OK;
  const char *p = v, *tb = NULL, *te = NULL;
  if (ss_xml_vec_count(v) == 1) {
    ss_xml_vec_next(&p, 1, &tb, &te);
    size_t n = (size_t)(te - tb);
    if ((n == 4 && !strncmp(tb, "true", 4)) || (n == 1 && *tb == '1')) {
      *out = 1;
      return SS_OK;
    }
    if ((n == 5 && !strncmp(tb, "false", 5)) || (n == 1 && *tb == '0')) {
      *out = 0;
      return SS_OK;
    }
  }
  return fail(c, SS_ERR_PARSE, e->line,
              "%s: attribute '%s' is '%.40s' (allowed: true, false, 1, 0)",
              e->label, name, v);
}

/* A required integer in [lo, hi] with two spellings (x_sample /
 * x_samples); messages name `a` when neither is given.  *used tells which
 * spelling was read. */
static ssStatus get_alias_long(readCtx *c, xEl *e, const char *a,
                               const char *b, long lo, long hi,
                               const char **used, long *out)
{
  const char *va = el_find(e, a), *vb = el_find(e, b);
  if (va && vb)
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: give either '%s' or '%s', not both", e->label, a, b);
  if (!va && !vb) return missing(c, e, a);
  *used = va ? a : b;
  return get_long(c, e, *used, 1, lo, hi, out);
}

/* Non-element children: blank text, comments, processing instructions
 * and XInclude markers are fine; anything else is an error. */
static ssStatus check_other_node(readCtx *c, xmlNodePtr n, const xEl *parent)
{
  char msg[sizeof c->e.message];
  if (n->type == XML_XINCLUDE_START || n->type == XML_XINCLUDE_END ||
      !ss_xml_stray(n, parent->name, msg, sizeof msg))
    return SS_OK;
  return fail(c, SS_ERR_PARSE, ss_xml_line(n) ? ss_xml_line(n) : parent->line,
              "%s", msg);
}

static ssStatus unknown_child(readCtx *c, xmlNodePtr n, const xEl *parent,
                              const char *const *allowed)
{
  char list[400];
  ss_xml_join_names(list, sizeof list, allowed);
  if (!allowed[0])
    return fail(c, SS_ERR_PARSE, ss_xml_line(n),
                "unknown element <%s> inside <%s> (<%s> has no child "
                "elements)", (const char *)n->name, parent->name, parent->name);
  return fail(c, SS_ERR_PARSE, ss_xml_line(n),
              "unknown element <%s> inside <%s> (allowed: %s)",
              (const char *)n->name, parent->name, list);
}

/* A leaf element: no element children, no text. */
static ssStatus check_leaf(readCtx *c, const xEl *e)
{
  static const char *const none[] = {NULL};
  for (xmlNodePtr n = e->node->children; n; n = n->next) {
    ssStatus st = n->type == XML_ELEMENT_NODE ? unknown_child(c, n, e, none)
                                              : check_other_node(c, n, e);
    if (st) return st;
  }
  return SS_OK;
}

/* Open a leaf child element with its allowed attributes. */
static ssStatus open_leaf(readCtx *c, xmlNodePtr n, const char *parent_label,
                          const char *const *allowed, xEl *e)
{
  ssStatus st = el_open(c, n, parent_label, e);
  if (!st) st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  return st;
}

static ssStatus once(readCtx *c, int *seen, const xEl *e)
{
  if (*seen)
    return fail(c, SS_ERR_PARSE, e->line,
                "element <%s> given twice in the same place (first at line %d)",
                e->name, *seen);
  *seen = e->line ? e->line : -1;
  return SS_OK;
}

/* once() for the child element k, named kn, before it is opened. */
static ssStatus once_at(readCtx *c, int *seen, xmlNodePtr k, const char *kn)
{
  xEl tmp;
  tmp.line = ss_xml_line(k);
  snprintf(tmp.name, sizeof tmp.name, "%s", kn);
  return once(c, seen, &tmp);
}

/* In a loop over an element's children: 1 when k is an element (its name
 * normalised into kn); otherwise 0, with k checked into *st. */
static int child_el(readCtx *c, xmlNodePtr k, const xEl *parent,
                    char kn[NAME_CAP], ssStatus *st)
{
  if (k->type != XML_ELEMENT_NODE) {
    *st = check_other_node(c, k, parent);
    return 0;
  }
  if (k->ns && k->ns->prefix) {
    *st = fail(c, SS_ERR_PARSE, ss_xml_line(k),
               "%s: namespaced element <%s:%s> (the scene format has no "
               "namespaces)", parent->label, (const char *)k->ns->prefix,
               (const char *)k->name);
    return 0;
  }
  norm_name((const char *)k->name, kn);
  return 1;
}

/* Expand [THIS_DIR]; a relative path without it is relative to the scene's
 * folder. */
static ssStatus resolve_path(readCtx *c, xEl *e, const char *name,
                             const char *raw, char *out, size_t cap)
{
  if (!*raw)
    return fail(c, SS_ERR_PARSE, e->line, "%s: attribute '%s' is empty",
                e->label, name);
  static const char tag[] = "[THIS_DIR]";
  size_t k = 0, tl = sizeof tag - 1;
  int expanded = 0;
  out[0] = 0;
  for (const char *p = raw; *p;) {
    const char *piece = p;
    size_t plen = 1;
    if (!strncmp(p, tag, tl)) {
      piece = c->dir;
      plen = strlen(c->dir);
      p += tl;
      expanded = 1;
    } else {
      p++;
    }
    if (k + plen + 1 > cap)
      return fail(c, SS_ERR_VALUE, e->line, "%s: path in '%s' is too long",
                  e->label, name);
    memcpy(out + k, piece, plen);
    k += plen;
  }
  out[k] = 0;
  if (!expanded && raw[0] != '/') {
    size_t dl = strlen(c->dir);
    if (dl + 1 + k + 1 > cap)
      return fail(c, SS_ERR_VALUE, e->line, "%s: path in '%s' is too long",
                  e->label, name);
    memmove(out + dl + 1, out, k + 1);
    memcpy(out, c->dir, dl);
    out[dl] = '/';
  }
  return SS_OK;
}

static int quat_is_zero(const double q[4])
{
  return q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] < 1e-18;
}

/* A quaternion whose squared length overflows (components of 1e200) would
 * be normalised to 0 0 0 0 and stored as the identity: divide it by its
 * largest component first (the direction is what it says).  Ordinary
 * quaternions are left as they are, bit for bit. */
static void quat_rescale(double q[4])
{
  double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (n2 < 1e300) return;
  double big = 0;
  for (int k = 0; k < 4; k++) big = fmax(big, fabs(q[k]));
  if (big > 0 && isfinite(big))
    for (int k = 0; k < 4; k++) q[k] /= big;
}

/* A quaternion already of unit length (to 1e-14) is stored as written, so
 * that an exported state reads back bit for bit (normalising it again could
 * move the last bit). */
static void keep_unit_quat(double *dst, const double q[4])
{
  double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (fabs(n2 - 1) <= 1e-14) memcpy(dst, q, 4 * sizeof(double));
}

/* ---------------------------------------------------------------------- */
/* objects                                                                 */

static ssStatus read_ground(readCtx *c, xmlNodePtr n)
{
  static const char *const allowed[] = {"name", "height", "material", NULL};
  xEl e;
  ssStatus st = open_leaf(c, n, NULL, allowed, &e);
  const char *name = NULL, *mat = NULL;
  double h = 0;
  if (!st) st = get_str(c, &e, "name", 1, &name);
  if (!st) snprintf(e.label, sizeof e.label, "ground '%s'", name);
  if (!st) st = get_num(c, &e, "height", 0, &h);
  if (!st) st = get_material(c, &e, &mat);
  if (!st && ss_model_add_plane(c->m, name, h, mat, e.line, &c->e) < 0)
    st = fix_error(c, e.line, NULL);
  el_free(&e);
  return st;
}

typedef struct xforceDef {
  double force[3], torque[3], start, end;
  int line;
} xforceDef;

static ssStatus read_dim(readCtx *c, xmlNodePtr n, const char *label,
                         ssBodyDef *def)
{
  static const char *const box[] = {"x", "y", "z", NULL};
  static const char *const sph[] = {"radius", NULL};
  static const char *const cyl[] = {"radius", "height", NULL};
  const char *const *names = def->shape == SS_GEOM_BOX      ? box
                             : def->shape == SS_GEOM_SPHERE ? sph
                                                            : cyl;
  xEl e;
  ssStatus st = open_leaf(c, n, label, names, &e);
  for (int k = 0; !st && names[k]; k++) {
    st = get_num(c, &e, names[k], 1, &def->size[k]);
    if (!st && !(def->size[k] > 0))
      st = fail(c, SS_ERR_VALUE, e.line, "%s: %s = %g is invalid: must be > 0",
                e.label, names[k], def->size[k]);
  }
  el_free(&e);
  return st;
}

static ssStatus read_state(readCtx *c, xmlNodePtr n, const char *label,
                           ssBodyDef *def)
{
  static const char *const allowed[] = {"pos", "quat", "lin_vel", "ang_vel",
                                        NULL};
  xEl e;
  ssStatus st = open_leaf(c, n, label, allowed, &e);
  if (!st) st = get_vec(c, &e, "pos", 3, 0, def->pos);
  if (!st) st = get_vec(c, &e, "quat", 4, 0, def->quat);
  if (!st) st = get_vec(c, &e, "lin_vel", 3, 0, def->lin_vel);
  if (!st) st = get_vec(c, &e, "ang_vel", 3, 0, def->ang_vel);
  if (!st) quat_rescale(def->quat);
  if (!st && quat_is_zero(def->quat))
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: quat = %g %g %g %g has zero length (quaternions are w x y z)",
              e.label, def->quat[0], def->quat[1], def->quat[2], def->quat[3]);
  el_free(&e);
  return st;
}

static ssStatus read_inertia(readCtx *c, xmlNodePtr n, const char *label,
                             ssBodyDef *def)
{
  static const char *const allowed[] = {"xx", "xy", "xz", "yy", "yz", "zz",
                                        NULL};
  xEl e;
  double *I = def->inertia;
  I[1] = I[2] = I[4] = 0;
  ssStatus st = open_leaf(c, n, label, allowed, &e);
  if (!st) st = get_num(c, &e, "xx", 1, &I[0]);
  if (!st) st = get_num(c, &e, "xy", 0, &I[1]);
  if (!st) st = get_num(c, &e, "xz", 0, &I[2]);
  if (!st) st = get_num(c, &e, "yy", 1, &I[3]);
  if (!st) st = get_num(c, &e, "yz", 0, &I[4]);
  if (!st) st = get_num(c, &e, "zz", 1, &I[5]);
  if (!st) {
    /* Sylvester: leading principal minors > 0 */
    double m2 = I[0] * I[3] - I[1] * I[1];
    double det = I[0] * (I[3] * I[5] - I[4] * I[4]) -
                 I[1] * (I[1] * I[5] - I[4] * I[2]) +
                 I[2] * (I[1] * I[4] - I[3] * I[2]);
    if (!(I[0] > 0) || !(m2 > 0) || !(det > 0))
      st = fail(c, SS_ERR_VALUE, e.line,
                "%s: the inertia matrix must be positive definite (xx, yy, zz "
                "> 0 and the products of inertia small enough)", e.label);
  }
  def->inertia_given = 1;
  el_free(&e);
  return st;
}

static ssStatus read_xforce(readCtx *c, xmlNodePtr n, const char *label,
                            xforceDef *x)
{
  static const char *const allowed[] = {"force", "torque", "start", "end",
                                        NULL};
  xEl e;
  memset(x, 0, sizeof *x);
  x->end = INFINITY;
  x->line = ss_xml_line(n);
  ssStatus st = open_leaf(c, n, label, allowed, &e);
  if (!st) st = get_vec(c, &e, "force", 3, 0, x->force);
  if (!st) st = get_vec(c, &e, "torque", 3, 0, x->torque);
  if (!st) st = get_num(c, &e, "start", 0, &x->start);
  if (!st) st = get_num(c, &e, "end", 0, &x->end);
  if (!st && !(x->start <= x->end))
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: start = %g is after end = %g (times in s; end defaults to "
              "never)", e.label, x->start, x->end);
  el_free(&e);
  return st;
}

/* A mesh's scale: one value for all three axes or three (as URDF's), each
 * non-zero. */
static ssStatus get_mesh_scale(readCtx *c, xEl *e, double s[3])
{
  const char *v = el_find(e, "scale");
  if (!v) return SS_OK;
  long n = ss_xml_vec_count(v);
  if (n >= 0 && n != 1 && n != 3)
    return fail(c, SS_ERR_PARSE, e->line,
                "%s: attribute 'scale' has %ld values, expected 1 (all axes) "
                "or 3 (x y z)", e->label, n);
  ssStatus st = parse_values(c, e, "scale", v, n == 1 ? 1 : 3, NULL, s);
  if (!st && n == 1) s[1] = s[2] = s[0];
  for (int k = 0; !st && k < 3; k++)
    if (s[k] == 0)
      st = fail(c, SS_ERR_VALUE, e->line,
                "%s: scale value %d is 0; mesh scales must be non-zero",
                e->label, k + 1);
  return st;
}

/* <box|sphere|cylinder|capsule name mass material body_type rgba> with
 * <dim>, or <mesh ... file_name scale> without; either with optional
 * <state>, <inertia> and any number of <external_force> */
static ssStatus read_body(readCtx *c, xmlNodePtr n, ssGeomType shape)
{
  static const char *const allowed[] = {"name", "mass", "material",
                                        "body_type", "rgba", NULL};
  static const char *const allowed_mesh[] = {"name", "mass", "material",
                                             "body_type", "rgba", "file_name",
                                             "scale", NULL};
  static const char *const kids[] = {"dim", "state", "inertia",
                                     "external_force", NULL};
  static const char *const kids_mesh[] = {"state", "inertia", "external_force",
                                          NULL};
  const int is_mesh = shape == SS_GEOM_MESH;
  ssBodyDef def = ss_body_def_default();
  def.shape = shape;
  xEl e;
  xforceDef *xf = NULL;
  int nxf = 0;
  const char *type = NULL;
  /* the mesh file as found (messages) and kept (absolute, normalised, as
   * an articulated system's urdf_path: an export anywhere names it) */
  char path[1024] = "", abspath[4096] = "";
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, is_mesh ? allowed_mesh : allowed);
  if (!st) st = get_str(c, &e, "name", 1, &def.name);
  if (!st) snprintf(e.label, sizeof e.label, "%s '%s'", e.name, def.name);
  if (!st) st = get_str(c, &e, "body_type", 0, &type);
  if (!st && type) {
    if (!strcmp(type, "static"))
      def.is_static = 1;
    else if (strcmp(type, "dynamic"))
      st = fail(c, SS_ERR_PARSE, e.line,
                "%s: body_type is '%.40s' (allowed: static, dynamic)", e.label,
                type);
  }
  if (!st) st = get_num(c, &e, "mass", !def.is_static, &def.mass);
  if (!st && !def.is_static && !(def.mass > 0))
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: mass = %g is invalid: a dynamic body needs a mass > 0 kg",
              e.label, def.mass);
  /* a static body's mass is not used, but one written must still be a
   * mass (a typo is reported, not dropped) */
  if (!st && def.is_static && el_find(&e, "mass") && !(def.mass > 0))
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: mass = %g is invalid: must be > 0 kg (a static body's mass "
              "is not used; it may be left out)", e.label, def.mass);
  if (!st) st = get_material(c, &e, &def.material);
  if (!st && el_find(&e, "rgba")) {
    st = get_vec(c, &e, "rgba", 4, 0, def.rgba);
    for (int k = 0; !st && k < 4; k++)
      if (!(def.rgba[k] >= 0 && def.rgba[k] <= 1))
        st = fail(c, SS_ERR_VALUE, e.line,
                  "%s: rgba component %d = %g is invalid: must be in [0, 1]",
                  e.label, k + 1, def.rgba[k]);
    /* the model takes alpha 0 for "no colour given" and draws the body in
     * its default colour: an invisible body cannot be asked for */
    if (!st && def.rgba[3] == 0)
      st = fail(c, SS_ERR_VALUE, e.line,
                "%s: rgba alpha (component 4) = 0 is invalid: must be in (0, "
                "1] (bodies are drawn opaque at 1, translucent below; leave "
                "rgba out for the default colour)", e.label);
  }
  if (!st && is_mesh) {
    const char *raw = NULL;
    st = get_str(c, &e, "file_name", 1, &raw);
    if (!st) st = resolve_path(c, &e, "file_name", raw, path, sizeof path);
    if (!st && ss_scene_path_absolute(path, abspath, sizeof abspath))
      st = fail(c, SS_ERR_VALUE, e.line, "%s: file_name '%s' is too long as "
                "an absolute path", e.label, path);
    if (!st) st = get_mesh_scale(c, &e, def.mesh_scale);
    def.mesh_path = abspath;
  }
  int seen_dim = 0, seen_state = 0, seen_inertia = 0;
  double quat_read[4] = {1, 0, 0, 0};
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    char kn[NAME_CAP];
    if (!child_el(c, k, &e, kn, &st)) continue;
    if (!strcmp(kn, "dim") && !is_mesh) {
      st = once_at(c, &seen_dim, k, kn);
      if (!st) st = read_dim(c, k, e.label, &def);
    } else if (!strcmp(kn, "state")) {
      st = once_at(c, &seen_state, k, kn);
      if (!st) st = read_state(c, k, e.label, &def);
      memcpy(quat_read, def.quat, sizeof quat_read);
    } else if (!strcmp(kn, "inertia")) {
      st = once_at(c, &seen_inertia, k, kn);
      if (!st) st = read_inertia(c, k, e.label, &def);
    } else if (!strcmp(kn, "external_force")) {
      xforceDef *p = realloc(xf, (size_t)(nxf + 1) * sizeof *xf);
      if (!p) {
        st = fail(c, SS_ERR_NOMEM, ss_xml_line(k), "out of memory");
        break;
      }
      xf = p;
      st = read_xforce(c, k, e.label, &xf[nxf]);
      if (!st) nxf++;
    } else {
      st = unknown_child(c, k, &e, is_mesh ? kids_mesh : kids);
    }
  }
  if (!st && !seen_dim && !is_mesh)
    st = fail(c, SS_ERR_PARSE, e.line, "%s: missing its <dim> element",
              e.label);
  /* a static body never moves: a velocity or a force given it would be
   * dropped without a word */
  if (!st && def.is_static) {
    int moving = 0;
    for (int k = 0; k < 3; k++) moving |= def.lin_vel[k] != 0 || def.ang_vel[k] != 0;
    if (moving)
      st = fail(c, SS_ERR_VALUE, e.line,
                "%s: a static body does not move: its <state> lin_vel and "
                "ang_vel must be 0 (or left out)", e.label);
    else if (nxf)
      st = fail(c, SS_ERR_VALUE, xf[0].line,
                "%s: a static body does not move: <external_force> is allowed "
                "on dynamic bodies only", e.label);
  }
  if (!st) {
    def.line = e.line;
    int s = ss_model_add_body(c->m, &def, &c->e);
    if (s < 0) {
      st = fix_error(c, e.line, NULL);
    } else {
      keep_unit_quat(c->m->qpos0 + c->m->sys_qadr[s] + 3, quat_read);
      int b = c->m->sys_bodyadr[s];
      for (int k = 0; !st && k < nxf; k++)
        if (ss_model_add_xforce(c->m, b, xf[k].force, xf[k].torque,
                                xf[k].start, xf[k].end, &c->e) < 0) {
          c->e.line = 0;
          st = fix_error(c, xf[k].line, NULL);
        }
    }
  }
  free(xf);
  el_free(&e);
  return st;
}

/* ---------------------------------------------------------------------- */
/* height maps                                                             */

static ssStatus read_terrain_props(readCtx *c, xmlNodePtr n, const char *label,
                                   ssTerrainProps *p)
{
  static const char *const allowed[] = {
    "x_size", "y_size", "x_samples", "y_samples", "x_sample", "y_sample",
    "frequency", "z_scale", "fractal_octaves", "fractal_lacunarity",
    "fractal_gain", "seed", "height_offset", "step_size", NULL};
  xEl e;
  *p = ss_terrain_props_default();
  ssStatus st = open_leaf(c, n, label, allowed, &e);
  if (!st) st = get_num(c, &e, "x_size", 1, &p->x_size);
  if (!st) st = get_num(c, &e, "y_size", 1, &p->y_size);
  for (int k = 0; k < 2 && !st; k++) {
    const char *used = NULL;
    long x = 0;
    st = get_alias_long(c, &e, k ? "y_samples" : "x_samples",
                        k ? "y_sample" : "x_sample", 2, INT_MAX, &used, &x);
    if (!st) *(k ? &p->y_samples : &p->x_samples) = (int)x;
  }
  if (!st) st = get_num(c, &e, "frequency", 0, &p->frequency);
  if (!st) st = get_num(c, &e, "z_scale", 0, &p->z_scale);
  if (!st) st = get_int(c, &e, "fractal_octaves", 0, 0, 16, &p->fractal_octaves);
  if (!st) st = get_num(c, &e, "fractal_lacunarity", 0, &p->fractal_lacunarity);
  if (!st) st = get_num(c, &e, "fractal_gain", 0, &p->fractal_gain);
  long seed = 0;
  if (!st) st = get_long(c, &e, "seed", 0, 0, 4294967295L, &seed);
  p->seed = (uint32_t)seed;
  if (!st) st = get_num(c, &e, "height_offset", 0, &p->height_offset);
  if (!st) st = get_num(c, &e, "step_size", 0, &p->step_size);
  if (!st) {
    const char *bad = NULL;
    double v = 0;
    if (!(p->x_size > 0)) bad = "x_size", v = p->x_size;
    else if (!(p->y_size > 0)) bad = "y_size", v = p->y_size;
    else if (!(p->frequency >= 0)) bad = "frequency", v = p->frequency;
    else if (!(p->fractal_lacunarity > 0))
      bad = "fractal_lacunarity", v = p->fractal_lacunarity;
    else if (!(p->fractal_gain >= 0)) bad = "fractal_gain", v = p->fractal_gain;
    else if (!(p->step_size >= 0)) bad = "step_size", v = p->step_size;
    if (bad)
      st = fail(c, SS_ERR_VALUE, e.line,
                "%s: %s = %g is invalid: must be %s", e.label, bad, v,
                !strcmp(bad, "x_size") || !strcmp(bad, "y_size") ||
                        !strcmp(bad, "fractal_lacunarity")
                    ? "> 0"
                    : ">= 0");
  }
  if (!st && (long)p->x_samples * (long)p->y_samples > MAX_VERTICES)
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: %d x %d samples exceed the limit of %ld vertices", e.label,
              p->x_samples, p->y_samples, MAX_VERTICES);
  el_free(&e);
  return st;
}

/* <soil>: material (validated here, at its line) and optional state. */
static ssStatus read_soil(readCtx *c, xmlNodePtr n, const char *label, int nx,
                          int ny, ssSoilMaterial *mat, pendingSoil *ps)
{
  static const char *const fields[] = {
    "bekker_kc", "bekker_kphi", "sinkage_exponent", "elastic_stiffness",
    "damping", "cohesion", "friction_coefficient", "shear_displacement", NULL};
  static const char *const allowed[] = {
    "bekker_kc", "bekker_kphi", "sinkage_exponent", "elastic_stiffness",
    "damping", "cohesion", "friction_coefficient", "shear_displacement",
    "sinkage", "plastic_sinkage", "shear", NULL};
  xEl e;
  *mat = ss_soil_material_default();
  double *dst[] = {&mat->bekker_kc, &mat->bekker_kphi, &mat->sinkage_exponent,
                   &mat->elastic_stiffness, &mat->damping, &mat->cohesion,
                   &mat->friction_coefficient, &mat->shear_displacement};
  ssStatus st = open_leaf(c, n, label, allowed, &e);
  for (int k = 0; !st && fields[k]; k++) st = get_num(c, &e, fields[k], 0, dst[k]);
  if (!st) {
    ssError e2;
    if (ss_soil_material_validate(mat, &e2) != SS_OK)
      st = fail(c, SS_ERR_VALUE, e.line, "%s: %s", label, e2.message);
  }
  char what[96];
  long nv = (long)nx * ny;
  snprintf(what, sizeof what, "nx*ny = %d*%d", nx, ny);
  ps->line = e.line;
  if (!st) st = get_array(c, &e, "sinkage", nv, what, 0, &ps->sinkage);
  if (!st) st = get_array(c, &e, "plastic_sinkage", nv, what, 0, &ps->plastic);
  if (!st) st = get_array(c, &e, "shear", nv, what, 0, &ps->shear);
  el_free(&e);
  return st;
}

static void pending_free(pendingSoil *p)
{
  free(p->sinkage);
  free(p->plastic);
  free(p->shear);
  p->sinkage = p->plastic = p->shear = NULL;
}

enum { HF_EXPLICIT, HF_PNG, HF_TEXT, HF_GENERATED };

static ssStatus read_heightmap(readCtx *c, xmlNodePtr n)
{
  static const char *const common[] = {"name", "center_x", "center_y",
                                       "material", "pos", "quat", NULL};
  static const char *const a_explicit[] = {
    "name", "x_size", "y_size", "x_sample", "y_sample", "x_samples",
    "y_samples", "center_x", "center_y", "height", "material", "pos", "quat",
    NULL};
  static const char *const a_png[] = {
    "name", "png", "x_size", "y_size", "center_x", "center_y", "z_scale",
    "z_offset", "material", "pos", "quat", NULL};
  static const char *const a_text[] = {"name", "text", "x_size", "y_size",
                                       "center_x", "center_y", "material",
                                       "pos", "quat", NULL};
  static const char *const kids_plain[] = {"soil", NULL};
  static const char *const kids_gen[] = {"soil", "terrain_properties", NULL};

  ssHfieldDef def = ss_hfield_def_default();
  pendingSoil ps;
  memset(&ps, 0, sizeof ps);
  double *height = NULL;
  xEl e;
  ssStatus st = el_open(c, n, NULL, &e);
  const char *name = NULL;

  /* which form: exactly one of height, png, text, <terrain_properties> */
  xmlNodePtr tp = NULL;
  int ntp = 0;
  for (xmlNodePtr k = n->children; k; k = k->next)
    if (k->type == XML_ELEMENT_NODE) {
      char kn[NAME_CAP];
      norm_name((const char *)k->name, kn);
      if (!strcmp(kn, "terrain_properties")) {
        if (!tp) tp = k;
        ntp++;
      }
    }
  if (!st) {
    /* the name first, so that later messages can use it */
    const char *v = el_find(&e, "name");
    if (v) snprintf(e.label, sizeof e.label, "heightmap '%s'", v);
  }
  int form = HF_EXPLICIT;
  if (!st) {
    const char *given[4];
    int ng = 0;
    if (el_find(&e, "height")) given[ng++] = "height";
    if (el_find(&e, "png")) given[ng++] = "png", form = HF_PNG;
    if (el_find(&e, "text")) given[ng++] = "text", form = HF_TEXT;
    if (tp) given[ng++] = "<terrain_properties>", form = HF_GENERATED;
    if (ng > 1)
      st = fail(c, SS_ERR_PARSE, e.line,
                "%s: give exactly one of height, png, text or "
                "<terrain_properties> (found %s and %s)", e.label, given[0],
                given[1]);
  }
  if (!st)
    st = el_allow(c, &e, form == HF_EXPLICIT ? a_explicit
                         : form == HF_PNG    ? a_png
                         : form == HF_TEXT   ? a_text
                                             : common);
  if (!st) st = get_str(c, &e, "name", 1, &name);
  def.name = name;
  def.line = e.line;
  if (!st) st = get_num(c, &e, "center_x", 0, &def.center_x);
  if (!st) st = get_num(c, &e, "center_y", 0, &def.center_y);
  if (!st) st = get_material(c, &e, &def.material);
  if (!st) st = get_vec(c, &e, "pos", 3, 0, def.pos);
  if (!st) st = get_vec(c, &e, "quat", 4, 0, def.quat);
  if (!st) quat_rescale(def.quat);
  if (!st && quat_is_zero(def.quat))
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: quat = %g %g %g %g has zero length (quaternions are w x y z)",
              e.label, def.quat[0], def.quat[1], def.quat[2], def.quat[3]);
  double quat_read[4];
  memcpy(quat_read, def.quat, sizeof quat_read);
  if (!st && form != HF_GENERATED) {
    st = get_num(c, &e, "x_size", 1, &def.x_size);
    if (!st) st = get_num(c, &e, "y_size", 1, &def.y_size);
    if (!st && !(def.x_size > 0))
      st = fail(c, SS_ERR_VALUE, e.line, "%s: x_size = %g is invalid: must be > 0",
                e.label, def.x_size);
    if (!st && !(def.y_size > 0))
      st = fail(c, SS_ERR_VALUE, e.line, "%s: y_size = %g is invalid: must be > 0",
                e.label, def.y_size);
  }
  if (!st && form == HF_EXPLICIT) {
    def.source = SS_HFIELD_EXPLICIT;
    long cnt[2] = {0, 0};
    for (int k = 0; k < 2 && !st; k++) {
      const char *used = NULL;
      st = get_alias_long(c, &e, k ? "y_sample" : "x_sample",
                          k ? "y_samples" : "x_samples", LONG_MIN, LONG_MAX,
                          &used, &cnt[k]);
      if (!st && cnt[k] < 2)
        st = fail(c, SS_ERR_VALUE, e.line,
                  "%s: %s = %ld is invalid: need at least 2 samples along %c",
                  e.label, used, cnt[k], k ? 'y' : 'x');
      if (!st && cnt[k] > MAX_VERTICES / 2)
        st = fail(c, SS_ERR_VALUE, e.line, "%s: %s = %ld is too large",
                  e.label, used, cnt[k]);
    }
    if (!st && cnt[0] * cnt[1] > MAX_VERTICES)
      st = fail(c, SS_ERR_VALUE, e.line,
                "%s: %ld x %ld samples exceed the limit of %ld vertices",
                e.label, cnt[0], cnt[1], MAX_VERTICES);
    if (!st) {
      def.nx = (int)cnt[0];
      def.ny = (int)cnt[1];
      st = get_array(c, &e, "height", cnt[0] * cnt[1], "x_sample*y_sample", 1,
                     &height);
    }
  } else if (!st && (form == HF_PNG || form == HF_TEXT)) {
    const char *attr = form == HF_PNG ? "png" : "text";
    char path[1200];
    double z_scale = 1, z_offset = 0;
    if (form == HF_PNG) {
      st = get_num(c, &e, "z_scale", 0, &z_scale);
      if (!st) st = get_num(c, &e, "z_offset", 0, &z_offset);
    }
    if (!st) st = resolve_path(c, &e, attr, el_find(&e, attr), path, sizeof path);
    if (!st) {
      ssError e2;
      memset(&e2, 0, sizeof e2);
      ssStatus r = form == HF_PNG
                       ? ss_hfield_read_png(path, z_scale, z_offset, &def.nx,
                                            &def.ny, &height, &e2)
                       : ss_hfield_read_text(path, &def.nx, &def.ny, &height,
                                             &e2);
      if (r != SS_OK) {
        if (e2.line > 0)
          st = fail(c, r, e.line, "%s: %s file '%s' line %d: %s", e.label,
                    attr, path, e2.line, e2.message);
        else
          st = fail(c, r, e.line, "%s: cannot use %s file '%s': %s", e.label,
                    attr, path, e2.message);
      }
      def.source = form == HF_PNG ? SS_HFIELD_PNG : SS_HFIELD_TEXT;
    }
  } else if (!st && form == HF_GENERATED) {
    ssTerrainProps p;
    if (ntp > 1) {
      int seen = 0;
      once_at(c, &seen, tp, "terrain_properties");
      for (xmlNodePtr k = tp->next; k; k = k->next)
        if (k->type == XML_ELEMENT_NODE) {
          char kn[NAME_CAP];
          norm_name((const char *)k->name, kn);
          if (!strcmp(kn, "terrain_properties")) {
            st = once_at(c, &seen, k, kn);
            break;
          }
        }
    }
    if (!st) st = read_terrain_props(c, tp, e.label, &p);
    if (!st) {
      def.nx = p.x_samples;
      def.ny = p.y_samples;
      def.x_size = p.x_size;
      def.y_size = p.y_size;
      def.source = SS_HFIELD_GENERATED;
      height = malloc((size_t)def.nx * (size_t)def.ny * sizeof *height);
      if (!height)
        st = fail(c, SS_ERR_NOMEM, e.line, "%s: out of memory", e.label);
      else
        ss_terrain_generate(&p, height);
    }
  }
  /* children: <soil>, and <terrain_properties> (read above) */
  int seen_soil = 0;
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    char kn[NAME_CAP];
    if (!child_el(c, k, &e, kn, &st)) continue;
    if (!strcmp(kn, "soil")) {
      st = once_at(c, &seen_soil, k, kn);
      if (!st) st = read_soil(c, k, e.label, def.nx, def.ny, &def.soilmat, &ps);
      def.soil = 1;
    } else if (!(form == HF_GENERATED && !strcmp(kn, "terrain_properties"))) {
      st = unknown_child(c, k, &e, form == HF_GENERATED ? kids_gen : kids_plain);
    }
  }
  if (!st) {
    def.height = height;
    int h = ss_model_add_hfield(c->m, &def, &c->e);
    if (h < 0) {
      st = fix_error(c, e.line, NULL);
    } else {
      keep_unit_quat(c->m->hfield_quat0 + 4 * h, quat_read);
      if (ps.sinkage || ps.plastic || ps.shear) {
        pendingSoil *p = realloc(c->pend, (size_t)(c->npend + 1) * sizeof *p);
        if (!p) {
          st = fail(c, SS_ERR_NOMEM, e.line, "out of memory");
        } else {
          c->pend = p;
          ps.hfield = h;
          c->pend[c->npend++] = ps;
          memset(&ps, 0, sizeof ps);
        }
      }
    }
  }
  pending_free(&ps);
  free(height);
  el_free(&e);
  return st;
}

static ssStatus pend_qpos(readCtx *c, int sys, double *q, int line)
{
  if (c->nqpend == c->capqpend) {
    int cap = c->capqpend ? 2 * c->capqpend : 8;
    int *ps = realloc(c->qpend_sys, (size_t)cap * sizeof *ps);
    if (ps) c->qpend_sys = ps;
    double **pq = ps ? realloc(c->qpend, (size_t)cap * sizeof *pq) : NULL;
    if (!pq) return fail(c, SS_ERR_NOMEM, line, "out of memory");
    c->qpend = pq;
    c->capqpend = cap;
  }
  c->qpend_sys[c->nqpend] = sys;
  c->qpend[c->nqpend++] = q;
  return SS_OK;
}

/* <articulated_system name urdf_path res_dir base material> with optional
 * <state qpos qvel pos quat> and any number of <pd joint p_gain d_gain
 * position_target velocity_target effort_limit> */
typedef struct pendingPd {
  char joint[128];
  double g[5];
  int line;
} pendingPd;

static ssStatus read_articulated(readCtx *c, xmlNodePtr n)
{
  static const char *const allowed[] = {"name", "urdf_path", "res_dir", "base",
                                        "material", NULL};
  static const char *const kids[] = {"state", "pd", NULL};
  xEl e;
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, allowed);
  const char *name = NULL, *raw = NULL, *res = NULL, *base = NULL, *mat = NULL;
  if (!st) st = get_str(c, &e, "name", 1, &name);
  if (!st) snprintf(e.label, sizeof e.label, "%s '%.100s'", e.name, name);
  if (!st) st = get_str(c, &e, "urdf_path", 1, &raw);
  if (!st) st = get_str(c, &e, "res_dir", 0, &res);
  if (!st) st = get_str(c, &e, "base", 0, &base);
  if (!st) st = get_material(c, &e, &mat);
  char path[1024] = "", resdir[1024] = "";
  if (!st) st = resolve_path(c, &e, "urdf_path", raw, path, sizeof path);
  if (!st && res) st = resolve_path(c, &e, "res_dir", res, resdir, sizeof resdir);
  if (!st && base && strcmp(base, "floating") && strcmp(base, "fixed"))
    st = fail(c, SS_ERR_VALUE, e.line,
              "%s: base = '%s' (allowed: floating, fixed)", e.label, base);
  ssArtDef def = ss_art_def_default();
  def.line = e.line;
  double *qpos = NULL, *qvel = NULL, *ref = NULL;
  int nqpos = 0, nqvel = 0, nref = 0, seen_state = 0, npd = 0;
  pendingPd *pd = NULL; /* (npd) read here, added once the system exists */
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    char kn[NAME_CAP];
    if (!child_el(c, k, &e, kn, &st)) continue;
    if (!strcmp(kn, "state")) {
      static const char *const sa[] = {"qpos", "qvel", "pos", "quat",
                                       "reference_qpos", NULL};
      xEl se;
      st = open_leaf(c, k, e.label, sa, &se);
      if (!st) st = once(c, &seen_state, &se);
      if (!st) st = get_list(c, &se, "qpos", &nqpos, &qpos);
      if (!st) st = get_list(c, &se, "qvel", &nqvel, &qvel);
      if (!st) st = get_list(c, &se, "reference_qpos", &nref, &ref);
      if (!st) st = get_vec(c, &se, "pos", 3, 0, def.pos);
      if (!st) st = get_vec(c, &se, "quat", 4, 0, def.quat);
      if (!st) quat_rescale(def.quat);
      def.pose_given = el_find(&se, "pos") || el_find(&se, "quat");
      if (!st && quat_is_zero(def.quat))
        st = fail(c, SS_ERR_VALUE, se.line, "%s: quat has zero length", se.label);
      el_free(&se);
    } else if (!strcmp(kn, "pd")) {
      static const char *const pa[] = {"joint", "p_gain", "d_gain", "position_target",
                                       "velocity_target", "effort_limit", NULL};
      xEl pe;
      st = open_leaf(c, k, e.label, pa, &pe);
      const char *jn = NULL;
      if (!st) st = get_str(c, &pe, "joint", 1, &jn);
      /* cut short, it could name another joint (URDF names are shorter) */
      if (!st && strlen(jn) >= sizeof pd->joint)
        st = fail(c, SS_ERR_VALUE, pe.line,
                  "%s: joint name '%.40s...' is too long (at most %d "
                  "characters)", pe.label, jn, (int)sizeof pd->joint - 1);
      if (!st) {
        pendingPd *p = realloc(pd, (size_t)(npd + 1) * sizeof *pd);
        if (!p) {
          st = fail(c, SS_ERR_NOMEM, pe.line, "out of memory");
          el_free(&pe);
          break;
        }
        pd = p;
        p += npd;
        snprintf(p->joint, sizeof p->joint, "%s", jn);
        memset(p->g, 0, sizeof p->g);
        p->line = pe.line;
        st = get_num(c, &pe, "p_gain", 0, &p->g[0]);
        if (!st) st = get_num(c, &pe, "d_gain", 0, &p->g[1]);
        if (!st) st = get_num(c, &pe, "position_target", 0, &p->g[2]);
        if (!st) st = get_num(c, &pe, "velocity_target", 0, &p->g[3]);
        if (!st) st = get_num(c, &pe, "effort_limit", 0, &p->g[4]);
        if (!st) npd++;
      }
      el_free(&pe);
    } else {
      st = unknown_child(c, k, &e, kids);
    }
  }
  ssUrdf *u = NULL;
  if (!st) {
    ssError ue;
    if (ss_urdf_load(path, res ? resdir : NULL, &u, &ue) != SS_OK) {
      /* errors inside the URDF name the URDF's line; a URDF that cannot
       * be read at all is reported where the scene names it */
      if (ue.line > 0)
        c->e = ue;
      else
        fail(c, ue.code, e.line, "%s: cannot load URDF %s: %s", e.label,
             path, ue.message);
      st = ue.code;
    }
  }
  /* a floating base (the default unless the URDF roots it at a fixed
   * "world") needs mass: checked here, where the URDF's line is known, so
   * that it is not a singular mass matrix at the first step */
  if (!st && (base ? !strcmp(base, "floating")
                   : u->world_base != SS_URDF_BASE_FIXED)) {
    ssError ue;
    if (ss_urdf_check_floating_root(u, &ue) != SS_OK) {
      c->e = ue;
      st = ue.code;
    }
  }
  /* kept absolute and normalised, so an export anywhere can name the same
   * files (messages above keep the path as the scene gives it) */
  char abspath[4096], absres[4096] = "";
  if (!st && ss_scene_path_absolute(path, abspath, sizeof abspath))
    st = fail(c, SS_ERR_VALUE, e.line, "%s: urdf_path '%s' is too long as an "
              "absolute path", e.label, path);
  if (!st && res && ss_scene_path_absolute(resdir, absres, sizeof absres))
    st = fail(c, SS_ERR_VALUE, e.line, "%s: res_dir '%s' is too long as an "
              "absolute path", e.label, resdir);
  if (!st) {
    def.name = name;
    def.fixed_base = base ? !strcmp(base, "fixed") : -1;
    def.material = mat;
    /* closures and springs derive their implicit anchors and lengths from
     * the reference configuration (an export writes the one the original
     * scene started from), then the state moves to qpos */
    def.qpos = ref ? ref : qpos;
    def.nqpos = ref ? nref : nqpos;
    def.qpos_name = ref ? "reference_qpos" : "qpos";
    def.qvel = qvel;
    def.nqvel = nqvel;
    def.urdf_path = abspath;
    def.res_dir = absres;
    int sys = ss_model_add_articulated(c->m, u, &def, &c->e);
    if (sys < 0) {
      st = c->e.code ? c->e.code : SS_ERR_VALUE;
      if (!c->e.file[0] || !strcmp(c->e.file, c->path)) {
        snprintf(c->e.file, sizeof c->e.file, "%s", c->path);
        if (!c->e.line) c->e.line = e.line;
      }
    }
    for (int i = 0; !st && i < npd; i++) {
      const double *g = pd[i].g;
      if (ss_model_add_pd(c->m, sys, pd[i].joint, g[0], g[1], g[2], g[3], g[4],
                          pd[i].line, &c->e) < 0) {
        st = c->e.code ? c->e.code : SS_ERR_VALUE;
        snprintf(c->e.file, sizeof c->e.file, "%s", c->path);
        c->e.line = pd[i].line;
      }
    }
  }
  if (!st && ref && qpos) {
    int sys = c->m->nsys - 1;
    if (nqpos != c->m->sys_nq[sys])
      st = fail(c, SS_ERR_VALUE, e.line, "%s: qpos has %d values, expected %d",
                e.label, nqpos, c->m->sys_nq[sys]);
    else
      st = pend_qpos(c, sys, qpos, e.line);
    if (!st) qpos = NULL; /* owned by the pending list */
  }
  ss_urdf_free(u);
  free(pd);
  free(qpos);
  free(qvel);
  free(ref);
  el_free(&e);
  return st;
}

/* RaiSim's granular media (GranularSystem) and deformable objects
 * (DeformableObject, deformable cloth) have no counterpart here, and a soil
 * bed cannot be combined with them.  Their elements are recognized (under
 * the names RaiSim's object classes give them, and short forms) so that
 * the refusal says why instead of "unknown element". */
static const char *const media_names[] = {
  "granular_system", "granular_media", "granular", "deformable_object",
  "deformable_cloth", "deformable", NULL};

/* 1 if a <heightmap> among the children of n has a <soil> */
static int has_soil_bed(xmlNodePtr n)
{
  for (xmlNodePtr k = n->children; k; k = k->next) {
    if (k->type != XML_ELEMENT_NODE) continue;
    char kn[NAME_CAP];
    norm_name((const char *)k->name, kn);
    if (strcmp(kn, "heightmap")) continue;
    for (xmlNodePtr s = k->children; s; s = s->next) {
      if (s->type != XML_ELEMENT_NODE) continue;
      norm_name((const char *)s->name, kn);
      if (!strcmp(kn, "soil")) return 1;
    }
  }
  return 0;
}

static ssStatus refuse_media(readCtx *c, xmlNodePtr k, const char *kn,
                             int soil)
{
  xmlChar *nm = xmlGetProp(k, BAD_CAST "name");
  const char *why =
      soil ? "soil beds cannot be combined with granular media or deformable "
             "objects (not supported)"
      : kn[0] == 'g' ? "granular media are not supported"
                     : "deformable objects are not supported";
  ssStatus st = fail(c, SS_ERR_UNSUPPORTED, ss_xml_line(k),
                     "<%s>%s%.100s%s: %s",
                     kn, nm ? " '" : "", nm ? (const char *)nm : "",
                     nm ? "'" : "", why);
  if (nm) xmlFree(nm);
  return st;
}

static ssStatus read_objects(readCtx *c, xmlNodePtr n)
{
  static const char *const kids[] = {"ground", "box", "sphere", "cylinder",
                                     "capsule", "mesh", "heightmap",
                                     "articulated_system", NULL};
  static const char *const none[] = {NULL};
  xEl e;
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, none);
  int soil = has_soil_bed(n);
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    char kn[NAME_CAP];
    if (!child_el(c, k, &e, kn, &st)) continue;
    if (!strcmp(kn, "ground")) st = read_ground(c, k);
    else if (!strcmp(kn, "box")) st = read_body(c, k, SS_GEOM_BOX);
    else if (!strcmp(kn, "sphere")) st = read_body(c, k, SS_GEOM_SPHERE);
    else if (!strcmp(kn, "cylinder")) st = read_body(c, k, SS_GEOM_CYLINDER);
    else if (!strcmp(kn, "capsule")) st = read_body(c, k, SS_GEOM_CAPSULE);
    else if (!strcmp(kn, "heightmap")) st = read_heightmap(c, k);
    else if (!strcmp(kn, "articulated_system")) st = read_articulated(c, k);
    else if (!strcmp(kn, "mesh")) st = read_body(c, k, SS_GEOM_MESH);
    else if (ss_xml_in_list(kn, media_names))
      st = refuse_media(c, k, kn, soil);
    else
      st = unknown_child(c, k, &e, kids);
  }
  el_free(&e);
  return st;
}

/* ---------------------------------------------------------------------- */
/* materials, options, camera, clock                                       */

/* <pair_prop>s read so far, by their material indices a <= b: an
 * open-addressing hash table, at most half full */
typedef struct seenPair {
  int a, b, line, used;
} seenPair;

typedef struct seenPairs {
  seenPair *slot;
  int cap;  /* a power of two, or 0 */
  int n;
} seenPairs;

static unsigned seen_slot(const seenPairs *t, int a, int b)
{
  uint64_t h = ((uint64_t)(unsigned)a << 32 | (unsigned)b) * 0x9E3779B97F4A7C15ULL;
  unsigned mask = (unsigned)t->cap - 1, k = (unsigned)(h ^ (h >> 29)) & mask;
  while (t->slot[k].used && (t->slot[k].a != a || t->slot[k].b != b))
    k = (k + 1) & mask;
  return k;
}

/* Enter the pair a <= b read at `line`, or set *first to the line of the
 * one entered before; 0, or -1 out of memory. */
static int seen_enter(seenPairs *t, int a, int b, int line, int *first)
{
  if (2 * (t->n + 1) > t->cap) {
    if (t->cap > INT_MAX / 4) return -1;
    seenPairs g = {NULL, t->cap ? 2 * t->cap : 64, t->n};
    if (!(g.slot = calloc((size_t)g.cap, sizeof *g.slot))) return -1;
    for (int k = 0; k < t->cap; k++)
      if (t->slot[k].used)
        g.slot[seen_slot(&g, t->slot[k].a, t->slot[k].b)] = t->slot[k];
    free(t->slot);
    *t = g;
  }
  seenPair *p = &t->slot[seen_slot(t, a, b)];
  if (p->used) {
    *first = p->line;
    return 0;
  }
  *p = (seenPair){a, b, line, 1};
  t->n++;
  return 0;
}

static ssStatus read_material(readCtx *c, xmlNodePtr n)
{
  static const char *const kids[] = {"default", "pair_prop", NULL};
  static const char *const a_def[] = {"friction", "restitution",
                                      "restitution_threshold", NULL};
  static const char *const a_pair[] = {"name1", "name2", "friction",
                                       "restitution", "restitution_threshold",
                                       NULL};
  static const char *const none[] = {NULL};
  xEl e;
  int seen_default = 0;
  /* pairs already given (in either order), for the duplicate check: a
   * hash table by the pair's material indices (names and indices are one
   * to one, and the materials are the ones ss_model_set_pair makes below,
   * in the same order), so that n pairs are checked in linear time, not
   * each against every earlier one */
  seenPairs seen = {NULL, 0, 0};
  ssStatus st = el_open(c, n, NULL, &e);
  if (!st) st = el_allow(c, &e, none);
  for (xmlNodePtr k = n->children; !st && k; k = k->next) {
    char kn[NAME_CAP];
    if (!child_el(c, k, &e, kn, &st)) continue;
    xEl x;
    if (!strcmp(kn, "default")) {
      ssMaterialPair p = c->m->material_default;
      st = open_leaf(c, k, "<material>", a_def, &x);
      if (!st) st = once(c, &seen_default, &x);
      if (!st) st = get_num(c, &x, "friction", 0, &p.friction);
      if (!st) st = get_num(c, &x, "restitution", 0, &p.restitution);
      if (!st)
        st = get_num(c, &x, "restitution_threshold", 0, &p.restitution_threshold);
      if (!st && ss_model_set_pair(c->m, NULL, NULL, p.friction, p.restitution,
                                   p.restitution_threshold, &c->e) != SS_OK) {
        c->e.line = 0;
        st = fix_error(c, x.line, x.label);
      }
      el_free(&x);
    } else if (!strcmp(kn, "pair_prop")) {
      const char *n1 = NULL, *n2 = NULL;
      double f = 0, r = 0, t = 0;
      st = open_leaf(c, k, "<material>", a_pair, &x);
      if (!st) st = get_str(c, &x, "name1", 1, &n1);
      if (!st) st = get_str(c, &x, "name2", 1, &n2);
      if (!st && (!*n1 || !*n2))
        st = fail(c, SS_ERR_VALUE, x.line,
                  "%s: name1 and name2 must be non-empty material names",
                  x.label);
      int ma = -1, mb = -1;
      if (!st) {
        ma = ss_model_material(c->m, n1);
        mb = ss_model_material(c->m, n2);
        if (ma < 0 || mb < 0) st = fail(c, SS_ERR_NOMEM, x.line, "out of memory");
        if (ma > mb) {
          int swap = ma;
          ma = mb;
          mb = swap;
        }
      }
      int first = -1;
      if (!st && seen_enter(&seen, ma, mb, x.line, &first) < 0)
        st = fail(c, SS_ERR_NOMEM, x.line, "out of memory");
      if (!st && first >= 0)
        st = fail(c, SS_ERR_PARSE, x.line,
                  "%s: the pair '%.100s' / '%.100s' is given twice (first "
                  "at line %d)", x.label, n1, n2, first);
      if (!st) st = get_num(c, &x, "friction", 1, &f);
      if (!st) st = get_num(c, &x, "restitution", 0, &r);
      if (!st) st = get_num(c, &x, "restitution_threshold", 0, &t);
      if (!st && ss_model_set_pair(c->m, n1, n2, f, r, t, &c->e) != SS_OK) {
        c->e.line = 0;
        st = fix_error(c, x.line, x.label);
      }
      el_free(&x);
    } else {
      st = unknown_child(c, k, &e, kids);
    }
  }
  free(seen.slot);
  el_free(&e);
  return st;
}

static ssStatus read_time_step(readCtx *c, xEl *e)
{
  static const char *const allowed[] = {"value", NULL};
  ssStatus st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  double dt = 0;
  if (!st) st = get_num(c, e, "value", 1, &dt);
  if (!st && !(dt > 0 && dt <= 1))
    st = fail(c, SS_ERR_VALUE, e->line,
              "<time_step>: value = %g is invalid: must be in (0, 1] s", dt);
  if (!st) c->m->opt.timestep = dt;
  return st;
}

static ssStatus read_gravity(readCtx *c, xEl *e)
{
  static const char *const allowed[] = {"value", NULL};
  ssStatus st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  if (!st) st = get_vec(c, e, "value", 3, 1, c->m->opt.gravity);
  return st;
}

static ssStatus read_contact_solver(readCtx *c, xEl *e)
{
  static const char *const allowed[] = {
    "max_sweeps", "tolerance", "scalar_tolerance", "terrain_warm_start",
    "contact_margin", "rigid_erp", NULL};
  ssOption *o = &c->m->opt;
  ssStatus st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  if (!st) st = get_int(c, e, "max_sweeps", 0, 1, 1000000, &o->solver_max_sweeps);
  if (!st) st = get_num(c, e, "tolerance", 0, &o->solver_tolerance);
  if (!st) st = get_num(c, e, "scalar_tolerance", 0, &o->scalar_tolerance);
  if (!st) st = get_bool(c, e, "terrain_warm_start", &o->terrain_warm_start);
  if (!st) st = get_num(c, e, "contact_margin", 0, &o->contact_margin);
  if (!st) st = get_num(c, e, "rigid_erp", 0, &o->rigid_erp);
  if (!st) {
    const char *bad = NULL, *rule = NULL;
    double v = 0;
    if (!(o->solver_tolerance > 0 && o->solver_tolerance < 1))
      bad = "tolerance", v = o->solver_tolerance, rule = "in (0, 1)";
    else if (!(o->scalar_tolerance > 0 && o->scalar_tolerance < 1))
      bad = "scalar_tolerance", v = o->scalar_tolerance, rule = "in (0, 1)";
    else if (!(o->contact_margin >= 0))
      bad = "contact_margin", v = o->contact_margin, rule = ">= 0 m";
    else if (!(o->rigid_erp >= 0 && o->rigid_erp <= 1))
      bad = "rigid_erp", v = o->rigid_erp, rule = "in [0, 1]";
    if (bad)
      st = fail(c, SS_ERR_VALUE, e->line, "<contact_solver>: %s = %g is "
                "invalid: must be %s", bad, v, rule);
  }
  return st;
}

static ssStatus read_clock(readCtx *c, xEl *e)
{
  static const char *const allowed[] = {"time", "step", NULL};
  ssStatus st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  if (!st) st = get_num(c, e, "time", 0, &c->clock_time);
  if (!st) st = get_long(c, e, "step", 0, 0, LONG_MAX, &c->clock_step);
  if (!st && !(c->clock_time >= 0))
    st = fail(c, SS_ERR_VALUE, e->line,
              "<clock>: time = %g is invalid: must be >= 0 s", c->clock_time);
  c->clock_given = 1;
  return st;
}

static ssStatus read_camera(readCtx *c, xEl *e)
{
  static const char *const allowed[] = {"pos", "look_at", "fov_deg", "follow",
                                        NULL};
  ssModel *m = c->m;
  const char *follow = NULL;
  ssStatus st = el_allow(c, e, allowed);
  if (!st) st = check_leaf(c, e);
  if (!st) st = get_vec(c, e, "pos", 3, 1, m->camera_pos);
  if (!st) st = get_vec(c, e, "look_at", 3, 1, m->camera_look_at);
  if (!st && !ss_camera_valid(m->camera_pos, m->camera_look_at))
    st = fail(c, SS_ERR_VALUE, e->line,
              "<camera>: pos and look_at must be distinct points (the camera looks "
              "from pos towards look_at)");
  if (!st) st = get_num(c, e, "fov_deg", 0, &m->camera_fov_deg);
  if (!st && !(m->camera_fov_deg > 0 && m->camera_fov_deg < 180))
    st = fail(c, SS_ERR_VALUE, e->line,
              "<camera>: fov_deg = %g is invalid: must be in (0, 180)",
              m->camera_fov_deg);
  if (!st) st = get_str(c, e, "follow", 0, &follow);
  if (!st && follow) {
    if (!*follow)
      st = fail(c, SS_ERR_VALUE, e->line, "<camera>: follow is empty (give "
                "the name of a body to follow, or leave the attribute out)");
    else if (strlen(follow) >= sizeof m->camera_follow)
      st = fail(c, SS_ERR_VALUE, e->line, "<camera>: follow name is too long");
    else
      snprintf(m->camera_follow, sizeof m->camera_follow, "%s", follow);
  }
  m->camera_given = 1;
  c->camera_line = e->line;
  return st;
}

static ssStatus read_root(readCtx *c, xmlNodePtr root)
{
  static const char *const kids[] = {"time_step", "gravity", "contact_solver",
                                     "clock", "camera", "objects", "material",
                                     NULL};
  static const char *const allowed[] = {"version", NULL};
  xEl e;
  ssStatus st = el_open(c, root, NULL, &e);
  if (!st && strcmp(e.name, "raisim"))
    st = fail(c, SS_ERR_PARSE, e.line,
              "root element is <%s>, expected <raisim>", e.raw);
  if (!st) st = el_allow(c, &e, allowed);
  int seen[7] = {0};
  for (xmlNodePtr k = root->children; !st && k; k = k->next) {
    char kn[NAME_CAP];
    if (!child_el(c, k, &e, kn, &st)) continue;
    int which = -1;
    for (int i = 0; kids[i]; i++)
      if (!strcmp(kn, kids[i])) which = i;
    if (which < 0) {
      st = unknown_child(c, k, &e, kids);
      break;
    }
    xEl x;
    st = el_open(c, k, NULL, &x);
    if (!st) st = once(c, &seen[which], &x);
    if (!st) {
      switch (which) {
      case 0: st = read_time_step(c, &x); break;
      case 1: st = read_gravity(c, &x); break;
      case 2: st = read_contact_solver(c, &x); break;
      case 3: st = read_clock(c, &x); break;
      case 4: st = read_camera(c, &x); break;
      case 5: st = read_objects(c, k); break;
      case 6: st = read_material(c, k); break;
      }
    }
    el_free(&x);
  }
  /* the camera may follow a body defined anywhere in the file */
  if (!st && c->m->camera_given && c->m->camera_follow[0] &&
      ss_model_find_sys(c->m, c->m->camera_follow) < 0)
    st = fail(c, SS_ERR_NOTFOUND, c->camera_line,
              "<camera>: follow = '%s' names no body in the scene",
              c->m->camera_follow);
  el_free(&e);
  return st;
}

/* ---------------------------------------------------------------------- */
/* parsing                                                                 */

static ssStatus parse_xml(readCtx *c, const char *buf, size_t len,
                          xmlDocPtr *out)
{
  *out = NULL;
  if (len == 0)
    return fail(c, SS_ERR_PARSE, 1, "empty scene: expected a <raisim> element");
  if (len > (size_t)SS_SCENE_MAX_BYTES)
    return fail(c, SS_ERR_IO, 0, "scene is %zu bytes, larger than the limit "
                "of %ld", len, (long)SS_SCENE_MAX_BYTES);
  /* huge: see scene.h */
  ssXmlResult r;
  *out = ss_xml_parse(buf, len, 1, &r);
  switch (r.fail) {
  case SS_XML_OK:
    return SS_OK;
  case SS_XML_NOMEM:
    return fail(c, SS_ERR_NOMEM, 0, "out of memory starting the XML parser");
  case SS_XML_DOCTYPE:
    return fail(c, SS_ERR_PARSE, r.line,
                "DOCTYPE declarations are not allowed in scene files (no DTDs, "
                "no entities)");
  case SS_XML_SYNTAX:
    return fail(c, SS_ERR_PARSE, r.line, "XML syntax error: %s", r.message);
  case SS_XML_NO_ROOT:
    break;
  }
  return fail(c, SS_ERR_PARSE, r.line, "no root element: expected <raisim>");
}

/* ---------------------------------------------------------------------- */
/* entry points                                                            */

static void ctx_free(readCtx *c)
{
  for (int i = 0; i < c->npend; i++) pending_free(&c->pend[i]);
  for (int i = 0; i < c->nqpend; i++) free(c->qpend[i]);
  free(c->qpend);
  free(c->qpend_sys);
  c->qpend = NULL;
  c->qpend_sys = NULL;
  c->nqpend = c->capqpend = 0;
  free(c->pend);
  c->pend = NULL;
  c->npend = 0;
}

static ssStatus load(const char *buf, size_t len, const char *path,
                     ssModel **mout, ssData **dout, ssError *err)
{
  readCtx c;
  memset(&c, 0, sizeof c);
  c.path = path;
  c.buf = buf;
  c.len = len;
  ss_scene_path_dir(path, c.dir, sizeof c.dir);

  ssCLocale loc;
  if (ss_scene_c_locale_begin(&loc, path, err) != SS_OK) return SS_ERR_STATE;

  ssData *d = NULL;
  ssStatus st = parse_xml(&c, buf, len, &c.doc);
  if (!st) {
    c.m = ss_model_new();
    if (!c.m) st = fail(&c, SS_ERR_NOMEM, 0, "out of memory");
  }
  if (!st) {
    snprintf(c.m->source_path, sizeof c.m->source_path, "%s", path);
    st = read_root(&c, xmlDocGetRootElement(c.doc));
  }
  if (!st && ss_model_validate(c.m, &c.e) != SS_OK) st = fix_error(&c, 0, NULL);
  if (!st) {
    d = ss_data_new(c.m);
    if (!d) st = fail(&c, SS_ERR_NOMEM, 0, "out of memory");
  }
  for (int i = 0; !st && i < c.npend; i++) {
    pendingSoil *p = &c.pend[i];
    ssError e2;
    if (ss_soil_set_state(c.m, d, p->hfield, p->sinkage, p->plastic, p->shear,
                          &e2) != SS_OK)
      st = fail(&c, e2.code, p->line, "heightmap '%s': %s",
                c.m->hfield_name[p->hfield], e2.message);
  }
  for (int i = 0; !st && i < c.nqpend; i++) {
    int sys = c.qpend_sys[i];
    memcpy(d->qpos + c.m->sys_qadr[sys], c.qpend[i],
           (size_t)c.m->sys_nq[sys] * sizeof(double));
    ss_forward(c.m, d);
  }
  if (!st && c.clock_given) {
    d->time = c.clock_time;
    d->step = c.clock_step;
  }
  if (c.doc) xmlFreeDoc(c.doc);
  ctx_free(&c);
  ss_scene_c_locale_pop(&loc);
  if (st) {
    ss_data_free(d);
    ss_model_free(c.m);
    if (err) *err = c.e;
    return st;
  }
  *mout = c.m;
  *dout = d;
  return SS_OK;
}

ssStatus ss_scene_load_buffer(const char *buf, size_t len,
                              const char *base_path, ssModel **mout,
                              ssData **dout, ssError *err)
{
  if (!mout || !dout)
    return ss_error_set(err, SS_ERR_VALUE, base_path, 0,
                        "ss_scene_load_buffer: NULL output argument");
  *mout = NULL;
  *dout = NULL;
  if (!buf && len)
    return ss_error_set(err, SS_ERR_VALUE, base_path, 0,
                        "ss_scene_load_buffer: NULL buffer");
  return load(buf ? buf : "", len, base_path ? base_path : "(buffer)", mout,
              dout, err);
}

ssStatus ss_scene_load(const char *path, ssModel **mout, ssData **dout,
                       ssError *err)
{
  if (!mout || !dout)
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "ss_scene_load: NULL output argument");
  *mout = NULL;
  *dout = NULL;
  char *buf = NULL;
  size_t len = 0;
  ssStatus st = ss_read_file(path, SS_SCENE_MAX_BYTES, &buf, &len, err);
  if (st != SS_OK) return st;
  st = load(buf, len, path, mout, dout, err);
  free(buf);
  return st;
}
