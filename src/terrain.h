/* terrain.h -- contact generation on soil beds, rigid height maps and ground
 * planes (quadrature of DESIGN 2.6), and the soil state update after the
 * solve. */
#ifndef SS_TERRAIN_H
#define SS_TERRAIN_H

#include "soilsim.h"
#include "point.h"

/* Build d->contact for the current positions (d->ncontact). */
ssStatus ss_terrain_contacts(const ssModel *m, ssData *d, ssError *err);
/* Room in d->soil_loaded for ss_terrain_update's list of the loaded
 * vertices and its scratch (two per contact), made before the solve so
 * that a step without it fails (SS_ERR_NOMEM) with nothing changed. */
ssStatus ss_terrain_reserve(ssData *d, ssError *err);
/* After the solve: update sinkage, plastic sinkage and shear of every soil
 * vertex touched (DESIGN 3.1, last paragraph), and step statistics. */
void ss_terrain_update(const ssModel *m, ssData *d);
/* The permanent sinkage after reaching s > s_p where the envelope there
 * is py: max(s_p, s - min(p_e, py)/K_e) (on the elastic branch s - p/K_e
 * reproduces s_p up to round-off).  Inline: the soil update calls it for
 * every loaded point (ss_soil_plastic_update in soil.c shares it). */
static inline double ss_soil_plastic_from(const ssSoilMaterial *mat, double s, double s_p,
                                          double py)
{
  double pe = mat->elastic_stiffness * (s - s_p), p = pe < py ? pe : py;
  double sp = s - p / mat->elastic_stiffness;
  return sp > s_p ? sp : s_p;
}

/* ss_soil_plastic_update (soil.c) with s^(n-1) given (sn1) and the
 * modulus k = ss_soil_modulus(mat, b) (point.h), the envelope formed as
 * the law forms it, k s s^(n-1): the soil update takes the power from its
 * bed's table (solver.h) and the modulus once per width */
static inline double ss_soil_plastic_update_pow(const ssSoilMaterial *mat, double k, double s,
                                                double s_p, double sn1)
{
  if (!(s > s_p)) return s_p;
  return ss_soil_plastic_from(mat, s, s_p, k * (s * sn1));
}
/* Bed-frame <-> world transforms of height map h for the current pose. */
void ss_hfield_frame(const ssData *d, int h, double R[9], double p[3]);

#endif
