/* test_checkpoint.c -- checkpoints and exact replay (DESIGN 5), the soil
 * state API (DESIGN 2.2) and exact XML export of the soil state.
 *
 * Replay: for the plate, the dragged plate, an articulated system on soil
 * and the buggy, N steps straight must equal K steps, checkpoint, restore
 * into a fresh data, N - K steps -- bit for bit, with warm starts on and off
 * (the buggy: on only).  Damage:
 * every byte position class of a checkpoint (header, section table,
 * payload, checksum) flipped, truncations at many lengths, foreign files and
 * files of another world are refused without a crash and leave the data as
 * it was.  Scenes come from $top_srcdir/scenes (default "."). */
#include "soilsim.h"
#include "solver.h"
#include "ss_math.h"
#include "tap.h"
#include "worlds.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[512];

static const char *srcdir(void)
{
  const char *s = getenv("top_srcdir");
  return s && *s ? s : ".";
}

static void tmp_path(char *buf, size_t size, const char *name)
{
  snprintf(buf, size, "%s/%s", tmpdir, name);
}

/* scenes/NAME of the source tree (worlds.c) */
static int load_scene(const char *name, ssModel **m, ssData **d)
{
  char rel[512];
  snprintf(rel, sizeof rel, "scenes/%s", name);
  return load_scene_file(rel, m, d);
}

static int run(const ssModel *m, ssData *d, int steps)
{
  ssError e;
  for (int k = 0; k < steps; k++)
    if (ss_step(m, d, &e) != SS_OK) {
      diag("step %ld failed: %s", d->step + 1, e.message);
      return 0;
    }
  return 1;
}

/* the whole state of d as checkpoint bytes (caller frees) */
static unsigned char *snapshot(const ssModel *m, const ssData *d, size_t *len)
{
  unsigned char *b = NULL;
  ssError e;
  if (ss_checkpoint_save_buffer(m, d, &b, len, &e) != SS_OK) {
    diag("save failed: %s", e.message);
    return NULL;
  }
  return b;
}

/* bit-identical dynamic state, compared field by field (not through the
 * checkpoint writer) */
static int same_state(const ssModel *m, const ssData *a, const ssData *b)
{
  size_t nhd = (size_t)m->nhfielddata * sizeof(double);
  if (memcmp(&a->time, &b->time, sizeof a->time) || a->step != b->step) return 0;
  if (m->nq && memcmp(a->qpos, b->qpos, (size_t)m->nq * sizeof(double))) return 0;
  if (m->nv && memcmp(a->qvel, b->qvel, (size_t)m->nv * sizeof(double))) return 0;
  if (nhd && (memcmp(a->soil_sinkage, b->soil_sinkage, nhd) ||
              memcmp(a->soil_plastic, b->soil_plastic, nhd) ||
              memcmp(a->soil_shear, b->soil_shear, nhd)))
    return 0;
  if (m->nsys && memcmp(a->sys_active, b->sys_active, (size_t)m->nsys)) return 0;
  if (m->npd && memcmp(a->pd_target, b->pd_target, 2 * (size_t)m->npd * sizeof(double)))
    return 0;
  if (a->nwarm != b->nwarm || a->nsoil_loaded != b->nsoil_loaded) return 0;
  for (int k = 0; k < a->nwarm; k++)
    if (a->warm[k].vertex != b->warm[k].vertex || a->warm[k].geom != b->warm[k].geom ||
        memcmp(a->warm[k].traction, b->warm[k].traction, sizeof a->warm[k].traction) ||
        memcmp(a->warm[k].rate, b->warm[k].rate, sizeof a->warm[k].rate))
      return 0;
  if (a->nsoil_loaded &&
      memcmp(a->soil_loaded, b->soil_loaded, (size_t)a->nsoil_loaded * sizeof(int)))
    return 0;
  return 1;
}

/* the same, and the same checkpoint bytes */
static int identical(const ssModel *m, const ssData *a, const ssData *b)
{
  size_t la, lb;
  unsigned char *ba = snapshot(m, a, &la), *bb = snapshot(m, b, &lb);
  int same = ba && bb && la == lb && !memcmp(ba, bb, la) && same_state(m, a, b);
  free(ba);
  free(bb);
  return same;
}

/* ---------------------------------------------------------------------- */
/* worlds built in code                                                    */

/* plate_world, its failure reported */
static int build_plate_on(int n, double size, double slope, double pull,
                          const ssSoilMaterial *soil, ssModel **mout, ssData **dout)
{
  ssError e;
  if (plate_world(n, size, slope, pull, soil, mout, dout, &e)) return 1;
  diag("world build failed: %s", e.message);
  return 0;
}

/* on a gentle slope, so that the state is not symmetric */
static int build_plate(int n, double size, double pull, ssModel **mout,
                       ssData **dout)
{
  return build_plate_on(n, size, 0.002, pull, NULL, mout, dout);
}

/* ---------------------------------------------------------------------- */
/* replay                                                                  */

/* N straight against K + checkpoint + restore into a fresh data + N - K;
 * also through a file, and restored into a data that had run elsewhere. */
static void replay(const char *what, const ssModel *m, int N, int K)
{
  ssError e;
  ssData *a = ss_data_new(m), *b = ss_data_new(m), *c = ss_data_new(m);
  ssData *u = ss_data_new(m);
  if (!a || !b || !c || !u) {
    ok(0, "%s: data", what);
    goto out;
  }
  int ran = run(m, a, N) && run(m, b, K);
  size_t len = 0;
  unsigned char *buf = ran ? snapshot(m, b, &len) : NULL;
  ok(buf != NULL && b->nwarm > 0 && b->nsoil_loaded > 0,
     "%s: checkpoint after %d steps (%zu bytes, %d cached tractions, %d "
     "loaded vertices)", what, K, len, b->nwarm, b->nsoil_loaded);
  if (!buf) goto out;
  ok(ss_checkpoint_load_buffer(m, c, buf, len, &e) == SS_OK && identical(m, b, c),
     "%s: restored into a fresh data, the state is the one saved", what);
  ok(run(m, c, N - K) && identical(m, a, c),
     "%s: %d + %d steps after the restore = %d steps straight, bit for bit",
     what, K, N - K, N);

  /* through a file, into a data that was somewhere else */
  char path[600];
  tmp_path(path, sizeof path, "replay.ckpt");
  int io = run(m, u, K + 7) && ss_checkpoint_save(m, b, path, &e) == SS_OK &&
           ss_checkpoint_load(m, u, path, &e) == SS_OK;
  if (!io) diag("%s", e.message);
  ok(io && identical(m, b, u) && run(m, u, N - K) && identical(m, a, u),
     "%s: through a file, restored over a data that had run %d steps: the "
     "same %d-step state", what, K + 7, N);
  FILE *fp = fopen(path, "rb");
  unsigned char *fbuf = malloc(len + 1);
  size_t got = fp && fbuf ? fread(fbuf, 1, len + 1, fp) : 0;
  if (fp) fclose(fp);
  ok(got == len && !memcmp(fbuf, buf, len),
     "%s: the file holds the same bytes as the memory checkpoint", what);
  free(fbuf);
  unlink(path);

  /* the original continues identically too (determinism on one build) */
  ok(run(m, b, N - K) && identical(m, a, b), "%s: the run that saved continues "
     "to the same state", what);
  free(buf);
out:
  ss_data_free(a);
  ss_data_free(b);
  ss_data_free(c);
  ss_data_free(u);
}

static void replay_scene(const char *scene, int N, int K)
{
  ssModel *m;
  ssData *d;
  char what[256];
  if (!load_scene(scene, &m, &d)) {
    ok(0, "%s loads", scene);
    return;
  }
  ss_data_free(d);
  snprintf(what, sizeof what, "%s, warm start on", scene);
  replay(what, m, N, K);
  m->opt.terrain_warm_start = 0;
  snprintf(what, sizeof what, "%s, warm start off", scene);
  replay(what, m, N, K);
  ss_model_free(m);
}

/* N steps straight against K, a checkpoint restored into a fresh data and
 * N - K more, bit for bit (for slow scenes: without replay's file and
 * overwrite variants); at K the cache holds at least min_rigid rigid
 * contacts' entries */
static void replay_straight(const char *scene, int N, int K, int min_rigid)
{
  ssModel *m;
  ssData *a;
  ssError e;
  if (!load_scene(scene, &m, &a)) {
    ok(0, "%s loads", scene);
    return;
  }
  ssData *b = ss_data_new(m), *c = ss_data_new(m);
  size_t len = 0;
  unsigned char *buf = NULL;
  int r = b && c && run(m, a, N) && run(m, b, K) && (buf = snapshot(m, b, &len)) &&
          ss_checkpoint_load_buffer(m, c, buf, len, &e) == SS_OK;
  int rigid = 0;
  for (int k = 0; r && k < b->nwarm; k++) rigid += b->warm[k].vertex < 0 && b->warm[k].geom >= 0;
  ok(r && identical(m, b, c) && b->nwarm > 0 && rigid >= min_rigid,
     "%s: checkpoint after %d steps (%zu bytes, %d cache entries, %d of them rigid "
     "contacts') restores into a fresh data", scene, K, len, b ? b->nwarm : 0, rigid);
  ok(r && run(m, c, N - K) && identical(m, a, c),
     "%s: %d + %d steps after the restore = %d steps straight, bit for bit", scene, K, N - K,
     N);
  free(buf);
  ss_data_free(a);
  ss_data_free(b);
  ss_data_free(c);
  ss_model_free(m);
}

/* The buggy (a 241 k-vertex bed, four wheels, closures, coil-overs, PD
 * drive) is slow: only N straight against K + restore + N - K. */
static void test_replay_buggy(void)
{
  replay_straight("buggy.xml", 100, 60, 0);
}

/* The creeping solve (newton.c) in the replayed stretch: drag.xml's
 * plate comes to rest rocking on its front edge at steps 1159-1164, which
 * that solve takes; from a checkpoint of step 1150 the restored run goes
 * through them bit for bit. */
static void test_replay_creep(void)
{
  replay_straight("drag.xml", 1200, 1150, 0);
}

static void test_replay(void)
{
  replay_scene("plate.xml", 200, 80);
  replay_scene("plate_arm.xml", 60, 25);

  ssModel *m;
  ssData *d;
  if (!build_plate(41, 1.6, 110, &m, &d)) {
    ok(0, "dragged plate builds");
    return;
  }
  ss_data_free(d);
  replay("dragged plate (110 N), warm start on", m, 160, 90);
  m->opt.terrain_warm_start = 0;
  replay("dragged plate (110 N), warm start off", m, 160, 90);
  ss_model_free(m);
}

