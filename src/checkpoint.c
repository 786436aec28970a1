/* checkpoint.c -- binary save and restore of a world's state (DESIGN 5).
 *
 * A checkpoint holds everything in an ssData that the next step reads:
 * time and step count, generalized positions and velocities, which systems
 * are still in the world, controller targets, bed poses, the three soil
 * arrays, the list of loaded vertices, the solver's warm-start cache, the
 * solver configuration, the Newton phase's last answers (its start) and
 * the last step's statistics.  Restoring it and
 * stepping gives bit-identical results to stepping on from the moment it was
 * written.  It does not hold the model: it is restored into a data made for
 * the same world, which a fingerprint of the model checks.
 *
 * Format, version 5 (versions 1, before the warm-start cache kept its
 * rates, 2, before its entries said whether their collider crept, 3,
 * before the Newton phase's start was kept, and 4, before rigid contacts
 * were warm started, are refused: they cannot replay this build's
 * steps).  Every integer is little-endian; every double is its
 * IEEE-754 bit pattern as a little-endian 64-bit integer (bit-exact).
 *
 *   header (32 bytes; the same layout in every version)
 *     0   8  magic "SOILCKPT"
 *     8   4  u32 format version (5)
 *    12   4  u32 header size (32)
 *    16   8  u64 file size in bytes, trailer included
 *    24   4  u32 number of sections
 *    28   4  u32 CRC-32 of bytes 0-27 (so that a damaged size field is
 *              told from a truncated file)
 *   sections, each a 4-byte ASCII tag, a u32 reserved word (0), the u64
 *   payload size and the payload; written in this order, read in any order
 *   but each exactly once:
 *     MODL  the model's fingerprint: u32 count of counts, the counts (u32
 *           each: nq nv nsys nbody ngeom nhfield nhfielddata npd neq nspring
 *           nplane nxforce nmaterial npair nmesh), u32 count of hashes, the
 *           hashes (u64 FNV-1a each, one per group of model arrays, see
 *           fingerprint(); the rigid materials as the friction and
 *           restitution each collider meets on each rigid support, not
 *           by their indices, which earlier builds hashed and a restore
 *           still accepts, and as the table of those the colliders'
 *           materials meet on each other, which builds before contacts
 *           between bodies left out and a restore still accepts), u32
 *           length and bytes of the model's source path
 *     OPTS  ssOption: timestep, gravity x y z (f64), solver_max_sweeps (i32),
 *           solver_tolerance, scalar_tolerance (f64), terrain_warm_start
 *           (i32), contact_margin, rigid_erp (f64)
 *     CLCK  time (f64), step (i64), closure_error (f64); time and step
 *           as <clock> takes them (finite and >= 0 s; 0 to LONG_MAX)
 *     QPOS  nq f64          QVEL  nv f64          SYSA  nsys u8
 *     PDTG  npd x 2 f64     HPOS  nhfield x 3 f64 HQUA  nhfield x 4 f64
 *     SINK, PLAS, SHEA      nhfielddata f64 each (sinkage, plastic, shear)
 *     LOAD  nsoil_loaded i32, strictly ascending vertex indices; every
 *           vertex with sinkage above its plastic sinkage or with shear
 *           is among them
 *     WARM  nwarm entries of 60 bytes: vertex (i32), geom (i32), creep
 *           (i32: 0 or 1, only for soil entries), traction (3 f64), rate
 *           (3 f64), in the solver's sort order.  Soil points: geom and
 *           soil vertex; rigid contacts: geom and a negative key
 *           (solver.h, ss_rigid_feature: a rigid height map or ground
 *           plane and the collider's candidate point), a positive normal
 *           force and rate 0; joint rows: geom -2 (PD) or -3 (limit) and
 *           2 dof + side
 *     NEWT  the Newton phase's last two answers (ssNewtonRecord, the later
 *           first), each: step (i64, -1: none), key (u64, 0 for none),
 *           n (i32, 0 for none) and n f64 (c, each within 1e100)
 *     STAT  soil_contacts, soil_loaded (i32), soil_contact_area,
 *           soil_normal_force (f64), rigid_contacts, sweeps (i32), residual
 *           (f64), converged (i32); the stage wall times are not saved, so
 *           a checkpoint of a given state is the same bytes run to run
 *   trailer (8 bytes): "CRC " and the u32 CRC-32 (IEEE 802.3, as zlib's
 *   crc32) of every byte before the CRC itself.
 *
 * Reading checks, in order: signature, header checksum, version, file
 * size, file checksum, section table, model fingerprint, solver
 * configuration, then every value (finite, soil state consistent, indices
 * in range, caches sorted).  Sizes read from the file are compared with the
 * model's counts before anything is allocated, and the data is written only
 * once everything has been read into temporaries (and the data's caches
 * have room), so a refused file leaves the data as it was.  The contacts of
 * the last step are not saved: the next step rebuilds them. */
#include "soilsim.h"
#include "dynamics.h"
#include "mesh.h"
#include "scene.h"
#include "solver.h"
#include "ss_math.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define CKPT_MAGIC "SOILCKPT"
#define CKPT_VERSION 5u
#define CKPT_HEADER 32u
#define CKPT_SECTION_HEAD 16u
#define CKPT_TRAILER 8u
#define CKPT_WARM_BYTES 60u
#define CKPT_SOURCE_MAX 4096u
/* largest magnitude of a Newton record's value (NEWT): far above what a
 * step writes, far enough below DBL_MAX that the next step's prediction
 * (2 c_1 - c_2 added to the free velocities) and the sums of its squares
 * stay finite */
#define CKPT_NEWT_MAX 1e100

/* ---------------------------------------------------------------------- */
/* checksum and hashes                                                     */

static uint32_t crc_table[256];
static int crc_ready;

static void crc_init(void)
{
  for (uint32_t n = 0; n < 256; n++) {
    uint32_t c = n;
    for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    crc_table[n] = c;
  }
  crc_ready = 1;
}

static uint32_t crc32_bytes(const unsigned char *p, size_t n)
{
  if (!crc_ready) crc_init();
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; i++) c = crc_table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

/* 64-bit FNV-1a over the little-endian bytes of each value */
typedef struct Hash {
  uint64_t h;
} Hash;

static void hash_init(Hash *h) { h->h = 0xcbf29ce484222325ull; }

static void hash_u64(Hash *h, uint64_t v)
{
  for (int k = 0; k < 8; k++) {
    h->h ^= (v >> (8 * k)) & 0xFF;
    h->h *= 0x100000001b3ull;
  }
}

static void hash_ints(Hash *h, const int *v, long n)
{
  hash_u64(h, (uint64_t)n);
  for (long i = 0; v && i < n; i++) hash_u64(h, (uint64_t)(int64_t)v[i]);
}

static void hash_doubles(Hash *h, const double *v, long n)
{
  hash_u64(h, (uint64_t)n);
  for (long i = 0; v && i < n; i++) {
    uint64_t u;
    memcpy(&u, v + i, 8);
    hash_u64(h, u);
  }
}

/* ---------------------------------------------------------------------- */
/* the model's fingerprint                                                 */

enum { NCOUNT = 15, NHASH = 7 };

/* the sections, in the order they are written */
enum {
  S_MODL, S_OPTS, S_CLCK, S_QPOS, S_QVEL, S_SYSA, S_PDTG, S_HPOS, S_HQUA,
  S_SINK, S_PLAS, S_SHEA, S_LOAD, S_WARM, S_NEWT, S_STAT, NTAG
};

static const char section_tag[NTAG][5] = {
  "MODL", "OPTS", "CLCK", "QPOS", "QVEL", "SYSA", "PDTG", "HPOS", "HQUA",
  "SINK", "PLAS", "SHEA", "LOAD", "WARM", "NEWT", "STAT"};

