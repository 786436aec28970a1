/* fuzz_scene.c -- libFuzzer target: the world XML reader.
 *
 * The input is a scene file, read with ss_scene_load_buffer as if it were
 * SRCDIR/scenes/fuzz.xml (so [THIS_DIR]/../assets/... reaches the real
 * URDFs).  A scene that loads is then, when it is small enough to be quick,
 *   - stepped a few times (ss_step may fail, e.g. SS_ERR_NUMERIC, but must
 *     not crash or trip a sanitizer), and
 *   - exported and read back: whatever the reader accepts, the writer must
 *     write in a form the reader accepts again (names with quotes or '<',
 *     extreme numbers, every height-map form).
 * A failed round trip is a bug: the target aborts with both messages. */
#include "fuzz_common.h"
#include "soilsim.h"

#include <stdio.h>
#include <stdlib.h>

/* Work bounds for the optional stages (loading itself is always done).
 * STEP_MAX_SWEEPS caps the scene's own sweep cap while stepping (a scene
 * may ask for 10^6): the solver's paths are the same, each step's work is
 * bounded, and a slow but legitimate input is not taken for a hang.  (Its
 * first case: the buggy of buggy_rigid.xml 4.6 m under its ground plane,
 * every candidate point of every collider loaded and each wheel's block
 * of 16 contacts cycling through its states, 0.2 s a step at 200 sweeps
 * in the optimized build and over the 10 s limit for 3 steps under the
 * sanitizers; README, Decisions, the push.) */
#define STEP_MAX_VERTICES 20000
#define STEP_MAX_BODIES 64
#define STEP_MAX_SWEEPS 20
#define STEPS 3

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char path[] = SS_FUZZ_SRCDIR "/scenes/fuzz.xml";
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  if (ss_scene_load_buffer((const char *)data, size, path, &m, &d, &e) != SS_OK)
    return 0;
  if (!m || !d) abort(); /* SS_OK must return the world */

  if (m->nhfielddata <= STEP_MAX_VERTICES && m->nbody <= STEP_MAX_BODIES) {
    /* export and read back before stepping (the state is as loaded) */
    const char *dir = ss_fuzz_tmpdir();
    if (dir) {
      char out[600];
      snprintf(out, sizeof out, "%s/export.xml", dir);
      ssError we;
      if (ss_scene_export(m, d, out, &we) == SS_OK) {
        ssModel *m2 = NULL;
        ssData *d2 = NULL;
        ssError re;
        if (ss_scene_load(out, &m2, &d2, &re) != SS_OK) {
          fprintf(stderr, "fuzz_scene: an exported scene does not load again: "
                  "%s:%d: %s\n", re.file, re.line, re.message);
          abort();
        }
        ss_data_free(d2);
        ss_model_free(m2);
      }
    }
    if (m->opt.solver_max_sweeps > STEP_MAX_SWEEPS) m->opt.solver_max_sweeps = STEP_MAX_SWEEPS;
    for (int k = 0; k < STEPS; k++)
      if (ss_step(m, d, &e) != SS_OK) break;
  }
  ss_data_free(d);
  ss_model_free(m);
  return 0;
}