/* After a step that took no Newton step the next step forms its first
 * Jacobian only if a Newton step needs it (newton.c); a restored data
 * forms it at once.  Both must give the same bits: a step right after a
 * settled one that then needs Newton steps, taken straight and taken
 * after a restore into a fresh data. */
static void lazy_jacobian(const char *what, const ssSoilMaterial *soil)
{
  ssModel *m;
  ssData *a;
  if (!build_plate_on(41, 1.6, 0, 0, soil, &m, &a)) {
    ok(0, "%s: builds", what);
    return;
  }
  /* the plate at rest on a level bed until a step is settled: the Newton
   * phase's answer at once, no sweeps */
  ssError e;
  int settled = 0;
  for (int s = 0; s < 1500 && !settled; s++) {
    if (ss_step(m, a, &e) != SS_OK) break;
    const ssStepStats *st = &a->stats;
    settled = st->soil_loaded > 0 && st->sweeps == 0 && st->newton == 0 && st->converged;
  }
  size_t len = 0;
  unsigned char *buf = settled ? snapshot(m, a, &len) : NULL;
  ssData *c = ss_data_new(m);
  int r = buf && c && ss_checkpoint_load_buffer(m, c, buf, len, &e) == SS_OK;
  /* a sideways kick, the same to both: the next step needs Newton steps */
  if (r) {
    a->qvel[0] += 0.02;
    c->qvel[0] += 0.02;
  }
  r = r && run(m, a, 1);
  int newton = a->stats.newton;
  r = r && run(m, c, 1);
  ok(r && settled && newton > 0 && c->stats.newton == newton && identical(m, a, c),
     "%s: settled after %ld steps, then kicked: its next step (%d Newton steps, "
     "the first Jacobian formed when needed) is bit for bit the one after a "
     "restore (formed at once)", what, a->step - 1, newton);
  ok(r && run(m, a, 30) && run(m, c, 30) && identical(m, a, c),
     "%s: ... and so are the 30 steps after it", what);
  free(buf);
  ss_data_free(a);
  ss_data_free(c);
  ss_model_free(m);
}

static void test_lazy_jacobian(void)
{
  ssSoilMaterial soil = plate_soil();
  lazy_jacobian("plate, linear soil", &soil);
  /* a power law and cohesion: the laws' pow and exp memos in play */
  soil.sinkage_exponent = 1.1;
  soil.bekker_kphi = 2.5e5;
  soil.cohesion = 800;
  lazy_jacobian("plate, n = 1.1 and cohesion", &soil);
}

/* The warm-start cache and the Newton phase's last answers are what make
 * warm replays exact: restoring without either changes the result (so the
 * replay tests above can tell).  (Without the cache alone the dragged
 * plate replays exactly: its Newton phase starts from its last answers,
 * extrapolated, and not from the cache.) */
static void test_cache_matters(void)
{
  ssModel *m;
  ssData *d;
  if (!build_plate(41, 1.6, 110, &m, &d)) return;
  ssData *a = ss_data_new(m);
  size_t len;
  unsigned char *buf = NULL;
  ssError e;
  int okr = run(m, a, 120) && run(m, d, 60) && (buf = snapshot(m, d, &len));
  const char *what[2] = {"the warm-start cache and the Newton phase's last answers",
                         "the Newton phase's last answers"};
  for (int k = 0; k < 2; k++) {
    ssData *c = ss_data_new(m);
    int okc = okr && ss_checkpoint_load_buffer(m, c, buf, len, &e) == SS_OK;
    /* as an XML reload would have it */
    if (k == 0) c->nwarm = 0;
    c->newton_rec[0].step = c->newton_rec[1].step = -1;
    okc = okc && run(m, c, 60);
    ok(okc && !same_state(m, a, c) && a->step == c->step,
       "dragged plate: a restore without %s does not replay exactly (needed and saved)",
       what[k]);
    ss_data_free(c);
  }
  free(buf);
  ss_data_free(a);
  ss_data_free(d);
  ss_model_free(m);
}

/* A bed moved between steps, a removed system and changed PD targets are
 * part of the state: saved and restored. */
static void test_state_changes(void)
{
  ssModel *m;
  ssData *d;
  ssError e;
  if (!load_scene("plate_arm.xml", &m, &d)) {
    ok(0, "plate_arm.xml loads");
    return;
  }
  ssData *a = ss_data_new(m);
  double pos[3] = {0.001, 0, -0.0005}, quat[4] = {1, 0, 0, 0.01};
  int okr = run(m, d, 20) && run(m, a, 20);
  okr = okr && ss_hfield_set_pose(m, d, 0, pos, quat, &e) == SS_OK &&
        ss_hfield_set_pose(m, a, 0, pos, quat, &e) == SS_OK;
  if (m->npd) d->pd_target[0] = a->pd_target[0] = 0.05;
  size_t len;
  unsigned char *buf = okr ? snapshot(m, d, &len) : NULL;
  ssData *c = ss_data_new(m);
  okr = buf && ss_checkpoint_load_buffer(m, c, buf, len, &e) == SS_OK;
  ok(okr && !memcmp(c->hfield_pos, d->hfield_pos, 3 * sizeof(double)) &&
     !memcmp(c->hfield_quat, d->hfield_quat, 4 * sizeof(double)) &&
     (!m->npd || c->pd_target[0] == 0.05),
     "bed pose and PD target set between steps are restored");
  ok(okr && run(m, c, 15) && run(m, a, 15) && identical(m, a, c),
     "after a bed move and a PD target change: restore + 15 steps = 15 steps");
  free(buf);

  /* a removed system */
  ssModel *pm;
  ssData *pd;
  if (load_scene("plate.xml", &pm, &pd)) {
    ssData *pa = ss_data_new(pm), *pc = ss_data_new(pm);
    buf = NULL;
    int r = run(pm, pd, 40) && run(pm, pa, 40) &&
            ss_remove(pm, pd, "plate", &e) == SS_OK &&
            ss_remove(pm, pa, "plate", &e) == SS_OK &&
            (buf = snapshot(pm, pd, &len)) &&
            ss_checkpoint_load_buffer(pm, pc, buf, len, &e) == SS_OK;
    ok(r && pc->sys_active[0] == 0 && run(pm, pc, 30) && run(pm, pa, 30) &&
       identical(pm, pa, pc),
       "a system removed before the checkpoint stays removed; the soil "
       "recovers identically");
    free(buf);
    ss_data_free(pa);
    ss_data_free(pc);
    ss_data_free(pd);
    ss_model_free(pm);
  }
  ss_data_free(a);
  ss_data_free(c);
  ss_data_free(d);
  ss_model_free(m);
}

/* ---------------------------------------------------------------------- */
/* damaged, foreign and mismatched files                                   */

/* An independent bitwise CRC-32 (IEEE), to check the trailer and to forge
 * files whose checksum is right but whose contents are not. */
static uint32_t crc32_ref(const unsigned char *p, size_t n)
{
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; i++) {
    c ^= p[i];
    for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1)));
  }
  return ~c;
}

static uint64_t le(const unsigned char *p, int n)
{
  uint64_t v = 0;
  for (int k = n - 1; k >= 0; k--) v = v << 8 | p[k];
  return v;
}

static void put(unsigned char *p, uint64_t v, int n)
{
  for (int k = 0; k < n; k++) p[k] = (unsigned char)(v >> (8 * k));
}

/* both checksums right again: the header's, then the file's */
static void reseal(unsigned char *p, size_t n)
{
  put(p + 28, crc32_ref(p, 28), 4);
  uint32_t c = crc32_ref(p, n - 4);
  for (int k = 0; k < 4; k++) p[n - 4 + k] = (unsigned char)(c >> (8 * k));
}

/* offset of a section's 16-byte head, or 0 */
static size_t find_section(const unsigned char *p, size_t n, const char *tag)
{
  size_t at = 32;
  while (at + 16 <= n - 8) {
    if (!memcmp(p + at, tag, 4)) return at;
    at += 16 + (size_t)le(p + at + 8, 8);
  }
  return 0;
}

typedef struct Victim {
  const ssModel *m;
  ssData *d;
  const ssData *twin;  /* a data in d's state: d must stay equal to it */
  int refused, changed, silent;
} Victim;

/* load a damaged buffer: it must fail, say something, and leave d alone */
static void attack(Victim *v, const unsigned char *p, size_t n)
{
  ssError e;
  ss_error_clear(&e);
  if (ss_checkpoint_load_buffer(v->m, v->d, p, n, &e) != SS_OK) v->refused++;
  if (!e.message[0]) v->silent++;
  if (!same_state(v->m, v->d, v->twin) ||
      memcmp(&v->d->stats, &v->twin->stats, offsetof(ssStepStats, time_stage)))
    v->changed++;
}

