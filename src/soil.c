/* soil.c -- the soil constitutive law of DESIGN 2.3-2.5 as pure functions. */
#include "soilsim.h"
#include "terrain.h"

#include <math.h>
#include <string.h>

ssSoilMaterial ss_soil_material_default(void)
{
  ssSoilMaterial s;
  s.bekker_kc = 0.0;
  s.bekker_kphi = 4.0e4;
  s.sinkage_exponent = 1.1;
  s.elastic_stiffness = 2.0e6;
  s.damping = 2000;
  s.cohesion = 100;
  s.friction_coefficient = 0.6;
  s.shear_displacement = 0.01;
  return s;
}

ssStatus ss_soil_material_validate(const ssSoilMaterial *s, ssError *err)
{
  /* field, value, lower bound, strict (> rather than >=) */
  struct { const char *name; double v; int strict; } f[] = {
    {"bekker_kc", s->bekker_kc, 0},
    {"bekker_kphi", s->bekker_kphi, 0},
    {"sinkage_exponent", s->sinkage_exponent, 1},
    {"elastic_stiffness", s->elastic_stiffness, 1},
    {"damping", s->damping, 0},
    {"cohesion", s->cohesion, 0},
    {"friction_coefficient", s->friction_coefficient, 0},
    {"shear_displacement", s->shear_displacement, 0},
  };
  for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
    double v = f[i].v;
    if (!isfinite(v) || (f[i].strict ? !(v > 0) : !(v >= 0)))
      return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                          "soil %s = %g is invalid: must be finite and %s 0",
                          f[i].name, v, f[i].strict ? ">" : ">=");
  }
  if (!(s->bekker_kc > 0) && !(s->bekker_kphi > 0))
    return ss_error_set(err, SS_ERR_VALUE, NULL, 0,
                        "soil bekker_kc = %g and bekker_kphi = %g are invalid: "
                        "at least one must be > 0", s->bekker_kc, s->bekker_kphi);
  return SS_OK;
}

/* modulus of the envelope for width b: k_c / b + k_phi */
static double modulus(const ssSoilMaterial *s, double b)
{
  return (b > 0 ? s->bekker_kc / b : 0) + s->bekker_kphi;
}

double ss_soil_envelope(const ssSoilMaterial *s, double b, double z)
{
  if (!(z > 0)) return 0;
  double n = s->sinkage_exponent;
  return modulus(s, b) * (n == 1.0 ? z : pow(z, n));
}

double ss_soil_envelope_slope(const ssSoilMaterial *s, double b, double z)
{
  double n = s->sinkage_exponent;
  if (n == 1.0) return modulus(s, b);
  if (!(z > 0)) return n < 1 ? INFINITY : 0;
  return modulus(s, b) * n * pow(z, n - 1);
}

double ss_soil_elastic(const ssSoilMaterial *s, double z, double z_p)
{
  return s->elastic_stiffness * (z - z_p);
}

double ss_soil_pressure(const ssSoilMaterial *s, double b, double z, double z_p)
{
  if (!(z > z_p)) return 0;
  double pe = ss_soil_elastic(s, z, z_p), py = ss_soil_envelope(s, b, z);
  return pe < py ? pe : py;
}

/* the update on the envelope value py at z > z_p */
static double plastic_update(const ssSoilMaterial *s, double z, double z_p, double py)
{
  double pe = ss_soil_elastic(s, z, z_p), p = pe < py ? pe : py;
  double zp = z - p / s->elastic_stiffness;
  /* on the elastic branch z - p/K_e reproduces z_p up to round-off */
  return zp > z_p ? zp : z_p;
}

double ss_soil_plastic_update(const ssSoilMaterial *s, double b, double z,
                              double z_p)
{
  if (!(z > z_p)) return z_p;
  return plastic_update(s, z, z_p, ss_soil_envelope(s, b, z));
}

double ss_soil_plastic_update_pow(const ssSoilMaterial *s, double b, double z,
                                  double z_p, double zn1)
{
  if (!(z > z_p)) return z_p;
  return plastic_update(s, z, z_p, modulus(s, b) * (z * zn1));
}

double ss_soil_viscous(const ssSoilMaterial *s, double sdot)
{
  return sdot > 0 ? s->damping * sdot : 0;
}

double ss_soil_shear_strength(const ssSoilMaterial *s, double p_n)
{
  return s->cohesion + s->friction_coefficient * (p_n > 0 ? p_n : 0);
}

double ss_soil_shear_limit(const ssSoilMaterial *s, double p_n, double j)
{
  double tf = ss_soil_shear_strength(s, p_n);
  if (!(s->shear_displacement > 0)) return tf;
  return tf * -expm1(-(j > 0 ? j : 0) / s->shear_displacement);
}

double ss_soil_shear_limit_slope(const ssSoilMaterial *s, double p_n, double j)
{
  if (!(s->shear_displacement > 0)) return 0;
  double tf = ss_soil_shear_strength(s, p_n);
  return tf * exp(-(j > 0 ? j : 0) / s->shear_displacement) /
         s->shear_displacement;
}