static const char *const count_name[NCOUNT] = {
  "generalized coordinates (nq)", "generalized velocities (nv)",
  "systems (bodies and articulated systems)", "rigid bodies and links",
  "colliders", "height maps", "height-map vertices", "PD controllers",
  "loop closures", "spring-dampers", "ground planes", "external forces",
  "rigid materials", "material pairs", "meshes"};

static const char *const hash_name[NHASH] = {
  "time step and gravity", "systems and joints", "masses and inertias",
  "colliders", "height maps and soil materials",
  "loop closures, spring-dampers and PD gains",
  "ground planes, contact materials and external forces"};

typedef struct Fingerprint {
  uint32_t count[NCOUNT];
  uint64_t hash[NHASH];
} Fingerprint;

/* The contact material each collider meets on each rigid support (the
 * rigid height maps, then the ground planes): the pair's friction and
 * restitution, which is all a step reads of the materials (terrain.c,
 * rigid_contacts).  Material indices are only the order in which a file
 * named the materials, and an export names them in another order (its
 * ground planes before its bodies), so they are not hashed. */
static void hash_pair(Hash *h, const ssModel *m, int a, int b)
{
  const ssMaterialPair *p = ss_model_pair(m, a, b);
  const double v[3] = {p->friction, p->restitution, p->restitution_threshold};
  hash_doubles(h, v, 3);
}

/* with colliders: also the material each collider meets on each other
 * collider (contacts between bodies), as a table over the colliders'
 * materials numbered by the first collider that names each (an order an
 * export keeps); 0 for the builds before contacts between bodies, which
 * left it out (a checkpoint they wrote still restores) */
static int hash_contact_materials(Hash *h, const ssModel *m, int colliders)
{
  for (int g = 0; g < m->ngeom; g++)
    for (int k = 0; k < m->nhfield + m->nplane; k++) {
      if (k < m->nhfield && m->hfield_soil[k]) continue;
      int mat = k < m->nhfield ? m->hfield_material[k] : m->plane_material[k - m->nhfield];
      hash_pair(h, m, m->geom_material[g], mat);
    }
  if (!colliders || m->ngeom == 0) return 1;
  /* the colliders' distinct materials in the order of their first use */
  int *used = malloc((size_t)m->ngeom * sizeof(int)), nu = 0;
  if (!used) return 0;
  for (int g = 0; g < m->ngeom; g++) {
    int mat = m->geom_material[g], seen = 0;
    for (int k = 0; k < nu && !seen; k++) seen = used[k] == mat;
    if (!seen) used[nu++] = mat;
  }
  for (int a = 0; a < nu; a++)
    for (int b = a; b < nu; b++) hash_pair(h, m, used[a], used[b]);
  free(used);
  return 1;
}

/* Everything in the model that changes what a step computes, grouped so
 * that a mismatch can say what differs.  Initial states (qpos0, qvel0,
 * pd_target0, bed poses) are left out: a checkpoint replaces them.  Names,
 * colours and file paths are left out: they do not change the dynamics;
 * so is the numbering of the rigid materials (hash_contact_materials).
 * legacy (FP_LEGACY): the fingerprint of earlier builds, which hashed the
 * material indices and the pair table as numbered; FP_NO_BETWEEN: of the
 * builds before contacts between bodies, which left out the materials
 * colliders meet on each other (a checkpoint either wrote is still
 * compared with it, so it restores into the world it was written for).
 * Returns 0 out of memory. */
enum { FP_NOW, FP_LEGACY, FP_NO_BETWEEN };

static int fingerprint(const ssModel *m, Fingerprint *f, int variant)
{
  const int legacy = variant == FP_LEGACY, no_between = variant == FP_NO_BETWEEN;
  const int c[NCOUNT] = {m->nq, m->nv, m->nsys, m->nbody, m->ngeom,
                         m->nhfield, m->nhfielddata, m->npd, m->neq,
                         m->nspring, m->nplane, m->nxforce, m->nmaterial,
                         m->npair, m->nmesh};
  for (int k = 0; k < NCOUNT; k++) f->count[k] = (uint32_t)c[k];
  Hash h;

  hash_init(&h);
  hash_doubles(&h, &m->opt.timestep, 1);
  hash_doubles(&h, m->opt.gravity, 3);
  f->hash[0] = h.h;

  hash_init(&h);
  hash_ints(&h, m->sys_type, m->nsys);
  hash_ints(&h, m->sys_qadr, m->nsys);
  hash_ints(&h, m->sys_nq, m->nsys);
  hash_ints(&h, m->sys_vadr, m->nsys);
  hash_ints(&h, m->sys_nv, m->nsys);
  hash_ints(&h, m->sys_bodyadr, m->nsys);
  hash_ints(&h, m->sys_nbody, m->nsys);
  hash_ints(&h, m->sys_fixed, m->nsys);
  hash_ints(&h, m->body_sys, m->nbody);
  hash_ints(&h, m->body_parent, m->nbody);
  hash_ints(&h, m->body_jnttype, m->nbody);
  /* a floating root's joint frame is only where the scene placed it (qpos
   * holds its pose), and an export places it elsewhere: left out */
  for (int b = 0; b < m->nbody; b++) {
    int placement = m->body_parent[b] < 0 && m->body_jnttype[b] == SS_JOINT_FLOATING;
    static const double none[7] = {0, 0, 0, 0, 0, 0, 0};
    hash_doubles(&h, placement ? none : m->body_jntpos + 3 * b, 3);
    hash_doubles(&h, placement ? none + 3 : m->body_jntquat + 4 * b, 4);
  }
  hash_doubles(&h, m->body_jntaxis, 3L * m->nbody);
  hash_ints(&h, m->body_qadr, m->nbody);
  hash_ints(&h, m->body_dofadr, m->nbody);
  hash_ints(&h, m->body_ndof, m->nbody);
  hash_doubles(&h, m->body_jntdamping, m->nbody);
  hash_doubles(&h, m->body_jntstiffness, m->nbody);
  hash_doubles(&h, m->body_jntref, m->nbody);
  hash_ints(&h, m->body_jntlimited, m->nbody);
  hash_doubles(&h, m->body_jntrange, 2L * m->nbody);
  f->hash[1] = h.h;

  hash_init(&h);
  hash_doubles(&h, m->body_mass, m->nbody);
  hash_doubles(&h, m->body_inertia, 9L * m->nbody);
  hash_doubles(&h, m->body_ipos, 3L * m->nbody);
  f->hash[2] = h.h;

  hash_init(&h);
  hash_ints(&h, m->geom_type, m->ngeom);
  hash_ints(&h, m->geom_body, m->ngeom);
  hash_doubles(&h, m->geom_size, 3L * m->ngeom);
  hash_doubles(&h, m->geom_pos, 3L * m->ngeom);
  hash_doubles(&h, m->geom_quat, 4L * m->ngeom);
  if (legacy) hash_ints(&h, m->geom_material, m->ngeom);
  hash_ints(&h, m->geom_mesh, m->ngeom);
  for (int g = 0; g < m->ngeom; g++) hash_u64(&h, (uint64_t)(m->geom_group[g] & 1));
  for (int k = 0; k < m->nmesh; k++) {
    const ssMesh *mesh = m->mesh[k];
    if (!mesh) {
      hash_u64(&h, 0);
      continue;
    }
    hash_doubles(&h, mesh->vert, 3L * mesh->nvert);
    hash_ints(&h, mesh->tri, 3L * mesh->ntri);
  }
  f->hash[3] = h.h;

  hash_init(&h);
  hash_ints(&h, m->hfield_nx, m->nhfield);
  hash_ints(&h, m->hfield_ny, m->nhfield);
  hash_doubles(&h, m->hfield_size, 2L * m->nhfield);
  hash_doubles(&h, m->hfield_center, 2L * m->nhfield);
  hash_ints(&h, m->hfield_adr, m->nhfield);
  if (legacy) hash_ints(&h, m->hfield_material, m->nhfield);
  hash_ints(&h, m->hfield_soil, m->nhfield);
  for (int k = 0; k < m->nhfield; k++) {
    const ssSoilMaterial *s = m->hfield_soilmat + k;
    const double v[8] = {s->bekker_kc, s->bekker_kphi, s->sinkage_exponent,
                         s->elastic_stiffness, s->damping, s->cohesion,
                         s->friction_coefficient, s->shear_displacement};
    hash_doubles(&h, v, 8);
  }
  hash_doubles(&h, m->hfield_data, m->nhfielddata);
  f->hash[4] = h.h;

  hash_init(&h);
  hash_ints(&h, m->eq_type, m->neq);
  hash_ints(&h, m->eq_sys, m->neq);
  hash_ints(&h, m->eq_body, 2L * m->neq);
  hash_doubles(&h, m->eq_anchor, 6L * m->neq);
  hash_doubles(&h, m->eq_data, 2L * m->neq);
  hash_ints(&h, m->spring_body, 2L * m->nspring);
  hash_doubles(&h, m->spring_anchor, 6L * m->nspring);
  hash_doubles(&h, m->spring_param, 3L * m->nspring);
  hash_ints(&h, m->pd_body, m->npd);
  hash_doubles(&h, m->pd_gain, 3L * m->npd);
  f->hash[5] = h.h;

  hash_init(&h);
  hash_doubles(&h, m->plane_height, m->nplane);
  if (legacy) {
    hash_ints(&h, m->plane_material, m->nplane);
    for (int k = -1; k < m->npair; k++) {
      const ssMaterialPair *p = k < 0 ? &m->material_default : m->pair + k;
      const int mi[2] = {p->mat1, p->mat2};
      const double v[3] = {p->friction, p->restitution, p->restitution_threshold};
      hash_ints(&h, mi, 2);
      hash_doubles(&h, v, 3);
    }
  } else if (!hash_contact_materials(&h, m, !no_between)) {
    return 0;
  }
  hash_ints(&h, m->xforce_body, m->nxforce);
  hash_doubles(&h, m->xforce_force, 3L * m->nxforce);
  hash_doubles(&h, m->xforce_torque, 3L * m->nxforce);
  hash_doubles(&h, m->xforce_time, 2L * m->nxforce);
  f->hash[6] = h.h;
  return 1;
}