static void damage_tests(const char *what, const ssModel *m, const ssData *src,
                         int every_byte)
{
  size_t n;
  unsigned char *good = snapshot(m, src, &n);
  if (!good) {
    ok(0, "%s: checkpoint", what);
    return;
  }
  ok(!memcmp(good, "SOILCKPT", 8) && le(good + 8, 4) == 5 && le(good + 16, 8) == n &&
     le(good + 28, 4) == crc32_ref(good, 28) && !memcmp(good + n - 8, "CRC ", 4) &&
     le(good + n - 4, 4) == crc32_ref(good, n - 4),
     "%s: layout: signature, version 5, size and CRC-32 in the header, CRC-32 "
     "trailer (%zu bytes)", what, n);

  /* the victim: a data in another state that must survive every attack */
  ssData *d = ss_data_new(m), *twin = ss_data_new(m);
  if (!run(m, d, 3) || !run(m, twin, 3)) return;
  Victim v = {m, d, twin, 0, 0, 0};
  unsigned char *p = malloc(n + 16);

  /* byte classes: header, section heads, payloads, checksum trailer */
  size_t classes[4] = {0, 0, 0, 0}, tried[4] = {0, 0, 0, 0};
  int bad_before = 0;
  const char *cname[4] = {"header", "section sizes and tags", "payload",
                          "checksum"};
  for (size_t i = 0; i < n; i++) {
    int cls;
    if (i < 32) cls = 0;
    else if (i >= n - 8) cls = 3;
    else {
      /* inside a section head? walk the table */
      size_t at = 32;
      cls = 2;
      while (at + 16 <= n - 8) {
        if (i >= at && i < at + 16) {
          cls = 1;
          break;
        }
        at += 16 + (size_t)le(good + at + 8, 8);
        if (at > i) break;
      }
    }
    classes[cls]++;
    if (!every_byte && cls == 2 && i % 499) continue;
    tried[cls]++;
    for (int pat = 0; pat < 2; pat++) {
      memcpy(p, good, n);
      p[i] ^= pat ? 0xFF : 0x01;
      int before = v.refused;
      attack(&v, p, n);
      if (v.refused == before) bad_before++;
    }
  }
  for (int c = 0; c < 4; c++) diag("%s: %s bytes: %zu, flipped %zu", what,
                                   cname[c], classes[c], tried[c]);
  ok(bad_before == 0 && v.changed == 0 && v.silent == 0 && tried[0] && tried[1] &&
     tried[2] && tried[3],
     "%s: a flipped byte in the header, the section table, any payload or the "
     "checksum is refused with a message, the data unchanged (%d loads)",
     what, v.refused);

  /* truncations and additions */
  int nbad = 0;
  v.refused = 0;
  int tries = 0;
  for (size_t l = 0; l < n; l += every_byte || l < 64 || l > n - 64 ? 1 : 331) {
    int before = v.refused;
    attack(&v, good, l);
    tries++;
    if (v.refused == before) nbad++;
  }
  memcpy(p, good, n);
  memset(p + n, 0, 16);
  attack(&v, p, n + 1);
  attack(&v, p, n + 16);
  tries += 2;
  ok(nbad == 0 && v.refused == tries && v.changed == 0,
     "%s: truncated at %d lengths (0 to %zu bytes) or with bytes appended: "
     "refused, data unchanged", what, tries - 2, n - 1);

  /* forged: right checksum, wrong structure or values */
  struct {
    const char *desc;
    const char *tag; /* section, or NULL for the header */
    long off;        /* byte offset from the section head (or file start) */
    int width;
    uint64_t value;
  } forge[] = {
    {"version 4 (an older build's)", NULL, 8, 4, 4},
    {"version 6", NULL, 8, 4, 6},
    {"header size", NULL, 12, 4, 64},
    {"section count too high", NULL, 24, 4, 17},
    {"section count too low", NULL, 24, 4, 14},
    {"section count huge", NULL, 24, 4, 0xFFFFFFFFu},
    {"file size beyond the end", NULL, 16, 8, 0},
    {"file size below the header", NULL, 16, 8, 20},
    {"QPOS size one double short", "QPOS", 8, 8, 0},
    {"QPOS size huge", "QPOS", 8, 8, UINT64_C(1) << 62},
    {"SINK size off by 8", "SINK", 8, 8, 0},
    {"LOAD size not a multiple of 4", "LOAD", 8, 8, 0},
    {"WARM size not a multiple of 60", "WARM", 8, 8, 0},
    {"unknown section tag", "CLCK", 0, 4, 0x58585858u},
    {"section reserved word", "OPTS", 4, 4, 7},
    {"count of nq in the model section", "MODL", 16 + 4, 4, 99},
    {"a model hash", "MODL", 16 + 4 + 60 + 4 + 8, 8, 12345},
    {"max_sweeps 0", "OPTS", 16 + 32, 4, 0},
    {"tolerance NaN", "OPTS", 16 + 36, 8, UINT64_C(0x7ff8000000000000)},
    {"negative step count", "CLCK", 16 + 8, 8, UINT64_C(0xFFFFFFFFFFFFFFFF)},
    {"time +inf", "CLCK", 16, 8, UINT64_C(0x7ff0000000000000)},
    {"time -1 s", "CLCK", 16, 8, UINT64_C(0xbff0000000000000)},
    {"qpos NaN", "QPOS", 16, 8, UINT64_C(0x7ff8000000000001)},
    {"qvel 2e5 (above SS_SPEED_MAX)", "QVEL", 16, 8, UINT64_C(0x41086a0000000000)},
    {"negative plastic sinkage", "PLAS", 16, 8, UINT64_C(0xbff0000000000000)},
    {"system flag 2", "SYSA", 16, 1, 2},
    {"bed quaternion of norm 2", "HQUA", 16, 8, UINT64_C(0x4000000000000000)},
    {"loaded vertex out of range", "LOAD", 16, 4, 0x7FFFFFFF},
    {"loaded vertex negative", "LOAD", 16, 4, 0xFFFFFFFFu},
    {"warm entry collider out of range", "WARM", 16 + 4, 4, 0x10000},
    {"warm entry vertex negative", "WARM", 16, 4, 0xFFFFFFF0u},
    {"warm entry rate NaN", "WARM", 16 + 12 + 24, 8, UINT64_C(0x7ff8000000000000)},
    {"warm entry creep flag 2", "WARM", 16 + 8, 4, 2},
    {"Newton record of step -2", "NEWT", 16, 8, UINT64_C(0xFFFFFFFFFFFFFFFE)},
    {"Newton record of a step not yet taken", "NEWT", 16, 8, UINT64_C(1) << 40},
    {"Newton record of 2^31 - 1 unknowns", "NEWT", 16 + 16, 4, 0x7FFFFFFFu},
  };
  int nforge = (int)(sizeof forge / sizeof forge[0]), fail = 0;
  for (int k = 0; k < nforge; k++) {
    memcpy(p, good, n);
    size_t at = forge[k].tag ? find_section(p, n, forge[k].tag) : 0;
    if (forge[k].tag && !at) {
      diag("no section %s", forge[k].tag);
      fail++;
      continue;
    }
    uint64_t value = forge[k].value;
    /* sizes relative to the real one */
    if (forge[k].off == 8 && forge[k].tag) {
      uint64_t real = le(p + at + 8, 8);
      if (!strcmp(forge[k].desc, "QPOS size one double short")) value = real - 8;
      if (!strcmp(forge[k].desc, "SINK size off by 8")) value = real + 8;
      if (!strncmp(forge[k].desc, "LOAD", 4)) value = real + 2;
      if (!strncmp(forge[k].desc, "WARM", 4)) value = real + 8;
    }
    if (!forge[k].tag && forge[k].off == 16 && value == 0) value = n + 8;
    if (forge[k].tag && !strcmp(forge[k].tag, "LOAD") && forge[k].off >= 16 &&
        le(p + at + 8, 8) < 4)
      continue; /* no loaded vertex to damage */
    if (forge[k].tag && !strcmp(forge[k].tag, "WARM") && forge[k].off >= 16 &&
        le(p + at + 8, 8) < 60)
      continue;
    put(p + at + forge[k].off, value, forge[k].width);
    reseal(p, n);
    ssError e;
    ss_error_clear(&e);
    int before = v.refused;
    attack(&v, p, n);
    if (v.refused == before) {
      diag("forged '%s' was accepted", forge[k].desc);
      fail++;
    } else if (k < 7 || k == 14 || k == 15) {
      ss_checkpoint_load_buffer(m, d, p, n, &e);
      diag("forged '%s': %s", forge[k].desc, e.message);
    }
  }
  ok(fail == 0 && v.changed == 0,
     "%s: %d forged files with a correct checksum but a bad version, header, "
     "section table, fingerprint or values are refused, data unchanged",
     what, nforge);
  free(p);
  free(good);
  ss_data_free(d);
  ss_data_free(twin);
}

static void test_damage(void)
{
  ssModel *m;
  ssData *d;
  /* a small world: every byte of its checkpoint */
  if (build_plate(9, 1.0, 40, &m, &d)) {
    run(m, d, 40);
    damage_tests("small bed (every byte)", m, d, 1);
    ss_data_free(d);
    ss_model_free(m);
  }
  if (load_scene("plate.xml", &m, &d)) {
    run(m, d, 30);
    damage_tests("plate.xml", m, d, 0);
    ss_data_free(d);
    ss_model_free(m);
  }
  if (load_scene("plate_arm.xml", &m, &d)) {
    run(m, d, 10);
    damage_tests("plate_arm.xml", m, d, 0);
    ss_data_free(d);
    ss_model_free(m);
  }
}

/* Rigid contacts' cache entries (solver.h, ss_rigid_feature): the buggy
 * driving on concrete replays bit for bit from a checkpoint (its wheels'
 * rim points warm start the next step: without them in the file the
 * restored run would start them cold and part from the straight one); and
 * a checkpoint whose rigid entry names a soil bed or no support at all,
 * or holds what the solver never stores (no normal force, a rate, a creep
 * flag), is refused. */
static void test_rigid_cache(void)
{
  replay_straight("buggy_rigid.xml", 600, 450, 4);
  /* bodies on bodies: the cache's entries of contacts between bodies
   * (a static table's and pair contacts) restore with the rest */
  replay_straight("stack.xml", 700, 450, 12);
  /* and those of a box's edges across a cylinder's side and of two
   * cylinders' sides (their own ids in the cache) */
  replay_straight("logs.xml", 700, 450, 6);

  ssModel *m;
  ssError e;
  /* a soil bed (height map 0) and, off it, a box resting on a ground
   * plane (support nhfield + 0 = 1) */
  m = ss_model_new();
  int bed = add_soil_bed(m, 0.4, 0.05);
  int plane = ss_model_add_plane(m, "ground", -0.5, NULL, 0, &e);
  ssBodyDef bx = ss_body_def_default();
  bx.name = "box";
  bx.size[0] = bx.size[1] = 0.2;
  bx.size[2] = 0.1;
  bx.mass = 2;
  ss_v3_set(bx.pos, 3, 0, -0.45);
  int body = ss_model_add_body(m, &bx, &e);
  ssData *d = bed >= 0 && plane >= 0 && body >= 0 ? ss_data_new(m) : NULL;
  size_t n = 0;
  unsigned char *good = d && run(m, d, 20) ? snapshot(m, d, &n) : NULL;
  size_t at = good ? find_section(good, n, "WARM") : 0;
  int entries = at ? (int)(le(good + at + 8, 8) / 60) : 0, first = -1;
  for (int k = 0; k < entries && first < 0; k++)
    if ((int32_t)le(good + at + 16 + 60 * k, 4) < 0) first = k;
  ok(first >= 0 && entries == 4 && ss_checkpoint_load_buffer(m, d, good, n, &e) == SS_OK,
     "a box on a ground plane beside a soil bed: its four corners cached, the "
     "checkpoint restores");
  struct {
    const char *desc;
    int off, width;
    uint64_t value;
  } forge[] = {
    {"the soil bed as its support", 0, 4, 0x80000000u + 0 * SS_RIGID_CANDIDATES},
    {"a support past the ground planes", 0, 4, 0x80000000u + 2 * SS_RIGID_CANDIDATES},
    {"no normal force", 12, 8, 0},
    {"a rate", 36, 8, UINT64_C(0x3ff0000000000000)},
    {"a creep flag", 8, 4, 1},
  };
  int nforge = (int)(sizeof forge / sizeof forge[0]), accepted = 0;
  unsigned char *p = good ? malloc(n) : NULL;
  for (int k = 0; k < nforge && p && first >= 0; k++) {
    memcpy(p, good, n);
    put(p + at + 16 + 60 * first + forge[k].off, forge[k].value, forge[k].width);
    reseal(p, n);
    ss_error_clear(&e);
    if (ss_checkpoint_load_buffer(m, d, p, n, &e) == SS_OK || !strstr(e.message, "warm-start")) {
      diag("forged rigid entry with %s: %s", forge[k].desc, e.message[0] ? e.message : "accepted");
      accepted++;
    }
  }
  ok(p && first >= 0 && accepted == 0,
     "%d forged rigid cache entries (a soil bed or no support named, no normal force, a "
     "rate, a creep flag) are refused as a bad warm-start cache", nforge);
  free(p);
  free(good);
  ss_data_free(d);
  ss_model_free(m);
}

