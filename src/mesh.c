/* mesh.c -- triangle meshes: import with assimp's C API, a bounding-volume
 * hierarchy, watertight ray casts, the mass properties of the solid, and
 * the points a footprint on a soil bed is the hull of (hull_points).
 *
 * Ray casts.  The triangle test is Moller-Trumbore's determinant test
 * written in the ray's own sheared frame (Woop, Benthin and Wald, "Watertight
 * ray/triangle intersection", JCGT 2013): the ray becomes the +z axis
 * through the origin, each vertex is translated and sheared once, and the
 * three barycentric numerators are 2-D edge functions of vertex pairs.  An
 * edge shared by two triangles gives the same function with opposite sign
 * (computed from the same sheared vertices), and the sign is made exact
 * (an fma-based difference of products when the plain one is too close to
 * zero to trust), so a ray through an edge or a vertex of a closed mesh
 * always finds at least one of the triangles there: no cracks.  Tie-
 * breaking: a ray through an edge or a vertex counts as inside every
 * triangle that touches it; all of those report (to rounding) the same t,
 * and the smallest t found is returned.  Faces are two-sided (no back-face
 * culling), so a ray starting inside a closed mesh hits its inside.  A ray
 * lying in a face's plane does not hit that face (its determinant is 0); it
 * hits the faces across whose edges it passes.  A ray starting on the
 * surface hits at t = 0. */
#include "mesh.h"
#include "ss_math.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* largest mesh accepted, in triangles */
#define MESH_MAX_TRIS 10000000L
/* largest mesh file read (bytes), checked before assimp reads any of it:
 * room for 10 million triangles as binary STL or as text */
#define MESH_MAX_BYTES (512LL * 1024 * 1024)
/* triangles per BVH leaf, at most */
#define LEAF_MAX 4
/* BVH depth bound: splits halve the count, so the depth is at most
 * log2(MESH_MAX_TRIS / LEAF_MAX) + 2 < 32; the stack has room to spare */
#define STACK_MAX 96

/* ---------------------------------------------------------------------- */
/* BVH                                                                     */

typedef struct keyTri {
  double key; /* centroid coordinate on the split axis */
  int tri;    /* triangle index (breaks ties) */
  int pos;    /* position in the node's range before the split */
} keyTri;

/* total order: key, then triangle index (deterministic with equal keys) */
static int kt_less(const keyTri *a, const keyTri *b)
{
  return a->key < b->key || (a->key == b->key && a->tri < b->tri);
}

static int kt_cmp(const void *pa, const void *pb)
{
  const keyTri *a = pa, *b = pb;
  return kt_less(a, b) ? -1 : kt_less(b, a) ? 1 : 0;
}

static void kt_swap(keyTri *a, keyTri *b)
{
  keyTri t = *a;
  *a = *b;
  *b = t;
}

/* Rearrange v[0..n) so that v[k] is the k-th smallest, smaller ones before
 * it and larger ones after: quickselect with a median-of-three pivot,
 * falling back to a sort when it takes too many rounds. */
static void kt_select(keyTri *v, int n, int k)
{
  int lo = 0, hi = n - 1, rounds = 0;
  while (hi > lo) {
    if (++rounds > 64) {
      qsort(v + lo, (size_t)(hi - lo + 1), sizeof *v, kt_cmp);
      return;
    }
    int mid = lo + (hi - lo) / 2;
    if (kt_less(&v[mid], &v[lo])) kt_swap(&v[mid], &v[lo]);
    if (kt_less(&v[hi], &v[lo])) kt_swap(&v[hi], &v[lo]);
    if (kt_less(&v[hi], &v[mid])) kt_swap(&v[hi], &v[mid]);
    keyTri pivot = v[mid];
    int i = lo, j = hi;
    while (i <= j) {
      while (kt_less(&v[i], &pivot)) i++;
      while (kt_less(&pivot, &v[j])) j--;
      if (i <= j) {
        kt_swap(&v[i], &v[j]);
        i++;
        j--;
      }
    }
    if (k <= j)
      hi = j;
    else if (k >= i)
      lo = i;
    else
      return;
  }
}

/* Centroids and bounds are kept in the order of bvh_tri and permuted with
 * it, so that each level reads them sequentially. */
typedef struct bvhBuild {
  ssMesh *m;
  double *cent;  /* (ntri x 3) triangle centroids, bvh_tri order */
  double *tbox;  /* (ntri x 6) triangle bounds lo xyz, hi xyz, same order */
  double *tmp;   /* (ntri x 9) permutation buffer */
  keyTri *scratch;
} bvhBuild;