/* ---------------------------------------------------------------------- */
/* writing                                                                 */

typedef struct Writer {
  unsigned char *p;
  size_t n, cap;
  int oom;
} Writer;

static void w_bytes(Writer *w, const void *src, size_t n)
{
  if (w->oom) return;
  if (w->n + n > w->cap) {
    size_t cap = w->cap ? w->cap : 4096;
    while (cap < w->n + n) cap *= 2;
    unsigned char *p = realloc(w->p, cap);
    if (!p) {
      w->oom = 1;
      return;
    }
    w->p = p;
    w->cap = cap;
  }
  memcpy(w->p + w->n, src, n);
  w->n += n;
}

static void put_le(unsigned char *b, uint64_t v, int n)
{
  for (int k = 0; k < n; k++) b[k] = (unsigned char)(v >> (8 * k));
}

static void w_u32(Writer *w, uint32_t v)
{
  unsigned char b[4];
  put_le(b, v, 4);
  w_bytes(w, b, 4);
}

static void w_u64(Writer *w, uint64_t v)
{
  unsigned char b[8];
  put_le(b, v, 8);
  w_bytes(w, b, 8);
}

static void w_i32(Writer *w, int v) { w_u32(w, (uint32_t)(int32_t)v); }

static void w_f64(Writer *w, double v)
{
  uint64_t u;
  memcpy(&u, &v, 8);
  w_u64(w, u);
}

static void w_f64s(Writer *w, const double *v, size_t n)
{
  for (size_t i = 0; i < n; i++) w_f64(w, v[i]);
}

/* A section: tag, reserved word, then its size, patched by section_end. */
static size_t section_begin(Writer *w, int tag)
{
  w_bytes(w, section_tag[tag], 4);
  w_u32(w, 0);
  w_u64(w, 0);
  return w->n;
}

static void section_end(Writer *w, size_t start)
{
  if (w->oom) return;
  put_le(w->p + start - 8, (uint64_t)(w->n - start), 8);
}

static void w_options(Writer *w, const ssOption *o)
{
  w_f64(w, o->timestep);
  w_f64s(w, o->gravity, 3);
  w_i32(w, o->solver_max_sweeps);
  w_f64(w, o->solver_tolerance);
  w_f64(w, o->scalar_tolerance);
  w_i32(w, o->terrain_warm_start);
  w_f64(w, o->contact_margin);
  w_f64(w, o->rigid_erp);
}

/* The first soil vertex that holds elastic sinkage or shear but is not in
 * the ascending list loaded (nloaded), or -1.  The next step recovers only
 * the listed ones (ss_terrain_update), so one left out would keep its
 * load for ever: the list a step leaves holds every vertex it loaded,
 * ss_soil_set_state and an export's reader rebuild it from the arrays,
 * and no checkpoint is written or read without it. */
static long unlisted_vertex(const ssModel *m, const double *sink, const double *plas,
                            const double *shea, const int *loaded, int nloaded)
{
  int at = 0;
  for (int k = 0; k < m->nhfielddata; k++) {
    while (at < nloaded && loaded[at] < k) at++;
    if ((sink[k] > plas[k] || shea[k] > 0) && !(at < nloaded && loaded[at] == k)) return k;
  }
  return -1;
}

static ssStatus check_pair(const ssModel *m, const ssData *d, const char *what,
                           const char *path, ssError *err)
{
  if (!m || !d)
    return ss_error_set(err, SS_ERR_VALUE, path, 0, "%s: NULL model or data",
                        what);
  if (d->model != m)
    return ss_error_set(err, SS_ERR_STATE, path, 0,
                        "%s: the data was made for another model", what);
  if (d->in_step)
    return ss_error_set(err, SS_ERR_STATE, path, 0,
                        "%s: only possible between steps, not in the middle "
                        "of one", what);
  return SS_OK;
}

