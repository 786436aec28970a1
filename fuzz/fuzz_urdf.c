/* fuzz_urdf.c -- libFuzzer target: the URDF reader and the articulated
 * system built from it.
 *
 * The input is a URDF, read with ss_urdf_load_buffer as if it were
 * SRCDIR/tests/data/urdf/fuzz.urdf (so meshes/cube.obj, meshes/tetra.stl
 * and meshes/tetra.gltf resolve).  A URDF that parses is instantiated as an
 * articulated system (floating base, then again with a fixed base): mass
 * checks, mesh loading, closure resolution, the independence check of the
 * closures; then the data is made and the kinematics run once.  Any of
 * these may refuse the input; none may crash or trip a sanitizer. */
#include "fuzz_common.h"
#include "soilsim.h"
#include "articulated.h"
#include "urdf.h"

#include <stdlib.h>

/* Bound on the articulated system stepped (degrees of freedom). */
#define STEP_MAX_DOF 64

static void build(const ssUrdf *u, int fixed_base)
{
  ssModel *m = ss_model_new();
  if (!m) return;
  ssError e;
  ssArtDef def = ss_art_def_default();
  def.name = "fuzz";
  def.fixed_base = fixed_base;
  def.urdf_path = u->path;
  def.res_dir = "";
  def.pos[2] = 1;
  if (ss_model_add_articulated(m, u, &def, &e) >= 0 &&
      ss_model_validate(m, &e) == SS_OK) {
    ssData *d = ss_data_new(m);
    if (d) {
      ss_forward(m, d);
      if (m->nv <= STEP_MAX_DOF)
        for (int k = 0; k < 2; k++)
          if (ss_step(m, d, &e) != SS_OK) break;
    }
    ss_data_free(d);
  }
  ss_model_free(m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char path[] = SS_FUZZ_SRCDIR "/tests/data/urdf/fuzz.urdf";
  ssUrdf *u = NULL;
  ssError e;
  if (ss_urdf_load_buffer((const char *)data, size, path, NULL, &u, &e) != SS_OK)
    return 0;
  if (!u) abort(); /* SS_OK must return the description */
  build(u, 0);
  build(u, 1);
  ss_urdf_free(u);
  return 0;
}
