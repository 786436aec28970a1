/* scene.h -- internal interface of the scene module: world XML in and out
 * (scene_read.c, scene_write.c) and the height-map sources behind the
 * non-explicit <heightmap> forms (hfield_source.c).  The public entry points
 * are ss_scene_load, ss_scene_load_buffer and ss_scene_export in soilsim.h.
 *
 * ---------------------------------------------------------------------------
 * World XML accepted by the reader (DESIGN 4.1)
 *
 * Names.  Every element and attribute name may be written in snake_case or
 * camelCase: an upper-case letter stands for '_' plus its lower-case form
 * (xSize = x_size, centerX = center_x, linVel = lin_vel, bodyType =
 * body_type, articulatedSystem = articulated_system, pairProp = pair_prop).
 * Nothing else: a camelCase name starts with a lower-case letter and has no
 * '_' and no two capitals in a row, so Box, TimeStep, x_Size and MASS are
 * unknown names.  `timestep` is a third spelling of time_step.  Giving one attribute twice
 * in two spellings is an error.  Unknown elements and attributes are errors;
 * so is non-blank text inside an element.  Comments are ignored.
 *
 * Values.  Numbers are decimal (C locale whatever the process locale): an
 * optional sign, digits, an optional fraction and exponent; NaN, infinity,
 * hexadecimal, overflow (1e999) and trailing characters are errors (values
 * that underflow to a subnormal or zero are accepted, so that every double
 * written by the exporter reads back exactly).  Integers are plain decimal
 * digits.  Vectors separate their values by white space or by one comma
 * (with optional white space around it).  Booleans are true/false/1/0.
 * Quaternions are w x y z; a zero quaternion is an error; others are
 * normalised (one already of unit length to 1e-14 is kept bit for bit).
 * Paths (png, text, urdf_path, res_dir) may contain [THIS_DIR], the folder
 * of the scene file; a relative path without it is taken relative to the
 * scene file's folder.  The model keeps the URDF and resource folder of an
 * articulated system as absolute, normalised paths (ss_scene_path_absolute),
 * so that the export can write them relative to its own folder.
 *
 * Structure (R = required attribute; others optional, default in brackets):
 *
 *   <raisim version>                                 root element
 *     <time_step value=R/>                           (also timeStep, timestep)
 *     <gravity value="x y z"R/>                      [0 0 -9.81]
 *     <contact_solver max_sweeps tolerance scalar_tolerance
 *                     terrain_warm_start contact_margin rigid_erp/>
 *                                     extension: ssOption fields, defaults of
 *                                     ss_option_default()
 *     <clock time step/>              extension: simulated time (s) [0] and
 *                                     completed steps [0]; written by export
 *     <camera pos=R look_at=R fov_deg [45] follow/>  follow names a body
 *     <objects>
 *       <ground name=R height [0] material [default]/>
 *       <box|sphere|cylinder|capsule name=R mass=R(dynamic; static: optional,
 *            > 0) material body_type [dynamic|static] rgba="r g b a" (each
 *            in [0, 1], a > 0)>   (a static body: no velocity, no external
 *            force)
 *         <dim .../>R   box: x y z (full edges); sphere: radius;
 *                       cylinder, capsule: radius height (along local z)
 *         <state pos [0 0 0] quat [1 0 0 0] lin_vel [0] ang_vel [0]/>
 *         <inertia xx=R yy=R zz=R xy [0] xz [0] yz [0]/>
 *         <external_force force [0] torque [0] start [0] end [+inf]/>  (0..n)
 *       </box>
 *       <heightmap name=R center_x [0] center_y [0] material pos [0 0 0]
 *                  quat [1 0 0 0] + one of the four forms below>
 *         <soil .../>   optional: makes the map a soil bed
 *       </heightmap>
 *       <articulated_system name=R urdf_path=R res_dir base [floating|fixed]
 *            material>   (read_articulated: a URDF, urdf.h)
 *         <state qpos qvel pos quat reference_qpos/>   (a floating base's pose
 *                       from qpos or from pos quat, not both)
 *         <pd joint=R p_gain d_gain position_target velocity_target
 *             effort_limit/>   (0..64, at most one per joint)
 *       </articulated_system>
 *       <mesh name=R mass=R file_name=R scale [1] material body_type rgba>
 *         (read_body: a rigid body of a mesh file, ss_mesh_load; no <dim>;
 *         file_name relative or with [THIS_DIR], kept absolute; scale one
 *         value or x y z, each non-zero; the body frame has the file's
 *         axes, its origin at the enclosed solid's centroid, so state pos
 *         is the centre of mass; a mesh enclosing no volume needs
 *         <inertia>)
 *         <state/> <inertia/> <external_force/>   as for <box>
 *       </mesh>
 *     </objects>
 *     <material>
 *       <default friction [0.8] restitution [0] restitution_threshold [0]/>
 *       <pair_prop name1=R name2=R friction=R restitution [0]
 *                  restitution_threshold [0]/>                       (0..n)
 *     </material>
 *   </raisim>
 *
 * Each child of <raisim> may appear at most once, and so may <dim>, <state>,
 * <inertia>, <soil> and <terrain_properties> inside their parents.
 *
 * Height-map forms (exactly one per <heightmap>):
 *   explicit   x_size=R y_size=R x_sample=R y_sample=R (or x_samples,
 *              y_samples) height="nx*ny values"R, vertex (i, j) at index
 *              j*nx + i, j = 0 on the -y edge (DESIGN 2.1).
 *   png        png="file"R x_size=R y_size=R z_scale [1] z_offset [0]:
 *              nx, ny = image width, height; height = z_offset + z_scale *
 *              grey, grey in [0, 1] (colour converted to luminance, 16-bit
 *              kept).  Image row 0 (the top of the picture) is the +y edge
 *              (the far side) and image column 0 the -x edge, so the picture
 *              looks like the bed seen from above with +x right, +y up.
 *   text       text="file"R x_size=R y_size=R: a text file of numbers
 *              separated by white space or by one comma (",," or a comma
 *              before the first or after the last number is an empty
 *              value, an error, as in vectors), '#' starting a comment
 *              that runs to the end of the line (a UTF-8 byte order mark
 *              at the start is skipped).  The first two numbers
 *              are the integers nx ny (by convention the first line), then
 *              nx*ny heights in the order of `height` (x fastest, first row
 *              on the -y edge).
 *   generated  a child <terrain_properties x_size=R y_size=R x_samples=R
 *              y_samples=R (or x_sample, y_sample) frequency [0.2]
 *              z_scale [1] fractal_octaves [5] fractal_lacunarity [2]
 *              fractal_gain [0.5] seed [0] height_offset [0]
 *              step_size [0]/>: deterministic fractal Perlin noise, see
 *              ss_terrain_generate.
 *
 * <soil> takes the eight material attributes of DESIGN 2.5 (bekker_kc,
 * bekker_kphi, sinkage_exponent, elastic_stiffness, damping, cohesion,
 * friction_coefficient, shear_displacement; missing ones take
 * ss_soil_material_default()) and optionally the state arrays sinkage,
 * plastic_sinkage and shear (nx*ny values each, order of `height`), applied
 * with ss_soil_set_state.
 *
 * Safety.  The file is at most SS_SCENE_MAX_BYTES, checked before parsing.
 * Any DOCTYPE is refused: the parser is stopped at the DOCTYPE declaration
 * itself, before its internal subset (entity declarations) is read, so no
 * entity is ever declared, expanded or fetched.  On top of that the parser
 * runs without XML_PARSE_NOENT, XML_PARSE_DTDLOAD or network access
 * (XML_PARSE_NONET), and a deny-by-default external entity loader is
 * installed while it runs.  XML_PARSE_HUGE is set because exported soil
 * beds carry attribute values above libxml2's 10 MB default (a 1601 x 601
 * bed writes about 23 MB per state array); the limits it lifts guard
 * against entity amplification and unbounded input, and both are excluded
 * here (no DOCTYPE, size cap).  libxml2's own messages are captured with a
 * structured error handler and reported with the scene path and line; the
 * library never prints.  The handlers are process-global in libxml2 2.9, so
 * loading is not safe to run concurrently with other libxml2 users.
 *
 * Errors.  Every error carries file = the scene path (as given) and line =
 * the line of the element at fault (where its start tag begins; for a bad
 * number, the line the number stands on, which in an attribute over many
 * lines is a later one; for stray text, the line of the text), and a
 * message naming the object, element or attribute and what is allowed.  Nothing is returned on error.
 * ---------------------------------------------------------------------------
 */