ssStatus ss_checkpoint_save_buffer(const ssModel *m, const ssData *d,
                                   unsigned char **buf, size_t *len,
                                   ssError *err)
{
  if (!buf || !len)
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "ss_checkpoint_save_buffer: NULL output argument");
  *buf = NULL;
  *len = 0;
  ssStatus st = check_pair(m, d, "cannot write a checkpoint", NULL, err);
  if (st) return st;
  /* what a restore would refuse, or the next step (SS_SPEED_MAX) */
  char why[300];
  if (!ss_dyn_check_state(m, d, why, sizeof why))
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0, "cannot write a checkpoint: %s", why);
  long v = unlisted_vertex(m, d->soil_sinkage, d->soil_plastic, d->soil_shear,
                           d->soil_loaded, d->nsoil_loaded);
  if (v >= 0)
    return ss_error_set(err, SS_ERR_STATE, NULL, 0,
                        "cannot write a checkpoint: soil vertex %ld holds elastic "
                        "sinkage or shear but is not among the loaded vertices "
                        "(soil state written into the data directly? set it with "
                        "ss_soil_set_state)", v);

  Writer w = {NULL, 0, 0, 0};
  Fingerprint f;
  if (!fingerprint(m, &f, FP_NOW))
    return ss_error_set(err, SS_ERR_NOMEM, NULL, 0, "cannot write a checkpoint: out of memory");
  size_t hd = 0, s;

  w_bytes(&w, CKPT_MAGIC, 8);
  w_u32(&w, CKPT_VERSION);
  w_u32(&w, CKPT_HEADER);
  hd = w.n;
  w_u64(&w, 0); /* file size, patched below */
  w_u32(&w, NTAG);
  w_u32(&w, 0); /* header checksum, patched below */

  s = section_begin(&w, S_MODL);
  w_u32(&w, NCOUNT);
  for (int k = 0; k < NCOUNT; k++) w_u32(&w, f.count[k]);
  w_u32(&w, NHASH);
  for (int k = 0; k < NHASH; k++) w_u64(&w, f.hash[k]);
  size_t srclen = strlen(m->source_path);
  if (srclen > CKPT_SOURCE_MAX) srclen = CKPT_SOURCE_MAX;
  w_u32(&w, (uint32_t)srclen);
  w_bytes(&w, m->source_path, srclen);
  section_end(&w, s);

  s = section_begin(&w, S_OPTS);
  w_options(&w, &m->opt);
  section_end(&w, s);

  s = section_begin(&w, S_CLCK);
  w_f64(&w, d->time);
  w_u64(&w, (uint64_t)(int64_t)d->step);
  w_f64(&w, d->closure_error);
  section_end(&w, s);

  s = section_begin(&w, S_QPOS);
  w_f64s(&w, d->qpos, (size_t)m->nq);
  section_end(&w, s);
  s = section_begin(&w, S_QVEL);
  w_f64s(&w, d->qvel, (size_t)m->nv);
  section_end(&w, s);
  s = section_begin(&w, S_SYSA);
  w_bytes(&w, d->sys_active, (size_t)m->nsys);
  section_end(&w, s);
  s = section_begin(&w, S_PDTG);
  w_f64s(&w, d->pd_target, 2 * (size_t)m->npd);
  section_end(&w, s);
  s = section_begin(&w, S_HPOS);
  w_f64s(&w, d->hfield_pos, 3 * (size_t)m->nhfield);
  section_end(&w, s);
  s = section_begin(&w, S_HQUA);
  w_f64s(&w, d->hfield_quat, 4 * (size_t)m->nhfield);
  section_end(&w, s);
  s = section_begin(&w, S_SINK);
  w_f64s(&w, d->soil_sinkage, (size_t)m->nhfielddata);
  section_end(&w, s);
  s = section_begin(&w, S_PLAS);
  w_f64s(&w, d->soil_plastic, (size_t)m->nhfielddata);
  section_end(&w, s);
  s = section_begin(&w, S_SHEA);
  w_f64s(&w, d->soil_shear, (size_t)m->nhfielddata);
  section_end(&w, s);

  s = section_begin(&w, S_LOAD);
  for (int k = 0; k < d->nsoil_loaded; k++) w_i32(&w, d->soil_loaded[k]);
  section_end(&w, s);

  s = section_begin(&w, S_WARM);
  for (int k = 0; k < d->nwarm; k++) {
    const ssWarmEntry *e = d->warm + k;
    w_i32(&w, e->vertex);
    w_i32(&w, e->geom);
    w_i32(&w, e->creep);
    w_f64s(&w, e->traction, 3);
    w_f64s(&w, e->rate, 3);
  }
  section_end(&w, s);

  s = section_begin(&w, S_NEWT);
  for (int k = 0; k < 2; k++) {
    const ssNewtonRecord *r = d->newton_rec + k;
    int some = r->step >= 0;
    w_u64(&w, (uint64_t)(int64_t)(some ? r->step : -1));
    w_u64(&w, some ? r->key : 0);
    w_i32(&w, some ? r->n : 0);
    if (some) w_f64s(&w, r->c, (size_t)r->n);
  }
  section_end(&w, s);

  s = section_begin(&w, S_STAT);
  const ssStepStats *ps = &d->stats;
  w_i32(&w, ps->soil_contacts);
  w_i32(&w, ps->soil_loaded);
  w_f64(&w, ps->soil_contact_area);
  w_f64(&w, ps->soil_normal_force);
  w_i32(&w, ps->rigid_contacts);
  w_i32(&w, ps->sweeps);
  w_f64(&w, ps->residual);
  w_i32(&w, ps->converged);
  section_end(&w, s);

  w_bytes(&w, "CRC ", 4);
  if (!w.oom) {
    put_le(w.p + hd, (uint64_t)(w.n + 4), 8);
    put_le(w.p + 28, crc32_bytes(w.p, 28), 4);
  }
  if (!w.oom) w_u32(&w, crc32_bytes(w.p, w.n));
  if (w.oom) {
    free(w.p);
    return ss_error_set(err, SS_ERR_NOMEM, NULL, 0,
                        "out of memory writing a checkpoint");
  }
  *buf = w.p;
  *len = w.n;
  return SS_OK;
}

ssStatus ss_checkpoint_save(const ssModel *m, const ssData *d,
                            const char *path, ssError *err)
{
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "no checkpoint file name given");
  unsigned char *buf;
  size_t len;
  ssStatus st = ss_checkpoint_save_buffer(m, d, &buf, &len, err);
  if (st) {
    if (err && !err->file[0]) snprintf(err->file, sizeof err->file, "%s", path);
    return st;
  }
  ssAtomicFile f;
  st = ss_atomic_open(&f, path, err);
  if (st == SS_OK) {
    /* a failed write is reported by the commit, with its reason */
    ss_atomic_write(&f, buf, len);
    st = ss_atomic_commit(&f, err);
  }
  free(buf);
  return st;
}

/* ---------------------------------------------------------------------- */
/* reading                                                                 */

static uint64_t get_le(const unsigned char *b, int n)
{
  uint64_t v = 0;
  for (int k = n - 1; k >= 0; k--) v = v << 8 | b[k];
  return v;
}

/* A cursor over one section's payload; reads past its end set bad. */
typedef struct Reader {
  const unsigned char *p;
  size_t n, off;
  int bad;
} Reader;

static const unsigned char *r_take(Reader *r, size_t n)
{
  if (r->bad || n > r->n - r->off) {
    r->bad = 1;
    return NULL;
  }
  const unsigned char *q = r->p + r->off;
  r->off += n;
  return q;
}

static uint32_t r_u32(Reader *r)
{
  const unsigned char *q = r_take(r, 4);
  return q ? (uint32_t)get_le(q, 4) : 0;
}

static uint64_t r_u64(Reader *r)
{
  const unsigned char *q = r_take(r, 8);
  return q ? get_le(q, 8) : 0;
}

static int r_i32(Reader *r) { return (int)(int32_t)r_u32(r); }

static double r_f64(Reader *r)
{
  uint64_t u = r_u64(r);
  double v;
  memcpy(&v, &u, 8);
  return v;
}

static void r_f64s(Reader *r, double *v, size_t n)
{
  for (size_t i = 0; i < n; i++) v[i] = r_f64(r);
}

static void r_options(Reader *r, ssOption *o)
{
  memset(o, 0, sizeof *o);
  o->timestep = r_f64(r);
  r_f64s(r, o->gravity, 3);
  o->solver_max_sweeps = r_i32(r);
  o->solver_tolerance = r_f64(r);
  o->scalar_tolerance = r_f64(r);
  o->terrain_warm_start = r_i32(r);
  o->contact_margin = r_f64(r);
  o->rigid_erp = r_f64(r);
}

/* sizes of the fixed-size sections (bytes) */
#define OPTS_BYTES (8u * 4 + 4 + 8 + 8 + 4 + 8 + 8)
#define CLCK_BYTES 24u
#define STAT_BYTES (4u * 2 + 8 * 2 + 4 * 2 + 8 + 4)

/* A verified file: where each section's payload lies. */
typedef struct Parsed {
  const unsigned char *p;
  size_t len;
  size_t off[NTAG], size[NTAG];
} Parsed;

static Reader section(const Parsed *f, int s)
{
  Reader r = {f->p + f->off[s], f->size[s], 0, 0};
  return r;
}

/* Signature, version, header, size, checksum and section table.  path
 * names the file in messages (may be NULL for a buffer). */