/* A force too large for a double: a 1000 t box strikes a ground plane at
 * 90 km/s with dt = 1e-300 s, an impulse of 9e10 N s over the step, 9e310 N
 * as a force.  The cache keeps no start for it (an infinite start made the
 * next step fail, and the checkpoint reader refuses non-finite entries):
 * the steps go on, and their checkpoint restores. */
static void test_cache_overflow(void)
{
  ssError e;
  ssModel *m = ss_model_new();
  m->opt.timestep = 1e-300;
  int plane = ss_model_add_plane(m, "ground", 0, NULL, 0, &e);
  ssBodyDef bx = ss_body_def_default();
  bx.name = "box";
  bx.size[0] = bx.size[1] = 0.2;
  bx.size[2] = 0.1;
  bx.mass = 1e6;
  ss_v3_set(bx.pos, 0, 0, 0.05);
  int body = ss_model_add_body(m, &bx, &e);
  ssData *d = plane >= 0 && body >= 0 ? ss_data_new(m) : NULL;
  if (d) d->qvel[2] = -9e4;
  int stepped = d && run(m, d, 3);
  size_t n = 0;
  unsigned char *b = stepped ? snapshot(m, d, &n) : NULL;
  ss_error_clear(&e);
  int restored = b && ss_checkpoint_load_buffer(m, d, b, n, &e) == SS_OK;
  if (b && !restored) diag("restore: %s", e.message);
  ok(stepped && restored && fabs(d->qvel[2]) < 1e-6,
     "a 1000 t box striking a plane at 90 km/s with dt = 1e-300 s (a force "
     "over 1e308 N): it stops, the steps after go on and their checkpoint "
     "restores");
  free(b);
  ss_data_free(d);
  ss_model_free(m);
}

static int write_file(const char *path, const void *p, size_t n)
{
  FILE *fp = fopen(path, "wb");
  if (!fp) return 0;
  int okw = fwrite(p, 1, n, fp) == n;
  return fclose(fp) == 0 && okw;
}

static void test_foreign_and_mismatch(void)
{
  ssModel *m, *m2;
  ssData *d, *d2;
  ssError e;
  char path[600], scene[1024];
  if (!load_scene("plate.xml", &m, &d) || !load_scene("plate.xml", &m2, &d2)) {
    ok(0, "plate.xml loads");
    return;
  }
  run(m, d, 20);
  size_t n;
  unsigned char *good = snapshot(m, d, &n);
  ssData *fresh = ss_data_new(m2); /* d2 must stay in this state */
  tmp_path(path, sizeof path, "x.ckpt");

  /* foreign files */
  snprintf(scene, sizeof scene, "%s/scenes/plate.xml", srcdir());
  ss_error_clear(&e);
  ok(ss_checkpoint_load(m2, d2, scene, &e) != SS_OK && strstr(e.message, "not a soilsim checkpoint") &&
     strstr(e.file, "plate.xml"),
     "a scene file given as a checkpoint: '%s: %s'", e.file, e.message);
  write_file(path, "", 0);
  ok(ss_checkpoint_load(m2, d2, path, &e) != SS_OK && strstr(e.message, "empty"),
     "an empty file: '%s'", e.message);
  write_file(path, "SOILC", 5);
  ok(ss_checkpoint_load(m2, d2, path, &e) != SS_OK && strstr(e.message, "truncated"),
     "the first bytes of the signature only: '%s'", e.message);
  unsigned char junk[4096];
  for (size_t i = 0; i < sizeof junk; i++) junk[i] = (unsigned char)(i * 131 + 7);
  write_file(path, junk, sizeof junk);
  ok(ss_checkpoint_load(m2, d2, path, &e) != SS_OK && strstr(e.message, "not a soilsim"),
     "random bytes: '%s'", e.message);
  unlink(path);
  ok(ss_checkpoint_load(m2, d2, path, &e) == SS_ERR_IO && strstr(e.file, "x.ckpt"),
     "a missing file: SS_ERR_IO naming it ('%s')", e.message);
  ok(ss_checkpoint_load(m2, d2, tmpdir, &e) == SS_ERR_IO,
     "a directory: SS_ERR_IO ('%s')", e.message);
  ok(ss_checkpoint_save(m, d, tmpdir, &e) != SS_OK, "saving over a directory "
     "fails ('%s')", e.message);
  ok(ss_checkpoint_save(m, d, "/nonexistent-dir/x.ckpt", &e) == SS_ERR_IO,
     "saving into a missing folder: SS_ERR_IO");

  /* info without a model */
  ssCheckpointInfo info;
  ok(ss_checkpoint_save(m, d, path, &e) == SS_OK && ss_checkpoint_info(path, &info, &e) == SS_OK &&
     info.version == 5 && info.step == 20 && info.time == d->time &&
     info.bytes == n && strstr(info.source, "plate.xml") &&
     info.opt.solver_max_sweeps == m->opt.solver_max_sweeps,
     "ss_checkpoint_info: version 5, step 20, time, size, source '%s'", info.source);

  /* another world */
  ssModel *ml;
  ssData *dl;
  if (load_scene("plate_large.xml", &ml, &dl)) {
    ss_error_clear(&e);
    ok(ss_checkpoint_load(ml, dl, path, &e) == SS_ERR_VALUE &&
       strstr(e.message, "checkpoint was written for a different world"),
       "plate.xml's checkpoint into plate_large.xml: '%s'", e.message);
    ss_data_free(dl);
    ss_model_free(ml);
  }
  ssModel *ma;
  ssData *da;
  if (load_scene("plate_arm.xml", &ma, &da)) {
    ok(ss_checkpoint_load(ma, da, path, &e) == SS_ERR_VALUE &&
       strstr(e.message, "different world") && strstr(e.message, "plate.xml"),
       "into an articulated world: '%s'", e.message);
    ss_data_free(da);
    ss_model_free(ma);
  }
  double mass = m2->body_mass[0];
  m2->body_mass[0] = 21;
  ok(ss_checkpoint_load_buffer(m2, d2, good, n, &e) == SS_ERR_VALUE &&
     strstr(e.message, "different world") && strstr(e.message, "masses"),
     "same scene with another mass: '%s'", e.message);
  m2->body_mass[0] = mass;
  double k_phi = m2->hfield_soilmat[0].bekker_kphi;
  m2->hfield_soilmat[0].bekker_kphi *= 2;
  ok(ss_checkpoint_load_buffer(m2, d2, good, n, &e) == SS_ERR_VALUE &&
     strstr(e.message, "soil materials"), "another soil: '%s'", e.message);
  m2->hfield_soilmat[0].bekker_kphi = k_phi;
  double dt = m2->opt.timestep;
  m2->opt.timestep = 0.002;
  ok(ss_checkpoint_load_buffer(m2, d2, good, n, &e) == SS_ERR_VALUE &&
     strstr(e.message, "time step"), "another time step: '%s'", e.message);
  m2->opt.timestep = dt;

  /* the solver configuration: refused when it differs, then applied */
  m2->opt.solver_max_sweeps = 17;
  m2->opt.terrain_warm_start = 0;
  ok(ss_checkpoint_load_buffer(m2, d2, good, n, &e) == SS_ERR_STATE &&
     strstr(e.message, "max_sweeps 200 in the checkpoint, 17"),
     "different solver options are refused: '%s'", e.message);
  ok(same_state(m2, d2, fresh), "every refusal above left the data unchanged");
  ok(ss_checkpoint_info_buffer(good, n, &info, &e) == SS_OK, "info from memory");
  ss_option_copy_solver(&m2->opt, &info.opt);
  ok(m2->opt.solver_max_sweeps == 200 && m2->opt.terrain_warm_start == 1 &&
     m2->opt.timestep == dt && ss_checkpoint_load_buffer(m2, d2, good, n, &e) == SS_OK &&
     same_state(m, d, d2),
     "after ss_option_copy_solver the checkpoint restores into the other model "
     "of the same scene");

  /* data of another model, and in the middle of a step */
  ok(ss_checkpoint_load_buffer(m, d2, good, n, &e) == SS_ERR_STATE &&
     strstr(e.message, "another model"), "a data made for another model is "
     "refused: '%s'", e.message);
  d->in_step = 1;
  unsigned char *b2 = NULL;
  size_t n2;
  ok(ss_checkpoint_save_buffer(m, d, &b2, &n2, &e) == SS_ERR_STATE && !b2 &&
     ss_checkpoint_load_buffer(m, d, good, n, &e) == SS_ERR_STATE &&
     ss_checkpoint_save(m, d, path, &e) == SS_ERR_STATE,
     "save and restore are refused in the middle of a step: '%s'", e.message);
  d->in_step = 0;

  unlink(path);
  free(good);
  ss_data_free(fresh);
  ss_data_free(d);
  ss_data_free(d2);
  ss_model_free(m);
  ss_model_free(m2);
}

/* Checkpoints of the same state are the same bytes, run to run. */
static void test_reproducible(void)
{
  ssModel *m;
  ssData *d;
  if (!build_plate(21, 1.2, 80, &m, &d)) return;
  ssData *d2 = ss_data_new(m);
  size_t n1, n2;
  unsigned char *b1 = NULL, *b2 = NULL;
  int r = run(m, d, 50) && run(m, d2, 50) && (b1 = snapshot(m, d, &n1)) &&
          (b2 = snapshot(m, d2, &n2));
  ok(r && n1 == n2 && !memcmp(b1, b2, n1),
     "two runs to the same step give byte-identical checkpoints (no wall "
     "times, no pointers in the file)");
  free(b1);
  free(b2);
  ss_data_free(d);
  ss_data_free(d2);
  ss_model_free(m);
}

/* ---------------------------------------------------------------------- */
/* the soil state API (DESIGN 2.2)                                         */