/* Node for bvh_tri[first .. first + count); returns its index. */
static int build_node(bvhBuild *b, int first, int count, int depth)
{
  ssMesh *m = b->m;
  int k = m->nnode++;
  double *box = m->bvh_box + 6 * k;
  double clo[3], chi[3];
  for (int a = 0; a < 3; a++) {
    box[a] = clo[a] = INFINITY;
    box[3 + a] = chi[a] = -INFINITY;
  }
  for (int i = first; i < first + count; i++) {
    const double *tb = b->tbox + 6 * i;
    for (int a = 0; a < 3; a++) {
      if (tb[a] < box[a]) box[a] = tb[a];
      if (tb[3 + a] > box[3 + a]) box[3 + a] = tb[3 + a];
      double cc = b->cent[3 * i + a];
      if (cc < clo[a]) clo[a] = cc;
      if (cc > chi[a]) chi[a] = cc;
    }
  }
  if (count <= LEAF_MAX || depth >= STACK_MAX / 2) {
    m->bvh_child[2 * k] = -1 - first;
    m->bvh_child[2 * k + 1] = count;
    return k;
  }
  /* median split on the longest axis of the centroid bounds (the first
   * such axis on ties); equal centroids still split by triangle index */
  int axis = 0;
  for (int a = 1; a < 3; a++)
    if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
  keyTri *v = b->scratch + first;
  for (int i = 0; i < count; i++) {
    v[i].key = b->cent[3 * (first + i) + axis];
    v[i].tri = m->bvh_tri[first + i];
    v[i].pos = i;
  }
  int half = count / 2;
  kt_select(v, count, half);
  double *tc = b->tmp + 9 * (size_t)first;
  for (int i = 0; i < count; i++) {
    int src = first + v[i].pos;
    memcpy(tc + 9 * i, b->cent + 3 * src, 3 * sizeof *tc);
    memcpy(tc + 9 * i + 3, b->tbox + 6 * src, 6 * sizeof *tc);
  }
  for (int i = 0; i < count; i++) {
    m->bvh_tri[first + i] = v[i].tri;
    memcpy(b->cent + 3 * (first + i), tc + 9 * i, 3 * sizeof *tc);
    memcpy(b->tbox + 6 * (first + i), tc + 9 * i + 3, 6 * sizeof *tc);
  }
  int left = build_node(b, first, half, depth + 1);
  int right = build_node(b, first + half, count - half, depth + 1);
  m->bvh_child[2 * k] = left;
  m->bvh_child[2 * k + 1] = right;
  return k;
}

static ssStatus build_bvh(ssMesh *m, ssError *err, const char *what)
{
  int n = m->ntri;
  size_t cap = (size_t)2 * (size_t)n; /* at most 2n - 1 nodes */
  bvhBuild b;
  b.m = m;
  b.cent = malloc((size_t)n * 3 * sizeof *b.cent);
  b.tbox = malloc((size_t)n * 6 * sizeof *b.tbox);
  b.tmp = malloc((size_t)n * 9 * sizeof *b.tmp);
  b.scratch = malloc((size_t)n * sizeof *b.scratch);
  m->bvh_box = malloc(cap * 6 * sizeof *m->bvh_box);
  m->bvh_child = malloc(cap * 2 * sizeof *m->bvh_child);
  m->bvh_tri = malloc((size_t)n * sizeof *m->bvh_tri);
  if (!b.cent || !b.tbox || !b.tmp || !b.scratch || !m->bvh_box ||
      !m->bvh_child || !m->bvh_tri) {
    free(b.cent);
    free(b.tbox);
    free(b.tmp);
    free(b.scratch);
    return ss_error_set(err, SS_ERR_NOMEM, what, 0,
                        "out of memory building the BVH of %d triangles", n);
  }
  for (int t = 0; t < n; t++) {
    m->bvh_tri[t] = t;
    for (int a = 0; a < 3; a++) {
      double x = m->vert[3 * m->tri[3 * t] + a];
      double y = m->vert[3 * m->tri[3 * t + 1] + a];
      double z = m->vert[3 * m->tri[3 * t + 2] + a];
      b.cent[3 * t + a] = (x + y + z) / 3.0;
      double lo = x < y ? x : y, hi = x > y ? x : y;
      b.tbox[6 * t + a] = z < lo ? z : lo;
      b.tbox[6 * t + 3 + a] = z > hi ? z : hi;
    }
  }
  m->nnode = 0;
  build_node(&b, 0, n, 0);
  free(b.cent);
  free(b.tbox);
  free(b.tmp);
  free(b.scratch);
  /* give back the unused node slots */
  double *bb = realloc(m->bvh_box, (size_t)m->nnode * 6 * sizeof *bb);
  if (bb) m->bvh_box = bb;
  int *bc = realloc(m->bvh_child, (size_t)m->nnode * 2 * sizeof *bc);
  if (bc) m->bvh_child = bc;
  return SS_OK;
}

/* ---------------------------------------------------------------------- */
/* assimp's file access                                                    */

/* Every file assimp opens for an import goes through these: the mesh file
 * and what it names (an OBJ's mtllib, a glTF's buffers, ...).  Only a
 * regular file of at most MESH_MAX_BYTES is opened, and for reading only:
 * a FIFO or a device named inside a mesh file is refused at once instead
 * of waited on (opened without O_NONBLOCK, a FIFO blocks until a writer
 * comes, so the import would hang), and a huge or endless one is never
 * read into memory.  Refused, the file is missing to assimp. */