#ifndef SS_SCENE_H
#define SS_SCENE_H

#include "soilsim.h"

#include <locale.h>
#include <stdint.h>

/* Largest scene (and height-map text file) read, in bytes: 512 MiB. */
#define SS_SCENE_MAX_BYTES (512L * 1024 * 1024)

/* Read a whole regular file (at most max_bytes) into a malloc'd,
 * NUL-terminated buffer.  Errors name `path` (line 0). */
ssStatus ss_read_file(const char *path, long max_bytes, char **buf,
                      size_t *len, ssError *err);

/* Parse one decimal number occupying exactly [s, end) (C locale; NaN, Inf,
 * hexadecimal, overflow and junk refused).  Returns 0 on success, 1 when it
 * is not a number, 2 when it overflows.  The caller must have the C numeric
 * locale in effect (ss_scene_c_locale_push). */
int ss_scene_parse_double(const char *s, const char *end, double *out);
/* Strict decimal integer in [s, end) (optional sign, digits only). Returns
 * 0, 1 (not an integer) or 2 (out of range of long). */
int ss_scene_parse_long(const char *s, const char *end, long *out);

/* Switch the calling thread to the C locale (numbers read and written with
 * '.') and back.  push returns 0, or -1 when no C locale object could be
 * made (then the process locale's decimal point must already be '.'). */
