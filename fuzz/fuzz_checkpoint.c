/* fuzz_checkpoint.c -- libFuzzer target: the checkpoint reader.
 *
 * A checkpoint is restored into a data made for one fixed world,
 * fuzz/checkpoint_world.xml (soil bed, articulated system with a closure, a
 * coil-over and a PD, a free body), loaded once.  Each input is restored
 *   1. as it is: most mutations end at the checksum, which is what a
 *      corrupted file must do, and
 *   2. with its size field and CRC trailer made consistent with its bytes,
 *      so that the fuzzer reaches the section table, the fingerprint and
 *      every value check behind them.
 * Properties checked (the target aborts when one fails):
 *   - a refused checkpoint leaves the data exactly as it was (its own
 *     checkpoint is the same bytes before and after);
 *   - an accepted one can be stepped, saved, and the saved bytes restore
 *     again.
 *
 * Seeds: run the target with SS_FUZZ_WRITE_SEEDS=DIR and it writes
 * checkpoints of its world (fresh, after 1 step, after 40 steps, and after
 * 250, when the sphere rests on the ground: a rigid contact's entry in the
 * warm-start cache) into DIR and exits; fuzz/seed-corpus.sh does this. */
#include "fuzz_common.h"
#include "soilsim.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static ssModel *model;
static ssData *fresh;          /* the data every restore starts from */
static unsigned char *fresh_ckpt;
static size_t fresh_len;

static uint32_t crc32_ieee(const unsigned char *p, size_t n)
{
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; i++) {
    c ^= p[i];
    for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

static void die(const char *what, const ssError *e)
{
  fprintf(stderr, "fuzz_checkpoint: %s%s%s\n", what, e ? ": " : "",
          e ? e->message : "");
  abort();
}

static void write_seed(const char *dir, const char *name, const ssData *d)
{
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  ssError e;
  if (ss_checkpoint_save(model, d, path, &e) != SS_OK) die("cannot write a seed", &e);
}

int LLVMFuzzerInitialize(int *argc, char ***argv);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
  (void)argc;
  (void)argv;
  ssError e;
  ssData *d = NULL;
  if (ss_scene_load(SS_FUZZ_SRCDIR "/fuzz/checkpoint_world.xml", &model, &d,
                    &e) != SS_OK)
    die("cannot load fuzz/checkpoint_world.xml", &e);
  const char *seeds = getenv("SS_FUZZ_WRITE_SEEDS");
  if (seeds) write_seed(seeds, "fresh.ckpt", d);
  for (int k = 0; k < 40; k++) {
    if (ss_step(model, d, &e) != SS_OK) die("the world does not step", &e);
    if (seeds && k == 0) write_seed(seeds, "step1.ckpt", d);
  }
  if (seeds) {
    write_seed(seeds, "step40.ckpt", d);
    for (int k = 40; k < 250; k++)
      if (ss_step(model, d, &e) != SS_OK) die("the world does not step", &e);
    write_seed(seeds, "step250.ckpt", d);
    exit(0);
  }
  fresh = d;
  if (ss_checkpoint_save_buffer(model, fresh, &fresh_ckpt, &fresh_len, &e) != SS_OK)
    die("cannot save the world", &e);
  return 0;
}

/* Restore buf into a copy of the fresh data and check the properties. */
static void restore(const unsigned char *buf, size_t len)
{
  ssError e;
  ssData *d = ss_data_new(model);
  if (!d) return;
  if (ss_checkpoint_load_buffer(model, d, fresh_ckpt, fresh_len, &e) != SS_OK)
    die("the world's own checkpoint is refused", &e);
  ssStatus st = ss_checkpoint_load_buffer(model, d, buf, len, &e);
  unsigned char *out = NULL;
  size_t out_len = 0;
  ssError se;
  if (ss_checkpoint_save_buffer(model, d, &out, &out_len, &se) != SS_OK)
    die("cannot save after a restore", &se);
  if (st != SS_OK) {
    if (out_len != fresh_len || memcmp(out, fresh_ckpt, out_len))
      die("a refused checkpoint changed the data", &e);
  } else {
    /* restored: the saved bytes restore again, and the state steps */
    ssData *d2 = ss_data_new(model);
    if (d2 && ss_checkpoint_load_buffer(model, d2, out, out_len, &se) != SS_OK)
      die("a checkpoint saved from a restored state is refused", &se);
    ss_data_free(d2);
    for (int k = 0; k < 2; k++)
      if (ss_step(model, d, &e) != SS_OK) break;
  }
  free(out);
  ss_data_free(d);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  restore(data, size);
  /* the same bytes with a consistent size field and CRC trailer */
  if (size >= 40) {
    unsigned char *b = malloc(size);
    if (!b) return 0;
    memcpy(b, data, size);
    for (int k = 0; k < 8; k++) b[16 + k] = (unsigned char)((uint64_t)size >> (8 * k));
    memcpy(b + size - 8, "CRC ", 4);
    uint32_t c = crc32_ieee(b, size - 4);
    for (int k = 0; k < 4; k++) b[size - 4 + k] = (unsigned char)(c >> (8 * k));
    restore(b, size);
    free(b);
  }
  return 0;
}