static ssStatus parse_frame(const unsigned char *p, size_t len,
                            const char *path, Parsed *f, ssError *err)
{
  memset(f, 0, sizeof *f);
  f->p = p;
  f->len = len;
  if (len == 0)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "not a soilsim checkpoint: the file is empty");
  size_t nm = len < 8 ? len : 8;
  if (memcmp(p, CKPT_MAGIC, nm))
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "not a soilsim checkpoint (no SOILCKPT signature)");
  if (len < CKPT_HEADER)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is truncated: %zu bytes, shorter than "
                        "its header", len);
  uint32_t hstored = (uint32_t)get_le(p + 28, 4), hcrc = crc32_bytes(p, 28);
  if (hstored != hcrc)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: header checksum mismatch "
                        "(stored %08lx, computed %08lx)",
                        (unsigned long)hstored, (unsigned long)hcrc);
  uint32_t version = (uint32_t)get_le(p + 8, 4);
  if (version != CKPT_VERSION)
    return ss_error_set(err, SS_ERR_UNSUPPORTED, path, 0,
                        "checkpoint format version %lu is not supported "
                        "(this build reads version %u)",
                        (unsigned long)version, CKPT_VERSION);
  uint64_t size = get_le(p + 16, 8);
  if (get_le(p + 12, 4) != CKPT_HEADER || size < CKPT_HEADER + CKPT_TRAILER)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: bad header");
  if (size > len)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is truncated: %zu bytes, its header says "
                        "%llu", len, (unsigned long long)size);
  if (size < len)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: %zu bytes, its header says "
                        "%llu (data appended?)", len, (unsigned long long)size);
  uint32_t stored = (uint32_t)get_le(p + len - 4, 4);
  uint32_t crc = crc32_bytes(p, len - 4);
  if (stored != crc || memcmp(p + len - CKPT_TRAILER, "CRC ", 4))
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: checksum mismatch (stored "
                        "%08lx, computed %08lx)", (unsigned long)stored,
                        (unsigned long)crc);
  /* from here on the bytes are as written; what follows guards against a
   * file written by something else that got its checksums right */
  uint64_t nsec = get_le(p + 24, 4);
  size_t at = CKPT_HEADER, end = len - CKPT_TRAILER;
  int seen[NTAG] = {0};
  for (uint64_t k = 0; k < nsec; k++) {
    if (end - at < CKPT_SECTION_HEAD)
      return ss_error_set(err, SS_ERR_PARSE, path, 0,
                          "checkpoint is corrupted: section %llu runs past "
                          "the end", (unsigned long long)k + 1);
    const unsigned char *h = p + at;
    uint64_t n = get_le(h + 8, 8);
    if (get_le(h + 4, 4) != 0 || n > end - at - CKPT_SECTION_HEAD)
      return ss_error_set(err, SS_ERR_PARSE, path, 0,
                          "checkpoint is corrupted: bad size of section %llu",
                          (unsigned long long)k + 1);
    int s = -1;
    for (int t = 0; t < NTAG; t++)
      if (!memcmp(h, section_tag[t], 4)) s = t;
    if (s < 0 || seen[s]) {
      char tag[5];
      for (int c = 0; c < 4; c++)
        tag[c] = h[c] >= 32 && h[c] < 127 ? (char)h[c] : '?';
      tag[4] = 0;
      return ss_error_set(err, SS_ERR_PARSE, path, 0,
                          "checkpoint is corrupted: %s section '%s'",
                          s < 0 ? "unknown" : "repeated", tag);
    }
    seen[s] = 1;
    f->off[s] = at + CKPT_SECTION_HEAD;
    f->size[s] = (size_t)n;
    at += CKPT_SECTION_HEAD + (size_t)n;
  }
  if (at != end)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: %zu bytes after its last "
                        "section", end - at);
  for (int t = 0; t < NTAG; t++)
    if (!seen[t])
      return ss_error_set(err, SS_ERR_PARSE, path, 0,
                          "checkpoint is corrupted: section '%s' is missing",
                          section_tag[t]);
  return SS_OK;
}

/* The fixed part of MODL; the source path is returned as a pointer into
 * the file (not terminated) with its length. */
static ssStatus parse_model(const Parsed *f, const char *path, Fingerprint *fp,
                            const char **src, size_t *srclen, ssError *err)
{
  Reader r = section(f, S_MODL);
  memset(fp, 0, sizeof *fp);
  if (r_u32(&r) != NCOUNT) r.bad = 1;
  for (int k = 0; !r.bad && k < NCOUNT; k++) fp->count[k] = r_u32(&r);
  if (r_u32(&r) != NHASH) r.bad = 1;
  for (int k = 0; !r.bad && k < NHASH; k++) fp->hash[k] = r_u64(&r);
  uint32_t n = r_u32(&r);
  if (n > CKPT_SOURCE_MAX) r.bad = 1;
  *src = (const char *)r_take(&r, n);
  *srclen = n;
  if (r.bad || r.off != r.n)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: bad model section");
  return SS_OK;
}

static ssStatus parse_options(const Parsed *f, const char *path, ssOption *o,
                              ssError *err)
{
  Reader r = section(f, S_OPTS);
  if (r.n != OPTS_BYTES)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: bad options section");
  r_options(&r, o);
  /* the ranges of <contact_solver> */
  int ok = isfinite(o->timestep) && o->timestep > 0 &&
           isfinite(o->gravity[0]) && isfinite(o->gravity[1]) &&
           isfinite(o->gravity[2]) && o->solver_max_sweeps >= 1 &&
           o->solver_max_sweeps <= 1000000 && o->solver_tolerance > 0 &&
           o->solver_tolerance < 1 && o->scalar_tolerance > 0 &&
           o->scalar_tolerance < 1 &&
           (o->terrain_warm_start == 0 || o->terrain_warm_start == 1) &&
           isfinite(o->contact_margin) && o->contact_margin >= 0 &&
           o->rigid_erp >= 0 && o->rigid_erp <= 1;
  if (!ok)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: solver options out of range");
  return SS_OK;
}

static ssStatus parse_clock(const Parsed *f, const char *path, double *time,
                            long *step, double *closure, ssError *err)
{
  Reader r = section(f, S_CLCK);
  if (r.n != CLCK_BYTES)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: bad clock section");
  *time = r_f64(&r);
  int64_t s = (int64_t)r_u64(&r);
  *closure = r_f64(&r);
  /* the rules of <clock> (scene_read.c): a state the scene reader would
   * refuse must not come in this way, or its export could not be read */
  if (!(isfinite(*time) && *time >= 0))
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: clock time = %g is invalid: "
                        "must be finite and >= 0 s", *time);
  if (s < 0 || (uint64_t)s > (uint64_t)LONG_MAX)
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: clock step = %lld is invalid: "
                        "must be in [0, %ld]", (long long)s, LONG_MAX);
  if (!isfinite(*closure))
    return ss_error_set(err, SS_ERR_PARSE, path, 0,
                        "checkpoint is corrupted: bad closure error");
  *step = (long)s;
  return SS_OK;
}

static void copy_source(char *dst, size_t size, const char *src, size_t n)
{
  if (n >= size) n = size - 1;
  if (n) memcpy(dst, src, n);
  dst[n] = 0;
}

ssStatus ss_checkpoint_info_buffer(const void *buf, size_t len,
                                   ssCheckpointInfo *info, ssError *err)
{
  if (!info || (!buf && len))
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "ss_checkpoint_info_buffer: NULL argument");
  Parsed f;
  Fingerprint fp;
  const char *src;
  size_t srclen;
  ssCheckpointInfo in;
  memset(&in, 0, sizeof in);
  const unsigned char *p = buf ? buf : (const unsigned char *)"";
  ssStatus st = parse_frame(p, len, NULL, &f, err);
  if (!st) st = parse_model(&f, NULL, &fp, &src, &srclen, err);
  if (!st) st = parse_options(&f, NULL, &in.opt, err);
  double closure;
  if (!st) st = parse_clock(&f, NULL, &in.time, &in.step, &closure, err);
  if (st) return st;
  in.version = (int)CKPT_VERSION;
  in.bytes = len;
  copy_source(in.source, sizeof in.source, src, srclen);
  *info = in;
  return SS_OK;
}

