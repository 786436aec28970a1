/* mesh.h -- triangle meshes loaded with assimp (OBJ, glTF 2.0, STL, DAE),
 * with a bounding-volume hierarchy for exact ray casts. */
#ifndef SS_MESH_H
#define SS_MESH_H

#include "soilsim.h"

/* Most footprint points a mesh keeps (ssMesh.hull): each step a mesh near a
 * soil bed projects them and takes their hull (O(n log n), its buffers on
 * the stack: ss_points_footprint), so the cap bounds that cost and that
 * room.  Convex collision meshes have fewer (PhysX allows 255 vertices,
 * V-HACD makes 64 by default); a mesh with more keeps its bounding box's
 * footprint. */
#define SS_MESH_HULL_MAX 512

typedef struct ssMesh {
  int nvert, ntri;
  double *vert;          /* (nvert x 3) in the mesh frame, scaled */
  double *normal;        /* (nvert x 3) per-vertex normals (for rendering) */
  int *tri;              /* (ntri x 3) vertex indices, counter-clockwise */
  double lo[3], hi[3];   /* bounding box */
  /* footprint points (DESIGN 2.6; terrain.c): the distinct positions among
   * the vertices that triangles use, in the order they first come, as
   * offsets from the bounding box's centre (lo + hi) / 2.  The vertices of
   * any projection's convex hull are among them.  nhull 0 (hull NULL):
   * more than SS_MESH_HULL_MAX of them, and the footprint on a bed is the
   * bounding box's */
  int nhull;
  double *hull;          /* (nhull x 3) */
  /* BVH: node k has bounds (bvh_box + 6k: lo xyz, hi xyz); internal nodes
   * have children bvh_child[2k], bvh_child[2k+1]; leaves have
   * bvh_child[2k] = -1 - first and bvh_child[2k+1] = count into bvh_tri */
  int nnode;
  double *bvh_box;
  int *bvh_child;
  int *bvh_tri;
} ssMesh;

/* Load and merge all meshes of a file (node transforms applied), scaled
 * per axis (scale NULL: 1 1 1; each value non-zero; a mirroring scale keeps
 * the winding counter-clockwise), with a BVH.  Points and lines are
 * dropped; at most 10 million triangles.  Errors name the path and what
 * assimp said; nothing is printed.  The file and every file it names (an
 * OBJ's mtllib, a glTF's buffers) are opened only when they are regular
 * files of at most 512 MiB: a FIFO or device is never waited on. */
ssStatus ss_mesh_load(const char *path, const double scale[3], ssMesh **out,
                      ssError *err);
/* Build a mesh from arrays (copies them) -- for tests and generators. */
ssStatus ss_mesh_from_arrays(const double *vert, int nvert, const int *tri,
                             int ntri, ssMesh **out, ssError *err);
void ss_mesh_free(ssMesh *m);
/* First hit of the ray o + t d (t >= 0) with the mesh: returns 1 and *t
 * (in units of |d|; d need not be unit), 0 on a miss or a zero d.  Exact
 * through the BVH: Moller-Trumbore's determinant test in the ray's sheared
 * frame, watertight on shared edges and vertices; two-sided faces; see
 * mesh.c for the tie-breaking. */
int ss_mesh_raycast(const ssMesh *m, const double o[3], const double d[3],
                    double *t);
/* Mass properties of the closed mesh as a uniform solid of density
 * 1 kg/m^3 (for inertia when a scene gives none: multiply the inertia by
 * mass / volume): volume (m^3), centroid, inertia about the centroid in
 * the mesh frame (3 x 3 row-major, kg m^2 at unit density).  Any pointer
 * may be NULL.  A mesh wound inside out gives the same (positive) result. */
void ss_mesh_mass_properties(const ssMesh *m, double *volume,
                             double centroid[3], double inertia[9]);
/* 1 when the mesh encloses a solid: every edge (between positions, so
 * that vertices split per face still join) is run by its triangles as
 * often one way as the other, i.e. a consistently wound surface without
 * border; 0 when it is open (or has no triangles), -1 out of memory.
 * Only then are ss_mesh_mass_properties' results those of a solid. */
int ss_mesh_closed(const ssMesh *m);
/* The area-weighted centroid of the surface (of a shell), for a mesh that
 * encloses no volume; the bounding box's centre when it has no area. */
void ss_mesh_surface_centroid(const ssMesh *m, double c[3]);

#endif /* SS_MESH_H */