static void test_soil_api(void)
{
  ssModel *m;
  ssData *d;
  ssError e;
  if (!build_plate(11, 1.0, 0, &m, &d)) {
    ok(0, "world builds");
    return;
  }
  const int h = 0, nv = 121;
  double s[121], p[121], j[121], s2[121], p2[121], j2[121];
  for (int k = 0; k < nv; k++) {
    p[k] = 0.001 * (k % 7);
    s[k] = p[k] + (k % 3 ? 0.0005 : 0);
    j[k] = k % 5 ? 0 : 0.002;
  }
  ok(ss_soil_set_state(m, d, h, s, p, j, &e) == SS_OK &&
     ss_soil_get_state(m, d, h, s2, p2, j2, &e) == SS_OK &&
     !memcmp(s, s2, sizeof s) && !memcmp(p, p2, sizeof p) && !memcmp(j, j2, sizeof j),
     "set then get the three arrays: the same bits");
  int want = 0;
  for (int k = 0; k < nv; k++) want += s[k] > p[k] || j[k] > 0;
  ok(d->nsoil_loaded == want, "set_state rebuilds the loaded-vertex list (%d "
     "vertices hold elastic sinkage or shear)", want);
  ok(ss_hfield_surface(m, d, h, 3, 2) == ss_hfield_heights(m, h)[2 * 11 + 3] - s[2 * 11 + 3],
     "surface height = undeformed height - sinkage");

  /* invalid states are refused whole */
  double bad[121];
  memcpy(bad, s, sizeof bad);
  bad[60] = p[60] - 1e-6;
  ok(ss_soil_set_state(m, d, h, bad, NULL, NULL, &e) == SS_ERR_VALUE &&
     strstr(e.message, "vertex 60") && ss_soil_get_state(m, d, h, s2, NULL, NULL, &e) == SS_OK &&
     !memcmp(s2, s, sizeof s), "sinkage below plastic sinkage is refused and "
     "nothing is written");
  bad[60] = NAN;
  ok(ss_soil_set_state(m, d, h, bad, NULL, NULL, &e) == SS_ERR_VALUE, "NaN is refused");
  memcpy(bad, j, sizeof bad);
  bad[3] = -1e-9;
  ok(ss_soil_set_state(m, d, h, NULL, NULL, bad, &e) == SS_ERR_VALUE,
     "negative shear is refused");
  ok(ss_soil_get_state(m, d, 5, s2, p2, j2, &e) == SS_ERR_NOTFOUND &&
     ss_soil_set_state(m, d, -1, s, p, j, &e) == SS_ERR_NOTFOUND,
     "a bed index out of range: SS_ERR_NOTFOUND");

  /* undeformed heights */
  const double *z = ss_hfield_heights(m, h);
  ok(z && fabs(z[10] - 0.002) < 1e-15 && z[0] == 0 && ss_hfield_heights(m, 3) == NULL,
     "ss_hfield_heights: the undeformed heights (%g at the +x edge)", z ? z[10] : -1);
  ok(ss_hfield_set_heights(m, h, z, &e) == SS_ERR_STATE,
     "height edits on a soil bed are refused ('%s')", e.message);

  /* setters refused in the middle of a step */
  double pos[3] = {0, 0, 0.01}, quat[4] = {1, 0, 0, 0};
  size_t l0, l1;
  unsigned char *before = snapshot(m, d, &l0);
  d->in_step = 1;
  int refused = ss_soil_set_state(m, d, h, p, p, NULL, &e) == SS_ERR_STATE;
  refused &= ss_soil_reset(m, d, h, &e) == SS_ERR_STATE;
  refused &= ss_hfield_set_pose(m, d, h, pos, quat, &e) == SS_ERR_STATE;
  refused &= ss_soil_get_state(m, d, h, s2, NULL, NULL, &e) == SS_ERR_STATE;
  refused &= ss_remove(m, d, "plate", &e) == SS_ERR_STATE;
  refused &= ss_step(m, d, &e) == SS_ERR_STATE;
  d->in_step = 0;
  unsigned char *after = snapshot(m, d, &l1);
  ok(refused && before && after && l0 == l1 && !memcmp(before, after, l0),
     "in the middle of a step: set_state, reset, set_pose, get_state, remove "
     "and step are refused (SS_ERR_STATE), nothing changes");
  free(before);
  free(after);

  /* bed pose */
  ok(ss_hfield_set_pose(m, d, h, pos, quat, &e) == SS_OK && d->hfield_pos[2] == 0.01,
     "the bed moves between steps");
  double q0[4] = {0, 0, 0, 0}, pinf[3] = {INFINITY, 0, 0};
  ok(ss_hfield_set_pose(m, d, h, pos, q0, &e) == SS_ERR_VALUE &&
     ss_hfield_set_pose(m, d, h, pinf, quat, &e) == SS_ERR_VALUE &&
     ss_hfield_set_pose(m, d, 4, pos, quat, &e) == SS_ERR_NOTFOUND,
     "a zero quaternion, an infinite position, a missing bed are refused");
  double zero[3] = {0, 0, 0};
  ss_hfield_set_pose(m, d, h, zero, quat, &e);

  /* reset */
  ok(ss_soil_reset(m, d, h, &e) == SS_OK && d->nsoil_loaded == 0 && d->nwarm == 0 &&
     ss_soil_get_state(m, d, h, s2, p2, j2, &e) == SS_OK && s2[17] == 0 && p2[17] == 0 &&
     j2[0] == 0, "reset: all three arrays zero");

  /* step statistics of a settled plate: the loaded area is the plate's */
  ss_data_reset(m, d);
  ssModel *pm;
  ssData *pd;
  if (load_scene("plate.xml", &pm, &pd)) {
    run(pm, pd, 600);
    const ssStepStats *st = &pd->stats;
    ok(st->soil_contacts >= st->soil_loaded && st->soil_loaded > 500 &&
       fabs(st->soil_contact_area - 0.24) < 1e-9 &&
       fabs(st->soil_normal_force - 20 * 9.81) < 2.0 && st->sweeps + st->newton >= 1 &&
       st->converged,
       "step statistics after 0.6 s: %d points, %d loaded, area %.12g m^2, "
       "normal force %.4g N, %d sweeps + %d Newton iterations", st->soil_contacts,
       st->soil_loaded, st->soil_contact_area, st->soil_normal_force, st->sweeps, st->newton);
    ss_data_free(pd);
    ss_model_free(pm);
  }
  ss_data_free(d);
  ss_model_free(m);
}

/* ---------------------------------------------------------------------- */
/* XML export at step K: the soil arrays reload bit for bit                */

static void export_reload(const char *what, const ssModel *m, int N, int K)
{
  ssError e;
  char path[600];
  tmp_path(path, sizeof path, "export.xml");
  ssData *a = ss_data_new(m), *b = ss_data_new(m);
  ssModel *m2 = NULL;
  ssData *d2 = NULL;
  int r = run(m, a, N) && run(m, b, K) && ss_scene_export(m, b, path, &e) == SS_OK &&
          ss_scene_load(path, &m2, &d2, &e) == SS_OK;
  if (!r) {
    ok(0, "%s: export and reload (%s)", what, e.message);
    goto out;
  }
  size_t nhd = (size_t)m->nhfielddata * sizeof(double);
  ok(m2->nhfielddata == m->nhfielddata && !memcmp(d2->soil_sinkage, b->soil_sinkage, nhd) &&
     !memcmp(d2->soil_plastic, b->soil_plastic, nhd) &&
     !memcmp(d2->soil_shear, b->soil_shear, nhd) &&
     !memcmp(d2->qpos, b->qpos, (size_t)m->nq * sizeof(double)) &&
     !memcmp(d2->qvel, b->qvel, (size_t)m->nv * sizeof(double)) &&
     d2->time == b->time && d2->step == b->step,
     "%s: XML export at step %d, reload: sinkage, plastic sinkage, shear, "
     "qpos, qvel and the clock equal those written, bit for bit", what, K);
  int cont = run(m2, d2, N - K);
  ok(cont && !memcmp(d2->soil_sinkage, a->soil_sinkage, nhd) &&
     !memcmp(d2->soil_plastic, a->soil_plastic, nhd) &&
     !memcmp(d2->soil_shear, a->soil_shear, nhd) &&
     !memcmp(d2->qpos, a->qpos, (size_t)m->nq * sizeof(double)),
     "%s: the reloaded world continues %d steps to the straight run's state "
     "(warm start off: the export has no solver cache)", what, N - K);
out:
  unlink(path);
  ss_data_free(a);
  ss_data_free(b);
  ss_data_free(d2);
  ss_model_free(m2);
}

static void test_export(void)
{
  ssModel *m;
  ssData *d;
  if (load_scene("plate.xml", &m, &d)) {
    ss_data_free(d);
    m->opt.terrain_warm_start = 0;
    export_reload("plate.xml", m, 150, 70);
    ss_model_free(m);
  }
  if (build_plate(41, 1.6, 110, &m, &d)) {
    ss_data_free(d);
    m->opt.terrain_warm_start = 0;
    export_reload("dragged plate", m, 140, 100);
    ss_model_free(m);
  }
}

/* The ground of an export of buggy_rigid.xml moved before the buggy, as
 * a hand-edited or another tool's file may have it (and as exports were
 * written before they kept the scene's order: scene_write.c): the rigid
 * materials are then named in another order ("concrete" before "rubber")
 * and the two models number them differently, with the same friction on
 * every contact.  A checkpoint of one restores into the other: the
 * fingerprint once hashed the indices and refused it ("these differ:
 * colliders; ground planes, contact materials ...").  A friction really
 * changed is still refused. */
static int ground_first(const char *path)
{
  FILE *fp = fopen(path, "rb");
  if (!fp) return 0;
  char buf[1 << 16];
  size_t n = fread(buf, 1, sizeof buf - 1, fp);
  fclose(fp);
  buf[n] = 0;
  char *g = strstr(buf, "    <ground "), *o = strstr(buf, "<objects>\n");
  char *ge = g ? strchr(g, '\n') : NULL;
  if (!g || !o || !ge || o > g || n == sizeof buf - 1) return 0;
  o += strlen("<objects>\n");
  ge++;
  /* objects start, the ground line, the objects before it, the rest */
  char out[1 << 16];
  size_t a = (size_t)(o - buf), gl = (size_t)(ge - g), mid = (size_t)(g - o);
  memcpy(out, buf, a);
  memcpy(out + a, g, gl);
  memcpy(out + a + gl, o, mid);
  memcpy(out + a + gl + mid, ge, n - (size_t)(ge - buf));
  return write_file(path, out, n);
}

