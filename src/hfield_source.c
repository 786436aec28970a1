/* hfield_source.c -- height maps that are not written out in the scene:
 * generated fractal noise, text files and PNG images (see scene.h). */
#include "scene.h"
#include "png_io.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Largest height map these sources build (vertices); the model builder
 * applies the same cap, this one only keeps allocations sane before it. */
#define SS_SOURCE_MAX_VERTICES 100000000L

ssTerrainProps ss_terrain_props_default(void)
{
  ssTerrainProps p;
  memset(&p, 0, sizeof p);
  p.x_size = p.y_size = 10;
  p.x_samples = p.y_samples = 101;
  p.frequency = 0.2;
  p.z_scale = 1;
  p.fractal_octaves = 5;
  p.fractal_lacunarity = 2;
  p.fractal_gain = 0.5;
  p.seed = 0;
  p.height_offset = 0;
  p.step_size = 0;
  return p;
}

/* ---------------------------------------------------------------------- */
/* noise                                                                   */

/* A 32-bit integer mixer (good avalanche, no multiplication overflow UB on
 * unsigned types). */
static uint32_t mix32(uint32_t x)
{
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

static uint32_t lattice_hash(uint32_t ix, uint32_t iy, uint32_t seed)
{
  uint32_t h = mix32(seed ^ 0x9e3779b9U);
  h = mix32(h ^ ix);
  h = mix32(h ^ (iy * 0x85ebca6bU + 0x68e31da4U));
  return h;
}

/* Eight unit gradient directions, chosen by the hash. */
static const double grad8[8][2] = {
  {1, 0}, {-1, 0}, {0, 1}, {0, -1},
  {0.70710678118654752, 0.70710678118654752},
  {-0.70710678118654752, 0.70710678118654752},
  {0.70710678118654752, -0.70710678118654752},
  {-0.70710678118654752, -0.70710678118654752},
};

static double gradient_dot(uint32_t ix, uint32_t iy, uint32_t seed, double dx,
                           double dy)
{
  const double *g = grad8[lattice_hash(ix, iy, seed) & 7u];
  return g[0] * dx + g[1] * dy;
}

/* Perlin's quintic fade 6t^5 - 15t^4 + 10t^3. */
static double fade(double t)
{
  return t * t * t * (t * (t * 6 - 15) + 10);
}

/* Lattice index of floor(x) modulo 2^32 (exact for |x| < 2^52). */
static uint32_t cell_index(double xf)
{
  double w = xf - 4294967296.0 * floor(xf / 4294967296.0);
  return (uint32_t)w;
}

double ss_noise2(double x, double y, uint32_t seed)
{
  /* beyond 2^52 every double is an integer: a lattice point, where the
   * noise is 0 (and the cell arithmetic below would lose exactness) */
  if (!(fabs(x) < 4.0e15) || !(fabs(y) < 4.0e15)) return 0;
  double xf = floor(x), yf = floor(y);
  double dx = x - xf, dy = y - yf;
  uint32_t ix = cell_index(xf), iy = cell_index(yf);
  double n00 = gradient_dot(ix, iy, seed, dx, dy);
  double n10 = gradient_dot(ix + 1u, iy, seed, dx - 1, dy);
  double n01 = gradient_dot(ix, iy + 1u, seed, dx, dy - 1);
  double n11 = gradient_dot(ix + 1u, iy + 1u, seed, dx - 1, dy - 1);
  double u = fade(dx), v = fade(dy);
  double a = n00 + u * (n10 - n00);
  double b = n01 + u * (n11 - n01);
  /* unit gradients give at most sqrt(1/2) in 2-D: scale to about [-1, 1] */
  return 1.4142135623730951 * (a + v * (b - a));
}

void ss_terrain_generate(const ssTerrainProps *p, double *height)
{
  int nx = p->x_samples, ny = p->y_samples;
  double dx = p->x_size / (nx - 1), dy = p->y_size / (ny - 1);
  for (int j = 0; j < ny; j++) {
    double y = j * dy - 0.5 * p->y_size;
    for (int i = 0; i < nx; i++) {
      double x = i * dx - 0.5 * p->x_size;
      double h = 0, f = p->frequency, a = p->z_scale;
      for (int k = 0; k < p->fractal_octaves; k++) {
        h += a * ss_noise2(f * x, f * y, p->seed + (uint32_t)k);
        f *= p->fractal_lacunarity;
        a *= p->fractal_gain;
      }
      h += p->height_offset;
      if (p->step_size > 0) h = p->step_size * floor(h / p->step_size);
      height[(size_t)j * nx + i] = h;
    }
  }
}

/* ---------------------------------------------------------------------- */
/* text files                                                              */

typedef struct textScan {
  const char *p, *end;
  int line;
  int any;   /* a token was read */
  int comma; /* the line of a comma passed since the last token, or 0 */
} textScan;

/* Next token (a run of characters that are neither white space, ',' nor
 * '#'); comments and separators skipped.  Returns 1 with the token, 0 at
 * the end, -1 at an empty value (a comma before the first token, after
 * another comma or after the last token) with *line that comma's line. */
static int next_token(textScan *s, const char **tb, const char **te, int *line)
{
  const char *p = s->p;
  for (;;) {
    while (p < s->end && (*p == ' ' || *p == '\t' || *p == '\r' ||
                          *p == '\n' || *p == ',' || *p == '\f' || *p == '\v')) {
      if (*p == ',') {
        if (s->comma || !s->any) {
          *line = s->line;
          s->p = p;
          return -1;
        }
        s->comma = s->line;
      }
      if (*p == '\n') s->line++;
      p++;
    }
    if (p < s->end && *p == '#') {
      while (p < s->end && *p != '\n') p++;
      continue;
    }
    break;
  }
  if (p >= s->end) {
    s->p = p;
    if (s->comma) {
      *line = s->comma;
      return -1;
    }
    return 0;
  }
  *tb = p;
  while (p < s->end && !(*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n' ||
                         *p == ',' || *p == '#' || *p == '\f' || *p == '\v'))
    p++;
  *te = p;
  *line = s->line;
  s->p = p;
  s->any = 1;
  s->comma = 0;
  return 1;
}

/* The error for next_token's -1. */
static ssStatus empty_value(const char *path, int line, ssError *err)
{
  return ss_error_set(err, SS_ERR_PARSE, path, line,
                      "empty value in height-map text file: a comma with no "
                      "number on one side (numbers are separated by white "
                      "space or by one comma; none before the first or after "
                      "the last)");
}

ssStatus ss_hfield_read_text(const char *path, int *nx, int *ny,
                             double **height, ssError *err)
{
  *height = NULL;
  *nx = *ny = 0;
  char *buf = NULL;
  size_t len = 0;
  ssStatus st = ss_read_file(path, SS_SCENE_MAX_BYTES, &buf, &len, err);
  if (st != SS_OK) return st;

  /* a UTF-8 byte order mark (as Windows editors write) is no number */
  size_t bom = len >= 3 && !memcmp(buf, "\xef\xbb\xbf", 3) ? 3 : 0;
  textScan s = {buf + bom, buf + len, 1, 0, 0};
  const char *tb, *te;
  int line = 1;
  long dims[2];
  for (int k = 0; k < 2; k++) {
    int got = next_token(&s, &tb, &te, &line);
    if (got < 0) {
      free(buf);
      return empty_value(path, line, err);
    }
    if (!got) {
      free(buf);
      return ss_error_set(err, SS_ERR_PARSE, path, s.line,
                          "height-map text file ends before its size: it "
                          "must start with the integers nx ny");
    }
    int r = ss_scene_parse_long(tb, te, &dims[k]);
    if (r != 0 || dims[k] < 2 || dims[k] > INT_MAX) {
      int n = (int)(te - tb) > 40 ? 40 : (int)(te - tb);
      /* the message quotes the token, which lives in buf: free it after */
      ss_error_set(err, SS_ERR_PARSE, path, line,
                   "bad %s '%.*s' in height-map text file: it must start "
                   "with the integers nx ny, each >= 2",
                   k ? "ny" : "nx", n, tb);
      free(buf);
      return SS_ERR_PARSE;
    }
  }
  if (dims[0] * dims[1] > SS_SOURCE_MAX_VERTICES) {
    free(buf);
    return ss_error_set(err, SS_ERR_VALUE, path, 1,
                        "height-map text file declares %ld x %ld vertices "
                        "(at most %ld)", dims[0], dims[1],
                        SS_SOURCE_MAX_VERTICES);
  }
  size_t n = (size_t)dims[0] * (size_t)dims[1];
  /* count first, so that a short or long file is reported before a large
   * allocation */
  textScan c = s;
  size_t count = 0;
  int got;
  while ((got = next_token(&c, &tb, &te, &line)) > 0) count++;
  if (got < 0) {
    free(buf);
    return empty_value(path, line, err);
  }
  if (count != n) {
    free(buf);
    return ss_error_set(err, SS_ERR_PARSE, path, c.line,
                        "height-map text file has %zu heights after its size "
                        "line, expected nx*ny = %ld*%ld = %zu",
                        count, dims[0], dims[1], n);
  }
  double *h = malloc(n * sizeof *h);
  if (!h) {
    free(buf);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0,
                        "out of memory for %zu heights", n);
  }
  for (size_t k = 0; k < n; k++) {
    next_token(&s, &tb, &te, &line);
    int r = ss_scene_parse_double(tb, te, &h[k]);
    if (r != 0) {
      int tl = (int)(te - tb) > 40 ? 40 : (int)(te - tb);
      ss_error_set(err, SS_ERR_PARSE, path, line,
                   "bad number '%.*s' (height %zu of %zu) in height-map text "
                   "file: %s", tl, tb, k + 1, n,
                   r == 2 ? "out of range" : "expected a finite decimal number");
      free(h);
      free(buf);
      return err ? err->code : SS_ERR_PARSE;
    }
  }
  free(buf);
  *nx = (int)dims[0];
  *ny = (int)dims[1];
  *height = h;
  return SS_OK;
}

