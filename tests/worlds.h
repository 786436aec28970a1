/* worlds.h -- worlds built in code for the tests and the benchmarks. */
#ifndef SS_TEST_WORLDS_H
#define SS_TEST_WORLDS_H

#include "soilsim.h"
#include "urdf.h"

extern const double W_X[3], W_Y[3], W_Z[3];
/* pad centres of fourpad64(), frame coordinates */
extern const double FOURPAD_CX[4], FOURPAD_CY[4];

/* an in-memory URDF (room for 64 links/joints, 16 closures and springs),
 * freed with ss_urdf_free */
ssUrdf *urdf_new(void);
int add_link(ssUrdf *u, const char *name, double m, const double com[3],
             double ix, double iy, double iz);
void add_box(ssUrdf *u, int link, double x, double y, double z,
             const double pos[3]);
int add_joint(ssUrdf *u, const char *name, int type, int parent, int child,
              const double pos[3], const double axis[3]);
/* the soil of DESIGN 2.7 (k_c 0, k_phi 1e5, n 1, K_e 2e6) with D = 1e4 so
 * the plate settles without overshoot */
ssSoilMaterial plate_soil(void);
/* a flat size x size soil bed named "bed" at spacing h: of soil, or of
 * plate_soil() */
int add_bed(ssModel *m, double size, double h, ssSoilMaterial soil);
/* The 20 kg, 0.4 x 0.6 m plate of DESIGN 2.7 just above an n x n soil bed
 * of side size (soil, or plate_soil() when NULL) that rises by slope (m)
 * along x; with pull != 0, a horizontal force pull (N) along x from t =
 * 0.03 s.  Validated, with a data; 0 on failure (why in *e). */
int plate_world(int n, double size, double slope, double pull, const ssSoilMaterial *soil,
                ssModel **m, ssData **d, ssError *e);
int add_soil_bed(ssModel *m, double size, double h);
/* the scene file rel (a path from $top_srcdir, default "."), loaded; 0
 * with a TAP diagnostic when it does not load */
int load_scene_file(const char *rel, ssModel **m, ssData **d);
/* a chain of nlinks sprung revolute joints standing on link `on` */
int add_mast(ssUrdf *u, int on, int nlinks, double mass, const double at[3]);
/* the articulated bodies of DESIGN 8, each 20 kg on 0.24 m^2 */
ssUrdf *carrier60(void);
ssUrdf *carrier60_pinned(void);
ssUrdf *fourpad64(void);
/* One step of d taken twice from the same state with `sweeps` sweeps each:
 * with the solver's packed link groups, then with the full per-contact
 * update (d->solver_full).  Returns the largest difference of the
 * end-of-step velocities relative to the largest velocity (-1 on
 * failure); d holds the full path's step.  *ncontact: its contacts. */
double solver_paths_difference(ssModel *m, ssData *d, int sweeps, int *ncontact);

/* One step of d taken twice from the same state: with the sweeps alone
 * (d->solver_gs_only; index 1 of the arrays) and with the Newton phase
 * before them (index 0).  dlam: the largest difference of the contacts'
 * impulses (1-norms) relative to the largest impulse, the measure of the
 * solver's tolerance.  d holds the Newton path's step.  0 on failure. */
typedef struct PathCompare {
  double dlam;
  int ncontact, sweeps[2], newton[2], converged[2];
} PathCompare;
int newton_paths(ssModel *m, ssData *d, PathCompare *out);

#endif