static FILE *file_of(struct aiFile *f) { return (FILE *)(void *)f->UserData; }

static size_t io_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
  return fread(buf, size, count, file_of(f));
}

static size_t io_write(struct aiFile *f, const char *buf, size_t size,
                       size_t count)
{
  (void)f;
  (void)buf;
  (void)size;
  (void)count;
  return 0;
}

static size_t io_tell(struct aiFile *f)
{
  off_t t = ftello(file_of(f));
  return t < 0 ? 0 : (size_t)t;
}

static size_t io_size(struct aiFile *f)
{
  struct stat sb;
  return fstat(fileno(file_of(f)), &sb) == 0 && sb.st_size > 0
             ? (size_t)sb.st_size
             : 0;
}

static enum aiReturn io_seek(struct aiFile *f, size_t off, enum aiOrigin o)
{
  int whence = o == aiOrigin_CUR ? SEEK_CUR : o == aiOrigin_END ? SEEK_END
                                                                : SEEK_SET;
  /* a backward move arrives as a wrapped size_t */
  off_t d = whence == SEEK_SET ? (off_t)off : (off_t)(long long)off;
  if (whence == SEEK_SET && off > (size_t)MESH_MAX_BYTES) return aiReturn_FAILURE;
  return fseeko(file_of(f), d, whence) == 0 ? aiReturn_SUCCESS
                                            : aiReturn_FAILURE;
}

static void io_flush(struct aiFile *f) { (void)f; }

static struct aiFile *io_open(struct aiFileIO *io, const char *name,
                              const char *mode)
{
  (void)io;
  if (!name || !mode || strchr(mode, 'w') || strchr(mode, 'a') ||
      strchr(mode, '+'))
    return NULL;
  int fd = open(name, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return NULL;
  struct stat sb;
  int flags = fcntl(fd, F_GETFL);
  if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode) ||
      (long long)sb.st_size > MESH_MAX_BYTES || flags < 0 ||
      fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    close(fd);
    return NULL;
  }
  FILE *fp = fdopen(fd, "rb");
  struct aiFile *f = fp ? calloc(1, sizeof *f) : NULL;
  if (!f) {
    if (fp) fclose(fp);
    else close(fd);
    return NULL;
  }
  f->ReadProc = io_read;
  f->WriteProc = io_write;
  f->TellProc = io_tell;
  f->FileSizeProc = io_size;
  f->SeekProc = io_seek;
  f->FlushProc = io_flush;
  f->UserData = (aiUserData)(void *)fp;
  return f;
}

static void io_close(struct aiFileIO *io, struct aiFile *f)
{
  (void)io;
  if (!f) return;
  fclose(file_of(f));
  free(f);
}

/* ---------------------------------------------------------------------- */
/* construction                                                            */

void ss_mesh_free(ssMesh *m)
{
  if (!m) return;
  free(m->vert);
  free(m->normal);
  free(m->tri);
  free(m->bvh_box);
  free(m->bvh_child);
  free(m->bvh_tri);
  free(m->hull);
  free(m);
}

/* Area-weighted vertex normals. */
static void vertex_normals(ssMesh *m)
{
  memset(m->normal, 0, (size_t)m->nvert * 3 * sizeof *m->normal);
  for (int t = 0; t < m->ntri; t++) {
    const int *f = m->tri + 3 * t;
    double e1[3], e2[3], n[3];
    ss_v3_sub(e1, m->vert + 3 * f[1], m->vert + 3 * f[0]);
    ss_v3_sub(e2, m->vert + 3 * f[2], m->vert + 3 * f[0]);
    ss_v3_cross(n, e1, e2);
    for (int k = 0; k < 3; k++) ss_v3_add(m->normal + 3 * f[k], m->normal + 3 * f[k], n);
  }
  for (int v = 0; v < m->nvert; v++) ss_v3_normalize(m->normal + 3 * v);
}

static void bounds(ssMesh *m)
{
  for (int a = 0; a < 3; a++) {
    m->lo[a] = INFINITY;
    m->hi[a] = -INFINITY;
  }
  /* only vertices that triangles use */
  for (int i = 0; i < 3 * m->ntri; i++) {
    const double *p = m->vert + 3 * m->tri[i];
    for (int a = 0; a < 3; a++) {
      if (p[a] < m->lo[a]) m->lo[a] = p[a];
      if (p[a] > m->hi[a]) m->hi[a] = p[a];
    }
  }
}

/* ---------------------------------------------------------------------- */
/* footprint points                                                        */

/* vertex slots that triangles use, at most, for the footprint points to be
 * looked for: a mesh with more has, unless its positions are split into
 * more than 64 vertices each (per-face normals split them into 3 to 8
 * commonly, an STL's into about 6), more than SS_MESH_HULL_MAX distinct
 * positions anyway; it keeps the bounding box's footprint without a sort
 * of its millions of vertices at load */