/* Most unknowns a Newton phase can have: 6 per body (or link) and bed, 1
 * per PD row, at most 2 limit rows per dof */
static uint64_t newton_max(const ssModel *m)
{
  uint64_t n = 6 * (uint64_t)m->nbody * (uint64_t)m->nhfield + (uint64_t)m->npd +
               2 * (uint64_t)m->nv;
  return n < INT32_MAX ? n : INT32_MAX;
}

/* Most warm-start cache entries a model can have: a soil point for each
 * collider and soil vertex, a rigid contact for each collider, rigid
 * support and candidate point, the joint rows */
static uint64_t warm_max(const ssModel *m)
{
  return ((uint64_t)m->nhfielddata +
          ((uint64_t)m->nhfield + (uint64_t)m->nplane + (uint64_t)m->ngeom) *
              SS_RIGID_CANDIDATES) *
             (uint64_t)m->ngeom +
         (uint64_t)m->npd + 2 * (uint64_t)m->nv;
}

/* Largest checkpoint a model can have (bytes); bigger files are refused
 * before they are read. */
static uint64_t max_size(const ssModel *m)
{
  uint64_t nhd = (uint64_t)m->nhfielddata;
  uint64_t warm = warm_max(m);
  return CKPT_HEADER + CKPT_TRAILER + (uint64_t)NTAG * CKPT_SECTION_HEAD +
         8 + 4 * NCOUNT + 8 * NHASH + CKPT_SOURCE_MAX + OPTS_BYTES +
         CLCK_BYTES + STAT_BYTES + 8 * ((uint64_t)m->nq + (uint64_t)m->nv) +
         (uint64_t)m->nsys + 8 * (2 * (uint64_t)m->npd + 7 * (uint64_t)m->nhfield) +
         8 * 3 * nhd + 4 * nhd + CKPT_WARM_BYTES * warm + 2 * (20 + 8 * newton_max(m));
}

ssStatus ss_checkpoint_info(const char *path, ssCheckpointInfo *info,
                            ssError *err)
{
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "no checkpoint file name given");
  char *buf;
  size_t len;
  ssStatus st = ss_read_file(path, SS_SCENE_MAX_BYTES * 4L, &buf, &len, err);
  if (st) return st;
  st = ss_checkpoint_info_buffer(buf, len, info, err);
  free(buf);
  if (st && err) snprintf(err->file, sizeof err->file, "%s", path);
  return st;
}

void ss_option_copy_solver(ssOption *dst, const ssOption *src)
{
  dst->solver_max_sweeps = src->solver_max_sweeps;
  dst->solver_tolerance = src->solver_tolerance;
  dst->scalar_tolerance = src->scalar_tolerance;
  dst->terrain_warm_start = src->terrain_warm_start;
  dst->contact_margin = src->contact_margin;
  dst->rigid_erp = src->rigid_erp;
}

/* The first solver option that differs, as "name: X in the checkpoint, Y in
 * the world"; 0 when they all agree. */
static int options_differ(const ssOption *c, const ssOption *w, char *buf,
                          size_t size)
{
  if (c->solver_max_sweeps != w->solver_max_sweeps)
    snprintf(buf, size, "max_sweeps %d in the checkpoint, %d in the world",
             c->solver_max_sweeps, w->solver_max_sweeps);
  else if (c->solver_tolerance != w->solver_tolerance)
    snprintf(buf, size, "tolerance %.17g in the checkpoint, %.17g in the world",
             c->solver_tolerance, w->solver_tolerance);
  else if (c->scalar_tolerance != w->scalar_tolerance)
    snprintf(buf, size, "scalar_tolerance %.17g in the checkpoint, %.17g in "
             "the world", c->scalar_tolerance, w->scalar_tolerance);
  else if (c->terrain_warm_start != w->terrain_warm_start)
    snprintf(buf, size, "terrain_warm_start %s in the checkpoint, %s in the "
             "world", c->terrain_warm_start ? "true" : "false",
             w->terrain_warm_start ? "true" : "false");
  else if (c->contact_margin != w->contact_margin)
    snprintf(buf, size, "contact_margin %.17g in the checkpoint, %.17g in the "
             "world", c->contact_margin, w->contact_margin);
  else if (c->rigid_erp != w->rigid_erp)
    snprintf(buf, size, "rigid_erp %.17g in the checkpoint, %.17g in the world",
             c->rigid_erp, w->rigid_erp);
  else
    return 0;
  return 1;
}

/* The fingerprint of the file against the model's: what differs. */
static ssStatus compare_model(const ssModel *m, const Fingerprint *fc,
                              const char *src, size_t srclen, const char *path,
                              ssError *err)
{
  Fingerprint fm, fl, fb;
  if (!fingerprint(m, &fm, FP_NOW)) return ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
  char from[600] = "";
  if (srclen) {
    char s[512];
    copy_source(s, sizeof s, src, srclen);
    snprintf(from, sizeof from, " (from '%s')", s);
  }
  for (int k = 0; k < NCOUNT; k++)
    if (fc->count[k] != fm.count[k])
      return ss_error_set(err, SS_ERR_VALUE, path, 0,
                          "checkpoint was written for a different world%s: it "
                          "has %lu %s, this world has %lu", from,
                          (unsigned long)fc->count[k], count_name[k],
                          (unsigned long)fm.count[k]);
  char what[512] = "";
  size_t used = 0;
  /* a file of an earlier build holds the legacy hashes or those without
   * the materials between colliders (they differ from the current ones
   * only in the groups with materials); formed only where the current
   * ones do not all match (each variant hashes the whole model again) */
  int match = 1;
  for (int k = 0; k < NHASH; k++) match &= fc->hash[k] == fm.hash[k];
  if (match) return SS_OK;
  if (!fingerprint(m, &fl, FP_LEGACY) || !fingerprint(m, &fb, FP_NO_BETWEEN))
    return ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
  for (int k = 0; k < NHASH; k++)
    if (fc->hash[k] != fm.hash[k] && fc->hash[k] != fl.hash[k] && fc->hash[k] != fb.hash[k]) {
      int n = snprintf(what + used, sizeof what - used, "%s%s",
                       used ? "; " : "", hash_name[k]);
      if (n > 0 && (size_t)n < sizeof what - used) used += (size_t)n;
    }
  if (used)
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "checkpoint was written for a different world%s: "
                        "these differ: %s", from, what);
  return SS_OK;
}

static ssStatus corrupt(ssError *err, const char *path, const char *what)
{
  return ss_error_set(err, SS_ERR_PARSE, path, 0,
                      "checkpoint is corrupted: %s", what);
}

/* Read an array section of exactly n doubles, all finite. */
static ssStatus read_doubles(const Parsed *f, int s, size_t n, double *out,
                             const char *path, ssError *err)
{
  Reader r = section(f, s);
  char what[64];
  snprintf(what, sizeof what, "bad section '%s'", section_tag[s]);
  if (r.n != 8 * n) return corrupt(err, path, what);
  r_f64s(&r, out, n);
  for (size_t i = 0; i < n; i++)
    if (!isfinite(out[i])) return corrupt(err, path, what);
  return SS_OK;
}

/* Whether cache entry e, keyed as a rigid contact's (vertex < 0), names a
 * rigid support (a rigid height map, a ground plane, or another collider:
 * ss_rigid_feature) and a candidate point, and holds what the solver
 * stores for one: a positive normal force and no rate */