/* ---------------------------------------------------------------------- */
/* PNG images                                                              */

ssStatus ss_hfield_read_png(const char *path, double z_scale, double z_offset,
                            int *nx, int *ny, double **height, ssError *err)
{
  *height = NULL;
  *nx = *ny = 0;
  int w = 0, hgt = 0;
  double *grey = NULL;
  ssStatus st = ss_png_read_gray(path, &w, &hgt, &grey, err);
  if (st != SS_OK) return st;
  if (w < 2 || hgt < 2) {
    free(grey);
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "PNG height map is %d x %d pixels; at least 2 x 2 "
                        "are needed", w, hgt);
  }
  if ((long)w * (long)hgt > SS_SOURCE_MAX_VERTICES) {
    free(grey);
    return ss_error_set(err, SS_ERR_VALUE, path, 0,
                        "PNG height map is %d x %d pixels (at most %ld)", w,
                        hgt, SS_SOURCE_MAX_VERTICES);
  }
  double *h = malloc((size_t)w * (size_t)hgt * sizeof *h);
  if (!h) {
    free(grey);
    return ss_error_set(err, SS_ERR_NOMEM, path, 0, "out of memory");
  }
  /* image row 0 is the +y edge: bed row j reads image row hgt-1-j */
  for (int j = 0; j < hgt; j++) {
    const double *row = grey + (size_t)(hgt - 1 - j) * (size_t)w;
    for (int i = 0; i < w; i++)
      h[(size_t)j * w + i] = z_offset + z_scale * row[i];
  }
  free(grey);
  *nx = w;
  *ny = hgt;
  *height = h;
  return SS_OK;
}