#define HULL_SLOTS_MAX (64L * SS_MESH_HULL_MAX)

typedef struct keyVert {
  const double *p; /* position */
  int v;           /* vertex index (breaks ties) */
} keyVert;

static int kv_same(const keyVert *a, const keyVert *b)
{
  return a->p[0] == b->p[0] && a->p[1] == b->p[1] && a->p[2] == b->p[2];
}

/* total order: position x, y, z, then vertex index, so that each
 * position's first vertex leads its run (deterministic whatever qsort) */
static int kv_cmp(const void *pa, const void *pb)
{
  const keyVert *a = pa, *b = pb;
  for (int k = 0; k < 3; k++) {
    if (a->p[k] < b->p[k]) return -1;
    if (a->p[k] > b->p[k]) return 1;
  }
  return (a->v > b->v) - (a->v < b->v);
}

/* The distinct positions among the vertices v with used[v] != 0 (every
 * vertex where used is NULL; n of them): id[v] the position's rank in
 * kv_cmp's order (where id is not NULL) and bit 2 set in lead[v] on each
 * position's first vertex (where lead is not NULL).  Returns the number of
 * positions, -1 when out of memory. */
static int distinct_positions(const ssMesh *m, const unsigned char *used, long n, int *id,
                              unsigned char *lead)
{
  keyVert *kv = malloc((size_t)(n > 0 ? n : 1) * sizeof *kv);
  if (!kv) return -1;
  int k = 0;
  for (int v = 0; v < m->nvert; v++)
    if (!used || used[v]) kv[k++] = (keyVert){m->vert + 3 * v, v};
  qsort(kv, (size_t)k, sizeof *kv, kv_cmp);
  int d = -1;
  for (int i = 0; i < k; i++) {
    if (i == 0 || !kv_same(&kv[i], &kv[i - 1])) {
      d++;
      if (lead) lead[kv[i].v] |= 2;
    }
    if (id) id[kv[i].v] = d;
  }
  free(kv);
  return d + 1;
}

/* The footprint points (ssMesh.hull; after bounds): every position that
 * triangles use, once (its first vertex), in vertex order, which keeps a
 * ring's points in runs for the footprint's sort (ss_points_footprint).
 * Every vertex of the 3-D convex hull is among them, hence every vertex
 * of any projection's hull; the points strictly inside that hull are not
 * dropped (that would take a 3-D hull here): a non-convex mesh keeps them
 * all and may exceed the cap.  Returns 0 when out of memory. */
static int hull_points(ssMesh *m)
{
  m->nhull = 0;
  free(m->hull);
  m->hull = NULL;
  /* used[v]: bit 1 when a triangle uses v, bit 2 when v is also its
   * position's first vertex (distinct_positions) */
  unsigned char *used = calloc((size_t)m->nvert, 1);
  if (!used) return 0;
  for (long i = 0; i < 3L * m->ntri; i++) used[m->tri[i]] = 1;
  long nused = 0;
  for (int v = 0; v < m->nvert; v++) nused += used[v];
  if (nused > HULL_SLOTS_MAX) {
    free(used);
    return 1;
  }
  int distinct = distinct_positions(m, used, nused, NULL, used);
  if (distinct < 0) {
    free(used);
    return 0;
  }
  if (distinct > SS_MESH_HULL_MAX) {
    free(used);
    return 1;
  }
  m->hull = malloc((size_t)distinct * 3 * sizeof *m->hull);
  if (!m->hull) {
    free(used);
    return 0;
  }
  double c[3];
  for (int k = 0; k < 3; k++) c[k] = 0.5 * (m->hi[k] + m->lo[k]);
  for (int v = 0; v < m->nvert; v++)
    if (used[v] & 2) {
      double *h = m->hull + 3 * m->nhull++;
      for (int k = 0; k < 3; k++) h[k] = m->vert[3 * v + k] - c[k];
    }
  free(used);
  return 1;
}

static ssMesh *mesh_alloc(int nvert, int ntri)
{
  ssMesh *m = calloc(1, sizeof *m);
  if (!m) return NULL;
  m->nvert = nvert;
  m->ntri = ntri;
  m->vert = malloc((size_t)nvert * 3 * sizeof *m->vert);
  m->normal = malloc((size_t)nvert * 3 * sizeof *m->normal);
  m->tri = malloc((size_t)ntri * 3 * sizeof *m->tri);
  if (!m->vert || !m->normal || !m->tri) {
    ss_mesh_free(m);
    return NULL;
  }
  return m;
}

