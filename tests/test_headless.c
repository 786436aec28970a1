/* test_headless.c -- the library without its renderer: a program that
 * only simulates links against src/libsoilsim.a with libxml2, assimp and
 * libpng alone (no OSMesa, EGL or FreeType: Makefile.am gives this test
 * only those), as a headless user's program does.  The link itself is the
 * test: a call from the physics or the scene reader into render.c would
 * pull in the GL libraries and the build would fail.  Then the plate of
 * DESIGN 2.7 (scenes/plate.xml) settles at its analytic sinkage. */
#include "soilsim.h"
#include "tap.h"

#include <stdlib.h>

int main(void)
{
  const char *top = getenv("top_srcdir");
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/plate.xml", top && *top ? top : ".");
  ssModel *m = NULL;
  ssData *d = NULL;
  ssError e;
  int loaded = ss_scene_load(path, &m, &d, &e) == SS_OK;
  if (!ok(loaded, "a program linked without GL loads %s", path)) {
    diag("%s:%d: %s", e.file, e.line, e.message);
    return done_testing();
  }
  int good = 1;
  for (int k = 0; k < 1500 && good; k++) good = ss_step(m, d, &e) == SS_OK;
  int plate = ss_model_find_sys(m, "plate");
  double sink = plate >= 0 ? -(d->qpos[m->sys_qadr[plate] + 2] - 0.025) : NAN;
  /* 20 kg on 0.4 x 0.6 m, k_phi 1e5, n = 1: 981/0.24/1e5 = 8.175 mm; the
   * quadrature is exact for the plate's area, so 0.1 % covers round-off
   * and the last of the damped settling */
  ok(good && fabs(sink - 8.175e-3) <= 8.175e-6,
     "and steps it: the plate settles at %.4f mm (analytic 8.175)", 1e3 * sink);
  ss_data_free(d);
  ss_model_free(m);
  return done_testing();
}