static void test_restore_into_export(void)
{
  ssModel *m, *m2 = NULL;
  ssData *d, *d2 = NULL;
  ssError e;
  char path[600];
  tmp_path(path, sizeof path, "rigid_export.xml");
  if (!load_scene("buggy_rigid.xml", &m, &d)) {
    ok(0, "buggy_rigid.xml loads");
    return;
  }
  size_t len = 0;
  unsigned char *buf = NULL;
  int r = run(m, d, 30) && ss_scene_export(m, d, path, &e) == SS_OK && ground_first(path) &&
          ss_scene_load(path, &m2, &d2, &e) == SS_OK && (buf = snapshot(m, d, &len));
  if (!r) {
    ok(0, "buggy_rigid.xml: run, export and reload (%s)", e.message);
    goto out;
  }
  int renumbered = 0;
  for (int g = 0; g < m->ngeom && g < m2->ngeom; g++)
    renumbered |= m->geom_material[g] != m2->geom_material[g];
  ok(renumbered && m2->npair == 1 && m->npair == 1,
     "buggy_rigid.xml: its export with the ground first numbers the rigid materials "
     "differently");
  ssStatus st = ss_checkpoint_load_buffer(m2, d2, buf, len, &e);
  ok(st == SS_OK, "a checkpoint of buggy_rigid.xml at step 30 restores into that world (%s)",
     st ? e.message : "ok");
  if (st == SS_OK) {
    int ran = run(m, d, 40) && run(m2, d2, 40);
    ok(ran && !memcmp(d->qpos, d2->qpos, (size_t)m->nq * sizeof(double)) &&
       !memcmp(d->qvel, d2->qvel, (size_t)m->nv * sizeof(double)) && d->time == d2->time,
       "... and 40 steps there give the original world's 40 steps, bit for bit");
  }
  m2->pair[0].friction *= 0.5;
  st = ss_checkpoint_load_buffer(m2, d2, buf, len, &e);
  ok(st != SS_OK && strstr(e.message, "contact materials"),
     "a changed friction between the tyres and the ground is still refused (%s)",
     e.message);
out:
  free(buf);
  unlink(path);
  ss_data_free(d);
  ss_model_free(m);
  ss_data_free(d2);
  ss_model_free(m2);
}

/* The materials colliders meet on each other (contacts between bodies)
 * are in the fingerprint: two wooden boxes stacked on a concrete ground,
 * a checkpoint refused where the wood-on-wood friction differs (accepted
 * before: only the materials met on ground planes and rigid height maps
 * were hashed), restored where nothing differs. */
static void test_between_materials(void)
{
  static const char scene[] =
      "<raisim version=\"1.0\">\n"
      "  <timeStep value=\"0.001\"/>\n"
      "  <objects>\n"
      "    <ground name=\"ground\" height=\"0\" material=\"concrete\"/>\n"
      "    <box name=\"low\" mass=\"4\" material=\"wood\">\n"
      "      <dim x=\"0.4\" y=\"0.4\" z=\"0.2\"/><state pos=\"0 0 0.1\"/>\n"
      "    </box>\n"
      "    <box name=\"high\" mass=\"1\" material=\"wood\">\n"
      "      <dim x=\"0.2\" y=\"0.2\" z=\"0.1\"/><state pos=\"0 0 0.252\"/>\n"
      "    </box>\n"
      "  </objects>\n"
      "  <material>\n"
      "    <pair_prop name1=\"wood\" name2=\"concrete\" friction=\"0.7\" restitution=\"0\" "
      "restitution_threshold=\"0\"/>\n"
      "    <pair_prop name1=\"wood\" name2=\"wood\" friction=\"0.4\" restitution=\"0\" "
      "restitution_threshold=\"0\"/>\n"
      "  </material>\n"
      "</raisim>\n";
  char path[600];
  tmp_path(path, sizeof path, "between.xml");
  ssModel *m = NULL, *m2 = NULL;
  ssData *d = NULL, *d2 = NULL;
  ssError e;
  size_t len = 0;
  unsigned char *buf = NULL;
  int r = write_file(path, scene, sizeof scene - 1) &&
          ss_scene_load(path, &m, &d, &e) == SS_OK && ss_scene_load(path, &m2, &d2, &e) == SS_OK &&
          run(m, d, 50) && (buf = snapshot(m, d, &len));
  int ww = -1;
  for (int k = 0; r && k < m2->npair; k++)
    if (m2->pair[k].mat1 == m2->pair[k].mat2) ww = k;
  if (!r || ww < 0) {
    ok(0, "two wooden boxes on concrete: load, run, checkpoint (%s)", e.message);
  } else {
    ssStatus st = ss_checkpoint_load_buffer(m2, d2, buf, len, &e);
    ok(st == SS_OK, "two wooden boxes on concrete: a checkpoint restores into the same world (%s)",
       st ? e.message : "ok");
    m2->pair[ww].friction = 0.8;
    st = ss_checkpoint_load_buffer(m2, d2, buf, len, &e);
    ok(st == SS_ERR_VALUE && strstr(e.message, "contact materials"),
       "... and is refused where only the wood-on-wood friction differs (%s)",
       st ? e.message : "accepted");
  }
  free(buf);
  unlink(path);
  ss_data_free(d);
  ss_model_free(m);
  ss_data_free(d2);
  ss_model_free(m2);
}

/* A step that fails leaves everything as it was: the same checkpoint
 * bytes before and after, soil state and warm-start cache included.  Two
 * ways: the step itself blows up (gravity turned to 2e8 m/s^2 upward
 * throws the body off the soil at 2e5 m/s, past SS_SPEED_MAX, after the
 * warm start and the solve have run on its settled contacts), and a
 * state set beyond SS_SPEED_MAX between steps, refused before anything
 * is stepped. */
static void failed_step(const char *scene, int settle)
{
  ssModel *m;
  ssData *d;
  if (!load_scene(scene, &m, &d)) {
    ok(0, "failed step on %s: scene loads", scene);
    return;
  }
  ok(run(m, d, settle) && d->nwarm > 0 && d->nsoil_loaded > 0,
     "failed step on %s: %d steps settle on the soil with a warm cache", scene, settle);
  size_t la = 0, lb = 0;
  unsigned char *a = snapshot(m, d, &la), *b;
  ssError e;
  double g[3];
  memcpy(g, m->opt.gravity, sizeof g);
  m->opt.gravity[0] = m->opt.gravity[1] = 0;
  m->opt.gravity[2] = 2e8;
  ssStatus st = ss_step(m, d, &e);
  memcpy(m->opt.gravity, g, sizeof g);
  ok(st == SS_ERR_NUMERIC && strstr(e.message, "step 201 (") &&
         strstr(e.message, "became non-finite or absurd"),
     "failed step on %s: the step blows up with a numeric error (%s)", scene, e.message);
  b = snapshot(m, d, &lb);
  ok(a && b && la == lb && !memcmp(a, b, la),
     "failed step on %s: state, soil and warm cache unchanged", scene);
  free(b);
  /* and the next step runs as if the failed one had not been tried */
  ok(ss_step(m, d, &e) == SS_OK, "failed step on %s: the next step runs", scene);

  ssModel *m2 = NULL;
  ssData *d2 = NULL;
  ok(load_scene(scene, &m2, &d2) && run(m2, d2, settle + 1),
     "failed step on %s: the same steps run again without the failure", scene);
  free(a);
  a = d2 ? snapshot(m2, d2, &la) : NULL;
  b = snapshot(m, d, &lb);
  ok(a && b && la == lb && !memcmp(a, b, la),
     "failed step on %s: after it, the same bytes as a run that never failed", scene);
  free(a);
  free(b);
  ss_data_free(d2);
  ss_model_free(m2);

  /* (no checkpoint can hold this state: compared by hand) */
  for (int k = 0; k < m->nv; k++) d->qvel[k] = k < 3 ? 2e5 * (k == 2) : 0;
  size_t nb = (size_t)(m->nq + m->nv) * sizeof(double);
  long step0 = d->step;
  a = malloc(nb);
  b = malloc(nb);
  memcpy(a, d->qpos, (size_t)m->nq * sizeof(double));
  memcpy(a + (size_t)m->nq * sizeof(double), d->qvel, (size_t)m->nv * sizeof(double));
  st = ss_step(m, d, &e);
  ok(st == SS_ERR_VALUE && strstr(e.message, "velocity") &&
         strstr(e.message, "above 1e5 (m/s or rad/s) before the step"),
     "failed step on %s: a speed set past the limit is refused (%s)", scene, e.message);
  memcpy(b, d->qpos, (size_t)m->nq * sizeof(double));
  memcpy(b + (size_t)m->nq * sizeof(double), d->qvel, (size_t)m->nv * sizeof(double));
  ok(!memcmp(a, b, nb) && d->step == step0, "failed step on %s: nothing stepped", scene);
  memset(d->qvel, 0, (size_t)m->nv * sizeof(double));
  double q0 = d->qpos[0];
  d->qpos[0] = NAN;
  st = ss_step(m, d, &e);
  ok(st == SS_ERR_VALUE && strstr(e.message, "position") && strstr(e.message, "non-finite"),
     "failed step on %s: a non-finite position is refused (%s)", scene, e.message);
  d->qpos[0] = q0;
  d->hfield_pos[2] = NAN;
  st = ss_step(m, d, &e);
  ok(st == SS_ERR_VALUE && strstr(e.message, "pose of height map") &&
         strstr(e.message, "ss_hfield_set_pose"),
     "failed step on %s: a bed pose written as NaN is refused (%s)", scene, e.message);
  d->hfield_pos[2] = m->hfield_pos0[2];
  ok(ss_step(m, d, &e) == SS_OK, "failed step on %s: with the state mended, it steps", scene);
  free(a);
  free(b);
  ss_data_free(d);
  ss_model_free(m);
}

static void test_failed_step(void)
{
  failed_step("plate.xml", 200);
  failed_step("plate_arm.xml", 200);
}

/* ---------------------------------------------------------------------- */
/* the clock's limits (README and man page, <clock>)                       */

/* scenes/plate.xml with <clock time="1" step="STEP"/> after its
 * <timeStep>, read as the scene reader reads a file */
static int load_plate_at(long step, ssModel **m, ssData **d)
{
  char path[512], clock[96];
  snprintf(path, sizeof path, "%s/scenes/plate.xml", srcdir());
  snprintf(clock, sizeof clock, "<clock time=\"1\" step=\"%ld\"/>", step);
  FILE *f = fopen(path, "rb");
  char *xml = f ? malloc(1 << 20) : NULL, *out = xml ? malloc((1 << 20) + 128) : NULL;
  size_t n = out ? fread(xml, 1, (1 << 20) - 1, f) : 0;
  if (f) fclose(f);
  const char *ts = "<timeStep value=\"0.001\"/>";
  char *at = n ? (xml[n] = 0, strstr(xml, ts)) : NULL;
  ssError e;
  int r = 0;
  if (at) {
    size_t head = (size_t)(at - xml) + strlen(ts);
    memcpy(out, xml, head);
    strcpy(out + head, clock);
    memcpy(out + head + strlen(clock), xml + head, n - head);
    r = ss_scene_load_buffer(out, n + strlen(clock), path, m, d, &e) == SS_OK;
    if (!r) diag("plate.xml with %s: %s", clock, e.message);
  } else {
    diag("cannot read %s or find its %s", path, ts);
  }
  free(xml);
  free(out);
  return r;
}