ssStatus ss_mesh_from_arrays(const double *vert, int nvert, const int *tri,
                             int ntri, ssMesh **out, ssError *err)
{
  const char *what = "mesh from arrays";
  if (!out)
    return ss_error_set(err, SS_ERR_VALUE, what, 0, "NULL output argument");
  *out = NULL;
  if (nvert < 3 || ntri < 1 || !vert || !tri)
    return ss_error_set(err, SS_ERR_VALUE, what, 0,
                        "a mesh needs at least 3 vertices and 1 triangle "
                        "(got %d vertices, %d triangles)", nvert, ntri);
  if (ntri > MESH_MAX_TRIS || nvert > INT_MAX / 3)
    return ss_error_set(err, SS_ERR_VALUE, what, 0,
                        "%d triangles, %d vertices: at most %ld triangles",
                        ntri, nvert, MESH_MAX_TRIS);
  for (long i = 0; i < 3L * nvert; i++)
    if (!isfinite(vert[i]))
      return ss_error_set(err, SS_ERR_VALUE, what, 0,
                          "vertex %ld has a non-finite coordinate", i / 3);
  for (long i = 0; i < 3L * ntri; i++)
    if (tri[i] < 0 || tri[i] >= nvert)
      return ss_error_set(err, SS_ERR_VALUE, what, 0,
                          "triangle %ld uses vertex %d (vertices are 0..%d)",
                          i / 3, tri[i], nvert - 1);
  ssMesh *m = mesh_alloc(nvert, ntri);
  if (!m)
    return ss_error_set(err, SS_ERR_NOMEM, what, 0, "out of memory");
  memcpy(m->vert, vert, (size_t)nvert * 3 * sizeof *vert);
  memcpy(m->tri, tri, (size_t)ntri * 3 * sizeof *tri);
  vertex_normals(m);
  bounds(m);
  if (!hull_points(m)) {
    ss_mesh_free(m);
    return ss_error_set(err, SS_ERR_NOMEM, what, 0, "out of memory");
  }
  ssStatus st = build_bvh(m, err, what);
  if (st) {
    ss_mesh_free(m);
    return st;
  }
  *out = m;
  return SS_OK;
}

ssStatus ss_mesh_load(const char *path, const double scale[3], ssMesh **out,
                      ssError *err)
{
  if (!out)
    return ss_error_set(err, SS_ERR_VALUE, path ? path : "", 0,
                        "ss_mesh_load: NULL output argument");
  *out = NULL;
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "no mesh file name given");
  double s[3] = {1, 1, 1};
  if (scale) memcpy(s, scale, sizeof s);
  for (int a = 0; a < 3; a++)
    if (!isfinite(s[a]) || s[a] == 0)
      return ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "mesh scale %g %g %g: each value must be finite "
                          "and non-zero", s[0], s[1], s[2]);
  /* a clear message for the common failures before assimp's own */
  struct stat sb;
  if (stat(path, &sb) != 0)
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot open mesh: %s",
                        strerror(errno));
  if (!S_ISREG(sb.st_mode))
    return ss_error_set(err, SS_ERR_IO, path, 0,
                        "cannot read mesh: not a regular file");
  if ((long long)sb.st_size > MESH_MAX_BYTES)
    return ss_error_set(err, SS_ERR_IO, path, 0,
                        "mesh file is %lld bytes, larger than the limit of "
                        "%lld", (long long)sb.st_size, MESH_MAX_BYTES);
  if (access(path, R_OK) != 0)
    return ss_error_set(err, SS_ERR_IO, path, 0, "cannot read mesh: %s",
                        strerror(errno));

  /* no logger is attached: assimp prints nothing; it reads files through
   * io_open only */
  struct aiFileIO io = {io_open, io_close, NULL};
  const struct aiScene *sc = aiImportFileEx(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                aiProcess_GenSmoothNormals | aiProcess_PreTransformVertices |
                aiProcess_ValidateDataStructure, &io);
  if (!sc) {
    const char *why = aiGetErrorString();
    return ss_error_set(err, SS_ERR_PARSE, path, 0, "cannot load mesh: %s",
                        why && *why ? why : "assimp gave no reason");
  }
  ssStatus st = SS_OK;
  if (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE)
    st = ss_error_set(err, SS_ERR_PARSE, path, 0,
                      "cannot load mesh: the file describes an incomplete "
                      "scene (no geometry)");
  /* count what we keep: triangles (points and lines are dropped) */
  long long nv = 0, nt = 0;
  for (unsigned i = 0; !st && i < sc->mNumMeshes; i++) {
    const struct aiMesh *am = sc->mMeshes[i];
    nv += am->mNumVertices;
    for (unsigned f = 0; f < am->mNumFaces; f++)
      if (am->mFaces[f].mNumIndices == 3) nt++;
  }
  if (!st && nt == 0)
    st = ss_error_set(err, SS_ERR_VALUE, path, 0,
                      "mesh has no triangles");
  if (!st && (nt > MESH_MAX_TRIS || nv > INT_MAX / 3))
    st = ss_error_set(err, SS_ERR_VALUE, path, 0,
                      "mesh has %lld triangles and %lld vertices; at most %ld "
                      "triangles are allowed", nt, nv, MESH_MAX_TRIS);
  ssMesh *m = NULL;
  if (!st && !(m = mesh_alloc((int)nv, (int)nt)))
    st = ss_error_set(err, SS_ERR_NOMEM, path, 0,
                      "out of memory for %lld triangles", nt);
  if (!st) {
    /* a mirroring scale turns the winding; swap two corners to keep it
     * counter-clockwise seen from outside */
    int flip = (s[0] < 0) ^ (s[1] < 0) ^ (s[2] < 0);
    int vbase = 0, t = 0, need_normals = 0;
    for (unsigned i = 0; i < sc->mNumMeshes && !st; i++) {
      const struct aiMesh *am = sc->mMeshes[i];
      for (unsigned v = 0; v < am->mNumVertices; v++) {
        double *p = m->vert + 3 * (vbase + (int)v);
        double *n = m->normal + 3 * (vbase + (int)v);
        p[0] = s[0] * (double)am->mVertices[v].x;
        p[1] = s[1] * (double)am->mVertices[v].y;
        p[2] = s[2] * (double)am->mVertices[v].z;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
          st = ss_error_set(err, SS_ERR_VALUE, path, 0,
                            "mesh vertex %u of mesh %u is not finite", v, i);
          break;
        }
        if (am->mNormals) {
          /* normals transform with the inverse transpose of the scale */
          n[0] = (double)am->mNormals[v].x / s[0];
          n[1] = (double)am->mNormals[v].y / s[1];
          n[2] = (double)am->mNormals[v].z / s[2];
          if (!(ss_v3_normalize(n) > 0) || !isfinite(n[0])) need_normals = 1;
        } else {
          need_normals = 1;
        }
      }
      for (unsigned f = 0; f < am->mNumFaces && !st; f++) {
        const struct aiFace *fc = &am->mFaces[f];
        if (fc->mNumIndices != 3) continue;
        int *tr = m->tri + 3 * t++;
        tr[0] = vbase + (int)fc->mIndices[0];
        tr[1] = vbase + (int)fc->mIndices[flip ? 2 : 1];
        tr[2] = vbase + (int)fc->mIndices[flip ? 1 : 2];
      }
      vbase += (int)am->mNumVertices;
    }
    if (!st && need_normals) vertex_normals(m);
  }
  aiReleaseImport(sc);
  if (!st) {
    bounds(m);
    if (!hull_points(m))
      st = ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory for the footprint points of %lld "
                        "vertices", nv);
  }
  if (!st) st = build_bvh(m, err, path);
  if (st) {
    ss_mesh_free(m);
    return st;
  }
  *out = m;
  return SS_OK;
}