static int rigid_entry(const ssModel *m, const ssWarmEntry *e)
{
  int support, k;
  ss_rigid_feature_split(e->vertex, &support, &k);
  (void)k; /* any of SS_RIGID_CANDIDATES */
  int other = support - m->nhfield - m->nplane; /* a collider's index */
  int ok = support < m->nhfield + m->nplane
               ? support >= m->nhfield || !m->hfield_soil[support]
               : other < m->ngeom && other != e->geom && e->geom >= 0;
  return ok && e->traction[0] > 0 && e->rate[0] == 0 && e->rate[1] == 0 && e->rate[2] == 0;
}

/* Everything read from a file before it is put into the data. */
typedef struct State {
  double time, closure;
  long step;
  double *qpos, *qvel, *pd_target, *hpos, *hquat, *sink, *plas, *shea;
  unsigned char *active;
  int nloaded, *loaded;
  int nwarm;
  ssWarmEntry *warm;
  ssNewtonRecord rec[2];
  ssStepStats stats;
} State;

static void state_free(State *s)
{
  free(s->qpos); free(s->qvel); free(s->pd_target); free(s->hpos);
  free(s->hquat); free(s->sink); free(s->plas); free(s->shea);
  free(s->active); free(s->loaded); free(s->warm);
  free(s->rec[0].c); free(s->rec[1].c);
}

static void *alloc0(size_t n, size_t size)
{
  return calloc(n ? n : 1, size);
}

/* Whether soil vertex v (an index into the soil arrays) lies on a soil bed
 * rather than on a rigid height map. */
static int soil_vertex(const ssModel *m, int v)
{
  for (int h = 0; h < m->nhfield; h++) {
    int a = m->hfield_adr[h], n = m->hfield_nx[h] * m->hfield_ny[h];
    if (v >= a && v < a + n) return m->hfield_soil[h];
  }
  return 0;
}

static ssStatus parse_state(const ssModel *m, const Parsed *f, const char *path,
                            State *s, ssError *err)
{
  ssStatus st;
  const size_t nq = (size_t)m->nq, nv = (size_t)m->nv, ns = (size_t)m->nsys;
  const size_t npd = (size_t)m->npd, nh = (size_t)m->nhfield;
  const size_t nhd = (size_t)m->nhfielddata;

  /* sizes against the model before anything is allocated */
  uint64_t warm_cap = warm_max(m);
  if (f->size[S_LOAD] % 4 || f->size[S_LOAD] / 4 > nhd)
    return corrupt(err, path, "bad size of the loaded-vertex list");
  if (f->size[S_WARM] % CKPT_WARM_BYTES ||
      f->size[S_WARM] / CKPT_WARM_BYTES > warm_cap ||
      f->size[S_WARM] / CKPT_WARM_BYTES > (uint64_t)INT32_MAX)
    return corrupt(err, path, "bad size of the warm-start cache");
  if (f->size[S_SYSA] != ns) return corrupt(err, path, "bad section 'SYSA'");
  if (f->size[S_STAT] != STAT_BYTES) return corrupt(err, path, "bad section 'STAT'");
  s->nloaded = (int)(f->size[S_LOAD] / 4);
  s->nwarm = (int)(f->size[S_WARM] / CKPT_WARM_BYTES);

  s->qpos = alloc0(nq, sizeof(double));
  s->qvel = alloc0(nv, sizeof(double));
  s->pd_target = alloc0(2 * npd, sizeof(double));
  s->hpos = alloc0(3 * nh, sizeof(double));
  s->hquat = alloc0(4 * nh, sizeof(double));
  s->sink = alloc0(nhd, sizeof(double));
  s->plas = alloc0(nhd, sizeof(double));
  s->shea = alloc0(nhd, sizeof(double));
  s->active = alloc0(ns, 1);
  s->loaded = alloc0((size_t)s->nloaded, sizeof(int));
  s->warm = alloc0((size_t)s->nwarm, sizeof(ssWarmEntry));
  if (!s->qpos || !s->qvel || !s->pd_target || !s->hpos || !s->hquat ||
      !s->sink || !s->plas || !s->shea || !s->active || !s->loaded || !s->warm)
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory reading a checkpoint");

  if ((st = parse_clock(f, path, &s->time, &s->step, &s->closure, err)) ||
      (st = read_doubles(f, S_QPOS, nq, s->qpos, path, err)) ||
      (st = read_doubles(f, S_QVEL, nv, s->qvel, path, err)) ||
      (st = read_doubles(f, S_PDTG, 2 * npd, s->pd_target, path, err)) ||
      (st = read_doubles(f, S_HPOS, 3 * nh, s->hpos, path, err)) ||
      (st = read_doubles(f, S_HQUA, 4 * nh, s->hquat, path, err)) ||
      (st = read_doubles(f, S_SINK, nhd, s->sink, path, err)) ||
      (st = read_doubles(f, S_PLAS, nhd, s->plas, path, err)) ||
      (st = read_doubles(f, S_SHEA, nhd, s->shea, path, err)))
    return st;

  Reader r = section(f, S_SYSA);
  for (size_t k = 0; k < ns; k++) {
    s->active[k] = *r_take(&r, 1);
    if (s->active[k] > 1) return corrupt(err, path, "bad section 'SYSA'");
  }
  /* no step leaves a speed above SS_SPEED_MAX, and none is saved */
  for (size_t k = 0; k < ns; k++)
    if (s->active[k] &&
        !ss_all_within(s->qvel + m->sys_vadr[k], m->sys_nv[k], SS_SPEED_MAX))
      return corrupt(err, path, "a velocity above 1e5 (m/s or rad/s)");
  /* bed orientations are unit quaternions (ss_hfield_set_pose) */
  for (size_t h = 0; h < nh; h++) {
    if (!ss_quat_is_unit(s->hquat + 4 * h))
      return corrupt(err, path, "bad section 'HQUA'");
  }
  for (size_t k = 0; k < nhd; k++) {
    if (!soil_vertex(m, (int)k) && (s->sink[k] != 0 || s->plas[k] != 0 || s->shea[k] != 0))
      return corrupt(err, path, "soil state on a rigid height map");
    if (!(s->plas[k] >= 0 && s->sink[k] >= s->plas[k] && s->shea[k] >= 0))
      return corrupt(err, path, "soil state out of range (need 0 <= "
                     "plastic_sinkage <= sinkage, shear >= 0)");
  }

  r = section(f, S_LOAD);
  for (int k = 0; k < s->nloaded; k++) {
    int v = r_i32(&r);
    if (v < 0 || (size_t)v >= nhd || (k && v <= s->loaded[k - 1]) ||
        !soil_vertex(m, v))
      return corrupt(err, path, "bad loaded-vertex list");
    s->loaded[k] = v;
  }
  if (unlisted_vertex(m, s->sink, s->plas, s->shea, s->loaded, s->nloaded) >= 0)
    return corrupt(err, path, "bad loaded-vertex list (a vertex with elastic "
                   "sinkage or shear is not in it)");

  r = section(f, S_WARM);
  for (int k = 0; k < s->nwarm; k++) {
    ssWarmEntry *e = s->warm + k;
    e->vertex = r_i32(&r);
    e->geom = r_i32(&r);
    ss_solver_warm_key(e);
    e->creep = r_i32(&r);
    r_f64s(&r, e->traction, 3);
    r_f64s(&r, e->rate, 3);
    int key_ok = e->geom >= 0 && e->vertex < 0
                     ? e->geom < m->ngeom && rigid_entry(m, e)
                 : e->geom >= 0
                     ? (size_t)e->vertex < nhd && e->geom < m->ngeom && soil_vertex(m, e->vertex)
                     : (e->geom == -2 || e->geom == -3) && e->vertex >= 0 &&
                           (size_t)e->vertex < 2 * nv;
    key_ok = key_ok && (e->creep == 0 || (e->creep == 1 && e->geom >= 0 && e->vertex >= 0));
    if (!key_ok || !isfinite(e->traction[0]) || !isfinite(e->traction[1]) ||
        !isfinite(e->traction[2]) || !isfinite(e->rate[0]) || !isfinite(e->rate[1]) ||
        !isfinite(e->rate[2]) || (k && ss_solver_warm_cmp(e - 1, e) > 0))
      return corrupt(err, path, "bad warm-start cache");
  }

  /* the Newton phase's start: records of steps before this one, the later
   * first, none after none */
  r = section(f, S_NEWT);
  for (int k = 0; k < 2; k++) {
    ssNewtonRecord *q = s->rec + k;
    int64_t step = (int64_t)r_u64(&r);
    q->key = r_u64(&r);
    int n = r_i32(&r);
    int ok = !r.bad && step >= -1 && step < (int64_t)s->step && n >= 0 &&
             (uint64_t)n <= newton_max(m) && (uint64_t)n * 8 <= r.n - r.off &&
             (step >= 0 || (n == 0 && q->key == 0)) &&
             (k == 0 || step < 0 || step < s->rec[0].step);
    if (!ok) return corrupt(err, path, "bad section 'NEWT'");
    q->step = (long)step;
    q->n = n;
    q->c = alloc0((size_t)n, sizeof(double));
    if (!q->c)
      return ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory reading a checkpoint");
    q->cap = n;
    r_f64s(&r, q->c, (size_t)n);
    /* velocity changes of one step: no step makes one anywhere near
     * CKPT_NEWT_MAX (its velocities stay within SS_SPEED_MAX), and the
     * Newton phase's start from such values would overflow */
    for (int a = 0; a < n; a++)
      if (!(fabs(q->c[a]) <= CKPT_NEWT_MAX)) return corrupt(err, path, "bad section 'NEWT'");
  }
  if (r.bad || r.off != r.n) return corrupt(err, path, "bad section 'NEWT'");

  r = section(f, S_STAT);
  ssStepStats *ps = &s->stats;
  memset(ps, 0, sizeof *ps);
  ps->soil_contacts = r_i32(&r);
  ps->soil_loaded = r_i32(&r);
  ps->soil_contact_area = r_f64(&r);
  ps->soil_normal_force = r_f64(&r);
  ps->rigid_contacts = r_i32(&r);
  ps->sweeps = r_i32(&r);
  ps->residual = r_f64(&r);
  ps->converged = r_i32(&r);
  return SS_OK;
}