/* A <clock> 7 steps short of the step counter's limit (LONG_MAX, the
 * largest step the scene and checkpoint readers take): 7 steps run, the
 * next is refused with nothing changed (the counter would overflow), and
 * the checkpoint and the export of the state at the limit read back with
 * its clock.  The time stays finite (at DBL_MAX a step adds nothing it
 * cannot hold), and a clock set outside what <clock> allows is refused
 * before a step and by the checkpoint writer. */
static void test_step_limit(void)
{
  ssModel *m = NULL, *m2 = NULL;
  ssData *d = NULL, *c = NULL, *d2 = NULL;
  if (!load_plate_at(LONG_MAX - 7, &m, &d)) {
    ok(0, "plate.xml with a clock at step LONG_MAX - 7 loads");
    return;
  }
  int r = run(m, d, 7);
  ok(r && d->step == LONG_MAX && d->time > 1,
     "a <clock> 7 steps short of the limit: 7 steps run (step %ld, t = %.6g s)",
     d->step, d->time);
  size_t la = 0, lb = 0;
  unsigned char *a = snapshot(m, d, &la), *b;
  ssError e;
  ss_error_clear(&e);
  ssStatus st = ss_step(m, d, &e);
  b = snapshot(m, d, &lb);
  ok(st == SS_ERR_STATE && strstr(e.message, "step counter is at its maximum") &&
         strstr(e.message, "nothing was stepped") && a && b && la == lb &&
         !memcmp(a, b, la),
     "at step LONG_MAX the next step is refused, nothing changed (%s)", e.message);
  free(b);

  c = ss_data_new(m);
  ok(a && c && ss_checkpoint_load_buffer(m, c, a, la, &e) == SS_OK && identical(m, d, c) &&
         ss_step(m, c, &e) == SS_ERR_STATE,
     "the checkpoint at the limit restores and refuses to step on too");
  char path[600];
  tmp_path(path, sizeof path, "limit.xml");
  r = ss_scene_export(m, d, path, &e) == SS_OK &&
      ss_scene_load(path, &m2, &d2, &e) == SS_OK;
  ok(r && d2->step == LONG_MAX && d2->time == d->time &&
         ss_step(m2, d2, &e) == SS_ERR_STATE,
     "its export reloads with the clock written (step %ld) and refuses to step on",
     r ? d2->step : -1);
  unlink(path);

  /* the time */
  ss_data_reset(m, c);
  c->time = DBL_MAX;
  ok(run(m, c, 2) && c->time == DBL_MAX && c->step == 2,
     "a clock at t = DBL_MAX steps and its time stays finite");
  ss_data_reset(m, c);
  c->time = -1;
  st = ss_step(m, c, &e);
  ok(st == SS_ERR_VALUE && strstr(e.message, "clock") && c->step == 0 && c->time == -1,
     "a negative time set between steps is refused (%s)", e.message);
  unsigned char *bad = NULL;
  size_t nbad = 0;
  ok(ss_checkpoint_save_buffer(m, c, &bad, &nbad, &e) == SS_ERR_VALUE && !bad &&
         strstr(e.message, "clock"),
     "and no checkpoint holds it (%s)", e.message);
  free(a);
  ss_data_free(c);
  ss_data_free(d);
  ss_model_free(m);
  ss_data_free(d2);
  ss_model_free(m2);
}

/* A forged-checkpoint case: scene run for `steps` steps and checkpointed
 * (good, n bytes), and two more data of it run `settle` steps, the one a
 * forged file is loaded into (d2) and its twin, which shows that a
 * refused load leaves d2 as it was (forge_open: 0 where any of it
 * failed; forge_close frees what there is) */
typedef struct Forge {
  ssModel *m;
  ssData *d, *d2, *twin;
  unsigned char *good;
  size_t n;
} Forge;

static int forge_open(const char *scene, int steps, int settle, Forge *f)
{
  memset(f, 0, sizeof *f);
  if (!load_scene(scene, &f->m, &f->d)) return 0;
  f->good = run(f->m, f->d, steps) ? snapshot(f->m, f->d, &f->n) : NULL;
  f->d2 = ss_data_new(f->m);
  f->twin = ss_data_new(f->m);
  return f->good && f->d2 && f->twin && run(f->m, f->d2, settle) &&
         run(f->m, f->twin, settle);
}

static void forge_close(Forge *f)
{
  free(f->good);
  ss_data_free(f->twin);
  ss_data_free(f->d2);
  ss_data_free(f->d);
  ss_model_free(f->m);
}

/* A checkpoint forged with a correct checksum but a clock the scene
 * reader would refuse (time negative or not finite; the step count is
 * checked by the forge table above) is refused as corrupted with a
 * message naming the clock, by the loader and by the info reader, the
 * data unchanged: its export could not be read back. */
static void test_forged_clock(void)
{
  Forge f;
  int good = forge_open("plate.xml", 20, 20, &f);
  ssModel *m = f.m;
  size_t n = f.n, at = good ? find_section(f.good, n, "CLCK") : 0;
  unsigned char *p = at ? malloc(n) : NULL;
  if (!p) {
    ok(0, "forged clocks: a checkpoint of plate.xml with a clock section");
    forge_close(&f);
    return;
  }
  const double times[] = {-1.0, -1e-300, -INFINITY, NAN};
  int refused = 0, named = 0, info = 0;
  for (int k = 0; k < 4; k++) {
    memcpy(p, f.good, n);
    uint64_t bits;
    memcpy(&bits, &times[k], 8);
    put(p + at + 16, bits, 8);
    reseal(p, n);
    ssError e;
    ssCheckpointInfo ci;
    ss_error_clear(&e);
    refused += ss_checkpoint_load_buffer(m, f.d2, p, n, &e) == SS_ERR_PARSE;
    named += strstr(e.message, "clock time") && strstr(e.message, "finite and >= 0");
    diag("forged time %g: %s", times[k], e.message);
    info += ss_checkpoint_info_buffer(p, n, &ci, &e) == SS_ERR_PARSE;
  }
  ok(refused == 4 && named == 4 && info == 4 && same_state(m, f.d2, f.twin),
     "checkpoints with a correct checksum and a time of -1, -1e-300, -inf or NaN "
     "are refused as corrupted, naming the clock, data unchanged (%d, %d, %d)",
     refused, named, info);
  free(p);
  forge_close(&f);
}

/* good (n bytes) with section tag's payload replaced by the plen bytes
 * at pl, the sizes and checksums made right again; its length in *len
 * (caller frees; NULL when there is no such section) */
static unsigned char *with_section(const unsigned char *good, size_t n, const char *tag,
                                   const void *pl, size_t plen, size_t *len)
{
  size_t at = find_section(good, n, tag);
  if (!at) return NULL;
  size_t old = (size_t)le(good + at + 8, 8), tail = n - (at + 16 + old);
  *len = at + 16 + plen + tail;
  unsigned char *p = malloc(*len);
  if (!p) return NULL;
  memcpy(p, good, at + 16);
  put(p + at + 8, plen, 8);
  if (plen) memcpy(p + at + 16, pl, plen);
  memcpy(p + at + 16 + plen, good + at + 16 + old, tail);
  put(p + 16, *len, 8);
  reseal(p, *len);
  return p;
}

/* A checkpoint whose list of loaded vertices leaves out vertices that
 * hold elastic sinkage (the settled plate's 651, here all of them) is
 * refused.  It was accepted, and once the plate was lifted those vertices
 * kept their elastic sinkage for ever: only listed vertices recover
 * (the plate's whole imprint 8.175 mm deep instead of its 7.766 mm rut),
 * a state no run reaches and which the world's export, read back with
 * the list rebuilt, does not keep. */
static void test_forged_soil_list(void)
{
  Forge f;
  int opened = forge_open("plate.xml", 300, 5, &f);
  ssModel *m = f.m;
  ssData *d = f.d, *d2 = f.d2, *twin = f.twin;
  unsigned char *good = f.good;
  size_t n = f.n, len = 0;
  unsigned char *p = opened ? with_section(good, n, "LOAD", NULL, 0, &len) : NULL;
  if (!p) {
    ok(0, "forged loaded-vertex list: a checkpoint of the settled plate");
    goto out;
  }
  int elastic = 0;
  for (int k = 0; k < m->nhfielddata; k++) elastic += d->soil_sinkage[k] > d->soil_plastic[k];
  ssError e;
  ss_error_clear(&e);
  ssStatus st = ss_checkpoint_load_buffer(m, d2, p, len, &e);
  ok(elastic > 500 && st == SS_ERR_PARSE && strstr(e.message, "loaded-vertex list") &&
     same_state(m, d2, twin),
     "a checkpoint whose loaded-vertex list leaves out the %d vertices with elastic "
     "sinkage is refused, data unchanged (%s)", elastic, st ? e.message : "accepted");
  /* the real one restores, and its vertices recover once the plate goes */
  ssStatus st2 = ss_checkpoint_load_buffer(m, d2, good, n, &e);
  int left = -1;
  if (st2 == SS_OK && ss_remove(m, d2, "plate", &e) == SS_OK && run(m, d2, 1)) {
    left = 0;
    for (int k = 0; k < m->nhfielddata; k++) left += d2->soil_sinkage[k] > d2->soil_plastic[k];
  }
  ok(left == 0, "the checkpoint as written restores, and with the plate lifted every "
     "vertex recovers to its rut (%d keep elastic sinkage)", left);
  /* nor is such a state written: sinkage put into the data directly (not
   * through ss_soil_set_state, which lists the vertex) on a vertex far
   * from the plate */
  {
    int far = 0, h = ss_model_find_hfield(m, "soil");
    double keep = d2->soil_sinkage[far];
    d2->soil_sinkage[far] = d2->soil_plastic[far] + 1e-3;
    unsigned char *b = NULL;
    size_t bl = 0;
    ss_error_clear(&e);
    ssStatus sv = ss_checkpoint_save_buffer(m, d2, &b, &bl, &e);
    ok(sv == SS_ERR_STATE && strstr(e.message, "ss_soil_set_state") && !b,
       "a state with elastic sinkage on a vertex the data does not list is not "
       "written (%s)", sv ? e.message : "written");
    free(b);
    double *z = calloc((size_t)m->nhfielddata, sizeof(double));
    int set = z && h >= 0 && ss_soil_get_state(m, d2, h, z, NULL, NULL, &e) == SS_OK &&
              ss_soil_set_state(m, d2, h, z, NULL, NULL, &e) == SS_OK;
    b = NULL;
    ok(set && ss_checkpoint_save_buffer(m, d2, &b, &bl, &e) == SS_OK &&
       ss_checkpoint_load_buffer(m, twin, b, bl, &e) == SS_OK,
       "the same sinkage set with ss_soil_set_state is written and restores");
    free(b);
    free(z);
    d2->soil_sinkage[far] = keep;
  }
out:
  free(p);
  forge_close(&f);
}