/* ---------------------------------------------------------------------- */
/* ray casts                                                               */

typedef struct rayPre {
  double o[3], d[3];
  int kx, ky, kz;
  double sx, sy, sz;   /* shear */
  double inv[3];       /* 1 / d per axis; 0 where the ray is parallel */
  int par[3];          /* 1: d[a] is 0 (or so small 1/d overflows) */
} rayPre;

/* a b - c d with the exact sign: the plain difference when it is clearly
 * away from zero, else Kahan's fma form (relative error <= 2 ulp, so its
 * sign and its zero are exact).  Antisymmetric in (a b) <-> (c d), so an
 * edge seen from its two triangles gets opposite signs. */
static double diff_prod(double a, double b, double c, double d)
{
  double p = a * b, q = c * d, r = p - q;
  /* |error of r| <= 2u (|p| + |q|) with u = 2^-53; 4u leaves a margin */
  if (fabs(r) > 4.5e-16 * (fabs(p) + fabs(q))) return r;
  double e = fma(-c, d, q);  /* q - c d, exact */
  double f = fma(a, b, -q);  /* a b - q, one rounding */
  return f + e;
}

/* Ray / triangle: 1 and *t when hit at 0 <= t < tmax. */
static int ray_tri(const rayPre *r, const double *v0, const double *v1,
                   const double *v2, double tmax, double *t)
{
  int kx = r->kx, ky = r->ky, kz = r->kz;
  double A[3], B[3], C[3];
  ss_v3_sub(A, v0, r->o);
  ss_v3_sub(B, v1, r->o);
  ss_v3_sub(C, v2, r->o);
  double ax = A[kx] - r->sx * A[kz], ay = A[ky] - r->sy * A[kz];
  double bx = B[kx] - r->sx * B[kz], by = B[ky] - r->sy * B[kz];
  double cx = C[kx] - r->sx * C[kz], cy = C[ky] - r->sy * C[kz];
  double U = diff_prod(cx, by, cy, bx);
  double V = diff_prod(ax, cy, ay, cx);
  double W = diff_prod(bx, ay, by, ax);
  if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0)) return 0;
  double det = U + V + W;
  if (det == 0) return 0;
  double az = r->sz * A[kz], bz = r->sz * B[kz], cz = r->sz * C[kz];
  double T = U * az + V * bz + W * cz;
  double tt = T / det;
  if (!(tt >= 0) || !(tt < tmax)) return 0;
  *t = tt + 0.0; /* -0 -> +0 */
  return 1;
}