typedef struct ssCLocale {
  locale_t loc, old;
} ssCLocale;
int ss_scene_c_locale_push(ssCLocale *l);
void ss_scene_c_locale_pop(ssCLocale *l);
/* push for a reader of `path`: SS_OK (also when no C locale object could
 * be made but the decimal point is already '.'), or SS_ERR_STATE in *err.
 * Undo with pop either way. */
ssStatus ss_scene_c_locale_begin(ssCLocale *l, const char *path, ssError *err);

/* The folder of path into dir[cap]: "." for a bare name, "/" at the root. */
void ss_scene_path_dir(const char *path, char *dir, size_t cap);
/* path as an absolute, normalised path into out[cap] (ss_path_absolute,
 * soilsim.h).  Returns 0, or -1 when it does not fit or memory runs out. */
int ss_scene_path_absolute(const char *path, char *out, size_t cap);
/* The absolute path target as seen from the absolute folder dir (both
 * normalised, as ss_scene_path_absolute makes them): "../" as needed, then
 * the rest of target ("." when they are the same).  Returns -1, leaving
 * out unspecified, when they share nothing but the root (the caller then
 * keeps target absolute) or it does not fit. */
int ss_scene_path_relative(const char *target, const char *dir, char *out,
                           size_t cap);

/* ---------------------------------------------------------------------- */
/* height-map sources (hfield_source.c)                                    */

/* Parameters of a generated terrain (<terrain_properties>). */
typedef struct ssTerrainProps {
  double x_size, y_size;     /* (m) */
  int x_samples, y_samples;  /* vertex counts >= 2 */
  double frequency;          /* noise lattice cells per metre of the first
                                octave (1/m) */
  double z_scale;            /* amplitude of the first octave (m) */
  int fractal_octaves;       /* octaves summed, 0..16 (0: flat) */
  double fractal_lacunarity; /* frequency factor between octaves */
  double fractal_gain;       /* amplitude factor between octaves */
  uint32_t seed;             /* selects the noise pattern */
  double height_offset;      /* added to every height (m) */
  double step_size;          /* > 0: heights quantised down to multiples (m) */
} ssTerrainProps;

ssTerrainProps ss_terrain_props_default(void);

/* 2-D gradient (Perlin) noise at (x, y) in lattice units, roughly in
 * [-1, 1], 0 at lattice points.  Gradients come from an integer hash of the
 * lattice cell and seed; only +, -, *, / and floor are used, so values are
 * the same on every IEEE-754 machine (no rand(), no libm transcendentals). */
double ss_noise2(double x, double y, uint32_t seed);

/* Heights of a generated terrain, (y_samples x x_samples), j*nx + i.
 * Vertex (i, j) samples the noise at the bed-local point
 * (i*x_size/(nx-1) - x_size/2, j*y_size/(ny-1) - y_size/2) scaled by
 * frequency; octave k uses frequency*lacunarity^k, amplitude
 * z_scale*gain^k and seed + k:
 *   h = height_offset + sum_k z_scale gain^k noise2(f_k x, f_k y, seed + k)
 * then, when step_size > 0, h = step_size * floor(h / step_size). */
void ss_terrain_generate(const ssTerrainProps *p, double *height);

/* Read a height-map text file (format in the header comment above).
 * *height is malloc'd (nx*ny).  Errors: file = path, line = the line of the
 * text file at fault.  Needs the C numeric locale (see above). */
ssStatus ss_hfield_read_text(const char *path, int *nx, int *ny,
                             double **height, ssError *err);

/* Heights from a PNG: height = z_offset + z_scale * grey, with the image's
 * top row on the +y edge (so the picture is flipped into j order).
 * *height is malloc'd (nx*ny); nx, ny = image width, height. */
ssStatus ss_hfield_read_png(const char *path, double z_scale, double z_offset,
                            int *nx, int *ny, double **height, ssError *err);

#endif /* SS_SCENE_H */
