/* fuzz_mesh.c -- libFuzzer target: the mesh path (assimp import, the
 * triangle arrays, the BVH, ray casts, mass properties).
 *
 * ss_mesh_load reads a file, and assimp picks its importer from the file
 * name's extension, so the input is written to a file in a private
 * temporary folder with the extension its first bytes suggest:
 *   "solid" or a binary STL's 80-byte header + count -> .stl
 *   '{' (JSON)                                      -> .gltf
 *   '<' (XML)                                       -> .dae
 *   anything else                                   -> .obj
 * The formats are the ones DESIGN 6 names (OBJ, glTF 2.0, STL, DAE).  A
 * mesh that loads is ray cast from a few directions and integrated. */
#include "fuzz_common.h"
#include "soilsim.h"
#include "mesh.h"

#include <stdio.h>
#include <string.h>

static const char *extension_of(const uint8_t *data, size_t size)
{
  size_t i = 0;
  while (i < size && (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' ||
                      data[i] == '\n'))
    i++;
  if (size >= 5 && !memcmp(data, "solid", 5)) return "stl";
  if (size >= 84) {
    uint32_t n = (uint32_t)data[80] | (uint32_t)data[81] << 8 |
                 (uint32_t)data[82] << 16 | (uint32_t)data[83] << 24;
    if ((uint64_t)n * 50 + 84 == size) return "stl";
  }
  if (i < size && data[i] == '{') return "gltf";
  if (i < size && data[i] == '<') return "dae";
  return "obj";
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const char *dir = ss_fuzz_tmpdir();
  if (!dir) return 0;
  char path[600];
  snprintf(path, sizeof path, "%s/in.%s", dir, extension_of(data, size));
  if (ss_fuzz_write_file(path, data, size) != 0) return 0;

  /* a mirroring, non-uniform scale exercises the winding flip */
  static const double scales[2][3] = {{1, 1, 1}, {-2, 0.5, 1}};
  for (int s = 0; s < 2; s++) {
    ssMesh *m = NULL;
    ssError e;
    if (ss_mesh_load(path, scales[s], &m, &e) != SS_OK) break;
    double c[3];
    for (int a = 0; a < 3; a++) c[a] = 0.5 * (m->lo[a] + m->hi[a]);
    static const double dirs[4][3] = {
      {0, 0, -1}, {1, 0, 0}, {0.3, -0.7, 0.2}, {1e-300, 0, 1}};
    for (int k = 0; k < 4; k++) {
      double o[3], t = 0;
      for (int a = 0; a < 3; a++)
        o[a] = c[a] - dirs[k][a] * (1 + m->hi[a] - m->lo[a]);
      ss_mesh_raycast(m, o, dirs[k], &t);
      ss_mesh_raycast(m, c, dirs[k], &t);
    }
    double vol, cen[3], inertia[9];
    ss_mesh_mass_properties(m, &vol, cen, inertia);
    ss_mesh_free(m);
  }
  remove(path);
  return 0;
}