/* Entry parameter of the ray into a box, if it enters before tmax.  The
 * slab distances are widened by a few ulps so that a triangle lying on a
 * box face is never culled by rounding. */
static int ray_box(const rayPre *r, const double *box, double tmax,
                   double *tnear)
{
  double t0 = 0, t1 = tmax;
  for (int a = 0; a < 3; a++) {
    if (r->par[a]) {
      if (r->o[a] < box[a] || r->o[a] > box[3 + a]) return 0;
      continue;
    }
    double ta = (box[a] - r->o[a]) * r->inv[a];
    double tb = (box[3 + a] - r->o[a]) * r->inv[a];
    if (ta > tb) {
      double x = ta;
      ta = tb;
      tb = x;
    }
    ta -= fabs(ta) * 1e-15;
    tb += fabs(tb) * 1e-15;
    if (ta > t0) t0 = ta;
    if (tb < t1) t1 = tb;
    if (t0 > t1) return 0;
  }
  *tnear = t0;
  return 1;
}

int ss_mesh_raycast(const ssMesh *m, const double o[3], const double d[3],
                    double *t)
{
  if (!m || m->ntri <= 0 || m->nnode <= 0 || !o || !d) return 0;
  rayPre r;
  for (int a = 0; a < 3; a++) {
    if (!isfinite(o[a]) || !isfinite(d[a])) return 0;
    r.o[a] = o[a];
    r.d[a] = d[a];
  }
  /* shear frame: z along the largest direction component */
  int kz = 0;
  for (int a = 1; a < 3; a++)
    if (fabs(d[a]) > fabs(d[kz])) kz = a;
  if (d[kz] == 0) return 0;
  int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
  if (d[kz] < 0) {
    int x = kx;
    kx = ky;
    ky = x;
  }
  r.kx = kx;
  r.ky = ky;
  r.kz = kz;
  r.sx = d[kx] / d[kz];
  r.sy = d[ky] / d[kz];
  r.sz = 1.0 / d[kz];
  for (int a = 0; a < 3; a++) {
    double inv = d[a] != 0 ? 1.0 / d[a] : 0;
    r.par[a] = d[a] == 0 || !isfinite(inv);
    r.inv[a] = r.par[a] ? 0 : inv;
  }

  double best = INFINITY;
  int hit = 0;
  int stack[STACK_MAX];
  double snear[STACK_MAX]; /* entry distance of each stacked node's box */
  int top = 0;
  double tn;
  if (!ray_box(&r, m->bvh_box, best, &tn)) return 0;
  stack[top] = 0;
  snear[top++] = tn;
  while (top) {
    --top;
    int k = stack[top];
    /* a box entered after the best hit so far cannot hold a nearer one */
    if (snear[top] > best) continue;
    int c0 = m->bvh_child[2 * k], c1 = m->bvh_child[2 * k + 1];
    if (c0 < 0) {
      int first = -1 - c0;
      for (int i = first; i < first + c1; i++) {
        const int *f = m->tri + 3 * m->bvh_tri[i];
        double th;
        if (ray_tri(&r, m->vert + 3 * f[0], m->vert + 3 * f[1],
                    m->vert + 3 * f[2], best, &th)) {
          best = th;
          hit = 1;
        }
      }
      continue;
    }
    /* visit the nearer child first */
    double t0, t1;
    int h0 = ray_box(&r, m->bvh_box + 6 * c0, best, &t0);
    int h1 = ray_box(&r, m->bvh_box + 6 * c1, best, &t1);
    if (h0 && h1 && top + 2 <= STACK_MAX) {
      int nearc = t0 <= t1 ? c0 : c1, farc = t0 <= t1 ? c1 : c0;
      stack[top] = farc;
      snear[top++] = t0 <= t1 ? t1 : t0;
      stack[top] = nearc;
      snear[top++] = t0 <= t1 ? t0 : t1;
    } else if (h0 && top < STACK_MAX) {
      stack[top] = c0;
      snear[top++] = t0;
    } else if (h1 && top < STACK_MAX) {
      stack[top] = c1;
      snear[top++] = t1;
    }
  }
  if (hit && t) *t = best;
  return hit;
}

/* ---------------------------------------------------------------------- */
/* mass properties                                                         */

