/* soil.c -- the soil constitutive law of DESIGN 2.3-2.5 as pure functions. */
#include "soilsim.h"
#include "terrain.h"

#include <math.h>
#include <string.h>

ssSoilMaterial ss_soil_material_default(void)
{
  ssSoilMaterial mat;
  mat.bekker_kc = 0.0;
  mat.bekker_kphi = 4.0e4;
  mat.sinkage_exponent = 1.1;
  mat.elastic_stiffness = 2.0e6;
  mat.damping = 2000;
  mat.cohesion = 100;
  mat.friction_coefficient = 0.6;
  mat.shear_displacement = 0.01;
  return mat;
}

ssStatus ss_soil_material_validate(const ssSoilMaterial *mat, ssError *err)
{
  /* field, value, lower bound, strict (> rather than >=) */
  struct { const char *name; double v; int strict; } f[] = {
    {"bekker_kc", mat->bekker_kc, 0},
    {"bekker_kphi", mat->bekker_kphi, 0},
    {"sinkage_exponent", mat->sinkage_exponent, 1},
    {"elastic_stiffness", mat->elastic_stiffness, 1},
    {"damping", mat->damping, 0},
    {"cohesion", mat->cohesion, 0},
    {"friction_coefficient", mat->friction_coefficient, 0},
    {"shear_displacement", mat->shear_displacement, 0},
  };
  for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
    double v = f[i].v;
    if (!isfinite(v) || (f[i].strict ? !(v > 0) : !(v >= 0)))
      return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                          "soil %s = %g is invalid: must be finite and %s 0",
                          f[i].name, v, f[i].strict ? ">" : ">=");
  }
  if (!(mat->bekker_kc > 0) && !(mat->bekker_kphi > 0))
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "soil bekker_kc = %g and bekker_kphi = %g are invalid: "
                        "at least one must be > 0", mat->bekker_kc, mat->bekker_kphi);
  return SS_OK;
}

double ss_soil_envelope(const ssSoilMaterial *mat, double b, double s)
{
  if (!(s > 0)) return 0;
  double n = mat->sinkage_exponent;
  return ss_soil_modulus(mat, b) * (n == 1.0 ? s : pow(s, n));
}

double ss_soil_envelope_slope(const ssSoilMaterial *mat, double b, double s)
{
  double n = mat->sinkage_exponent;
  if (n == 1.0) return ss_soil_modulus(mat, b);
  if (!(s > 0)) return n < 1 ? INFINITY : 0;
  return ss_soil_modulus(mat, b) * n * pow(s, n - 1);
}

double ss_soil_elastic(const ssSoilMaterial *mat, double s, double s_p)
{
  return mat->elastic_stiffness * (s - s_p);
}

double ss_soil_pressure(const ssSoilMaterial *mat, double b, double s, double s_p)
{
  if (!(s > s_p)) return 0;
  double pe = ss_soil_elastic(mat, s, s_p), py = ss_soil_envelope(mat, b, s);
  return pe < py ? pe : py;
}

double ss_soil_plastic_update(const ssSoilMaterial *mat, double b, double s,
                              double s_p)
{
  if (!(s > s_p)) return s_p;
  return ss_soil_plastic_from(mat, s, s_p, ss_soil_envelope(mat, b, s));
}

double ss_soil_viscous(const ssSoilMaterial *mat, double sdot)
{
  return sdot > 0 ? mat->damping * sdot : 0;
}

double ss_soil_shear_strength(const ssSoilMaterial *mat, double p_n)
{
  return mat->cohesion + mat->friction_coefficient * (p_n > 0 ? p_n : 0);
}

double ss_soil_shear_limit(const ssSoilMaterial *mat, double p_n, double j)
{
  double tf = ss_soil_shear_strength(mat, p_n);
  if (!(ss_soil_janosi_inverse(mat) > 0)) return tf;
  return tf * -expm1(-(j > 0 ? j : 0) / mat->shear_displacement);
}

double ss_soil_shear_limit_slope(const ssSoilMaterial *mat, double p_n, double j)
{
  if (!(ss_soil_janosi_inverse(mat) > 0)) return 0;
  double tf = ss_soil_shear_strength(mat, p_n);
  return tf * exp(-(j > 0 ? j : 0) / mat->shear_displacement) /
         mat->shear_displacement;
}