/* A checkpoint whose Newton records (the next steps start from 2 c_1 -
 * c_2) hold finite but absurd values, 1e200 and -1e200, is refused.  It
 * was accepted, and the second step after the restore failed ("the
 * velocity of 'plate' became non-finite or absurd"): the Newton phase's
 * start overflowed. */
static void test_forged_newton(void)
{
  Forge f;
  int opened = forge_open("plate_arm.xml", 120, 5, &f);
  ssModel *m = f.m;
  ssData *d2 = f.d2, *twin = f.twin;
  unsigned char *good = f.good;
  size_t n = f.n, at = opened ? find_section(good, n, "NEWT") : 0;
  unsigned char *p = at ? malloc(n) : NULL;
  int n0 = at ? (int)le(good + at + 16 + 16, 4) : 0;
  if (!p || n0 <= 0) {
    ok(0, "forged Newton records: a checkpoint of plate_arm.xml with them");
    goto out;
  }
  memcpy(p, good, n);
  size_t r1 = at + 16 + 20 + 8 * (size_t)n0;
  int n1 = (int)le(p + r1 + 16, 4);
  const double big = 1e200, neg = -1e200;
  uint64_t bb, bn;
  memcpy(&bb, &big, 8);
  memcpy(&bn, &neg, 8);
  for (int a = 0; a < n0; a++) put(p + at + 16 + 20 + 8 * (size_t)a, bb, 8);
  for (int a = 0; a < n1; a++) put(p + r1 + 20 + 8 * (size_t)a, bn, 8);
  reseal(p, n);
  ssError e;
  ss_error_clear(&e);
  ssStatus st = ss_checkpoint_load_buffer(m, d2, p, n, &e);
  ok(st == SS_ERR_PARSE && strstr(e.message, "NEWT") && same_state(m, d2, twin),
     "a checkpoint whose Newton records hold 1e200 and -1e200 (%d and %d values) is "
     "refused, data unchanged (%s)", n0, n1, st ? e.message : "accepted");
  /* the real one restores and steps */
  st = ss_checkpoint_load_buffer(m, d2, good, n, &e);
  ok(st == SS_OK && run(m, d2, 5), "the checkpoint as written restores and steps");
out:
  free(p);
  forge_close(&f);
}

/* A soil material edited between steps (a supported use: test_plate's
 * power tables) into one ss_model_validate refuses: ss_step refuses it
 * with the same message, before anything is stepped (DESIGN 2.5), and
 * once mended the world steps on as if the edit had never been made. */
/* An invalid value v written into *p between steps (a field named field):
 * into counts, whether the step is refused (SS_ERR_VALUE, as
 * ss_model_validate finds it invalid), says ss_model_validate's message,
 * the field and "nothing was stepped", and leaves the world's bytes as
 * they were; *p is put back after */
static void edited_step(ssModel *m, ssData *d, const char *field, double *p, double v,
                        int counts[3])
{
  double keep = *p;
  *p = v;
  ssError ev, e;
  ss_error_clear(&e);
  int invalid = ss_model_validate(m, &ev) == SS_ERR_VALUE;
  size_t la = 0, lb = 0;
  unsigned char *a = snapshot(m, d, &la), *b;
  ssStatus st = ss_step(m, d, &e);
  b = snapshot(m, d, &lb);
  counts[0] += invalid && st == SS_ERR_VALUE;
  counts[1] += invalid && strstr(e.message, ev.message) && strstr(e.message, field) &&
               strstr(e.message, "nothing was stepped");
  counts[2] += a && b && la == lb && !memcmp(a, b, la);
  diag("%s = %g: %s", field, v, e.message);
  free(a);
  free(b);
  *p = keep;
}

static void test_edited_material(void)
{
  ssModel *m;
  ssData *d;
  if (!load_scene("plate.xml", &m, &d)) {
    ok(0, "plate.xml loads");
    return;
  }
  ssSoilMaterial *mat = &m->hfield_soilmat[0];
  const struct {
    const char *field;
    double *p, v;
  } edit[] = {
    {"damping", &mat->damping, -1e5},
    {"bekker_kphi", &mat->bekker_kphi, -1e3},
    {"bekker_kphi", &mat->bekker_kphi, 0}, /* k_c is 0 too */
    {"elastic_stiffness", &mat->elastic_stiffness, 0},
    {"sinkage_exponent", &mat->sinkage_exponent, -1},
    {"cohesion", &mat->cohesion, NAN},
    {"friction_coefficient", &mat->friction_coefficient, INFINITY},
  };
  const int nedit = (int)(sizeof edit / sizeof edit[0]);
  int settled = run(m, d, 20), counts[3] = {0, 0, 0};
  for (int k = 0; k < nedit; k++) edited_step(m, d, edit[k].field, edit[k].p, edit[k].v, counts);
  ok(settled && counts[0] == nedit && counts[1] == nedit && counts[2] == nedit,
     "%d soil materials edited between steps into invalid ones: each step "
     "refused with ss_model_validate's message, nothing changed (%d, %d, %d)",
     nedit, counts[0], counts[1], counts[2]);
  /* the options likewise (a time step of 0 stepped nothing forward and
   * NaN filled the state; a tolerance of 2 passed every step unsolved) */
  const struct {
    const char *field;
    double *p, v;
  } oedit[] = {
    {"time step", &m->opt.timestep, 0},
    {"time step", &m->opt.timestep, NAN},
    {"time step", &m->opt.timestep, 2},
    {"tolerance", &m->opt.solver_tolerance, 2},
    {"scalar_tolerance", &m->opt.scalar_tolerance, 0},
    {"gravity", &m->opt.gravity[2], INFINITY},
    {"contact_margin", &m->opt.contact_margin, -1},
    {"rigid_erp", &m->opt.rigid_erp, 2},
  };
  const int noedit = (int)(sizeof oedit / sizeof oedit[0]);
  int ocounts[3] = {0, 0, 0};
  for (int k = 0; k < noedit; k++)
    edited_step(m, d, oedit[k].field, oedit[k].p, oedit[k].v, ocounts);
  ok(ocounts[0] == noedit && ocounts[1] == noedit && ocounts[2] == noedit,
     "%d options edited between steps into invalid ones: each step refused "
     "with ss_model_validate's message, nothing changed (%d, %d, %d)", noedit,
     ocounts[0], ocounts[1], ocounts[2]);
  ssModel *m2 = NULL;
  ssData *d2 = NULL;
  size_t la = 0, lb = 0;
  unsigned char *a = NULL, *b = NULL;
  if (run(m, d, 10) && load_scene("plate.xml", &m2, &d2) && run(m2, d2, 30)) {
    a = snapshot(m, d, &la);
    b = snapshot(m2, d2, &lb);
  }
  ok(a && b && la == lb && !memcmp(a, b, la),
     "the material mended, the world steps on bit for bit as if never edited");
  free(a);
  free(b);
  ss_data_free(d2);
  ss_model_free(m2);
  ss_data_free(d);
  ss_model_free(m);
}


/* Mesh bodies (ss_model_add_body, SS_GEOM_MESH): the box-shaped mesh of
 * cube.obj settling on a soil bed and an octahedron rock (its rigid
 * contacts at its lowest vertices, warm started by vertex) dropped on a
 * ground plane below the bed: a checkpoint replays bit for bit, and an
 * XML export reloads to the same run. */
static void test_mesh_bodies(void)
{
  char cube[1024], octa[1024];
  snprintf(cube, sizeof cube, "%s/tests/data/urdf/meshes/cube.obj", srcdir());
  snprintf(octa, sizeof octa, "%s/tests/data/urdf/meshes/octa.obj", srcdir());
  ssError e;
  ssModel *m = ss_model_new();
  int ok_build = add_bed(m, 1.2, 0.02, plate_soil()) >= 0 &&
                 ss_model_add_plane(m, "ground", -0.5, NULL, 0, &e) >= 0;
  ssBodyDef bd = ss_body_def_default();
  bd.name = "slab";
  bd.shape = SS_GEOM_MESH;
  bd.mesh_path = cube;
  bd.mesh_scale[0] = 0.4;
  bd.mesh_scale[1] = 0.6;
  bd.mesh_scale[2] = 0.05;
  bd.mass = 20;
  ss_v3_set(bd.pos, 0.01, -0.02, 0.025);
  ok_build = ok_build && ss_model_add_body(m, &bd, &e) >= 0;
  bd.name = "rock";
  bd.mesh_path = octa;
  bd.mesh_scale[0] = bd.mesh_scale[1] = bd.mesh_scale[2] = 0.1;
  bd.mass = 3;
  double axis[3] = {1, 2, 0.5};
  ss_v3_normalize(axis);
  ss_quat_from_axis_angle(bd.quat, axis, 0.7);
  ss_v3_set(bd.pos, 1.5, 0, -0.3);
  ok_build = ok_build && ss_model_add_body(m, &bd, &e) >= 0;
  if (!ok(ok_build, "mesh bodies: the world builds")) {
    diag("%s", e.message);
    ss_model_free(m);
    return;
  }
  replay("mesh bodies on soil and a ground plane", m, 300, 180);
  m->opt.terrain_warm_start = 0;
  export_reload("mesh bodies", m, 300, 180);
  ss_model_free(m);
}

int main(void)
{
  const char *t = getenv("TMPDIR");
  snprintf(tmpdir, sizeof tmpdir, "%s/soilsim-ckpt.XXXXXX", t && *t ? t : "/tmp");
  if (!mkdtemp(tmpdir)) {
    printf("Bail out! mkdtemp failed\n");
    return 1;
  }
  test_soil_api();
  test_replay();
  test_replay_buggy();
  test_replay_creep();
  test_cache_matters();
  test_lazy_jacobian();
  test_state_changes();
  test_reproducible();
  test_foreign_and_mismatch();
  test_damage();
  test_rigid_cache();
  test_cache_overflow();
  test_export();
  test_restore_into_export();
  test_between_materials();
  test_mesh_bodies();
  test_failed_step();
  test_step_limit();
  test_forged_clock();
  test_forged_soil_list();
  test_forged_newton();
  test_edited_material();
  rmdir(tmpdir);
  return done_testing();
}