void ss_mesh_mass_properties(const ssMesh *m, double *volume,
                             double centroid[3], double inertia[9])
{
  double V = 0, S1[3] = {0, 0, 0}, S2[9] = {0};
  double ref[3] = {0, 0, 0};
  if (m && m->ntri > 0)
    for (int a = 0; a < 3; a++) ref[a] = 0.5 * (m->lo[a] + m->hi[a]);
  /* signed tetrahedra (ref, a, b, c): with ref at the origin,
   * vol = D/6, int x = D/24 sum, int x_i x_j = D/120 (sum_k v_ki v_kj +
   * s_i s_j), D = a . (b x c), s = a + b + c */
  for (int t = 0; m && t < m->ntri; t++) {
    const int *f = m->tri + 3 * t;
    double a[3], b[3], c[3], bc[3], s[3];
    ss_v3_sub(a, m->vert + 3 * f[0], ref);
    ss_v3_sub(b, m->vert + 3 * f[1], ref);
    ss_v3_sub(c, m->vert + 3 * f[2], ref);
    ss_v3_cross(bc, b, c);
    double D = ss_v3_dot(a, bc);
    V += D / 6;
    for (int i = 0; i < 3; i++) {
      s[i] = a[i] + b[i] + c[i];
      S1[i] += D / 24 * s[i];
    }
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        S2[3 * i + j] += D / 120 *
                         (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]);
  }
  /* a mesh wound inside out integrates to minus the solid */
  if (V < 0) {
    V = -V;
    for (int i = 0; i < 3; i++) S1[i] = -S1[i];
    for (int i = 0; i < 9; i++) S2[i] = -S2[i];
  }
  double g[3] = {0, 0, 0};
  if (V > 0)
    for (int i = 0; i < 3; i++) g[i] = S1[i] / V;
  double C[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[3 * i + j] = V > 0 ? S2[3 * i + j] - V * g[i] * g[j] : 0;
  double tr = C[0] + C[4] + C[8];
  if (volume) *volume = V;
  if (centroid)
    for (int i = 0; i < 3; i++) centroid[i] = ref[i] + g[i];
  if (inertia)
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        inertia[3 * i + j] = (i == j ? tr : 0) - C[3 * i + j];
}

/* an edge between two positions (ids into the distinct positions), from
 * lo to hi; dir +1 when a triangle runs it lo -> hi, -1 hi -> lo */
typedef struct edgeKey {
  int lo, hi, dir;
} edgeKey;

static int edge_cmp(const void *pa, const void *pb)
{
  const edgeKey *a = pa, *b = pb;
  if (a->lo != b->lo) return (a->lo > b->lo) - (a->lo < b->lo);
  if (a->hi != b->hi) return (a->hi > b->hi) - (a->hi < b->hi);
  return (a->dir > b->dir) - (a->dir < b->dir);
}

int ss_mesh_closed(const ssMesh *m)
{
  if (!m || m->ntri <= 0 || m->nvert <= 0) return 0;
  /* positions, not vertex indices: a file that splits its vertices per
   * face (for flat shading) is closed all the same */
  int *id = malloc((size_t)m->nvert * sizeof *id);
  edgeKey *ek = malloc((size_t)m->ntri * 3 * sizeof *ek);
  int closed = -1;
  if (!id || !ek || distinct_positions(m, NULL, m->nvert, id, NULL) < 0) goto done;
  long ne = 0;
  for (int t = 0; t < m->ntri; t++)
    for (int k = 0; k < 3; k++) {
      int a = id[m->tri[3 * t + k]], b = id[m->tri[3 * t + (k + 1) % 3]];
      if (a == b) continue; /* a degenerate triangle's collapsed edge */
      ek[ne++] = a < b ? (edgeKey){a, b, 1} : (edgeKey){b, a, -1};
    }
  qsort(ek, (size_t)ne, sizeof *ek, edge_cmp);
  /* closed: every edge run as often one way as the other (a consistently
   * wound surface without border; a mesh wound inside out passes too) */
  closed = ne > 0;
  for (long i = 0; i < ne && closed;) {
    long j = i;
    int sum = 0;
    while (j < ne && ek[j].lo == ek[i].lo && ek[j].hi == ek[i].hi) sum += ek[j++].dir;
    if (sum != 0) closed = 0;
    i = j;
  }
done:
  free(id);
  free(ek);
  return closed;
}

void ss_mesh_surface_centroid(const ssMesh *m, double c[3])
{
  double A = 0, S[3] = {0, 0, 0}, ref[3] = {0, 0, 0};
  if (m && m->ntri > 0)
    for (int k = 0; k < 3; k++) ref[k] = 0.5 * (m->lo[k] + m->hi[k]);
  for (int t = 0; m && t < m->ntri; t++) {
    const int *f = m->tri + 3 * t;
    double a[3], b[3], e[3], n[3];
    ss_v3_sub(a, m->vert + 3 * f[1], m->vert + 3 * f[0]);
    ss_v3_sub(b, m->vert + 3 * f[2], m->vert + 3 * f[0]);
    ss_v3_cross(n, a, b);
    double w = 0.5 * ss_v3_norm(n);
    A += w;
    for (int k = 0; k < 3; k++) {
      e[k] = (m->vert[3 * f[0] + k] + m->vert[3 * f[1] + k] +
              m->vert[3 * f[2] + k]) / 3 - ref[k];
      S[k] += w * e[k];
    }
  }
  for (int k = 0; k < 3; k++) c[k] = ref[k] + (A > 0 ? S[k] / A : 0);
}