/* Verify everything, then replace the data's state in one go. */
static ssStatus load(const ssModel *m, ssData *d, const unsigned char *p,
                     size_t len, const char *path, ssError *err)
{
  Parsed f;
  Fingerprint fp;
  const char *src;
  size_t srclen;
  ssOption opt;
  char diff[256];
  ssStatus st = check_pair(m, d, "cannot restore a checkpoint", path, err);
  if (!st) st = parse_frame(p, len, path, &f, err);
  if (!st) st = parse_model(&f, path, &fp, &src, &srclen, err);
  if (!st) st = compare_model(m, &fp, src, srclen, path, err);
  if (!st) st = parse_options(&f, path, &opt, err);
  if (!st && options_differ(&opt, &m->opt, diff, sizeof diff))
    st = ss_error_set(err, SS_ERR_STATE, path, 0,
                      "checkpoint's solver configuration differs from the "
                      "world's (%s); apply it first (ss_checkpoint_info, "
                      "ss_option_copy_solver)", diff);
  if (st) return st;

  State s;
  memset(&s, 0, sizeof s);
  st = parse_state(m, &f, path, &s, err);
  /* room for the caches, the last thing that can fail */
  if (!st && s.nloaded > d->cap_soil_loaded) {
    int *q = realloc(d->soil_loaded, (size_t)s.nloaded * sizeof *q);
    if (!q) st = ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
    else {
      d->soil_loaded = q;
      d->cap_soil_loaded = s.nloaded;
    }
  }
  if (!st && s.nwarm > d->cap_warm) {
    ssWarmEntry *q = realloc(d->warm, (size_t)s.nwarm * sizeof *q);
    if (!q) st = ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
    else {
      d->warm = q;
      d->cap_warm = s.nwarm;
    }
  }
  for (int k = 0; k < 2 && !st; k++) {
    ssNewtonRecord *r = d->newton_rec + k;
    if (s.rec[k].n > r->cap) {
      double *q = realloc(r->c, (size_t)s.rec[k].n * sizeof *q);
      if (!q) st = ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
      else {
        r->c = q;
        r->cap = s.rec[k].n;
      }
    }
  }
  if (st) {
    state_free(&s);
    return st;
  }

  const size_t nh = (size_t)m->nhfield, nhd = (size_t)m->nhfielddata;
  d->time = s.time;
  d->step = s.step;
  d->closure_error = s.closure;
  if (m->nq) memcpy(d->qpos, s.qpos, (size_t)m->nq * sizeof(double));
  if (m->nv) memcpy(d->qvel, s.qvel, (size_t)m->nv * sizeof(double));
  if (m->nsys) memcpy(d->sys_active, s.active, (size_t)m->nsys);
  if (m->npd) memcpy(d->pd_target, s.pd_target, 2 * (size_t)m->npd * sizeof(double));
  if (nh) {
    memcpy(d->hfield_pos, s.hpos, 3 * nh * sizeof(double));
    memcpy(d->hfield_quat, s.hquat, 4 * nh * sizeof(double));
  }
  if (nhd) {
    memcpy(d->soil_sinkage, s.sink, nhd * sizeof(double));
    memcpy(d->soil_plastic, s.plas, nhd * sizeof(double));
    memcpy(d->soil_shear, s.shea, nhd * sizeof(double));
  }
  if (s.nloaded) memcpy(d->soil_loaded, s.loaded, (size_t)s.nloaded * sizeof(int));
  d->nsoil_loaded = s.nloaded;
  if (s.nwarm) memcpy(d->warm, s.warm, (size_t)s.nwarm * sizeof(ssWarmEntry));
  d->nwarm = s.nwarm;
  for (int k = 0; k < 2; k++) {
    ssNewtonRecord *r = d->newton_rec + k;
    r->step = s.rec[k].step;
    r->key = s.rec[k].key;
    r->n = s.rec[k].n;
    if (r->n) memcpy(r->c, s.rec[k].c, (size_t)r->n * sizeof(double));
  }
  d->newton_rec[2].step = -1;
  d->stats = s.stats;
  /* the contacts of the step before belong to another state */
  d->ncontact = 0;
  state_free(&s);
  ss_forward(m, d);
  return SS_OK;
}

ssStatus ss_checkpoint_load_buffer(const ssModel *m, ssData *d,
                                   const void *buf, size_t len, ssError *err)
{
  if (!buf && len)
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "ss_checkpoint_load_buffer: NULL buffer");
  return load(m, d, buf ? buf : (const void *)"", len, NULL, err);
}

ssStatus ss_checkpoint_load(const ssModel *m, ssData *d, const char *path,
                            ssError *err)
{
  if (!path || !*path)
    return ss_error_set(err, SS_ERR_IO, "", 0, "no checkpoint file name given");
  ssStatus st = check_pair(m, d, "cannot restore a checkpoint", path, err);
  if (st) return st;
  /* a file larger than any checkpoint of this world is refused unread */
  uint64_t cap = max_size(m);
  struct stat sb;
  if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode) &&
      (uint64_t)sb.st_size > cap)
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "checkpoint was written for a different world or is "
                        "not a checkpoint: %lld bytes, at most %llu for this "
                        "world", (long long)sb.st_size,
                        (unsigned long long)cap);
  char *buf;
  size_t len;
  st = ss_read_file(path, cap > (uint64_t)LONG_MAX ? LONG_MAX : (long)cap, &buf,
                    &len, err);
  if (st) return st;
  st = load(m, d, (const unsigned char *)buf, len, path, err);
  free(buf);
  return st;
}
